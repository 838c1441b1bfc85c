"""The array form of :func:`sonar_gym.sonar.table_kernels.linear_maps`, as
:mod:`sonar_gym.sonar.echo_tables` built the maps before the compiled loop (kept verbatim: the
reference its bits are checked against)."""

from __future__ import annotations

import numpy as np

from sonar_gym.geometry import StaticGeometry


def reference_linear_maps(
    geometry: StaticGeometry,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """``(position_map, occlusion_map, vertex_order, n_wedges)`` of ``geometry``."""
    a = geometry.segment_starts
    d = geometry.segment_ends - a
    n_segments, n_circles = geometry.n_segments, geometry.n_circles
    length = np.hypot(d[:, 0], d[:, 1])
    normal = np.column_stack([-d[:, 1], d[:, 0]]) / length[:, None]  # left unit normal
    normal_offset = np.einsum("ij,ij->i", a, normal)

    arm_a, arm_b = geometry.vertex_arms[:, 0], geometry.vertex_arms[:, 1]
    cross_ab = arm_a[:, 0] * arm_b[:, 1] - arm_a[:, 1] * arm_b[:, 0]
    wedge = np.abs(cross_ab) > 1e-9
    order = np.concatenate([np.flatnonzero(wedge), np.flatnonzero(~wedge)])
    vertices = geometry.vertices[order]
    n_vertices, n_wedges = len(vertices), int(wedge.sum())

    # (rel_x, rel_y, 1) rows of every candidate, as coefficients of (px, py, 1).
    n_candidates = n_segments + n_circles + n_vertices
    rel = np.zeros((n_candidates, 3, 3))
    projector = normal[:, :, None] * normal[:, None, :]  # n n^T
    rel[:n_segments, :2, :2] = -projector  # -n n^T (p - a)
    rel[:n_segments, :2, 2] = normal * normal_offset[:, None]  # n (n . a)
    points = np.concatenate([geometry.circles[:, :2], vertices])
    rel[n_segments:, 0, 0] = -1.0
    rel[n_segments:, 1, 1] = -1.0
    rel[n_segments:, :2, 2] = points
    rel[:, 2, 2] = 1.0

    along = np.column_stack([d, -np.einsum("ij,ij->i", a, d)]) / (length * length)[:, None]
    distance = np.column_stack([normal, -normal_offset])
    sign = np.sign(cross_ab[order][:n_wedges])[:, None]
    va, vb, vw = arm_a[order][:n_wedges], arm_b[order][:n_wedges], vertices[:n_wedges]
    # sign * arm_a x (p - v) and sign * (p - v) x arm_b.
    wedge_a = sign * np.column_stack(
        [-va[:, 1], va[:, 0], va[:, 1] * vw[:, 0] - va[:, 0] * vw[:, 1]]
    )
    wedge_b = sign * np.column_stack(
        [vb[:, 1], -vb[:, 0], vb[:, 0] * vw[:, 1] - vb[:, 1] * vw[:, 0]]
    )
    position_map = np.concatenate([rel.reshape(-1, 3), along, distance, wedge_a, wedge_b])

    # Occlusion: N[row, column] as coefficients of (px, py, 1); columns act on (rel_x, rel_y, 1).
    n_rows = 3 * n_segments + n_circles
    occlusion = np.zeros((n_rows, 3, 3))
    den, u_num, v_num = (
        slice(0, n_segments),
        slice(n_segments, 2 * n_segments),
        slice(2 * n_segments, 3 * n_segments),
    )
    occlusion[den, 0, 2] = d[:, 1]  # rel x d = rel_x d_y - rel_y d_x
    occlusion[den, 1, 2] = -d[:, 0]
    occlusion[u_num, 2, 0] = -d[:, 1]  # (a - p) x d
    occlusion[u_num, 2, 1] = d[:, 0]
    occlusion[u_num, 2, 2] = a[:, 0] * d[:, 1] - a[:, 1] * d[:, 0]
    occlusion[v_num, 0, 1] = 1.0  # (a - p) x rel = (a_x - p_x) rel_y - (a_y - p_y) rel_x
    occlusion[v_num, 0, 2] = -a[:, 1]
    occlusion[v_num, 1, 0] = -1.0
    occlusion[v_num, 1, 2] = a[:, 0]
    circles = slice(3 * n_segments, n_rows)  # (c - p) . rel
    occlusion[circles, 0, 0] = -1.0
    occlusion[circles, 0, 2] = geometry.circles[:, 0]
    occlusion[circles, 1, 1] = -1.0
    occlusion[circles, 1, 2] = geometry.circles[:, 1]

    return position_map, occlusion.reshape(-1, 3), order, n_wedges
