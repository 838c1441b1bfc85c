"""APCS's matching of a detected vector to the map, one map wall at a time in Python: the form
the compiled loop of :mod:`sonar_gym.localization.apcs_match_kernels` replaced, kept as the
tests' reference (Yamamoto et al., sec. 4.3, Fig. 7).
"""

from __future__ import annotations

from collections.abc import Sequence

from sonar_gym.localization.apcs_walls import (
    AMBIGUOUS,
    MATCHED,
    NO_MATCH,
    APCSParameters,
    WallCheck,
    WallVector,
)
from sonar_gym.pose import wrap_angle


def reference_wall_check(
    detected: WallVector, map_wall: WallVector, map_index: int, params: APCSParameters
) -> WallCheck:
    """The three conditions of sec. 4.3 for one map wall, in Python floats."""
    detected_angle = detected._angle  # type: ignore[attr-defined]
    (start_x, start_y), (end_x, end_y) = detected.start, detected.end
    orientation_error = wrap_angle(detected_angle - map_wall._angle)  # type: ignore[attr-defined]
    wall_x, wall_y = map_wall.start
    ux, uy = map_wall._unit  # type: ignore[attr-defined]
    a, b, c = uy, -ux, map_wall._offset  # type: ignore[attr-defined]
    length = map_wall._length  # type: ignore[attr-defined]
    start_parameter = ((start_x - wall_x) * ux + (start_y - wall_y) * uy) / length
    end_parameter = ((end_x - wall_x) * ux + (end_y - wall_y) * uy) / length
    d1 = a * start_x + b * start_y + c
    d2 = a * end_x + b * end_y + c
    distance_squared = d1 * d1 + d2 * d2
    slack = 1e-12
    inside = -slack <= start_parameter <= 1.0 + slack and -slack <= end_parameter <= 1.0 + slack
    return WallCheck(
        map_index,
        map_wall,
        orientation_error,
        start_parameter,
        end_parameter,
        distance_squared,
        abs(orientation_error) <= params.orientation_tolerance_rad,
        inside,
        distance_squared < params.endpoint_distance_squared_m2,
    )


def reference_match(
    detected: WallVector, wall_map: Sequence[WallVector], params: APCSParameters
) -> tuple[str, tuple[WallCheck, ...], int | None]:
    """``(status, checks, wall_index)`` of matching ``detected`` to the map: a unique match."""
    checks = tuple(
        reference_wall_check(detected, wall, index, params) for index, wall in enumerate(wall_map)
    )
    candidates = [check for check in checks if check.matched]
    if len(candidates) == 1:
        return MATCHED, checks, candidates[0].map_index
    return (AMBIGUOUS if candidates else NO_MATCH), checks, None


def reference_closest(checks: Sequence[WallCheck]) -> WallCheck | None:
    """The check that came closest to matching, as ``rejection_reason`` chose it."""
    if not checks:
        return None
    return max(
        checks,
        key=lambda check: (
            check.orientation_ok + check.inclusion_ok + check.distance_ok,
            check.orientation_ok,
            check.inclusion_ok,
            -check.endpoint_distance_squared_m2,
        ),
    )
