""":func:`sonar_gym.sonar.kernels.on_axis_echoes` and
:func:`sonar_gym.sonar.kernels.audible_candidates` as they were when the on-axis amplitudes,
the clipped ranges and the centre distances came back as arrays of their own, kept verbatim as
the tests' reference for the forms that write the on-axis amplitudes into the map's amplitudes
rows and return the ranges and distances in one array."""

from __future__ import annotations

import math

import numpy as np
from numba import types

from sonar_gym.compiled import FLAGS, INDICES, NUMBERS, compiled, nan_max, nan_min
from sonar_gym.pose import FloatArray
from sonar_gym.sonar.kernels import passing_candidates


@compiled(  # type: ignore[misc]
    types.Tuple(
        (
            types.Array(types.boolean, 1, "C"),
            types.Array(types.float64, 1, "C"),
            types.Array(types.float64, 1, "C"),
            types.Array(types.float64, 1, "C"),
        )
    ),
    types.Array(types.float64, 1, "C"),  # mapped (ranges and scaled cylinder offsets written)
    INDICES,  # layout
    NUMBERS,  # radius_padded
    NUMBERS,  # radius
    NUMBERS,  # edge law constants
)
def on_axis_echoes_reference(
    mapped: FloatArray,
    layout: np.ndarray,
    radius_padded: FloatArray,
    radius: FloatArray,
    edge_law: FloatArray,
) -> tuple[np.ndarray, FloatArray, FloatArray, FloatArray]:
    """The ranges and on-axis echo laws of :func:`sonar_gym.sonar.echoes.echo_candidates`,
    candidate by candidate: ``(concave (W,), centre distances (C,), ranges clipped at 1 nm
    (N,), on-axis amplitudes before air and gain (N,))``, in metres and 1/m.

    ``mapped`` is the search map's product at the sensor: its ``(rel_x, rel_y, 1)`` rows come
    first (one per candidate); the ranges are written into its ranges rows and the cylinders'
    offsets scaled to their echo points, in place.

    Args:
        layout: ``(S, C, W, V, first ranges row, first wedge-side row a, b)``.
        radius_padded: ``(N,)`` each candidate's radius (0 but for cylinders), metres.
        radius: ``(C,)`` cylinder radii, metres.
        edge_law: ``(1, s)`` for the weak law ``s / r^2``, ``(0, G / (2 sqrt(pi k)))`` for the
            GTD law ``G / (2 sqrt(pi k) r^1.5)``.
    """
    n_segments, n_circles, n_wedges, n_vertices = layout[0], layout[1], layout[2], layout[3]
    ranges_start, wedge_a_start, wedge_b_start = layout[4], layout[5], layout[6]
    weak, edge_constant = edge_law[0] > 0.0, edge_law[1]
    n_specular = n_segments + n_circles
    n_candidates = n_specular + n_vertices
    concave = np.empty(n_wedges, dtype=np.bool_)
    for wedge in range(n_wedges):
        side = nan_min(mapped[wedge_a_start + wedge], mapped[wedge_b_start + wedge])
        concave[wedge] = side > 0.0
    safe = np.empty(n_candidates)
    centre_distance = np.empty(n_circles)
    for candidate in range(n_candidates):
        distance = np.hypot(mapped[3 * candidate], mapped[3 * candidate + 1])
        reach = distance - radius_padded[candidate]
        mapped[ranges_start + candidate] = reach
        safe[candidate] = nan_max(reach, 1e-9)
        circle = candidate - n_segments
        if 0 <= circle < n_circles:
            centre_distance[circle] = distance
            shrink = 1.0 - radius[circle] / nan_max(distance, 1e-12)
            mapped[3 * candidate] = mapped[3 * candidate] * shrink
            mapped[3 * candidate + 1] = mapped[3 * candidate + 1] * shrink
    on_axis = np.empty(n_candidates)
    for candidate in range(n_candidates):
        inverse_square = 0.5 / safe[candidate]
        if candidate < n_segments:
            on_axis[candidate] = inverse_square
        elif candidate < n_specular:
            rho = radius[candidate - n_segments]
            on_axis[candidate] = inverse_square * math.sqrt(rho / (safe[candidate] + rho))
        else:
            r = safe[candidate]
            edge = edge_constant / (r * r) if weak else edge_constant / (r * math.sqrt(r))
            wedge = candidate - n_specular
            if wedge < n_wedges and concave[wedge]:
                on_axis[candidate] = inverse_square
            else:
                on_axis[candidate] = edge
    return concave, centre_distance, safe, on_axis


@compiled(  # type: ignore[misc]
    types.Tuple(
        (
            types.Array(types.int64, 1, "C"),
            types.Array(types.float64, 2, "C"),
            types.Array(types.boolean, 1, "C"),
        )
    ),
    types.Array(types.float64, 1, "C"),  # mapped (amplitudes written)
    INDICES,  # layout
    NUMBERS,  # on_axis
    NUMBERS,  # absorption
    NUMBERS,  # gain
    NUMBERS,  # strict_bounds
    NUMBERS,  # inclusive_bounds
    FLAGS,  # concave
    INDICES,  # twin
    FLAGS,  # twin_comes_last
    types.boolean,  # has_t_junctions
    NUMBERS,  # footprint
)
def audible_candidates_reference(
    mapped: FloatArray,
    layout: np.ndarray,
    on_axis: FloatArray,
    absorption: FloatArray,
    gain: FloatArray,
    strict_bounds: FloatArray,
    inclusive_bounds: FloatArray,
    concave: np.ndarray,
    twin: np.ndarray,
    twin_comes_last: np.ndarray,
    has_t_junctions: bool,
    footprint: FloatArray,
) -> tuple[np.ndarray, FloatArray, np.ndarray]:
    """The middle of :func:`sonar_gym.sonar.echoes.echo_candidates`: the amplitudes, the
    per-candidate tests and the robot's footprint, candidate by candidate: ``(indices of the
    candidates that pass, (P, 3) their rows (rel_x, rel_y, 1), (S + C,) which primitives may
    occlude)``.

    ``mapped`` is the search map's product at the sensor after :func:`on_axis_echoes`; each
    candidate's amplitude, ``on_axis x absorption x gain`` in that order (1/m), is written into
    its amplitudes row, then :func:`passing_candidates` tests the rows from the first test row
    on.

    Args:
        layout: :func:`on_axis_echoes`' ``(S, C, W, V, first ranges row, ...)``.
        on_axis: ``(N,)`` on-axis amplitudes before air and gain (1/m).
        absorption, gain: ``(N,)`` air absorption and receiver gain factors, each empty when
            it is 1.
        strict_bounds, inclusive_bounds, concave, twin, twin_comes_last, has_t_junctions:
            those of :func:`passing_candidates`.
        footprint: ``(p_x - f_x, p_y - f_y, radius)``, the sensor's offset from the robot's
            footprint centre and its radius (metres, {W}): echo points with
            ``hypot(rel + offset) < radius`` are dropped; empty: no footprint test.
    """
    n_segments, n_circles, n_vertices = layout[0], layout[1], layout[3]
    n_specular = n_segments + n_circles
    n_candidates = n_specular + n_vertices
    ranges_start = layout[4]
    amplitudes_start = ranges_start + n_candidates
    for candidate in range(n_candidates):
        amplitude = on_axis[candidate]
        if absorption.shape[0] > 0:
            amplitude = amplitude * absorption[candidate]
        if gain.shape[0] > 0:
            amplitude = amplitude * gain[candidate]
        mapped[amplitudes_start + candidate] = amplitude
    passing, occluders = passing_candidates(
        mapped[ranges_start - 3 * n_candidates :],
        strict_bounds,
        inclusive_bounds,
        concave,
        twin,
        twin_comes_last,
        n_specular,
        has_t_junctions,
    )
    keep = np.empty(passing.shape[0], dtype=np.int64)
    kept = np.empty((passing.shape[0], 3))
    n_kept = 0
    for candidate in passing:
        rel_x, rel_y = mapped[3 * candidate], mapped[3 * candidate + 1]
        inside = footprint.shape[0] > 0 and not (
            np.hypot(rel_x + footprint[0], rel_y + footprint[1]) >= footprint[2]
        )
        if inside:  # the echo point lies on the robot's body
            continue
        keep[n_kept] = candidate
        kept[n_kept, 0], kept[n_kept, 1] = rel_x, rel_y
        kept[n_kept, 2] = mapped[3 * candidate + 2]
        n_kept += 1
    return keep[:n_kept].copy(), kept[:n_kept].copy(), occluders
