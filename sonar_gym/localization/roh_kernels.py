"""Compiled inner loops of Roh et al.'s localization: the usable rows and radii of a range
table, its paper centroids, the check of the fixes, and the windowed nearest-segment search of
the path errors (numba, :mod:`sonar_gym.compiled`).

Each does the arithmetic of the array form it replaces element by element, in the same order
(:func:`sonar_gym.localization.roh_trilateration.trilaterate_path` and
:func:`~sonar_gym.localization.roh_trilateration._paper_centroids`, and the windowed search
of :class:`sonar_gym.localization.roh_path_errors.TruePath`), so they return the same bits;
the array forms paid numpy's per-call cost on arrays of a few hundred rows.
"""

from __future__ import annotations

import math

import numpy as np
from numba import types

from sonar_gym.compiled import FLAGS, INDICES, NUMBERS, TABLE, compiled, nan_max, nan_min
from sonar_gym.pose import FloatArray


def second_is_nearer(
    first_dx: float, first_dy: float, second_dx: float, second_dy: float, radius: float
) -> bool:
    """``|hypot(second) - radius| < |hypot(first) - radius|``: whether the second point lies
    nearer the circle of ``radius`` about the origin of the offsets (metres).

    The comparison is made on ``sqrt(x^2 + y^2)``, within a few ulps of ``hypot`` and cheaper;
    where the two misses are too close for that to decide, ``hypot`` itself decides, so the
    answer is the ``hypot`` comparison's (:func:`paper_centroids`' choice of intersection).
    """
    to_first = math.sqrt(first_dx * first_dx + first_dy * first_dy)
    to_second = math.sqrt(second_dx * second_dx + second_dy * second_dy)
    miss_first, miss_second = abs(to_first - radius), abs(to_second - radius)
    margin = 1e-12 * (to_first + to_second + radius) + 1e-150
    if abs(miss_second - miss_first) > margin:
        return miss_second < miss_first
    return abs(np.hypot(second_dx, second_dy) - radius) < abs(np.hypot(first_dx, first_dy) - radius)


_second_is_nearer = compiled(types.boolean, *[types.float64] * 5)(second_is_nearer)


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.float64, 2, "C"), types.Array(types.boolean, 1, "C"))),
    TABLE,  # radii
    INDICES,  # first_of
    INDICES,  # second_of
    INDICES,  # third_of
    TABLE,  # first_centres
    TABLE,  # third_centres
    NUMBERS,  # separation
    NUMBERS,  # separation_sq
    TABLE,  # units
    types.float64,  # tolerance
)
def paper_centroids(
    radii: FloatArray,
    first_of: np.ndarray,
    second_of: np.ndarray,
    third_of: np.ndarray,
    first_centres: FloatArray,
    third_centres: FloatArray,
    separation: FloatArray,
    separation_sq: FloatArray,
    units: FloatArray,
    tolerance: float,
) -> tuple[FloatArray, np.ndarray]:
    """Per row of ``radii`` ``(m, 3)`` (metres): the centroid of the three kept intersection
    points (``(m, 2)``, NaN where not met) and whether every pair of circles meets (``(m,)``).

    Args:
        first_of, second_of, third_of: ``(3,)`` the circle indices of each pair and the third.
        first_centres, third_centres: ``(3, 2)`` the first circle's and the third circle's
            centre per pair, metres.
        separation, separation_sq: ``(3,)`` centre distance per pair and its square.
        units: ``(3, 2)`` unit vectors from the first centre to the second per pair.
        tolerance: the relative tangency tolerance.
    """
    n_rows = radii.shape[0]
    centroids = np.empty((n_rows, 2))
    met = np.empty(n_rows, dtype=np.bool_)
    along = np.empty(3)
    half_chord_sq = np.empty(3)
    tolerances = np.empty(3)
    for row in range(n_rows):
        meets = True
        for pair in range(3):
            ra, rb = radii[row, first_of[pair]], radii[row, second_of[pair]]
            ra_sq, rb_sq = ra * ra, rb * rb
            a = (ra_sq - rb_sq + separation_sq[pair]) / (2.0 * separation[pair])
            along[pair] = a
            half_chord_sq[pair] = ra_sq - a * a
            tolerances[pair] = tolerance * nan_max(nan_max(ra_sq, rb_sq), separation_sq[pair])
            if not half_chord_sq[pair] >= -tolerances[pair]:
                meets = False
        met[row] = meets
        centroids[row, 0], centroids[row, 1] = np.nan, np.nan
        if not meets:
            continue
        sum_x, sum_y = 0.0, 0.0
        for pair in range(3):
            ux, uy = units[pair, 0], units[pair, 1]
            foot_x = first_centres[pair, 0] + along[pair] * ux
            foot_y = first_centres[pair, 1] + along[pair] * uy
            h = half_chord_sq[pair]
            half_chord = 0.0 if h <= tolerances[pair] else math.sqrt(abs(h))
            chord_x, chord_y = half_chord * -uy, half_chord * ux
            first_x, first_y = foot_x + chord_x, foot_y + chord_y
            second_x, second_y = foot_x - chord_x, foot_y - chord_y
            rk = radii[row, third_of[pair]]
            d1x, d1y = first_x - third_centres[pair, 0], first_y - third_centres[pair, 1]
            d2x, d2y = second_x - third_centres[pair, 0], second_y - third_centres[pair, 1]
            take_second = _second_is_nearer(d1x, d1y, d2x, d2y, rk)
            kept_x = second_x if take_second else first_x
            kept_y = second_y if take_second else first_y
            if pair == 0:
                sum_x, sum_y = kept_x, kept_y
            else:
                sum_x, sum_y = sum_x + kept_x, sum_y + kept_y
        centroids[row, 0], centroids[row, 1] = sum_x / 3, sum_y / 3
    return centroids, met


@compiled(  # type: ignore[misc]
    types.Tuple(
        (
            types.Array(types.float64, 2, "C"),
            types.Array(types.boolean, 1, "C"),
            types.Array(types.boolean, 1, "C"),
        )
    ),
    TABLE,  # ranges
    NUMBERS,  # vertical
    types.float64,  # height_tolerance
)
def usable_radii(
    ranges: FloatArray, vertical: FloatArray, height_tolerance: float
) -> tuple[FloatArray, np.ndarray, np.ndarray]:
    """The rows of a range table ``(n, 3)`` (metres) that the paper method can use, and their
    horizontal radii, with the arithmetic of :func:`trilaterate_path`'s array form.

    Args:
        ranges: ``(n, 3)`` slant ranges, metres; NaN or inf marks a missing one.
        vertical: ``(3,)`` each beacon's height above the sensor plane, metres.
        height_tolerance: how far (metres) a range may fall below ``|vertical|``.

    Returns:
        ``(radii (k, 3), usable (n,), valid (n,))``: ``valid`` where every range is finite,
        ``usable`` where valid and no range falls short of its beacon's height, and
        ``sqrt(max(d^2 - vertical^2, 0))`` of the ``k`` usable rows in row order, metres.
    """
    n_rows, n_columns = ranges.shape
    limits = np.empty(n_columns)
    for column in range(n_columns):
        limits[column] = abs(vertical[column]) - height_tolerance
    valid = np.empty(n_rows, dtype=np.bool_)
    usable = np.empty(n_rows, dtype=np.bool_)
    count = 0
    for row in range(n_rows):
        finite, short = True, False
        for column in range(n_columns):
            value = ranges[row, column]
            if not math.isfinite(value):
                finite = False
            if value < limits[column]:
                short = True
        valid[row] = finite
        usable[row] = finite and not short
        if usable[row]:
            count += 1
    radii = np.empty((count, n_columns))
    kept = 0
    for row in range(n_rows):
        if not usable[row]:
            continue
        for column in range(n_columns):
            value = ranges[row, column]
            squared = value * value - vertical[column] * vertical[column]
            # np.maximum(squared, 0.0): a NaN stays NaN.
            radii[kept, column] = math.sqrt(0.0 if squared < 0.0 else squared)
        kept += 1
    return radii, usable, valid


@compiled(  # type: ignore[misc]
    types.Array(types.int64, 1, "C"),
    TABLE,  # positions
    FLAGS,  # ok
)
def unfinished_rows(positions: FloatArray, ok: np.ndarray) -> np.ndarray:
    """Indices of the rows of ``positions`` ``(n, 2)`` (metres) marked ``ok`` whose position
    has a non-finite coordinate, in order."""
    n_rows, n_columns = positions.shape
    found = np.empty(n_rows, dtype=np.int64)
    count = 0
    for row in range(n_rows):
        if not ok[row]:
            continue
        for column in range(n_columns):
            if not math.isfinite(positions[row, column]):
                found[count] = row
                count += 1
                break
    return found[:count].copy()


def _sorted_position(values: FloatArray, value: float, right: bool, start: int) -> int:
    """``np.searchsorted(values, value, side)`` of a finite ``value`` in ascending
    ``values``: the first index whose value is greater (``right``) or not less.

    The scan starts at ``start`` (any index in ``[0, len(values)]``; the answer does not
    depend on it): near the answer, as for the consecutive points of a path, it takes a few
    steps.
    """
    index = min(max(start, 0), values.shape[0])
    while index > 0 and not (values[index - 1] < value or (right and values[index - 1] == value)):
        index -= 1
    while index < values.shape[0] and (values[index] < value or (right and values[index] == value)):
        index += 1
    return index


_sorted_position_compiled = compiled(
    types.int64, NUMBERS, types.float64, types.boolean, types.int64, inline=True
)(_sorted_position)


@compiled(  # type: ignore[misc]
    types.Array(types.float64, 1, "C"),  # distances
    TABLE,  # points
    NUMBERS,  # y_difference
    NUMBERS,  # ends
    NUMBERS,  # xs
    types.boolean,  # increasing
    NUMBERS,  # sx
    NUMBERS,  # sy
    NUMBERS,  # dx
    NUMBERS,  # dy
    NUMBERS,  # safe_length_sq
    FLAGS,  # degenerate
)
def path_distances(
    points: FloatArray,
    y_difference: FloatArray,
    ends: FloatArray,
    xs: FloatArray,
    increasing: bool,
    sx: FloatArray,
    sy: FloatArray,
    dx: FloatArray,
    dy: FloatArray,
    safe_length_sq: FloatArray,
    degenerate: np.ndarray,
) -> FloatArray:
    """``(m,)`` distance (metres) of each point to a path ``y = f(x)``: the windowed search of
    :meth:`sonar_gym.localization.roh_path_errors.TruePath._distances`, whose array form it
    replaces with the same arithmetic per point.

    Args:
        points: ``(m, 2)`` finite points, metres.
        y_difference: ``(m,)`` each point's ``y - f(x)``, metres.
        ends: ``(4,)`` the path's first and last vertex ``(x0, y0, x1, y1)``, metres.
        xs: ``(n,)`` the vertices' x in ascending order, metres.
        increasing: whether the path's x increases along it.
        sx, sy, dx, dy, safe_length_sq, degenerate: per path segment its start and direction
            (metres), its squared length (1 where degenerate) and whether that length is 0.
    """
    n_points = points.shape[0]
    n_segments = xs.shape[0] - 1
    distances = np.empty(n_points)
    below, above = 0, 0  # the last searchsorted answers, where the next point's scans start
    for point in range(n_points):
        px, py = points[point, 0], points[point, 1]
        to_ends = nan_min(
            np.hypot(px - ends[0], py - ends[1]), np.hypot(px - ends[2], py - ends[3])
        )
        bound = to_ends
        if px >= xs[0] and px <= xs[n_segments]:
            bound = nan_min(abs(y_difference[point]), to_ends)
        bound = bound * (1.0 + 1e-9) + 1e-12  # rounding slack
        below = _sorted_position_compiled(xs, px - bound, True, below)
        above = _sorted_position_compiled(xs, px + bound, False, above)
        first = min(max(below - 1, 0), n_segments - 1)
        last = min(max(above, 1), n_segments) - 1
        if not increasing:  # segment k of the ascending vertices is path segment n - 1 - k
            first, last = n_segments - 1 - last, n_segments - 1 - first
        best = np.inf
        for segment in range(first, last + 1):
            rx, ry = px - sx[segment], py - sy[segment]
            t = (rx * dx[segment] + ry * dy[segment]) / safe_length_sq[segment]
            if t < 0.0:
                t = 0.0
            elif t > 1.0:
                t = 1.0
            if degenerate[segment]:
                t = 0.0
            gx, gy = rx - t * dx[segment], ry - t * dy[segment]
            squared = gx * gx + gy * gy
            if squared < best or squared != squared:
                best = squared
        distances[point] = math.sqrt(best)
    return distances


@compiled(types.int64, NUMBERS, types.int64, types.float64, types.float64)  # type: ignore[misc]
def first_side_change(
    distances: FloatArray, start: int, target: float, reference_sign: float
) -> int:
    """The first index from ``start`` on where ``np.sign(distances - target)`` differs from
    ``reference_sign`` (NaN differs from every sign), or ``len(distances)`` if none; the
    distances and ``target`` in metres."""
    for index in range(start, distances.shape[0]):
        excess = distances[index] - target
        if excess > 0.0:
            side = 1.0
        elif excess < 0.0:
            side = -1.0
        elif excess == 0.0:
            side = 0.0
        else:
            return index
        if side != reference_sign:
            return index
    return distances.shape[0]
