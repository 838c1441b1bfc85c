"""The APCS fast paths give exactly the numbers of the reference functions they stand for."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization.apcs import (
    AMBIGUOUS,
    DEFAULT_PARAMETERS,
    GROUP_OK,
    GROUP_TOO_FEW_POINTS,
    GROUP_TOO_MUCH_VARIANCE,
    MATCHED,
    NO_MATCH,
    DetectedWall,
    EstimatedReflectionPoints,
    WallVector,
    check_wall,
    correct_with_checked_wall,
    correct_with_detected_wall,
    estimated_reflection_points,
    fit_wall_group,
    match_wall,
    validated_covariance,
)
from sonar_gym.localization.apcs_online import APCSTracker, WallStream
from sonar_gym.pose import Pose
from sonar_gym.localization.apcs_walls import fit_group_points, newest_reflection_points
from tests.localization.side_readings import wobbly_side_readings


def _readings(seed: int, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wobbly side readings, a tenth of their directions turned by 7 pi (facing away)."""
    rng = np.random.default_rng(seed)
    positions, directions, ranges = wobbly_side_readings(rng, count, heading_std_rad=0.02)
    return positions, directions + 7.0 * np.pi * (rng.random(count) < 0.1), ranges


def test_newest_reflection_points_are_those_of_estimated_reflection_points() -> None:
    for seed in range(20):
        for count in (0, 1, 2, 3, 40):
            positions, directions, ranges = _readings(seed, count)
            reference = estimated_reflection_points(
                positions, directions, ranges, valid_range_m=DEFAULT_PARAMETERS.sensing_range_m
            )
            points, phis, readings = newest_reflection_points(
                positions, directions, ranges, DEFAULT_PARAMETERS.sensing_range_m
            )
            np.testing.assert_array_equal(points, reference.points)
            np.testing.assert_array_equal(phis, reference.reflection_directions_rad)
            np.testing.assert_array_equal(readings, reference.reading_indices)
            assert count < 40 or len(reference) > 5  # the scene does give ERPs


def test_a_stream_closes_its_groups_with_the_verdicts_of_fit_wall_group() -> None:
    rng = np.random.default_rng(3)
    steps = np.where(rng.random(400) < 0.08, 0.5, 0.03)  # a jump now and then
    along = np.cumsum(steps)
    points = np.column_stack([along, 1.0 + rng.normal(0.0, 0.03 * rng.random(400), 400)])
    phis = np.pi / 2.0 + rng.normal(0.0, 0.05, 400) + 2.0 * np.pi * (rng.random(400) < 0.2)
    stream = WallStream("left")
    closed = []
    for point, phi in zip(points, phis, strict=True):
        closed.extend(stream.accept((point[0], 0.0), 0.0, 1.0, (point.tolist(), float(phi))))
    closed.extend(stream.flush())
    verdicts = {group.fit.status for group in closed}
    assert {GROUP_OK, GROUP_TOO_FEW_POINTS, GROUP_TOO_MUCH_VARIANCE} <= verdicts
    first = 0
    for group in closed:
        count = len(group.points)
        np.testing.assert_array_equal(group.points, points[first : first + count])
        reference = fit_wall_group(
            EstimatedReflectionPoints.from_points(
                points[first : first + count], phis[first : first + count]
            ),
            range(count),
        )
        assert group.fit == reference
        first += count
    assert first == len(points)


def test_correcting_with_a_checked_wall_is_correcting_with_the_detected_wall() -> None:
    wall_map = (
        WallVector((-1.0, 1.0), (10.0, 1.0), name="left"),
        WallVector((10.0, -1.0), (-1.0, -1.0), name="right"),
        WallVector((4.0, 0.9), (6.0, 0.9), name="board"),
    )
    covariance = np.array([[4e-4, 1e-5, 2e-6], [1e-5, 3e-4, -4e-6], [2e-6, -4e-6, 1e-4]])
    pose = Pose(2.0, 0.03, 0.01)
    detected = [
        DetectedWall((1.0, 1.01), (1.2, 1.012), (0, 1, 2, 3), 1e-6),  # the left wall
        DetectedWall((1.2, -0.99), (1.0, -0.99), (0, 1, 2, 3), 1e-6),  # the right wall
        DetectedWall((4.5, 0.95), (4.7, 0.95), (0, 1, 2, 3), 1e-6),  # left wall or board
        DetectedWall((1.0, 1.0), (1.2, 1.05), (0, 1, 2, 3), 1e-6),  # off in orientation
    ]
    statuses = set()
    for wall in detected:
        for method in ("paper", "linear"):
            reference = correct_with_detected_wall(
                pose, covariance, wall, wall_map, 1e-4, 3e-4, method=method
            )
            checked = correct_with_checked_wall(
                pose, validated_covariance(covariance), wall, wall_map, 1e-4, 3e-4, method=method
            )
            assert checked[0] == reference[0]
            assert (checked[1].status, checked[1].pose) == (reference[1].status, reference[1].pose)
            np.testing.assert_array_equal(checked[1].covariance, reference[1].covariance)
            statuses.add(reference[0].status)
    assert statuses == {MATCHED, AMBIGUOUS, NO_MATCH}


def test_a_tracker_refuses_a_covariance_that_is_not_positive_definite() -> None:
    with pytest.raises(ValueError, match="positive definite"):
        APCSTracker(
            (),
            Pose(0.0, 0.0, 0.0),
            np.diag([1e-4, -1e-4, 1e-5]),
            wheel_base_m=0.3,
            variance_per_m=1e-6,
            range_variance_m2=1e-4,
            bearing_variance_rad2=1e-4,
        )


def _map_around(rng: np.random.Generator, count: int) -> tuple[WallVector, ...]:
    """Walls of every orientation, a few of them along the detected walls of the tests."""
    walls = []
    for _ in range(count):
        start = rng.uniform(-3.0, 3.0, 2)
        end = start + rng.uniform(0.5, 4.0) * np.array(
            [math.cos(angle := rng.uniform(-np.pi, np.pi)), math.sin(angle)]
        )
        walls.append(WallVector(tuple(start.tolist()), tuple(end.tolist())))
    walls += [
        WallVector((-1.0, 1.0), (10.0, 1.0)),
        WallVector((0.0, 1.0), (2.0, 1.0)),  # starts at a detected wall's first end
        WallVector((1.2, 1.1), (1.0, 1.1)),  # against its direction
        WallVector((-1.0, 0.9), (1.2, 0.9)),  # ends at its last end: on the inclusion slack
    ]
    return tuple(walls)


def test_matching_checks_every_map_wall_as_check_wall_does() -> None:
    rng = np.random.default_rng(8)
    wall_map = _map_around(rng, 12)
    tolerance = DEFAULT_PARAMETERS.orientation_tolerance_rad
    detected = [
        # numpy floats, as a fit gives them
        *(
            DetectedWall(
                tuple(np.array([0.0, 1.0]) + rng.normal(0.0, 0.05, 2)),
                tuple(np.array([1.2, 1.0]) + rng.normal(0.0, 0.05, 2)),
                (0, 1, 2, 3),
                1e-6,
            )
            for _ in range(30)
        ),
        DetectedWall((0.0, 1.0), (1.2, 1.0), (0, 1, 2, 3), 0.0),  # on three map walls
        DetectedWall((0.0, 1.0), (1.2, 1.0 + 1.2 * math.tan(tolerance)), (0, 1, 2, 3), 0.0),
        DetectedWall((1.2, 1.0), (0.0, 1.0), (0, 1, 2, 3), 0.0),  # the other way round
        # past the ends of the wall along y = 0.9, inside and outside the inclusion's slack
        DetectedWall((-1.0 - 1e-12, 1.0), (1.2 + 1e-12, 1.0), (0, 1, 2, 3), 0.0),
        DetectedWall((-1.0 - 3e-12, 1.0), (1.2 + 3e-12, 1.0), (0, 1, 2, 3), 0.0),
    ]
    seen = set()
    for wall in detected:
        for vector in (wall, wall.vector):
            match = match_wall(vector, wall_map)
            expected = tuple(
                check_wall(wall.vector, map_wall, index) for index, map_wall in enumerate(wall_map)
            )
            assert match.checks == expected
            for check, reference in zip(match.checks, expected, strict=True):
                assert [type(value) for value in vars(check).values()] == [
                    type(value) for value in vars(reference).values()
                ]
            seen.add(match.status)
            seen.update(check.reason for check in match.checks)
            seen.update(
                ("slack", check.inclusion_ok)
                for check in match.checks
                if 1.0 < max(check.start_parameter, check.end_parameter) < 1.0 + 1e-11
            )
    assert seen >= {MATCHED, AMBIGUOUS, NO_MATCH, "orientation", "inclusion", "distance", None}
    assert seen >= {("slack", True), ("slack", False)}


def test_a_detected_wall_keeps_its_vector() -> None:
    wall = DetectedWall((np.float64(0.5), 1.0), (1.5, np.float64(1.25)), (0, 1, 2, 3), 1e-6)
    assert wall.vector == WallVector(wall.start, wall.end, name="detected")
    assert wall.vector is wall.vector
    assert (wall.length, wall.direction_angle) == (wall.vector.length, wall.vector.direction_angle)


def _reference_wall_ends(
    members: np.ndarray, directions: np.ndarray
) -> tuple[np.ndarray, np.ndarray, float]:
    """``T_s``, ``T_e`` and the residual variance as ``fit_group_points`` of commit 074d50b
    computed them (members and directions of a flat group)."""
    centroid = members.mean(axis=0)
    centred = members - centroid
    scatter = centred.T @ centred / len(members)
    eigenvalues, eigenvectors = np.linalg.eigh(scatter)
    along = eigenvectors[:, 1]
    occupied_side = np.array([-along[1], along[0]])
    towards_wall = np.array([np.cos(directions).sum(), np.sin(directions).sum()])
    if float(occupied_side @ towards_wall) < 0.0:
        along = -along
    positions_along = centred @ along
    start = centroid + float(positions_along.min()) * along
    end = centroid + float(positions_along.max()) * along
    return start, end, float(max(eigenvalues[0], 0.0))


def test_a_group_is_fitted_as_before() -> None:
    rng = np.random.default_rng(11)
    for _ in range(400):
        count = int(rng.integers(DEFAULT_PARAMETERS.min_group_size, 9))
        angle = rng.uniform(-np.pi, np.pi)
        offset = rng.uniform(-1e3, 1e3, 2) * rng.choice([0.0, 1e-3, 1.0])
        along = np.arange(count) * rng.choice([0.03, 1e-7, 3.0]) + rng.normal(0.0, 0.01, count)
        across = rng.normal(0.0, 0.005, count)
        members = offset + np.column_stack(
            [along * math.cos(angle) - across * math.sin(angle), along * math.sin(angle)]
        )
        directions = np.full(count, angle + rng.choice([-1.0, 1.0]) * np.pi / 2.0)
        fit = fit_group_points(members, directions, tuple(range(count)))
        if fit.wall is None:
            continue
        start, end, variance = _reference_wall_ends(members, directions)
        # plain floats: every map wall's check reads them, several times slower as numpy scalars
        assert {type(value) for value in (*fit.wall.start, *fit.wall.end)} == {float}
        assert np.array(fit.wall.start).tobytes() == start.tobytes()
        assert np.array(fit.wall.end).tobytes() == end.tobytes()
        assert fit.residual_variance_m2 == variance
