"""The compiled loop that fills the linear maps of :mod:`sonar_gym.sonar.echo_tables` (numba).

The array form made some fifty numpy calls per geometry, each on a few dozen rows; a room with
unmapped boxes drawn per episode builds new tables every episode. This loop writes the same
entries, each by the same IEEE-754 steps (one product, quotient or difference at a time, no
fused multiply-add: :mod:`sonar_gym.compiled`; numpy's ``einsum`` dot products summed from
``+0.0``), so every entry has the array form's bits. The
segment lengths stay numpy's ``hypot`` and come in as an argument.
"""

from __future__ import annotations

import numpy as np
from numba import types

from sonar_gym.compiled import NUMBERS, TABLE, compiled
from sonar_gym.pose import FloatArray

WEDGE_CROSS_TOLERANCE = 1e-9
"""A vertex whose two unit arms have a cross product above this in magnitude is a wedge (a
possibly concave corner); straight-through and one-armed vertices are not."""

_MAP = types.Array(types.float64, 2, "C")


@compiled(  # type: ignore[misc]
    types.Tuple((_MAP, _MAP, types.Array(types.int64, 1, "C"), types.int64)),
    TABLE,  # segment starts a
    TABLE,  # segment vectors d
    NUMBERS,  # segment lengths |d|
    TABLE,  # circles [x, y, radius]
    TABLE,  # vertices
    TABLE,  # first arm of each vertex
    TABLE,  # second arm of each vertex
)
def linear_maps(
    starts: FloatArray,
    vectors: FloatArray,
    lengths: FloatArray,
    circles: FloatArray,
    vertices: FloatArray,
    arm_a: FloatArray,
    arm_b: FloatArray,
) -> tuple[FloatArray, FloatArray, np.ndarray, int]:
    """``(position_map, occlusion_map, vertex_order, n_wedges)`` of
    :class:`~sonar_gym.sonar.echo_tables.EchoTables` (see its attributes for the rows).

    Args:
        starts: ``(S, 2)`` segment starts ``a`` ({W}, metres).
        vectors: ``(S, 2)`` segment vectors ``d = end - a`` (metres).
        lengths: ``(S,)`` ``|d|``, numpy's ``hypot`` (metres).
        circles: ``(C, 3)`` cylinders ``[x, y, radius]`` (metres).
        vertices: ``(V, 2)`` vertices (metres); ``arm_a``, ``arm_b``: ``(V, 2)`` their unit arms.

    Returns:
        The two maps, the vertices' order in the tables (wedges first, each group in vertex
        order) and the number of wedges ``W``.
    """
    n_segments, n_circles, n_vertices = starts.shape[0], circles.shape[0], vertices.shape[0]
    cross = np.empty(n_vertices)
    order = np.empty(n_vertices, dtype=np.int64)
    n_wedges = 0
    for v in range(n_vertices):
        cross[v] = arm_a[v, 0] * arm_b[v, 1] - arm_a[v, 1] * arm_b[v, 0]
        if abs(cross[v]) > WEDGE_CROSS_TOLERANCE:
            order[n_wedges] = v
            n_wedges += 1
    rest = n_wedges
    for v in range(n_vertices):
        if not abs(cross[v]) > WEDGE_CROSS_TOLERANCE:
            order[rest] = v
            rest += 1

    n_candidates = n_segments + n_circles + n_vertices
    n_rel = 3 * n_candidates
    position_map = np.zeros((n_rel + 2 * n_segments + 2 * n_wedges, 3))
    along_row, distance_row = n_rel, n_rel + n_segments
    for s in range(n_segments):
        ax, ay, dx, dy = starts[s, 0], starts[s, 1], vectors[s, 0], vectors[s, 1]
        nx, ny = -dy / lengths[s], dx / lengths[s]  # left unit normal
        # n . a as numpy's einsum sums it: from +0.0 (so a sum of -0.0 terms is +0.0)
        offset = 0.0 + (ax * nx + ay * ny)
        row = 3 * s  # (rel_x, rel_y, 1) = -n n^T (p - a)
        position_map[row, 0] = -(nx * nx)
        position_map[row, 1] = -(nx * ny)
        position_map[row, 2] = nx * offset
        position_map[row + 1, 0] = -(ny * nx)
        position_map[row + 1, 1] = -(ny * ny)
        position_map[row + 1, 2] = ny * offset
        length_sq = lengths[s] * lengths[s]
        position_map[along_row + s, 0] = dx / length_sq
        position_map[along_row + s, 1] = dy / length_sq
        position_map[along_row + s, 2] = -(0.0 + (ax * dx + ay * dy)) / length_sq
        position_map[distance_row + s, 0] = nx
        position_map[distance_row + s, 1] = ny
        position_map[distance_row + s, 2] = -offset
    for k in range(n_circles + n_vertices):  # rel = point - p
        row = 3 * (n_segments + k)
        position_map[row, 0] = -1.0
        position_map[row + 1, 1] = -1.0
        if k < n_circles:
            position_map[row, 2] = circles[k, 0]
            position_map[row + 1, 2] = circles[k, 1]
        else:
            position_map[row, 2] = vertices[order[k - n_circles], 0]
            position_map[row + 1, 2] = vertices[order[k - n_circles], 1]
    for c in range(n_candidates):
        position_map[3 * c + 2, 2] = 1.0
    wedge_a_row, wedge_b_row = n_rel + 2 * n_segments, n_rel + 2 * n_segments + n_wedges
    for w in range(n_wedges):  # sign * arm_a x (p - v) and sign * (p - v) x arm_b
        v = order[w]
        sign = np.sign(cross[v])
        ax, ay, bx, by = arm_a[v, 0], arm_a[v, 1], arm_b[v, 0], arm_b[v, 1]
        vx, vy = vertices[v, 0], vertices[v, 1]
        position_map[wedge_a_row + w, 0] = sign * -ay
        position_map[wedge_a_row + w, 1] = sign * ax
        position_map[wedge_a_row + w, 2] = sign * (ay * vx - ax * vy)
        position_map[wedge_b_row + w, 0] = sign * by
        position_map[wedge_b_row + w, 1] = sign * -bx
        position_map[wedge_b_row + w, 2] = sign * (bx * vy - by * vx)

    # N[row] as a 3 x 3 block of coefficients of (px, py, 1), columns acting on (rel_x, rel_y, 1)
    n_rows = 3 * n_segments + n_circles
    occlusion = np.zeros((3 * n_rows, 3))
    for s in range(n_segments):
        ax, ay, dx, dy = starts[s, 0], starts[s, 1], vectors[s, 0], vectors[s, 1]
        den, u_num, v_num = 3 * s, 3 * (n_segments + s), 3 * (2 * n_segments + s)
        occlusion[den, 2] = dy  # rel x d = rel_x d_y - rel_y d_x
        occlusion[den + 1, 2] = -dx
        occlusion[u_num + 2, 0] = -dy  # (a - p) x d
        occlusion[u_num + 2, 1] = dx
        occlusion[u_num + 2, 2] = ax * dy - ay * dx
        occlusion[v_num, 1] = 1.0  # (a - p) x rel = (a_x - p_x) rel_y - (a_y - p_y) rel_x
        occlusion[v_num, 2] = -ay
        occlusion[v_num + 1, 0] = -1.0
        occlusion[v_num + 1, 2] = ax
    for c in range(n_circles):  # (c - p) . rel
        row = 3 * (3 * n_segments + c)
        occlusion[row, 0] = -1.0
        occlusion[row, 2] = circles[c, 0]
        occlusion[row + 1, 1] = -1.0
        occlusion[row + 1, 2] = circles[c, 1]
    return position_map, occlusion, order, n_wedges
