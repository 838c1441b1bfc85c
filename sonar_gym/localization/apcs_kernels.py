"""Compiled inner loops of APCS's estimated reflection points (Yamamoto et al., eqs 1-6).

A side sonar takes a few dozen readings over a motion command, where numpy's per-call cost of
the array form (:func:`~sonar_gym.localization.apcs_walls.reflection_direction_candidates` and
``_newest_points``, about 35 calls) is most of the time. These loops do that form's elementwise
arithmetic element by element, in the same order, so they return the same bits (see
:mod:`sonar_gym.sonar.kernels` for why elementwise steps agree). The trigonometry stays in
numpy, between the loops (its ``sin``, ``cos``, ``arctan2`` and ``arccos`` of arrays round
differently from libm's): callers pass it in. Each loop returns one table (each array a loop
returns costs a Python object), the rows numpy's trigonometry reads contiguous.

:func:`reading_table` puts a side stream's stored reading before a run of new ones. The
three loops, in order, for the pairs ``(i, i + 1)`` of consecutive readings
(:func:`~sonar_gym.localization.apcs_walls.newest_reflection_table` runs them):

1. :func:`pair_table`: the eq. (4) inputs per pair (``sin alpha``, ``cos alpha`` of
   eqs (5)-(6), the cosine of the root's offset, whether a root exists) and the summed beam
   axes whose ``arctan2`` is the mean beam axis, the rows of both ``arctan2`` one block (one
   numpy call gives both angles);
2. :func:`root_table`: the two roots of eq. (4), the one nearer the beam axis, for the pairs
   that have one;
3. :func:`erp_table`: ``R2 = P2 + r2 (cos phi, sin phi)`` of eqs (2)-(3), one row per
   reading.

:func:`wrapped_angles` wraps a closed group's reflection directions before its fit, and
:func:`centred_group` gives the group's centroid and its ERPs relative to it.

Positions are metres in {W}, angles radians counter-clockwise from the {W} x-axis.
"""

from __future__ import annotations

import math

import numpy as np
from numba import types

from sonar_gym.compiled import NUMBERS, TABLE, compiled, wrap_to_pi
from sonar_gym.pose import FloatArray

_VECTOR_OUT = types.Array(types.float64, 1, "C")
_TABLE_OUT = types.Array(types.float64, 2, "C")

# Below this, the sensor did not move between two readings (metres):
# apcs_walls.ZERO_LENGTH_M, repeated here so that the loops do not import the wall module.
_ZERO_LENGTH_M = 1e-9


@compiled(_VECTOR_OUT, NUMBERS)  # type: ignore[misc]
def wrapped_angles(angles: FloatArray) -> FloatArray:
    """:func:`sonar_gym.pose.wrap_angles` of finite angles (radians) into (-pi, pi]: the
    reflection directions of a closed ERP group after the frame moves have turned them."""
    wrapped = np.empty(angles.shape[0])
    for index in range(angles.shape[0]):
        wrapped[index] = wrap_to_pi(angles[index])
    return wrapped


READING_ROWS = ("x", "y", "direction", "range")
"""The rows of :func:`reading_table`'s output: sensor position (metres), beam-axis direction
(radians) and range (metres)."""
PAIR_ROWS = ("sin_alpha", "beam_y", "cos_alpha", "beam_x", "cosine", "solvable")
"""The rows of :func:`pair_table`'s output (``solvable`` as 1.0 or 0.0): ``arctan2`` of rows
0-1 over rows 2-3 gives ``alpha`` and the mean beam axis."""
ERP_COLUMNS = ("sensor_x", "sensor_y", "erp_x", "erp_y", "direction", "valid")
"""The columns of :func:`erp_table`'s output: the reading's sensor position (metres), its ERP
(metres), the reflection direction (radians) and whether it gives an ERP (1.0 or 0.0)."""


@compiled(  # type: ignore[misc]
    _TABLE_OUT,
    TABLE,  # positions
    NUMBERS,  # headings
    NUMBERS,  # ranges
    types.float64,  # beam_offset
    types.boolean,  # has_previous
    types.UniTuple(types.float64, 4),  # previous
)
def reading_table(
    positions: FloatArray,
    headings: FloatArray,
    ranges: FloatArray,
    beam_offset: float,
    has_previous: bool,
    previous: tuple[float, float, float, float],
) -> FloatArray:
    """A run of ``n`` readings, after the stream's previous reading if ``has_previous``, as
    one ``(4, N)`` table, rows :data:`READING_ROWS`, each row contiguous (``N = n + 1`` with a
    previous reading, else ``n``); the direction is ``heading + beam_offset``.

    Args:
        positions: ``(n, 2)`` sensor positions; ``headings`` ``(n,)`` robot headings;
            ``ranges`` ``(n,)`` ranges (NaN for a dropout).
        beam_offset: the side's beam axis relative to the heading, radians.
        previous: the previous reading's ``(x, y, direction, range)``; ignored without one.
    """
    count = positions.shape[0]
    first = 1 if has_previous else 0
    table = np.empty((4, count + first))
    if has_previous:
        table[0, 0], table[1, 0] = previous[0], previous[1]
        table[2, 0], table[3, 0] = previous[2], previous[3]
    for i in range(count):
        table[0, first + i] = positions[i, 0]
        table[1, first + i] = positions[i, 1]
        table[2, first + i] = headings[i] + beam_offset
        table[3, first + i] = ranges[i]
    return table


@compiled(  # type: ignore[misc]
    _TABLE_OUT,
    TABLE,  # readings
    types.float64,  # low
    types.float64,  # high
    NUMBERS,  # sines
    NUMBERS,  # cosines
)
def pair_table(
    readings: FloatArray, low: float, high: float, sines: FloatArray, cosines: FloatArray
) -> FloatArray:
    """Per pair of consecutive readings of a :func:`reading_table`, one column of a
    ``(6, max(N - 1, 0))`` table, rows :data:`PAIR_ROWS`, each row contiguous.

    ``alpha`` is that of eqs (5)-(6) (``arctan2(sin alpha, cos alpha)``); ``cosine`` is
    ``-(r2 - r1) / |P1P2|``, whose ``arccos`` is the offset of the roots of eq. (4), 0 where
    ``solvable`` is 0.0 (a dropout, a range outside ``[low, high]``, no motion or
    ``|r2 - r1| > |P1P2|``); ``arctan2(beam y, beam x)`` is the mean beam axis of the pair.
    As :func:`~sonar_gym.localization.apcs_walls.reflection_direction_candidates` on the ranges
    with those outside ``[low, high]`` made NaN.

    Args:
        readings: ``(4, N)`` a :func:`reading_table`.
        low, high: the valid ranges, metres.
        sines, cosines: ``(N,)`` numpy's ``sin`` and ``cos`` of the readings' directions.
    """
    count = max(readings.shape[1] - 1, 0)
    table = np.empty((6, count))
    for i in range(count):
        dx = readings[0, i + 1] - readings[0, i]
        dy = readings[1, i + 1] - readings[1, i]
        baseline = math.sqrt(dy * dy + dx * dx)  # |P1P2|, the corrected root of eq. (4)
        moved = baseline > _ZERO_LENGTH_M
        safe_baseline = baseline if moved else 1.0
        table[0, i] = dx / safe_baseline  # eq. (5)
        table[2, i] = dy / safe_baseline  # eq. (6)
        first, second = readings[3, i], readings[3, i + 1]
        ranged = (
            low <= first <= high
            and low <= second <= high
            and math.isfinite(first)
            and math.isfinite(second)
        )
        range_step = (second if ranged else 0.0) - (first if ranged else 0.0)
        value = -range_step / safe_baseline
        solvable = ranged and moved and abs(value) <= 1.0
        table[4, i] = value if solvable else 0.0
        table[5, i] = 1.0 if solvable else 0.0
        table[1, i] = sines[i] + sines[i + 1]
        table[3, i] = cosines[i] + cosines[i + 1]
    return table


@compiled(  # type: ignore[misc]
    _TABLE_OUT,
    TABLE,  # pairs
    TABLE,  # angles
    NUMBERS,  # offset
)
def root_table(pairs: FloatArray, angles: FloatArray, offset: FloatArray) -> FloatArray:
    """Of the roots ``pi/2 - alpha +- offset`` of eq. (4) (wrapped to (-pi, pi]), the one
    nearer the mean beam axis (``+`` on a tie), for each of the ``K`` pairs of a
    :func:`pair_table` that has one, as one ``(2, K)`` table: the chosen roots ``phi``
    (radians) and the indices of their pairs (as floats, exact), each row contiguous.

    Args:
        pairs: ``(6, N - 1)`` a :func:`pair_table`.
        angles: ``(2, N - 1)`` numpy's ``arctan2`` of its rows 0-1 over rows 2-3: ``alpha``
            and the mean beam axis, radians.
        offset: ``(N - 1,)`` numpy's ``arccos`` of its ``cosine`` row: the roots' offset,
            radians.
    """
    count = 0
    for i in range(pairs.shape[1]):
        if pairs[5, i] != 0.0:
            count += 1
    table = np.empty((2, count))
    k = 0
    for i in range(pairs.shape[1]):
        if pairs[5, i] == 0.0:
            continue
        alpha, beam_axis = angles[0, i], angles[1, i]
        phi_plus = wrap_to_pi(math.pi / 2.0 - alpha + offset[i])  # eq. (4), +
        phi_minus = wrap_to_pi(math.pi / 2.0 - alpha - offset[i])  # eq. (4), -
        off_axis_plus = abs(wrap_to_pi(phi_plus - beam_axis))
        off_axis_minus = abs(wrap_to_pi(phi_minus - beam_axis))
        table[0, k] = phi_plus if off_axis_plus <= off_axis_minus else phi_minus
        table[1, k] = i
        k += 1
    return table


@compiled(  # type: ignore[misc]
    _TABLE_OUT,
    TABLE,  # readings
    TABLE,  # roots
    NUMBERS,  # cos_phi
    NUMBERS,  # sin_phi
    types.int64,  # skipped
)
def erp_table(
    readings: FloatArray, roots: FloatArray, cos_phi: FloatArray, sin_phi: FloatArray, skipped: int
) -> FloatArray:
    """The ERPs ``R2 = P2 + r2 (cos phi, sin phi)`` (eqs (2)-(3)) of the pairs of a
    :func:`root_table` with each reading's sensor position, as one row per reading from
    reading ``skipped`` on: a ``(N - skipped, 6)`` table, columns :data:`ERP_COLUMNS` (zero ERP,
    direction and valid where the reading gives no ERP); ``phi`` wrapped by ``wrap_angles``
    once more, as :class:`~sonar_gym.localization.apcs_walls.EstimatedReflectionPoints` stores
    it.

    Args:
        readings: ``(4, N)`` a :func:`reading_table`.
        roots: ``(2, K)`` a :func:`root_table` of its pairs.
        cos_phi, sin_phi: ``(K,)`` numpy's ``cos`` and ``sin`` of the roots.
        skipped: 0 or 1, the readings before the first row.
    """
    rows = readings.shape[1] - skipped
    table = np.zeros((rows, 6))
    for row in range(rows):
        table[row, 0] = readings[0, row + skipped]
        table[row, 1] = readings[1, row + skipped]
    for k in range(roots.shape[1]):
        second = int(roots[1, k]) + 1
        row = second - skipped
        table[row, 2] = readings[0, second] + readings[3, second] * cos_phi[k]
        table[row, 3] = readings[1, second] + readings[3, second] * sin_phi[k]
        table[row, 4] = wrap_to_pi(roots[0, k])
        table[row, 5] = 1.0
    return table


@compiled(  # type: ignore[misc]
    types.Tuple((_TABLE_OUT, types.float64, types.float64)),
    TABLE,  # members
)
def centred_group(members: FloatArray) -> tuple[FloatArray, float, float]:
    """``(members - centroid, centroid_x, centroid_y)`` of a group's ``(n, 2)`` ERPs (metres),
    ``n >= 1``: the centroid as ``np.add.reduce(members, axis=0) / n`` gives it (numpy adds
    the rows one after the other, from 0.0), ``(n, 2)`` the ERPs relative to it."""
    count = members.shape[0]
    sum_x = 0.0
    sum_y = 0.0
    for i in range(count):
        sum_x += members[i, 0]
        sum_y += members[i, 1]
    centroid_x = sum_x / count
    centroid_y = sum_y / count
    centred = np.empty((count, 2))
    for i in range(count):
        centred[i, 0] = members[i, 0] - centroid_x
        centred[i, 1] = members[i, 1] - centroid_y
    return centred, centroid_x, centroid_y
