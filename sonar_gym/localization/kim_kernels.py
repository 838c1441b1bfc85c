"""Compiled inner loops of Kim, Lee & Jeong's voting (sec. 3.3): the free distances of the
unobstructed-ray table, the readings with an echo and their end points, the quantised beam
directions, the (reading, anchor) pairs that can vote inside the search circle, the vote
volume, and the votes of one heading in a window.

They do the arithmetic of the array forms they replace element by element, in the same order
(kept as references in ``tests/localization/test_kim_fast_paths.py``,
``test_kim_reading_kernels.py`` and ``kim_free_distance_reference.py``), so distances,
readings, votes, counts and positions are the same bits; the array forms paid numpy's per-call
cost on a few dozen readings, a few hundred pairs and a few thousand votes per fix, and traced
the table's rays in blocks of samples over every pending ray. The trigonometry stays in numpy
(its ``cos`` and ``sin`` of arrays round differently from libm's): callers pass cosines and
sines in.

Frames: readings' end points are in the first sweep's robot frame (metres); anchors, search
centre, grid origin and vote positions ``t = a - R(heading) e`` in the map frame {W} (metres).
"""

from __future__ import annotations

import math

import numpy as np
from numba import types

from sonar_gym.compiled import (
    INDEX_TABLE,
    INDICES,
    NUMBERS,
    TABLE,
    compiled,
    floor_remainder,
    pairwise_sum,
    wrap_to_pi,
)
from sonar_gym.pose import FloatArray


def _has_echo(range_m: float, max_range: float) -> bool:
    """Whether a reading returned an echo: a finite range (metres) below ``max_range``."""
    return bool(np.isfinite(range_m)) and range_m < max_range


_has_echo_compiled = compiled(types.boolean, types.float64, types.float64, inline=True)(_has_echo)


@compiled(  # type: ignore[misc]
    types.Array(types.float64, 1, "C"),
    NUMBERS,  # angles
    NUMBERS,  # ranges
    INDICES,  # counts
    TABLE,  # sweep_frames
    types.float64,  # max_range
)
def echo_beams(
    angles: FloatArray,
    ranges: FloatArray,
    counts: np.ndarray,
    sweep_frames: FloatArray,
    max_range: float,
) -> FloatArray:
    """The beam of each reading with an echo (a finite range below ``max_range``), in reading
    order: ``sweep heading + angle`` (rad, the first sweep's robot frame), the array form's one
    addition.

    Args:
        angles, ranges: every sweep's beam angles (rad, its own robot frame) and ranges
            (metres), concatenated; ``counts[i]`` readings belong to sweep ``i``.
        sweep_frames: ``(sweeps, 3)``: each sweep's heading (rad) and sensor position
            (metres) in the first sweep's robot frame; the heading is used here.
        max_range: readings at or beyond it count as no echo (metres; inf: none).
    """
    beam = np.empty(ranges.size)
    count = 0
    reading = 0
    for sweep in range(counts.size):
        for _ in range(counts[sweep]):
            if _has_echo_compiled(ranges[reading], max_range):
                beam[count] = sweep_frames[sweep, 0] + angles[reading]
                count += 1
            reading += 1
    return beam[:count].copy()


@compiled(  # type: ignore[misc]
    types.Array(types.float64, 2, "C"),
    NUMBERS,  # ranges
    INDICES,  # counts
    TABLE,  # sweep_frames
    NUMBERS,  # beam_cos
    NUMBERS,  # beam_sin
    types.float64,  # max_range
)
def echo_end_points(
    ranges: FloatArray,
    counts: np.ndarray,
    sweep_frames: FloatArray,
    beam_cos: FloatArray,
    beam_sin: FloatArray,
    max_range: float,
) -> FloatArray:
    """``(3, J)`` rows end x, end y and length of each reading with an echo (metres, the first
    sweep's robot frame), in the order of :func:`echo_beams`: ``end = sensor + range (cos,
    sin)`` and ``length = sqrt(dx^2 + dy^2)`` of ``end - sensor``, the array form's steps in its
    order (``beam_cos``, ``beam_sin``: numpy's of :func:`echo_beams`; ``ranges``, ``counts``,
    ``sweep_frames``, ``max_range``: its arguments, ``sweep_frames[i, 1:]`` the sensor of sweep
    ``i``)."""
    rows = np.empty((3, beam_cos.size))
    count = 0
    reading = 0
    for sweep in range(counts.size):
        from_x, from_y = sweep_frames[sweep, 1], sweep_frames[sweep, 2]
        for _ in range(counts[sweep]):
            reading_range = ranges[reading]
            reading += 1
            if not _has_echo_compiled(reading_range, max_range):
                continue
            to_x = from_x + reading_range * beam_cos[count]
            to_y = from_y + reading_range * beam_sin[count]
            run_x, run_y = to_x - from_x, to_y - from_y
            rows[0, count] = to_x
            rows[1, count] = to_y
            rows[2, count] = math.sqrt(run_x * run_x + run_y * run_y)
            count += 1
    return rows


@compiled(  # type: ignore[misc]
    types.Array(types.int64, 2, "C"),
    NUMBERS,  # headings
    NUMBERS,  # beams
    types.int64,  # direction_bins
    types.float64,  # bins_per_radian
)
def direction_indices(
    headings: FloatArray, beams: FloatArray, direction_bins: int, bins_per_radian: float
) -> np.ndarray:
    """``(h, J)`` quantised world beam directions ``rint((heading + beam) bins_per_radian)``
    modulo ``direction_bins`` (rad in; ``rint`` rounds half to even, as numpy's; the modulo is
    the floor modulo of numpy's integer ``%``)."""
    indices = np.empty((headings.size, beams.size), dtype=np.int64)
    for heading in range(headings.size):
        for reading in range(beams.size):
            turns = (headings[heading] + beams[reading]) * bins_per_radian
            index = int(np.rint(turns))
            # the floor modulo: an index at most one turn below 0 needs no integer division
            if index < 0:
                index += direction_bins
            if not 0 <= index < direction_bins:
                index %= direction_bins
            indices[heading, reading] = index
    return indices


_PAIRS = types.Tuple((types.Array(types.int64, 1, "C"), types.Array(types.int64, 1, "C")))


@compiled(  # type: ignore[misc]
    _PAIRS,
    NUMBERS,  # end_x
    NUMBERS,  # end_y
    TABLE,  # anchors
    types.float64,  # center_x
    types.float64,  # center_y
    types.float64,  # radius
    types.boolean,  # by_heading
    types.float64,  # middle_cos
    types.float64,  # middle_sin
    types.float64,  # spread_cos
    types.float64,  # spread_sin
)
def candidate_pairs(
    end_x: FloatArray,
    end_y: FloatArray,
    anchors: FloatArray,
    center_x: float,
    center_y: float,
    radius: float,
    by_heading: bool,
    middle_cos: float,
    middle_sin: float,
    spread_cos: float,
    spread_sin: float,
) -> tuple[np.ndarray, np.ndarray]:
    """``(reading index, anchor index)`` of the pairs whose vote can fall inside the circle.

    A vote ``t = a - R(heading) e`` lies within ``radius`` of the centre ``c`` only if
    ``| |a - c| - |e| | <= radius`` (triangle inequality, any heading). With ``by_heading``,
    a pair must also be reachable by a heading within ``spread`` of the ``middle`` candidate:
    ``phi <= spread`` or ``D E cos(phi - spread) >= (D^2 + E^2 - radius^2) / 2`` (``D = |a - c|``,
    ``E = |e|``, ``phi`` the angle between the heading that turns ``e`` onto ``a - c`` and the
    middle heading), where ``D E cos(phi - spread) = dot cos(spread) + |cross| sin(spread)``
    with ``dot`` and ``cross`` the products of ``a - c`` turned back by the middle heading and
    ``e``. Both tests are padded so that rounding never drops a pair that votes. Pairs come
    reading-major, anchors ascending: the order of the full ``(J, K)`` product.

    Args:
        end_x, end_y: ``(J,)`` reading end points, first-sweep robot frame, metres.
        anchors: ``(K, 2)`` anchor points of the occupied cells, {W}, metres.
        center_x, center_y, radius: the search circle, {W}, metres.
        by_heading: apply the heading test (False: the circle test only).
        middle_cos, middle_sin: cosine and sine of the middle candidate heading.
        spread_cos, spread_sin: of the largest angle from it to another candidate (padded).
    """
    n_readings, n_anchors = end_x.size, anchors.shape[0]
    anchor_distance = np.empty(n_anchors)
    back_x = np.empty(n_anchors)
    back_y = np.empty(n_anchors)
    squared_d = np.empty(n_anchors)
    for k in range(n_anchors):
        to_x, to_y = anchors[k, 0] - center_x, anchors[k, 1] - center_y
        anchor_distance[k] = np.hypot(to_x, to_y)
        back_x[k] = middle_cos * to_x + middle_sin * to_y
        back_y[k] = middle_cos * to_y - middle_sin * to_x
        squared_d[k] = to_x * to_x + to_y * to_y
    slack = radius * (1.0 + 1e-9) + 1e-12
    needed_radius = slack * slack
    pair_j = np.empty(n_readings * n_anchors, dtype=np.int64)
    pair_k = np.empty(n_readings * n_anchors, dtype=np.int64)
    near = np.empty(n_anchors, dtype=np.bool_)
    count = 0
    for j in range(n_readings):
        ex, ey = end_x[j], end_y[j]
        reach = np.hypot(ex, ey)
        squared_e = ex * ex + ey * ey
        for k in range(n_anchors):  # without branches: compiled to vector instructions
            near[k] = abs(anchor_distance[k] - reach) <= slack
        for k in range(n_anchors):
            if not near[k]:
                continue
            if by_heading:
                dot = back_x[k] * ex + back_y[k] * ey
                cross = abs(back_x[k] * ey - back_y[k] * ex)
                needed = 0.5 * (squared_d[k] + squared_e - needed_radius) - 1e-12
                reachable = dot * spread_cos + cross * spread_sin >= needed
                # "or" short-circuits: the square root only when the first test fails
                if not (
                    reachable or dot >= spread_cos * math.sqrt(squared_d[k] * squared_e) - 1e-12
                ):
                    continue
            pair_j[count] = j
            pair_k[count] = k
            count += 1
    return pair_j[:count].copy(), pair_k[:count].copy()


_CIRCLE = types.UniTuple(types.float64, 3)
"""``(centre x, centre y, radius)`` of the search circle, {W}, metres (radius inf: none)."""
_GRID_FRAME = types.UniTuple(types.float64, 3)
"""``(origin x, origin y, cell size)`` of the grid, {W}, metres."""
_CELLS = types.UniTuple(types.int64, 4)
"""``(low x, low y, high x, high y)``: a block of grid cells, inclusive."""

_VOTES_OF_ONE_HEADING = (
    INDICES,  # pair_j
    INDICES,  # pair_k
    INDICES,  # direction_index (of this heading, per reading)
    TABLE,  # free_distance
    NUMBERS,  # range_m
    NUMBERS,  # end_x
    NUMBERS,  # end_y
    TABLE,  # anchors
    types.float64,  # cos_heading
    types.float64,  # sin_heading
    _CIRCLE,
    _GRID_FRAME,
    _CELLS,  # window
    _CELLS,  # cells
)
"""The arguments of the loops over one heading's votes (:func:`votes_in_cells`,
:func:`vote_mean`)."""


def _vote_cell(
    t_x: float,
    t_y: float,
    circle: tuple[float, float, float],
    grid_frame: tuple[float, float, float],
    window: tuple[int, int, int, int],
) -> tuple[bool, int, int]:
    """Whether the vote at ``t`` counts (inside the circle and the ``window`` of cells) and its
    cell ``floor((t - origin) / cell size)``."""
    center_x, center_y, radius = circle
    off_x, off_y = t_x - center_x, t_y - center_y
    if not off_x * off_x + off_y * off_y <= radius * radius:
        return False, 0, 0
    origin_x, origin_y, cell_size = grid_frame
    cell_x = int(math.floor((t_x - origin_x) / cell_size))
    cell_y = int(math.floor((t_y - origin_y) / cell_size))
    low_x, low_y, high_x, high_y = window
    return low_x <= cell_x <= high_x and low_y <= cell_y <= high_y, cell_x, cell_y


_vote_cell_compiled = compiled(
    types.Tuple((types.boolean, types.int64, types.int64)),
    types.float64,
    types.float64,
    _CIRCLE,
    _GRID_FRAME,
    _CELLS,
    inline=True,
)(_vote_cell)


@compiled(  # type: ignore[misc]
    types.Array(types.int64, 3, "C"),
    INDICES,  # pair_j
    INDICES,  # pair_k
    INDEX_TABLE,  # direction_index
    TABLE,  # free_distance
    NUMBERS,  # range_m
    NUMBERS,  # end_x
    NUMBERS,  # end_y
    TABLE,  # anchors
    NUMBERS,  # cos_h
    NUMBERS,  # sin_h
    _CIRCLE,
    _GRID_FRAME,
    _CELLS,  # window
)
def vote_volume(
    pair_j: np.ndarray,
    pair_k: np.ndarray,
    direction_index: np.ndarray,
    free_distance: FloatArray,
    range_m: FloatArray,
    end_x: FloatArray,
    end_y: FloatArray,
    anchors: FloatArray,
    cos_h: FloatArray,
    sin_h: FloatArray,
    circle: tuple[float, float, float],
    grid_frame: tuple[float, float, float],
    window: tuple[int, int, int, int],
) -> np.ndarray:
    """``(h, wx, wy)`` votes per candidate heading and cell of the vote ``window``.

    A pair ``(j, k)`` votes under heading ``i`` when its ray is unobstructed,
    ``free_distance[direction_index[i, j], k] > range_m[j]``, for the robot at
    ``t = anchors[k] - R(heading_i) e_j`` (``cos_h``, ``sin_h``: of the headings); the vote
    counts when ``t`` lies inside the search ``circle`` and its cell inside ``window``.
    """
    low_x, low_y, high_x, high_y = window
    center_x, center_y, radius = circle
    squared_radius = radius * radius
    origin_x, origin_y, cell_size = grid_frame
    volume = np.zeros((cos_h.size, high_x - low_x + 1, high_y - low_y + 1), dtype=np.int64)
    # Integer counts: any order gives the same volume. Pairs of one reading come in a run
    # (reading-major): each heading's table row and turned end point are found once per run.
    # Headings stay the inner loop: along them a vote moves little, so its tests branch alike.
    n_headings = cos_h.size
    rows = np.empty(n_headings, dtype=np.int64)
    turned_x = np.empty(n_headings)
    turned_y = np.empty(n_headings)
    first = 0
    while first < pair_j.size:
        j = pair_j[first]
        stop = first + 1
        while stop < pair_j.size and pair_j[stop] == j:
            stop += 1
        reading_range, e_x, e_y = range_m[j], end_x[j], end_y[j]
        for heading in range(n_headings):
            rows[heading] = direction_index[heading, j]
            c, s = cos_h[heading], sin_h[heading]
            turned_x[heading] = c * e_x - s * e_y
            turned_y[heading] = s * e_x + c * e_y
        for pair in range(first, stop):
            k = pair_k[pair]
            a_x, a_y = anchors[k, 0], anchors[k, 1]
            for heading in range(n_headings):
                if not free_distance[rows[heading], k] > reading_range:
                    continue
                t_x = a_x - turned_x[heading]
                t_y = a_y - turned_y[heading]
                off_x, off_y = t_x - center_x, t_y - center_y
                if not off_x * off_x + off_y * off_y <= squared_radius:
                    continue
                cell_x = int(math.floor((t_x - origin_x) / cell_size))
                cell_y = int(math.floor((t_y - origin_y) / cell_size))
                if low_x <= cell_x <= high_x and low_y <= cell_y <= high_y:
                    volume[heading, cell_x - low_x, cell_y - low_y] += 1
        first = stop
    return volume


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.float64, 1, "C"), types.Array(types.float64, 1, "C"))),
    *_VOTES_OF_ONE_HEADING,
)
def votes_in_cells(
    pair_j: np.ndarray,
    pair_k: np.ndarray,
    direction_index: np.ndarray,
    free_distance: FloatArray,
    range_m: FloatArray,
    end_x: FloatArray,
    end_y: FloatArray,
    anchors: FloatArray,
    cos_heading: float,
    sin_heading: float,
    circle: tuple[float, float, float],
    grid_frame: tuple[float, float, float],
    window: tuple[int, int, int, int],
    cells: tuple[int, int, int, int],
) -> tuple[FloatArray, FloatArray]:
    """The positions ``t`` ({W}, metres) of one heading's votes, in pair order, that
    :func:`vote_volume` counts and whose cell lies in ``cells`` as well."""
    votes_x = np.empty(pair_j.size)
    votes_y = np.empty(pair_j.size)
    count = 0
    for pair in range(pair_j.size):
        j, k = pair_j[pair], pair_k[pair]
        if not free_distance[direction_index[j], k] > range_m[j]:
            continue
        t_x = anchors[k, 0] - (cos_heading * end_x[j] - sin_heading * end_y[j])
        t_y = anchors[k, 1] - (sin_heading * end_x[j] + cos_heading * end_y[j])
        in_window, cell_x, cell_y = _vote_cell_compiled(t_x, t_y, circle, grid_frame, window)
        low_x, low_y, high_x, high_y = cells
        if in_window and low_x <= cell_x <= high_x and low_y <= cell_y <= high_y:
            votes_x[count] = t_x
            votes_y[count] = t_y
            count += 1
    return votes_x[:count].copy(), votes_y[:count].copy()


_VOLUME = types.Array(types.int64, 3, "A", readonly=True)
"""``(h, nx, ny)`` integer votes per heading and cell."""
_LAYER = types.Array(types.int64, 2, "C")


def _smooth_layer(
    volume: np.ndarray, layer: int, along_x: np.ndarray, smoothed: np.ndarray
) -> None:
    """3x3 ``[1 2 1]^T [1 2 1]`` smoothing of ``volume[layer]`` into ``smoothed`` (``(nx, ny)``),
    zero outside the layer (integers: exact in any order); ``along_x`` is ``(nx, ny)``
    scratch."""
    _, nx, ny = volume.shape
    for ix in range(nx):
        for iy in range(ny):
            total = 2 * volume[layer, ix, iy]
            if ix > 0:
                total += volume[layer, ix - 1, iy]
            if ix < nx - 1:
                total += volume[layer, ix + 1, iy]
            along_x[ix, iy] = total
    for ix in range(nx):
        for iy in range(ny):
            total = 2 * along_x[ix, iy]
            if iy > 0:
                total += along_x[ix, iy - 1]
            if iy < ny - 1:
                total += along_x[ix, iy + 1]
            smoothed[ix, iy] = total


_smooth_layer_compiled = compiled(types.none, _VOLUME, types.int64, _LAYER, _LAYER, inline=True)(
    _smooth_layer
)


@compiled(types.Array(types.int64, 3, "C"), _VOLUME)  # type: ignore[misc]
def binomial_smooth(volume: np.ndarray) -> np.ndarray:
    """3x3 ``[1 2 1]^T [1 2 1]`` smoothing of each ``(nx, ny)`` layer of ``(h, nx, ny)`` integer
    votes, zero outside the layer (integers: exact in any order)."""
    n_layers, nx, ny = volume.shape
    along_x = np.empty((nx, ny), dtype=np.int64)
    smoothed = np.empty((n_layers, nx, ny), dtype=np.int64)
    for layer in range(n_layers):
        _smooth_layer_compiled(volume, layer, along_x, smoothed[layer])
    return smoothed


@compiled(types.UniTuple(types.int64, 4), _VOLUME)  # type: ignore[misc]
def smoothed_maximum(volume: np.ndarray) -> tuple[int, int, int, int]:
    """``(score, heading, x, y)``: the largest :func:`binomial_smooth` score of ``(h, nx, ny)``
    votes and the first cell holding it in C order (``np.argmax``'s tie rule), a layer at a
    time without storing the smoothed volume; ``(0, 0, 0, 0)`` for an empty volume."""
    n_layers, nx, ny = volume.shape
    along_x = np.empty((nx, ny), dtype=np.int64)
    smoothed = np.empty((nx, ny), dtype=np.int64)
    best, best_heading, best_x, best_y = -1, 0, 0, 0  # every score is >= 0
    for layer in range(n_layers):
        _smooth_layer_compiled(volume, layer, along_x, smoothed)
        for ix in range(nx):
            for iy in range(ny):
                if smoothed[ix, iy] > best:
                    best, best_heading, best_x, best_y = smoothed[ix, iy], layer, ix, iy
    if best < 0:
        return 0, 0, 0, 0
    return best, best_heading, best_x, best_y


@compiled(  # type: ignore[misc]
    types.Tuple((types.int64, types.float64, types.float64)),
    *_VOTES_OF_ONE_HEADING,
)
def vote_mean(
    pair_j: np.ndarray,
    pair_k: np.ndarray,
    direction_index: np.ndarray,
    free_distance: FloatArray,
    range_m: FloatArray,
    end_x: FloatArray,
    end_y: FloatArray,
    anchors: FloatArray,
    cos_heading: float,
    sin_heading: float,
    circle: tuple[float, float, float],
    grid_frame: tuple[float, float, float],
    window: tuple[int, int, int, int],
    cells: tuple[int, int, int, int],
) -> tuple[int, float, float]:
    """``(count, mean x, mean y)`` of the :func:`votes_in_cells` positions ({W}, metres; the
    means 0 without a vote): numpy's ``sum() / count`` of each coordinate, its pairwise sum
    (:data:`~sonar_gym.compiled.pairwise_sum`) and one division."""
    votes_x, votes_y = votes_in_cells(
        pair_j, pair_k, direction_index, free_distance, range_m, end_x, end_y, anchors,
        cos_heading, sin_heading, circle, grid_frame, window, cells,
    )  # fmt: skip
    count = votes_x.size
    if count == 0:
        return 0, 0.0, 0.0
    return count, pairwise_sum(votes_x) / count, pairwise_sum(votes_y) / count


_HEADING_TEST = types.Tuple(
    (types.boolean, types.float64, types.float64, types.float64, types.float64)
)
"""``(by heading, middle cos, middle sin, spread cos, spread sin)``: the heading test of
:func:`candidate_pairs`."""
_SMOOTHED_FIX = types.Tuple(
    (
        types.Array(types.int64, 3, "C"),
        types.int64,
        types.int64,
        types.int64,
        types.int64,
        types.int64,
        types.float64,
        types.float64,
    )
)


@compiled(  # type: ignore[misc]
    _SMOOTHED_FIX,
    NUMBERS,  # end_x
    NUMBERS,  # end_y
    NUMBERS,  # range_m
    TABLE,  # anchors
    INDEX_TABLE,  # direction_index
    TABLE,  # free_distance
    NUMBERS,  # cos_h
    NUMBERS,  # sin_h
    _HEADING_TEST,
    _CIRCLE,
    _GRID_FRAME,
    _CELLS,  # window
)
def smoothed_fix(
    end_x: FloatArray,
    end_y: FloatArray,
    range_m: FloatArray,
    anchors: FloatArray,
    direction_index: np.ndarray,
    free_distance: FloatArray,
    cos_h: FloatArray,
    sin_h: FloatArray,
    heading_test: tuple[bool, float, float, float, float],
    circle: tuple[float, float, float],
    grid_frame: tuple[float, float, float],
    window: tuple[int, int, int, int],
) -> tuple[np.ndarray, int, int, int, int, int, float, float]:
    """``(volume, score, heading, x, y, count, mean x, mean y)``: the whole vote of one fix
    with the smoothed selection, in one call.

    :func:`candidate_pairs` in the search ``circle`` (``heading_test`` gives its heading
    arguments), :func:`vote_volume` over the ``window``, its :func:`smoothed_maximum`
    (``score`` at ``heading`` and window cell ``x``, ``y``), and :func:`vote_mean` of the
    peak's heading over the peak cell +- 1 (cells of the whole grid; outside the window
    nothing votes). ``count`` is 0, and the means 0, when the peak scores 0 (no vote).
    """
    by_heading, middle_cos, middle_sin, spread_cos, spread_sin = heading_test
    center_x, center_y, radius = circle
    pair_j, pair_k = candidate_pairs(
        end_x, end_y, anchors, center_x, center_y, radius,
        by_heading, middle_cos, middle_sin, spread_cos, spread_sin,
    )  # fmt: skip
    volume = vote_volume(
        pair_j, pair_k, direction_index, free_distance, range_m, end_x, end_y, anchors,
        cos_h, sin_h, circle, grid_frame, window,
    )  # fmt: skip
    score, heading, x, y = smoothed_maximum(volume)
    if score == 0:
        return volume, score, heading, x, y, 0, 0.0, 0.0
    cell_x, cell_y = x + window[0], y + window[1]
    count, mean_x, mean_y = vote_mean(
        pair_j, pair_k, direction_index[heading], free_distance, range_m, end_x, end_y,
        anchors, cos_h[heading], sin_h[heading], circle, grid_frame, window,
        (cell_x - 1, cell_y - 1, cell_x + 1, cell_y + 1),
    )  # fmt: skip
    return volume, score, heading, x, y, count, mean_x, mean_y


@compiled(  # type: ignore[misc]
    types.Array(types.float64, 2, "C"),
    NUMBERS,  # back_x
    NUMBERS,  # back_y
    NUMBERS,  # start_x
    NUMBERS,  # start_y
    NUMBERS,  # samples
    NUMBERS,  # samples_m
    types.Array(types.boolean, 2, "A", readonly=True),  # blocked_cells
)
def free_distances(
    back_x: FloatArray,
    back_y: FloatArray,
    start_x: FloatArray,
    start_y: FloatArray,
    samples: FloatArray,
    samples_m: FloatArray,
    blocked_cells: np.ndarray,
) -> FloatArray:
    """``(directions, cells)`` free distance (metres) behind each occupied cell per direction:
    the first of ``samples_m`` at which the ray traced back from the cell meets a blocked cell,
    the last sample when none does.

    Sample ``i`` of cell ``k`` traced along direction ``d`` lies in the grid cell
    ``floor(start + samples[i] back)`` per axis, clipped to ``[-1, n]`` and shifted by one into
    ``blocked_cells`` (``(nx + 2, ny + 2)``, a blocked border for everything off the grid), the
    array form's steps in its order.

    Args:
        back_x, back_y: numpy's ``-cos``, ``-sin`` of each direction.
        start_x, start_y: each occupied cell's centre in cell units from the grid origin.
        samples: the sample distances in cell units; ``samples_m``: the same in metres.
        blocked_cells: occupied cells and the border.
    """
    n_x, n_y = blocked_cells.shape[0] - 2, blocked_cells.shape[1] - 2
    last = samples_m[samples_m.size - 1]
    distance = np.empty((back_x.size, start_x.size))
    for direction in range(back_x.size):
        step_x, step_y = back_x[direction], back_y[direction]
        for cell in range(start_x.size):
            from_x, from_y = start_x[cell], start_y[cell]
            found = last
            for sample in range(samples.size):
                cell_x = min(max(math.floor(from_x + samples[sample] * step_x), -1.0), n_x)
                cell_y = min(max(math.floor(from_y + samples[sample] * step_y), -1.0), n_y)
                if blocked_cells[int(cell_x) + 1, int(cell_y) + 1]:
                    found = samples_m[sample]
                    break
            distance[direction, cell] = found
    return distance


@compiled(types.float64, NUMBERS)  # type: ignore[misc]
def heading_offset(headings: FloatArray) -> float:
    """The largest angle (rad) from the middle candidate ``headings[size // 2]`` to another:
    ``max |np.remainder(h - middle + pi, 2 pi) - pi|``, numpy's steps in its order (0 for no
    heading)."""
    if headings.size == 0:
        return 0.0
    middle = headings[headings.size // 2]
    largest = 0.0
    for heading in headings:
        largest = max(largest, abs(floor_remainder(heading - middle + np.pi, 2.0 * np.pi) - np.pi))
    return largest


@compiled(types.Array(types.float64, 1, "C"), types.float64, types.float64, types.int64)  # type: ignore[misc]
def heading_grid(prior_rad: float, step_rad: float, count: int) -> FloatArray:
    """``wrap_angles(prior + step k)`` for ``k = -count .. count`` (rad): numpy's product of the
    step and the integer, the sum, then :data:`~sonar_gym.compiled.wrap_to_pi`."""
    headings = np.empty(2 * count + 1)
    for index in range(2 * count + 1):
        headings[index] = wrap_to_pi(prior_rad + step_rad * float(index - count))
    return headings
