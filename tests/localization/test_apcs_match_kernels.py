"""APCS's matching in one compiled loop against the per-wall Python form it replaces, bit for bit.

The reference is :mod:`tests.localization.apcs_match_reference`: every map wall checked in turn
in Python floats (Yamamoto et al., sec. 4.3, Fig. 7), the unique match, and the wall
``rejection_reason`` called the closest to matching.
"""

from __future__ import annotations

import math
import pickle
import struct

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from sonar_gym.compiled import wrap_angle as compiled_wrap_angle
from sonar_gym.localization.apcs_online import rejection_reason
from sonar_gym.localization.apcs_walls import (
    AMBIGUOUS,
    DEFAULT_PARAMETERS,
    MATCHED,
    NO_MATCH,
    APCSParameters,
    DetectedWall,
    WallCheck,
    WallMap,
    WallVector,
    check_wall,
    match_wall,
)
from sonar_gym.pose import wrap_angle
from tests.fuzzing import fuzz_settings
from tests.localization.apcs_match_reference import (
    reference_closest,
    reference_match,
    reference_wall_check,
)


def _bits(check: WallCheck) -> tuple[object, ...]:
    """Every field of a check, its floats as their bytes (``-0.0`` differs from ``0.0``)."""
    return tuple(
        struct.pack("<d", value) if isinstance(value, float) else (type(value), value)
        for value in vars(check).values()
    )


def _random_map(rng: np.random.Generator, count: int) -> tuple[WallVector, ...]:
    """Walls of every orientation; some parallel, overlapping or reversed copies of others."""
    walls: list[WallVector] = []
    for _ in range(count):
        kind = rng.integers(4)
        if walls and kind == 0:  # the same line, shifted along it: overlapping walls
            base = walls[rng.integers(len(walls))]
            shift = rng.uniform(-1.0, 1.0) * (base.end_point - base.start_point)
            start, end = base.start_point + shift, base.end_point + shift
        elif walls and kind == 1:  # reversed
            base = walls[rng.integers(len(walls))]
            start, end = base.end_point, base.start_point
        else:
            start = rng.uniform(-4.0, 4.0, 2)
            angle = rng.choice([rng.uniform(-np.pi, np.pi), np.pi, -np.pi / 2, 0.0, np.pi / 2])
            end = start + rng.uniform(0.2, 5.0) * np.array([math.cos(angle), math.sin(angle)])
        walls.append(WallVector(tuple(start.tolist()), tuple(end.tolist()), name=f"w{len(walls)}"))
    return tuple(walls)


def _detected_near(rng: np.random.Generator, wall_map: tuple[WallVector, ...]) -> WallVector:
    """A detected vector on, near, past the ends of, or far from a map wall."""
    kind = rng.integers(5)
    if not wall_map or kind == 0:
        start = rng.uniform(-4.0, 4.0, 2)
        end = start + rng.uniform(-1.0, 1.0, 2)
        if np.array_equal(start, end):
            end = end + 0.5
        return WallVector(tuple(start.tolist()), tuple(end.tolist()))
    wall = wall_map[rng.integers(len(wall_map))]
    start_parameter, end_parameter = np.sort(rng.uniform(-0.1, 1.1, 2))
    if kind == 1:  # exactly at the wall's ends
        start_parameter, end_parameter = 0.0, 1.0
    elif kind == 2:  # on the inclusion's slack
        start_parameter = -rng.choice([0.0, 5e-13, 1e-12, 2e-12])
        end_parameter = 1.0 + rng.choice([0.0, 5e-13, 1e-12, 2e-12])
    noise = rng.choice([0.0, 1e-9, 1e-3, 0.05, 0.2])
    start = wall.start_point + start_parameter * (wall.end_point - wall.start_point)
    end = wall.start_point + end_parameter * (wall.end_point - wall.start_point)
    start, end = start + rng.normal(0.0, noise, 2), end + rng.normal(0.0, noise, 2)
    if math.hypot(*(end - start)) <= 1e-6:
        end = start + wall.unit_direction
    return WallVector(tuple(start.tolist()), tuple(end.tolist()))


def _at_the_tolerances(
    detected: WallVector, wall_map: tuple[WallVector, ...], rng: np.random.Generator
) -> APCSParameters:
    """Thresholds equal to (or one ulp beside) a map wall's orientation error and distance."""
    check = reference_wall_check(
        detected, wall_map[rng.integers(len(wall_map))], 0, DEFAULT_PARAMETERS
    )
    tolerance = abs(check.orientation_error_rad)
    distance = check.endpoint_distance_squared_m2
    step = rng.choice([-1, 0, 1])
    tolerance = float(np.nextafter(tolerance, step * np.inf)) if step else tolerance
    if not 0.0 < tolerance < math.pi:
        tolerance = DEFAULT_PARAMETERS.orientation_tolerance_rad
    if not 0.0 < distance < math.inf:
        distance = DEFAULT_PARAMETERS.endpoint_distance_squared_m2
    return APCSParameters(
        orientation_tolerance_rad=tolerance, endpoint_distance_squared_m2=distance
    )


def _assert_as_the_reference(
    detected: WallVector, wall_map: tuple[WallVector, ...], params: APCSParameters
) -> str:
    status, checks, wall_index = reference_match(detected, wall_map, params)
    for given_map in (wall_map, list(wall_map), WallMap(wall_map)):
        match = match_wall(detected, given_map, params)
        assert (match.status, match.wall_index) == (status, wall_index)
        assert match.wall is (None if wall_index is None else wall_map[wall_index])
        assert match.checks == checks and len(match.checks) == len(checks)
        assert [_bits(check) for check in match.checks] == [_bits(check) for check in checks]
        closest = reference_closest(checks)
        assert (match.closest_check is None) == (closest is None)
        if closest is not None:
            assert match.closest_check is not None
            assert _bits(match.closest_check) == _bits(closest)
        assert match.candidate_indices == tuple(c.map_index for c in checks if c.matched)
        assert match.rejections == {
            c.map_index: reason for c in checks if (reason := c.reason) is not None
        }
    for index, wall in enumerate(wall_map):
        assert _bits(check_wall(detected, wall, index, params)) == _bits(
            reference_wall_check(detected, wall, index, params)
        )
    return status


def test_the_compiled_wrap_angle_is_pose_wrap_angle() -> None:
    rng = np.random.default_rng(3)
    angles = np.concatenate(
        [
            rng.uniform(-np.pi, np.pi, (20_000, 2)) @ np.array([1.0, -1.0]),
            [math.pi, -math.pi, 2.0 * math.pi, -2.0 * math.pi, 0.0, -0.0, 3.0 * math.pi],
            [np.nextafter(math.pi, 0.0), np.nextafter(-math.pi, 0.0), 1e-300, -5e-324],
            [math.pi - np.nextafter(-math.pi, 0.0), np.nextafter(math.pi, 4.0) + math.pi],
        ]
    )
    for angle in angles.tolist():
        assert struct.pack("<d", compiled_wrap_angle(angle)) == struct.pack("<d", wrap_angle(angle))


def test_matching_is_the_per_wall_python_form_on_random_maps() -> None:
    rng = np.random.default_rng(11)
    statuses: set[str] = set()
    reasons: set[str | None] = set()
    edges: set[tuple[str, bool]] = set()
    for trial in range(600):
        wall_map = _random_map(rng, int(rng.integers(0, 16)))
        detected = _detected_near(rng, wall_map)
        params = (
            _at_the_tolerances(detected, wall_map, rng)
            if wall_map and trial % 3 == 0
            else DEFAULT_PARAMETERS
        )
        statuses.add(_assert_as_the_reference(detected, wall_map, params))
        for check in match_wall(detected, wall_map, params).checks:
            reasons.add(check.reason)
            low = min(check.start_parameter, check.end_parameter)
            high = max(check.start_parameter, check.end_parameter)
            if -1e-11 < low < 0.0 or 1.0 < high < 1.0 + 1e-11:
                edges.add(("slack", check.inclusion_ok))
            if abs(check.orientation_error_rad) == params.orientation_tolerance_rad:
                edges.add(("at orientation tolerance", check.orientation_ok))
            if check.endpoint_distance_squared_m2 == params.endpoint_distance_squared_m2:
                edges.add(("at distance threshold", check.distance_ok))
    assert statuses == {MATCHED, AMBIGUOUS, NO_MATCH}
    assert reasons == {None, "orientation", "inclusion", "distance"}
    assert edges == {
        ("slack", True),
        ("slack", False),
        ("at orientation tolerance", True),
        ("at distance threshold", False),
    }


_COORDINATES = st.floats(-20.0, 20.0, allow_nan=False, allow_subnormal=True)


@fuzz_settings(300)
@given(
    ends=st.lists(_COORDINATES, min_size=4, max_size=4),
    walls=st.lists(st.lists(_COORDINATES, min_size=4, max_size=4), max_size=6),
)
def test_matching_is_the_per_wall_python_form_on_any_coordinates(
    ends: list[float], walls: list[list[float]]
) -> None:
    def vector(x0: float, y0: float, x1: float, y1: float) -> WallVector | None:
        return None if math.hypot(x1 - x0, y1 - y0) <= 1e-9 else WallVector((x0, y0), (x1, y1))

    detected = vector(*ends)
    wall_map = tuple(wall for numbers in walls if (wall := vector(*numbers)) is not None)
    if detected is not None:
        _assert_as_the_reference(detected, wall_map, DEFAULT_PARAMETERS)


def test_an_empty_map_matches_nothing() -> None:
    detected = DetectedWall((0.0, 1.0), (1.0, 1.0), (0, 1, 2, 3), 0.0)
    match = match_wall(detected, ())
    assert match.status == NO_MATCH and match.checks == () and not match.checks
    assert match.closest_check is None and rejection_reason(match) == "empty_map"
    assert match.rejections == {} and match.candidate_indices == ()


def test_checks_read_as_the_tuple_of_them() -> None:
    wall_map = WallMap((WallVector((0.0, 1.0), (2.0, 1.0)), WallVector((2.0, 2.0), (0.0, 2.0))))
    detected = WallVector((0.5, 1.01), (1.5, 1.01))
    match = match_wall(detected, wall_map)
    checks = tuple(match.checks)
    assert match.checks == checks and checks == match.checks
    assert match.checks == match_wall(detected, wall_map).checks
    assert match == match_wall(detected, list(wall_map))
    assert hash(match.checks) == hash(checks) and repr(match.checks) == repr(checks)
    assert match.checks[1] is checks[1] and match.checks[:1] == checks[:1]
    assert match.checks != list(checks)
    assert pickle.loads(pickle.dumps(match)) == match
    assert list(wall_map) == list(wall_map.walls) and wall_map[1] is wall_map.walls[1]
    assert wall_map == WallMap(tuple(wall_map)) and pickle.loads(pickle.dumps(wall_map)) == wall_map
    assert not wall_map.table.flags.writeable
