"""Compiled inner loops of the pan: the readout of many pings, the echo search's tests (numba).

The array forms in :mod:`sonar_gym.sonar.pulse_echo` and :mod:`sonar_gym.sonar.echoes` spend
most of a pan in numpy's per-call overhead on arrays of a few hundred elements. These loops do
the same arithmetic element by element, in the same order, so they return the same bits:

* every elementwise step (``+ - * /``, ``sqrt``, ``floor``, comparisons) is IEEE-754 in both, and
  numba fuses no multiply-add unless asked (no ``fastmath``);
* a product that numpy takes through BLAS with both sides at least two wide (``(pings, 2) @
  (2, candidates)``) is a fused multiply-add there, ``fma(b1, f1, b0 * f0)``;
  :data:`sonar_gym.compiled.fused_multiply_add` gives the loops that same single rounding.
  With one ping or one candidate numpy goes through another BLAS kernel that rounds
  differently, so callers keep numpy's path for those.
* the loops stop at the first detected candidate and the first occluder; numpy computes them
  all and discards the rest (the discarded values never reach a result).

How they are compiled (one signature, cached, numpy's division by zero):
:mod:`sonar_gym.compiled`. The sonar modules import this one; ``import sonar_gym`` alone does
not.
"""

from __future__ import annotations

import math

import numpy as np
from numba import types

from sonar_gym.compiled import (
    FLAGS,
    INDICES,
    NUMBERS,
    TABLE,
    compiled,
    fused_multiply_add,
    nan_max,
    nan_min,
)
from sonar_gym.pose import FloatArray


def _main_lobe_cos_limit(
    level: float,
    rising: FloatArray,
    main_lobe_cells: FloatArray,
    inverse_steps: float,
    smallest_cosine: float,
) -> float:
    """:meth:`~sonar_gym.sonar.acoustics.PistonBeam.main_lobe_cos_limits` of one level, in its
    order: the cosine a candidate needs to be heard when ``level`` is the threshold over its
    on-axis amplitude (2 for a level above 1; ``rising``, ``main_lobe_cells``: the beam's
    tables; ``inverse_steps``: ``1 / TABLE_STEPS_PER_UNIT``)."""
    clipped = min(level, 1.0)
    index = np.searchsorted(rising, clipped)
    number, value, slope = (
        main_lobe_cells[index, 0],
        main_lobe_cells[index, 1],
        main_lobe_cells[index, 2],
    )
    s_limit = (number + (clipped - value) / slope) * inverse_steps
    limit = max(1.0 - s_limit * s_limit, smallest_cosine)
    return 2.0 if level > 1.0 else limit


main_lobe_cos_limit = compiled(
    types.float64, types.float64, NUMBERS, TABLE, types.float64, types.float64, inline=True
)(_main_lobe_cos_limit)


@compiled(  # type: ignore[misc]
    types.Array(types.float64, 2, "C"),  # readings
    TABLE,  # directions
    TABLE,  # in_frame
    NUMBERS,  # rising
    TABLE,  # main_lobe_cells
    NUMBERS,  # amplitudes
    NUMBERS,  # path_lengths
    TABLE,  # cells
    NUMBERS,  # normals
    NUMBERS,  # constants
)
def main_lobe_readings(
    directions: FloatArray,
    in_frame: FloatArray,
    rising: FloatArray,
    main_lobe_cells: FloatArray,
    amplitudes: FloatArray,
    path_lengths: FloatArray,
    cells: FloatArray,
    normals: FloatArray,
    constants: FloatArray,
) -> FloatArray:
    """``(2, pings)`` rows of ranges (m, NaN for a dropout) and amplitudes (1/m, 0 for one).

    The loop of :func:`sonar_gym.sonar.pulse_echo._main_lobe_readings`: the cosine each
    candidate needs to be detected (:func:`main_lobe_cos_limit` of the threshold over its
    amplitude), then per ping the first candidate whose cosine reaches its limit, the beam's
    table at that cosine, then steps 1-5 of the readout.

    Args:
        directions: ``(pings, 2)`` beam directions in the robot frame {R} (unit vectors).
        in_frame: ``(2, candidates)`` candidate directions in {R}.
        rising, main_lobe_cells: the beam's main-lobe tables
            (:class:`~sonar_gym.sonar.acoustics.PistonBeam`).
        amplitudes, path_lengths: ``(candidates,)`` on-axis amplitudes (1/m), one-way paths (m).
        cells: the beam's ``(value, slope)`` table, :class:`~sonar_gym.sonar.acoustics.PistonBeam`.
        normals: ``(pings,)`` standard normals of the jitter, or empty without jitter.
        constants: table steps per unit of ``s``; seconds of flight per metre of path (``2 /
            c_true``); the crossing-delay numerator (``rise time x threshold``, 0 without the
            delay); jitter in seconds per normal; ``1 / T0`` and ``T0`` (0 without a counter);
            metres per second of flight (``c_assumed / 2``); the maximum range (m); the
            detection threshold (1/m); ``1 / TABLE_STEPS_PER_UNIT``; the smallest positive
            cosine.
    """
    steps, tof_per_m, delay_numerator = constants[0], constants[1], constants[2]
    jitter_s, inverse_period, period = constants[3], constants[4], constants[5]
    metres_per_s, max_range, threshold = constants[6], constants[7], constants[8]
    inverse_steps, smallest_cosine = constants[9], constants[10]
    n_pings, n_candidates = directions.shape[0], path_lengths.shape[0]
    limits = np.empty(n_candidates)
    for candidate in range(n_candidates):
        limits[candidate] = main_lobe_cos_limit(
            threshold / amplitudes[candidate],
            rising,
            main_lobe_cells,
            inverse_steps,
            smallest_cosine,
        )
    readings = np.empty((2, n_pings))
    for ping in range(n_pings):
        bx, by = directions[ping, 0], directions[ping, 1]
        first, cosine = -1, 0.0
        for candidate in range(n_candidates):  # sorted nearest first
            c = fused_multiply_add(by, in_frame[1, candidate], bx * in_frame[0, candidate])
            if c >= limits[candidate]:
                first, cosine = candidate, c
                break
        readings[0, ping], readings[1, ping] = np.nan, 0.0
        if first < 0:
            continue
        scaled = math.sqrt(abs(1.0 - cosine)) * steps
        whole = math.floor(scaled)
        cell = int(whole)
        amplitude = (cells[cell, 0] + (scaled - whole) * cells[cell, 1]) * amplitudes[first]
        tof = path_lengths[first] * tof_per_m
        if delay_numerator > 0.0:
            tof = tof + delay_numerator / amplitude
        if normals.shape[0] > 0:
            tof = tof + normals[ping] * jitter_s
        if period > 0.0:
            tof = math.floor(tof * inverse_period) * period
        reading = tof * metres_per_s
        if reading <= max_range:
            readings[0, ping], readings[1, ping] = reading, amplitude
    return readings


@compiled(  # type: ignore[misc]
    types.Array(types.boolean, 1, "C"),  # clear
    TABLE,  # products
    NUMBERS,  # ranges
    NUMBERS,  # centre_distance
    NUMBERS,  # radius_sq
    FLAGS,  # occluders
    types.float64,  # path_centre
)
def unoccluded(
    products: FloatArray,
    ranges: FloatArray,
    centre_distance: FloatArray,
    radius_sq: FloatArray,
    occluders: np.ndarray,
    path_centre: float,
) -> np.ndarray:
    """``(paths,)`` which paths no occluding segment crosses and no circle cuts.

    The tests of :func:`sonar_gym.sonar.echoes._unoccluded_nearest_first`, path by path.

    Args:
        products: ``(3 S + C, paths)`` the occlusion map times each path (crossing
            denominators, the ``u`` and ``v`` numerators per segment, then ``c - p . rel`` per
            circle), metres squared.
        ranges: ``(paths,)`` path lengths, metres.
        centre_distance: ``(C,)`` sensor-to-centre distances, metres.
        radius_sq: ``(C,)`` squared circle radii, m^2.
        occluders: ``(S + C,)`` which segments may occlude (the circle entries are ignored:
            every circle may).
        path_centre: the middle (and half width) of the blocking interval of ``u`` and ``u*``,
            ``(1 - tol) / 2``.
    """
    n_circles = centre_distance.shape[0]
    n_segments = (products.shape[0] - n_circles) // 3
    n_paths = ranges.shape[0]
    clear = np.ones(n_paths, dtype=np.bool_)
    for path in range(n_paths):
        for segment in range(n_segments):
            if not occluders[segment]:
                continue
            denominator = products[segment, path]
            u = products[n_segments + segment, path] / denominator
            if abs(u - path_centre) <= path_centre:
                v = products[2 * n_segments + segment, path] / denominator
                if abs(v - 0.5) <= 0.5:
                    clear[path] = False
                    break
        if not clear[path]:
            continue
        range_sq = ranges[path] * ranges[path]
        for circle in range(n_circles):
            dot = products[3 * n_segments + circle, path]
            nearest = dot / range_sq
            if abs(nearest - path_centre) <= path_centre:
                distance = centre_distance[circle]
                if distance * distance - dot * nearest < radius_sq[circle]:
                    clear[path] = False
                    break
    return clear


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.boolean, 1, "C"), types.Array(types.float64, 1, "C"))),
    types.Array(types.float64, 1, "C"),  # mapped (ranges, offsets, on-axis amplitudes written)
    INDICES,  # layout
    NUMBERS,  # radius_padded
    NUMBERS,  # radius
    NUMBERS,  # edge law constants
)
def on_axis_echoes(
    mapped: FloatArray,
    layout: np.ndarray,
    radius_padded: FloatArray,
    radius: FloatArray,
    edge_law: FloatArray,
) -> tuple[np.ndarray, FloatArray]:
    """The ranges and on-axis echo laws of :func:`sonar_gym.sonar.echoes.echo_candidates`,
    candidate by candidate: ``(concave (W,), distances (C + N,))``, the distances being the
    centre distances ``(C,)``, then the ranges clipped at 1 nm ``(N,)``, in metres.

    ``mapped`` is the search map's product at the sensor: its ``(rel_x, rel_y, 1)`` rows come
    first (one per candidate); the ranges are written into its ranges rows, the cylinders'
    offsets scaled to their echo points and the on-axis amplitudes before air and gain (1/m)
    written into its amplitudes rows, in place. (One returned array, not one per quantity:
    each array a compiled call returns costs about a microsecond to hand back.)

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
    amplitudes_start = ranges_start + n_candidates
    concave = np.empty(n_wedges, dtype=np.bool_)
    for wedge in range(n_wedges):
        side = nan_min(mapped[wedge_a_start + wedge], mapped[wedge_b_start + wedge])
        concave[wedge] = side > 0.0
    distances = np.empty(n_circles + n_candidates)
    centre_distance = distances[:n_circles]
    safe = distances[n_circles:]
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
    on_axis = mapped[amplitudes_start : amplitudes_start + n_candidates]
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
    return concave, distances


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.int64, 1, "C"), types.Array(types.boolean, 1, "C"))),
    NUMBERS,  # tested: mapped rows from the first test row on
    NUMBERS,  # strict_bounds
    NUMBERS,  # inclusive_bounds
    FLAGS,  # concave
    INDICES,  # twin
    FLAGS,  # twin_comes_last
    types.int64,  # n_specular
    types.boolean,  # has_t_junctions
)
def passing_candidates(
    tested: FloatArray,
    strict_bounds: FloatArray,
    inclusive_bounds: FloatArray,
    concave: np.ndarray,
    twin: np.ndarray,
    twin_comes_last: np.ndarray,
    n_specular: int,
    has_t_junctions: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """The per-candidate tests of :func:`sonar_gym.sonar.echoes.echo_candidates`, candidate
    by candidate: ``(indices of the candidates that pass, (S + C,) which primitives may
    occlude)``.

    Args:
        tested: the search map's product from its first test row on (``5 N + S + C``): the
            two strict tests, then the facing test, the ranges and the amplitudes, then the
            occluder rows.
        strict_bounds: ``(2 N,)`` bounds of the strict tests (``>``).
        inclusive_bounds: ``(3 N + S + C,)`` bounds of the others (``>=``).
        concave, twin, twin_comes_last: ``(W,)`` per wedge vertex: whether it is concave from
            the sensor, its T-junction twin, and whether the twin comes last (a T-junction
            echoes once: from its concave side if it has one, else from its first vertex).
        n_specular: segments plus circles (the first wedge's candidate index).
        has_t_junctions: whether any wedge has a twin.
    """
    n_candidates = strict_bounds.shape[0] // 2
    n_wedges = concave.shape[0]
    keep = np.empty(n_candidates, dtype=np.int64)
    n_kept = 0
    for candidate in range(n_candidates):
        passes = True
        for test in range(2):  # strictly inside the segment
            row = test * n_candidates + candidate
            if not tested[row] > strict_bounds[row]:
                passes = False
        for test in range(3):  # facing, minimum range, threshold
            row = (2 + test) * n_candidates + candidate
            if not tested[row] >= inclusive_bounds[row - 2 * n_candidates]:
                passes = False
        wedge = candidate - n_specular
        if passes and has_t_junctions and 0 <= wedge < n_wedges:
            if concave[twin[wedge]] == concave[wedge]:
                passes = twin_comes_last[wedge]
            else:
                passes = concave[wedge]
        if passes:
            keep[n_kept] = candidate
            n_kept += 1
    n_occluders = tested.shape[0] - 5 * n_candidates
    occluders = np.empty(n_occluders, dtype=np.bool_)
    for occluder in range(n_occluders):
        row = 5 * n_candidates + occluder
        occluders[occluder] = tested[row] >= inclusive_bounds[row - 2 * n_candidates]
    return keep[:n_kept].copy(), occluders


@compiled(  # type: ignore[misc]
    types.Tuple(
        (
            types.Array(types.int64, 1, "C"),
            types.Array(types.float64, 2, "C"),
            types.Array(types.float64, 1, "C"),
            types.Array(types.float64, 1, "C"),
        )
    ),
    INDICES,  # keep
    FLAGS,  # clear
    TABLE,  # kept
    NUMBERS,  # ranges
    NUMBERS,  # amplitudes
)
def nearest_first(
    keep: np.ndarray,
    clear: np.ndarray,
    kept: FloatArray,
    ranges: FloatArray,
    amplitudes: FloatArray,
) -> tuple[np.ndarray, FloatArray, FloatArray, FloatArray]:
    """The last step of :func:`sonar_gym.sonar.echoes.echo_candidates`: the candidates
    ``keep[clear]`` ordered nearest first, as ``argsort(kind="stable")`` orders their ranges
    (ties in their order, NaN last), and ``(indices, (K, 2) unit directions, path lengths,
    amplitudes)`` of them.

    Args:
        keep: ``(P,)`` candidate indices.
        clear: ``(P,)`` which of them to keep.
        kept: ``(P, >= 2)`` each one's offset ``rel`` from the sensor ({W}, metres).
        ranges, amplitudes: per candidate index (metres, 1/m).
    """
    n_clear = 0
    for place in range(keep.shape[0]):
        if clear[place]:
            n_clear += 1
    order = np.empty(n_clear, dtype=np.int64)  # places in keep, nearest first
    n_sorted = 0
    for place in range(keep.shape[0]):
        if not clear[place]:
            continue
        distance = ranges[keep[place]]
        slot = n_sorted
        while slot > 0:
            before = ranges[keep[order[slot - 1]]]
            if not (distance < before or (before != before and distance == distance)):
                break
            order[slot] = order[slot - 1]
            slot -= 1
        order[slot] = place
        n_sorted += 1
    indices = np.empty(n_clear, dtype=np.int64)
    directions = np.empty((n_clear, 2))
    path_lengths = np.empty(n_clear)
    kept_amplitudes = np.empty(n_clear)
    for rank in range(n_clear):
        place = order[rank]
        candidate = keep[place]
        path_length = ranges[candidate]
        indices[rank] = candidate
        directions[rank, 0] = kept[place, 0] / path_length
        directions[rank, 1] = kept[place, 1] / path_length
        path_lengths[rank] = path_length
        kept_amplitudes[rank] = amplitudes[candidate]
    return indices, directions, path_lengths, kept_amplitudes


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
def audible_candidates(
    mapped: FloatArray,
    layout: np.ndarray,
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
    its amplitudes row over the on-axis amplitude :func:`on_axis_echoes` left there, then
    :func:`passing_candidates` tests the rows from the first test row on.

    Args:
        layout: :func:`on_axis_echoes`' ``(S, C, W, V, first ranges row, ...)``.
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
        amplitude = mapped[amplitudes_start + candidate]
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


@compiled(  # type: ignore[misc]
    types.Tuple(
        (
            types.Array(types.int64, 1, "C"),
            types.Array(types.float64, 2, "C"),
            types.Array(types.float64, 1, "C"),
            types.Array(types.float64, 1, "C"),
        )
    ),
    TABLE,  # products
    INDICES,  # keep
    TABLE,  # kept
    NUMBERS,  # ranges
    NUMBERS,  # amplitudes
    NUMBERS,  # centre_distance
    NUMBERS,  # radius_sq
    FLAGS,  # occluders
    types.float64,  # path_centre
)
def clear_nearest_first(
    products: FloatArray,
    keep: np.ndarray,
    kept: FloatArray,
    ranges: FloatArray,
    amplitudes: FloatArray,
    centre_distance: FloatArray,
    radius_sq: FloatArray,
    occluders: np.ndarray,
    path_centre: float,
) -> tuple[np.ndarray, FloatArray, FloatArray, FloatArray]:
    """The end of :func:`sonar_gym.sonar.echoes.echo_candidates`: :func:`unoccluded` of the
    paths to ``keep``, then :func:`nearest_first` of the clear ones.

    Args:
        products: ``(3 S + C, P)`` the occlusion map times ``kept.T`` (see :func:`unoccluded`).
        keep: ``(P,)`` candidate indices; ``kept``: ``(P, 3)`` their rows ``(rel_x, rel_y, 1)``
            ({W}, metres).
        ranges, amplitudes: per candidate index (metres, 1/m).
        centre_distance, radius_sq, occluders, path_centre: those of :func:`unoccluded`.
    """
    kept_ranges = np.empty(keep.shape[0])
    for place in range(keep.shape[0]):
        kept_ranges[place] = ranges[keep[place]]
    clear = unoccluded(products, kept_ranges, centre_distance, radius_sq, occluders, path_centre)
    return nearest_first(keep, clear, kept, ranges, amplitudes)  # type: ignore[no-any-return]


@compiled(  # type: ignore[misc]
    types.Array(types.float64, 1, "C"),
    types.Array(types.float64, 1, "C"),  # mapped (ranges, offsets, on-axis amplitudes written)
    INDICES,  # layout
    NUMBERS,  # radius_padded
    NUMBERS,  # radius
    NUMBERS,  # edge law constants
    types.float64,  # exponent_per_m
    types.Array(types.boolean, 1, "C"),  # concave (written)
)
def echo_ranges(
    mapped: FloatArray,
    layout: np.ndarray,
    radius_padded: FloatArray,
    radius: FloatArray,
    edge_law: FloatArray,
    exponent_per_m: float,
    concave: np.ndarray,
) -> FloatArray:
    """:func:`on_axis_echoes` handing back one array: its concave flags written into
    ``concave`` (``(W,)``, in place) and its distances followed by the exponents of air
    absorption, ``(C + 2 N,)``: the centre distances ``(C,)``, the ranges clipped at 1 nm
    ``(N,)`` (metres), then ``exponent_per_m`` times each clipped range ``(N,)``, the
    elementwise product ``exponent_per_m * safe`` that numpy's ``exp`` takes (``exponent_per_m``
    in 1/m: ``-alpha ln(10) / 10`` for an absorption ``alpha`` in dB/m).

    Args:
        mapped, layout, radius_padded, radius, edge_law: those of :func:`on_axis_echoes`.
        exponent_per_m: the exponent of air absorption per metre of range (1/m).
        concave: ``(W,)`` written: whether each wedge vertex is concave from the sensor.
    """
    wedges, distances = on_axis_echoes(mapped, layout, radius_padded, radius, edge_law)
    concave[:] = wedges
    n_circles, n_distances = layout[1], distances.shape[0]
    n_candidates = n_distances - n_circles
    ranges_and_exponents = np.empty(n_distances + n_candidates)
    ranges_and_exponents[:n_distances] = distances
    for candidate in range(n_candidates):
        ranges_and_exponents[n_distances + candidate] = (
            exponent_per_m * distances[n_circles + candidate]
        )
    return ranges_and_exponents


@compiled(  # type: ignore[misc]
    types.Array(types.float64, 2, "C"),
    types.Array(types.float64, 1, "C"),  # mapped (amplitudes written)
    INDICES,  # layout
    NUMBERS,  # absorption
    NUMBERS,  # gain
    NUMBERS,  # strict_bounds
    NUMBERS,  # inclusive_bounds
    FLAGS,  # concave
    INDICES,  # twin
    FLAGS,  # twin_comes_last
    types.boolean,  # has_t_junctions
    types.float64,  # footprint_offset_x
    types.float64,  # footprint_offset_y
    types.float64,  # footprint_radius
    types.Array(types.int64, 1, "C"),  # picks (written)
)
def audible_paths(
    mapped: FloatArray,
    layout: np.ndarray,
    absorption: FloatArray,
    gain: FloatArray,
    strict_bounds: FloatArray,
    inclusive_bounds: FloatArray,
    concave: np.ndarray,
    twin: np.ndarray,
    twin_comes_last: np.ndarray,
    has_t_junctions: bool,
    footprint_offset_x: float,
    footprint_offset_y: float,
    footprint_radius: float,
    picks: np.ndarray,
) -> FloatArray:
    """:func:`audible_candidates` handing back one array: the ``(P, 3)`` rows
    ``(rel_x, rel_y, 1)`` of the candidates that pass, with their indices written into
    ``picks[:P]`` and which primitives may occlude (1 or 0) into its last ``S + C`` entries.

    Args:
        mapped, layout, absorption, gain, strict_bounds, inclusive_bounds, concave, twin,
            twin_comes_last, has_t_junctions: those of :func:`audible_candidates`.
        footprint_offset_x, footprint_offset_y, footprint_radius: its footprint as three
            floats (metres, {W}); a radius of 0 or less: no footprint test.
        picks: ``(N + S + C,)`` written (see above; the entries between are left as they are).
    """
    footprint = np.empty(3 if footprint_radius > 0.0 else 0)
    if footprint_radius > 0.0:
        footprint[0], footprint[1] = footprint_offset_x, footprint_offset_y
        footprint[2] = footprint_radius
    keep, kept, occluders = audible_candidates(
        mapped,
        layout,
        absorption,
        gain,
        strict_bounds,
        inclusive_bounds,
        concave,
        twin,
        twin_comes_last,
        has_t_junctions,
        footprint,
    )
    picks[: keep.shape[0]] = keep
    first_occluder = picks.shape[0] - occluders.shape[0]
    for occluder in range(occluders.shape[0]):
        picks[first_occluder + occluder] = 1 if occluders[occluder] else 0
    return kept


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.int64, 1, "C"), types.Array(types.float64, 1, "C"))),
    TABLE,  # products
    INDICES,  # picks
    TABLE,  # kept
    NUMBERS,  # mapped
    NUMBERS,  # distances
    INDICES,  # layout
    NUMBERS,  # radius_sq
    types.float64,  # path_centre
)
def clear_paths_nearest_first(
    products: FloatArray,
    picks: np.ndarray,
    kept: FloatArray,
    mapped: FloatArray,
    distances: FloatArray,
    layout: np.ndarray,
    radius_sq: FloatArray,
    path_centre: float,
) -> tuple[np.ndarray, FloatArray]:
    """:func:`clear_nearest_first` of the candidates :func:`audible_paths` picked, handing back
    two arrays: ``(indices (K,), (4 K,) the unit directions (K, 2) row by row, then the path
    lengths (K,), then the amplitudes (K,))``.

    Args:
        products: ``(3 S + C, P)`` the occlusion map times ``kept.T``.
        picks: :func:`audible_paths`' ``(N + S + C,)`` indices and occluder flags.
        kept: ``(P, 3)`` :func:`audible_paths`' rows.
        mapped: the search map's product after :func:`audible_paths`: the ranges and
            amplitudes of :func:`clear_nearest_first` are its ranges and amplitudes rows.
        distances: :func:`echo_ranges`' distances; their first ``C`` are the centre distances.
        layout: :func:`on_axis_echoes`' ``(S, C, W, V, first ranges row, ...)``.
        radius_sq, path_centre: those of :func:`clear_nearest_first`.
    """
    n_circles = layout[1]
    n_candidates = layout[0] + n_circles + layout[3]
    ranges_start = layout[4]
    amplitudes_start = ranges_start + n_candidates
    ranges = mapped[ranges_start:amplitudes_start]
    amplitudes = mapped[amplitudes_start : amplitudes_start + n_candidates]
    centre_distance = distances[:n_circles]
    n_occluders = (products.shape[0] - n_circles) // 3 + n_circles
    first_occluder = picks.shape[0] - n_occluders
    occluders = np.empty(n_occluders, dtype=np.bool_)
    for occluder in range(n_occluders):
        occluders[occluder] = picks[first_occluder + occluder] != 0
    indices, directions, path_lengths, kept_amplitudes = clear_nearest_first(
        products,
        picks[: kept.shape[0]],
        kept,
        ranges,
        amplitudes,
        centre_distance,
        radius_sq,
        occluders,
        path_centre,
    )
    n_kept = indices.shape[0]
    floats = np.empty(4 * n_kept)
    for rank in range(n_kept):
        floats[2 * rank] = directions[rank, 0]
        floats[2 * rank + 1] = directions[rank, 1]
        floats[2 * n_kept + rank] = path_lengths[rank]
        floats[3 * n_kept + rank] = kept_amplitudes[rank]
    return indices, floats
