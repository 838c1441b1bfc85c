"""Compiled loop of APCS's matching of a detected vector to the map (Yamamoto et al., sec. 4.3).

:func:`sonar_gym.localization.apcs_walls.match_wall` checks every map wall ``a_i`` against each
detected vector ``T_s -> T_e`` (Fig. 7): orientation, inclusion of the projection ``V_s V_e``
and ``d1^2 + d2^2``. :func:`check_map_walls` does that for all the map's walls in one loop, on
the walls' numbers held as one table (:data:`WALL_COLUMNS`), with Python's float arithmetic
step by step (the same bits: ``+ - * /`` round alike, and :func:`~sonar_gym.compiled.wrap_angle`
is :func:`sonar_gym.pose.wrap_angle`). It also gives the verdict: how many walls match, the
first of them, and the wall that came closest to matching.

Positions are metres in {W}, angles radians counter-clockwise from the {W} x-axis.
"""

from __future__ import annotations

import numpy as np
from numba import types

from sonar_gym.compiled import TABLE, compiled, wrap_angle
from sonar_gym.pose import FloatArray

WALL_COLUMNS = ("angle", "start_x", "start_y", "unit_x", "unit_y", "offset", "length")
"""The columns of a map wall's row: direction angle of ``start -> end`` (radians), ``start``
(metres), unit vector along the wall, ``c`` of the line ``uy x - ux y + c = 0`` (metres) and
length (metres); as :class:`~sonar_gym.localization.apcs_walls.WallVector` derives them."""
_ANGLE, _START_X, _START_Y, _UNIT_X, _UNIT_Y, _OFFSET, _LENGTH = range(len(WALL_COLUMNS))

CHECK_COLUMNS = ("orientation_error_rad", "start_parameter", "end_parameter", "distance_m2")
"""The columns of a wall's numbers in :func:`check_map_walls`' output, as in
:class:`~sonar_gym.localization.apcs_walls.WallCheck`."""
CONDITION_COLUMNS = ("orientation_ok", "inclusion_ok", "distance_ok")
"""The columns of a wall's conditions in :func:`check_map_walls`' output, in the paper's
order."""

INCLUSION_SLACK = 1e-12
"""How far outside ``[0, 1]`` a projection parameter may fall and still be included
(dimensionless): the rounding of an end point that lies on the end of a map wall."""

_NUMBERS_OUT = types.Array(types.float64, 2, "C")
_CONDITIONS_OUT = types.Array(types.boolean, 2, "C")


@compiled(  # type: ignore[misc]
    types.Tuple((_NUMBERS_OUT, _CONDITIONS_OUT, types.int64, types.int64, types.int64)),
    TABLE,  # walls
    types.float64,  # detected_angle
    types.float64,  # start_x
    types.float64,  # start_y
    types.float64,  # end_x
    types.float64,  # end_y
    types.float64,  # orientation_tolerance_rad
    types.float64,  # endpoint_distance_squared_m2
)
def check_map_walls(
    walls: FloatArray,
    detected_angle: float,
    start_x: float,
    start_y: float,
    end_x: float,
    end_y: float,
    orientation_tolerance_rad: float,
    endpoint_distance_squared_m2: float,
) -> tuple[FloatArray, np.ndarray, int, int, int]:
    """The three conditions of sec. 4.3 for every map wall (Fig. 7), and the verdict.

    ``T_s`` and ``T_e`` project on the line of ``a_i`` to ``V_s`` and ``V_e`` (parameters 0 at
    the wall's start, 1 at its end); ``d1`` and ``d2`` are their signed distances from it.

    Args:
        walls: ``(n, 7)`` the map walls' rows (:data:`WALL_COLUMNS`).
        detected_angle: direction angle of ``T_s -> T_e``, radians in (-pi, pi].
        start_x, start_y, end_x, end_y: ``T_s`` and ``T_e``, metres in {W}.
        orientation_tolerance_rad: largest ``|orientation error|`` that matches, radians.
        endpoint_distance_squared_m2: ``d1^2 + d2^2`` must be below this, m^2.

    Returns:
        ``(numbers, conditions, candidates, first_candidate, closest)``: ``(n, 4)`` numbers
        (:data:`CHECK_COLUMNS`) and ``(n, 3)`` conditions (:data:`CONDITION_COLUMNS`) per wall;
        how many walls pass all three; the first of them (-1 for none); and the wall that came
        closest to matching (-1 for an empty map): the most conditions passed, then
        orientation, then inclusion, then the smaller ``d1^2 + d2^2``, the first on a tie.
    """
    count = walls.shape[0]
    numbers = np.empty((count, 4))
    conditions = np.empty((count, 3), dtype=np.bool_)
    candidates = 0
    first_candidate = -1
    closest = -1
    closest_passed = 0
    closest_orientation = False
    closest_inclusion = False
    closest_distance = 0.0
    for i in range(count):
        orientation_error = wrap_angle(detected_angle - walls[i, _ANGLE])
        wall_x, wall_y = walls[i, _START_X], walls[i, _START_Y]
        ux, uy = walls[i, _UNIT_X], walls[i, _UNIT_Y]
        a, b, c = uy, -ux, walls[i, _OFFSET]
        length = walls[i, _LENGTH]
        start_parameter = ((start_x - wall_x) * ux + (start_y - wall_y) * uy) / length
        end_parameter = ((end_x - wall_x) * ux + (end_y - wall_y) * uy) / length
        d1 = a * start_x + b * start_y + c
        d2 = a * end_x + b * end_y + c
        distance_squared = d1 * d1 + d2 * d2
        orientation_ok = abs(orientation_error) <= orientation_tolerance_rad
        inclusion_ok = (
            -INCLUSION_SLACK <= start_parameter <= 1.0 + INCLUSION_SLACK
            and -INCLUSION_SLACK <= end_parameter <= 1.0 + INCLUSION_SLACK
        )
        distance_ok = distance_squared < endpoint_distance_squared_m2
        numbers[i, 0] = orientation_error
        numbers[i, 1] = start_parameter
        numbers[i, 2] = end_parameter
        numbers[i, 3] = distance_squared
        conditions[i, 0] = orientation_ok
        conditions[i, 1] = inclusion_ok
        conditions[i, 2] = distance_ok
        passed = int(orientation_ok) + int(inclusion_ok) + int(distance_ok)
        if passed == 3:
            candidates += 1
            if first_candidate < 0:
                first_candidate = i
        if closest < 0 or (
            passed > closest_passed
            or passed == closest_passed
            and (
                orientation_ok > closest_orientation
                or orientation_ok == closest_orientation
                and (
                    inclusion_ok > closest_inclusion
                    or inclusion_ok == closest_inclusion
                    and distance_squared < closest_distance
                )
            )
        ):
            closest = i
            closest_passed = passed
            closest_orientation = orientation_ok
            closest_inclusion = inclusion_ok
            closest_distance = distance_squared
    return numbers, conditions, candidates, first_candidate, closest
