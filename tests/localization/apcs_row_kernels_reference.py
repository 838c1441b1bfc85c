"""The compiled loops of APCS's estimated reflection points (Yamamoto et al., eqs 1-6) that
returned several arrays each, and the glue around them, as they were written: the forms
:func:`~sonar_gym.localization.apcs_kernels.reading_table`,
:func:`~sonar_gym.localization.apcs_kernels.pair_table`,
:func:`~sonar_gym.localization.apcs_kernels.root_table` and
:func:`~sonar_gym.localization.apcs_kernels.erp_table` replaced, kept as the tests' reference.

Positions are metres in {W}, angles radians counter-clockwise from the {W} x-axis.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from numba import types

from sonar_gym.compiled import FLAGS, INDICES, NUMBERS, TABLE, compiled, wrap_to_pi
from sonar_gym.localization.apcs_online import BEAM_OFFSET_RAD, WallStream
from sonar_gym.localization.apcs_walls import IntArray
from sonar_gym.pose import FloatArray

_VECTOR_OUT = types.Array(types.float64, 1, "C")
_TABLE_OUT = types.Array(types.float64, 2, "C")
_FLAGS_OUT = types.Array(types.boolean, 1, "C")
_INDICES_OUT = types.Array(types.int64, 1, "C")

# Below this, the sensor did not move between two readings (metres).
_ZERO_LENGTH_M = 1e-9


@compiled(  # type: ignore[misc]
    types.Tuple((_TABLE_OUT, _VECTOR_OUT, _VECTOR_OUT)),
    TABLE,  # positions
    NUMBERS,  # headings
    NUMBERS,  # ranges
    types.float64,  # beam_offset
    types.boolean,  # has_previous
    types.UniTuple(types.float64, 4),  # previous
)
def stream_readings(
    positions: FloatArray,
    headings: FloatArray,
    ranges: FloatArray,
    beam_offset: float,
    has_previous: bool,
    previous: tuple[float, float, float, float],
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(positions, directions, ranges)`` of a run of ``n`` readings, after the stream's
    previous reading if ``has_previous``: ``(n + 1, 2)`` (or ``(n, 2)``) sensor positions
    (metres), beam-axis directions ``heading + beam_offset`` (radians) and ranges (metres).

    Args:
        positions: ``(n, 2)`` sensor positions; ``headings`` ``(n,)`` robot headings;
            ``ranges`` ``(n,)`` ranges (NaN for a dropout).
        beam_offset: the side's beam axis relative to the heading, radians.
        previous: the previous reading's ``(x, y, direction, range)``; ignored without one.
    """
    count = positions.shape[0]
    first = 1 if has_previous else 0
    all_positions = np.empty((count + first, 2))
    directions = np.empty(count + first)
    all_ranges = np.empty(count + first)
    if has_previous:
        all_positions[0, 0], all_positions[0, 1] = previous[0], previous[1]
        directions[0], all_ranges[0] = previous[2], previous[3]
    for i in range(count):
        all_positions[first + i, 0] = positions[i, 0]
        all_positions[first + i, 1] = positions[i, 1]
        directions[first + i] = headings[i] + beam_offset
        all_ranges[first + i] = ranges[i]
    return all_positions, directions, all_ranges


@compiled(  # type: ignore[misc]
    types.Tuple((_VECTOR_OUT, _VECTOR_OUT, _VECTOR_OUT, _FLAGS_OUT, _VECTOR_OUT, _VECTOR_OUT)),
    TABLE,  # positions
    NUMBERS,  # ranges
    types.float64,  # low
    types.float64,  # high
    NUMBERS,  # first_sin
    NUMBERS,  # second_sin
    NUMBERS,  # first_cos
    NUMBERS,  # second_cos
)
def pair_geometry(
    positions: FloatArray,
    ranges: FloatArray,
    low: float,
    high: float,
    first_sin: FloatArray,
    second_sin: FloatArray,
    first_cos: FloatArray,
    second_cos: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, np.ndarray, FloatArray, FloatArray]:
    """Per pair of consecutive readings: ``(sin alpha, cos alpha, cosine, solvable, beam y,
    beam x)``, each ``(N - 1,)``.

    ``alpha`` is that of eqs (5)-(6) (``arctan2(sin alpha, cos alpha)``); ``cosine`` is
    ``-(r2 - r1) / |P1P2|``, whose ``arccos`` is the offset of the roots of eq. (4), 0 where
    ``solvable`` is False (a dropout, a range outside ``[low, high]``, no motion or
    ``|r2 - r1| > |P1P2|``); ``arctan2(beam y, beam x)`` is the mean beam axis of the pair.
    As :func:`~sonar_gym.localization.apcs_walls.reflection_direction_candidates` on the ranges
    with those outside ``[low, high]`` made NaN.

    Args:
        positions: ``(N, 2)`` sensor positions, metres in {W}.
        ranges: ``(N,)`` ranges, metres (NaN or inf for a dropout).
        low, high: the valid ranges, metres.
        first_sin, second_sin, first_cos, second_cos: ``(N - 1,)`` numpy's ``sin`` and ``cos``
            of the beam-axis directions of the first and the second reading of each pair.
    """
    count = positions.shape[0] - 1
    sin_alpha = np.empty(count)
    cos_alpha = np.empty(count)
    cosine = np.empty(count)
    solvable = np.empty(count, dtype=np.bool_)
    beam_y = np.empty(count)
    beam_x = np.empty(count)
    for i in range(count):
        dx = positions[i + 1, 0] - positions[i, 0]
        dy = positions[i + 1, 1] - positions[i, 1]
        baseline = math.sqrt(dy * dy + dx * dx)  # |P1P2|, the corrected root of eq. (4)
        moved = baseline > _ZERO_LENGTH_M
        safe_baseline = baseline if moved else 1.0
        sin_alpha[i] = dx / safe_baseline  # eq. (5)
        cos_alpha[i] = dy / safe_baseline  # eq. (6)
        first, second = ranges[i], ranges[i + 1]
        ranged = (
            low <= first <= high
            and low <= second <= high
            and math.isfinite(first)
            and math.isfinite(second)
        )
        range_step = (second if ranged else 0.0) - (first if ranged else 0.0)
        value = -range_step / safe_baseline
        solvable[i] = ranged and moved and abs(value) <= 1.0
        cosine[i] = value if solvable[i] else 0.0
        beam_y[i] = first_sin[i] + second_sin[i]
        beam_x[i] = first_cos[i] + second_cos[i]
    return sin_alpha, cos_alpha, cosine, solvable, beam_y, beam_x


@compiled(  # type: ignore[misc]
    types.Tuple((_VECTOR_OUT, _INDICES_OUT)),
    NUMBERS,  # alpha
    NUMBERS,  # offset
    NUMBERS,  # beam_axis
    FLAGS,  # solvable
)
def chosen_roots(
    alpha: FloatArray, offset: FloatArray, beam_axis: FloatArray, solvable: np.ndarray
) -> tuple[FloatArray, np.ndarray]:
    """``(phi, pairs)``: of the roots ``pi/2 - alpha +- offset`` of eq. (4) (wrapped to
    (-pi, pi]), the one nearer ``beam_axis`` (``+`` on a tie), for each pair that has one,
    and the indices of those pairs. Radians; inputs ``(N - 1,)``."""
    count = 0
    for i in range(solvable.shape[0]):
        if solvable[i]:
            count += 1
    phi = np.empty(count)
    pairs = np.empty(count, dtype=np.int64)
    k = 0
    for i in range(solvable.shape[0]):
        if not solvable[i]:
            continue
        phi_plus = wrap_to_pi(math.pi / 2.0 - alpha[i] + offset[i])  # eq. (4), +
        phi_minus = wrap_to_pi(math.pi / 2.0 - alpha[i] - offset[i])  # eq. (4), -
        off_axis_plus = abs(wrap_to_pi(phi_plus - beam_axis[i]))
        off_axis_minus = abs(wrap_to_pi(phi_minus - beam_axis[i]))
        phi[k] = phi_plus if off_axis_plus <= off_axis_minus else phi_minus
        pairs[k] = i
        k += 1
    return phi, pairs


@compiled(  # type: ignore[misc]
    types.Tuple((_TABLE_OUT, _VECTOR_OUT, _FLAGS_OUT)),
    TABLE,  # positions
    NUMBERS,  # ranges
    NUMBERS,  # phi
    INDICES,  # pairs
    NUMBERS,  # cos_phi
    NUMBERS,  # sin_phi
    types.int64,  # skipped
)
def newest_rows(
    positions: FloatArray,
    ranges: FloatArray,
    phi: FloatArray,
    pairs: np.ndarray,
    cos_phi: FloatArray,
    sin_phi: FloatArray,
    skipped: int,
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """The ERPs ``R2`` of the ``K`` pairs, eqs (2)-(3), as one row per reading from reading
    ``skipped`` on: ``(points (N - skipped, 2), directions (N - skipped,), valid
    (N - skipped,))``, zero where the reading gives no ERP; ``phi`` wrapped by ``wrap_angles``
    once more, as :class:`~sonar_gym.localization.apcs_walls.EstimatedReflectionPoints` stores
    it.

    Args:
        positions: ``(N, 2)`` sensor positions, metres in {W}; ``ranges`` ``(N,)`` metres.
        phi, pairs: :func:`chosen_roots`' output.
        cos_phi, sin_phi: numpy's ``cos`` and ``sin`` of ``phi``.
        skipped: 0 or 1, the readings before the first row.
    """
    rows = positions.shape[0] - skipped
    points = np.zeros((rows, 2))
    directions = np.zeros(rows)
    valid = np.zeros(rows, dtype=np.bool_)
    for k in range(pairs.shape[0]):
        second = pairs[k] + 1
        row = second - skipped
        points[row, 0] = positions[second, 0] + ranges[second] * cos_phi[k]
        points[row, 1] = positions[second, 1] + ranges[second] * sin_phi[k]
        directions[row] = wrap_to_pi(phi[k])
        valid[row] = True
    return points, directions, valid


def chosen_roots_once(
    positions: FloatArray,
    directions: FloatArray,
    ranges: FloatArray,
    valid_range_m: tuple[float, float],
) -> tuple[FloatArray, IntArray]:
    """``(phi, pairs)`` of ``_newest_points`` on checked inputs (``N >= 2``), with the ranges
    outside ``valid_range_m`` taken as dropouts: the loops of this module with numpy's
    trigonometry between them."""
    low, high = valid_range_m
    # numpy's sine and cosine act element by element: those of the first and the second
    # reading of every pair are slices of those of all the readings.
    sines, cosines = np.sin(directions), np.cos(directions)
    sin_alpha, cos_alpha, cosine, solvable, beam_y, beam_x = pair_geometry(
        positions, ranges, low, high, sines[:-1], sines[1:], cosines[:-1], cosines[1:]
    )
    return chosen_roots(  # type: ignore[no-any-return]
        np.arctan2(sin_alpha, cos_alpha),  # alpha of eqs (5)-(6)
        np.arccos(cosine),  # the offset of the roots of eq. (4)
        np.arctan2(beam_y, beam_x),  # the pair's mean beam axis
        solvable,
    )


def newest_reflection_rows(
    positions: FloatArray,
    directions: FloatArray,
    ranges: FloatArray,
    valid_range_m: tuple[float, float],
    skipped: int,
) -> tuple[FloatArray, FloatArray, npt.NDArray[np.bool_]]:
    """:func:`sonar_gym.localization.apcs_walls.newest_reflection_rows` through the loops of
    this module: ``(points (N - skipped, 2), directions (N - skipped,), valid
    (N - skipped,))``, zero where the reading gives no ERP."""
    if len(positions) < 2:
        rows = len(positions) - skipped
        return np.zeros((rows, 2)), np.zeros(rows), np.zeros(rows, dtype=bool)
    phi, pairs = chosen_roots_once(positions, directions, ranges, valid_range_m)
    return newest_rows(  # type: ignore[no-any-return]
        positions, ranges, phi, pairs, np.cos(phi), np.sin(phi), skipped
    )


def pending_rows(
    stream: WallStream, positions: FloatArray, headings: FloatArray, ranges: FloatArray
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """:meth:`sonar_gym.localization.apcs_online.WallStream._pending` through
    :func:`stream_readings` and :func:`newest_reflection_rows`."""
    has_previous, previous = stream._previous_reading()
    all_positions, directions, all_ranges = stream_readings(
        positions, headings, ranges, BEAM_OFFSET_RAD[stream.side], has_previous, previous
    )
    return newest_reflection_rows(
        all_positions,
        directions,
        all_ranges,
        stream.params.sensing_range_m,
        int(has_previous),
    )
