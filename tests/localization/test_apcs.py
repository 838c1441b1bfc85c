"""Tests of APCS (Yamamoto, Maeyama, Ohya & Yuta): ERPs, wall detection, matching, correction.

Every expected value is closed-form geometry of the synthetic scene or a number printed in the
paper (section 6), never an output of the code under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.localization.apcs import (
    AMBIGUOUS,
    GROUP_TOO_FEW_POINTS,
    GROUP_TOO_MUCH_VARIANCE,
    GROUP_ZERO_LENGTH,
    HEADING_DEGENERATE,
    MATCHED,
    NO_MATCH,
    PRIOR_ON_WALL_LINE,
    REJECT_DISTANCE,
    REJECT_INCLUSION,
    REJECT_ORIENTATION,
    APCSParameters,
    CorrectionResult,
    DetectedWall,
    EstimatedReflectionPoints,
    WallVector,
    correct_pose,
    correct_with_detected_wall,
    detect_walls,
    detect_walls_from_readings,
    estimated_reflection_points,
    fit_wall_group,
    fit_wall_groups,
    information_matrix,
    information_vector,
    match_wall,
    observe_wall,
)
from sonar_gym.localization.result import Localization
from sonar_gym.pose import Pose, angle_difference

TOL = 1e-9


# ---------------------------------------------------------------------------------------------
# Synthetic scenes
# ---------------------------------------------------------------------------------------------


def rotation(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def foot_of_perpendicular(
    points: np.ndarray, line_point: np.ndarray, line_angle: float
) -> np.ndarray:
    """Feet of the perpendiculars from ``points`` to the line through ``line_point``."""
    u = np.array([math.cos(line_angle), math.sin(line_angle)])
    return line_point + np.outer((points - line_point) @ u, u)


def specular_side_ranges(
    positions: np.ndarray, walls: list[WallVector], beam_axis: float = math.pi / 2
) -> np.ndarray:
    """Range of a side sonar to flat walls: the shortest perpendicular distance to a wall whose
    foot lies on the segment, whose free side faces the sensor and whose normal is within 15 deg
    of the beam axis (radians in {W}); NaN when there is none."""
    ranges = np.full(len(positions), np.nan)
    for wall in walls:
        inward = math.atan2(-wall.normal[1], -wall.normal[0])
        if abs(angle_difference(inward, beam_axis)) > math.radians(15.0):
            continue
        a = wall.start_point
        u = wall.unit_direction
        n = wall.normal
        t = (positions - a) @ u
        distance = (positions - a) @ n
        seen = (t >= 0.0) & (t <= wall.length) & (distance > 0.0)
        closer = seen & ~(ranges <= distance)
        ranges = np.where(closer, distance, ranges)
    return ranges


def straight_drive(
    start: tuple[float, float], heading: float, count: int, step: float = 0.03
) -> np.ndarray:
    s = np.arange(count) * step
    return np.array(start) + np.outer(s, [math.cos(heading), math.sin(heading)])


def literal_eq4_erps(positions: np.ndarray, ranges: np.ndarray) -> np.ndarray:
    """R2 of each pair with eq. (4) exactly as printed: sqrt((y2 - x2)^2 + (x2 - x1)^2)."""
    erps = []
    for (x1, y1), (x2, y2), r1, r2 in zip(
        positions[:-1], positions[1:], ranges[:-1], ranges[1:], strict=True
    ):
        length = math.sqrt((y2 - y1) ** 2 + (x2 - x1) ** 2)
        alpha = math.atan2((x2 - x1) / length, (y2 - y1) / length)
        printed_root = math.sqrt((y2 - x2) ** 2 + (x2 - x1) ** 2)
        phi = math.pi / 2 - alpha + math.acos(-(r2 - r1) / printed_root)
        erps.append([x2 + r2 * math.cos(phi), y2 + r2 * math.sin(phi)])
    return np.array(erps)


# ---------------------------------------------------------------------------------------------
# Map vectors and parameters
# ---------------------------------------------------------------------------------------------


def test_wall_vector_geometry_has_the_free_side_on_the_right() -> None:
    wall = WallVector((1.0, 2.0), (4.0, 6.0), name="a")
    assert wall.length == pytest.approx(5.0, abs=TOL)
    assert wall.direction_angle == pytest.approx(math.atan2(4.0, 3.0), abs=TOL)
    np.testing.assert_allclose(wall.normal, [0.8, -0.6], atol=TOL)
    # A point to the right of start -> end is on the free side, at a positive distance.
    assert wall.signed_distance((1.0 + 0.8, 2.0 - 0.6)) == pytest.approx(1.0, abs=TOL)
    assert wall.signed_distance((1.0 - 0.8, 2.0 + 0.6)) == pytest.approx(-1.0, abs=TOL)


def test_zero_length_wall_vector_is_a_bad_argument() -> None:
    with pytest.raises(ValueError, match="start"):
        WallVector((1.0, 1.0), (1.0, 1.0))
    with pytest.raises(ValueError, match="WallVector.end"):
        WallVector((0.0, 0.0), (np.nan, 1.0))


def test_default_parameters_are_the_thresholds_of_section_6_in_si() -> None:
    params = APCSParameters()
    assert params.grouping_distance_squared_m2 == pytest.approx(100 * 0.01**2)  # 100 cm^2
    assert params.min_group_size == 4  # groups of less than 4 points ignored
    assert params.max_group_size == 8
    assert params.orientation_tolerance_rad == pytest.approx(0.5 * math.pi / 180)
    assert params.endpoint_distance_squared_m2 == pytest.approx(200 * 0.01**2)  # 200 cm^2
    assert params.sampling_interval_m == pytest.approx(0.03)
    assert params.robot_speed_mps == pytest.approx(0.30)
    assert params.sampling_period_s == pytest.approx(0.1)
    assert params.sensing_range_m == pytest.approx((0.30, 5.00))  # section 5


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("grouping_distance_squared_m2", -1.0),
        ("variance_threshold_m2", 0.0),
        ("orientation_tolerance_rad", math.nan),
        ("endpoint_distance_squared_m2", -0.02),
        ("min_group_size", 1),
        ("max_group_size", 2.5),
    ],
)
def test_bad_parameters_raise_naming_the_field(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        APCSParameters(**{field: value})


def test_max_group_size_below_min_group_size_is_rejected() -> None:
    with pytest.raises(ValueError, match="max_group_size"):
        APCSParameters(min_group_size=5, max_group_size=4)


# ---------------------------------------------------------------------------------------------
# ERPs, eqs (1)-(6)
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("scene_angle", [0.0, 0.61, -2.3, math.pi / 2])
@pytest.mark.parametrize("approach_deg", [0.0, 4.0, -9.0])
def test_erps_lie_exactly_on_the_wall(scene_angle: float, approach_deg: float) -> None:
    # Wall y = 1.2 in a scene frame, robot driving from the origin at `approach_deg` to it,
    # the whole scene rotated by `scene_angle` into {W}.
    heading_scene = math.radians(approach_deg)
    positions_scene = straight_drive((0.0, 0.0), heading_scene, 30)
    ranges = 1.2 - positions_scene[:, 1]
    rot = rotation(scene_angle)
    positions = positions_scene @ rot.T
    sensor_directions = scene_angle + heading_scene + math.pi / 2
    erps = estimated_reflection_points(positions, sensor_directions, ranges)

    feet = np.column_stack([positions_scene[:, 0], np.full(30, 1.2)]) @ rot.T
    assert len(erps) == 29
    np.testing.assert_array_equal(erps.reading_indices, np.arange(1, 30))
    np.testing.assert_allclose(erps.points, feet[1:], atol=TOL)
    expected_phi = scene_angle + math.pi / 2
    phi_errors = [angle_difference(p, expected_phi) for p in erps.reflection_directions_rad]
    assert np.max(np.abs(phi_errors)) < TOL


def test_erps_from_a_right_side_sensor_lie_on_the_wall() -> None:
    positions = straight_drive((0.0, 0.0), math.radians(-6.0), 20)
    ranges = positions[:, 1] + 0.9  # wall y = -0.9 on the right
    erps = estimated_reflection_points(positions, math.radians(-6.0) - math.pi / 2, ranges)
    np.testing.assert_allclose(erps.points[:, 1], -0.9, atol=TOL)
    np.testing.assert_allclose(erps.points[:, 0], positions[1:, 0], atol=TOL)


def test_both_erps_of_each_pair_are_the_feet_of_both_readings() -> None:
    positions = straight_drive((0.0, 0.0), math.radians(7.0), 6)
    ranges = 1.0 - positions[:, 1]
    erps = estimated_reflection_points(
        positions, math.radians(97.0), ranges, points_per_pair="both"
    )
    np.testing.assert_array_equal(erps.reading_indices, [0, 1, 1, 2, 2, 3, 3, 4, 4, 5])
    np.testing.assert_array_equal(erps.pair_indices, [0, 0, 1, 1, 2, 2, 3, 3, 4, 4])
    np.testing.assert_allclose(erps.points[:, 1], 1.0, atol=TOL)
    np.testing.assert_allclose(erps.points[:, 0], positions[erps.reading_indices, 0], atol=TOL)


def test_literal_eq4_misplaces_the_erps_that_the_corrected_eq4_puts_on_the_wall() -> None:
    heading = math.radians(8.0)
    positions = straight_drive((0.4, 0.0), heading, 12)
    ranges = 1.5 - positions[:, 1]
    literal = literal_eq4_erps(positions, ranges)
    corrected = estimated_reflection_points(positions, heading + math.pi / 2, ranges).points
    np.testing.assert_allclose(corrected[:, 1], 1.5, atol=TOL)
    assert np.max(np.abs(literal[:, 1] - 1.5)) > 1e-3


@settings(max_examples=60, deadline=None)
@given(
    wall_angle=st.floats(-math.pi, math.pi),
    offsets=st.lists(st.floats(0.3, 3.0), min_size=3, max_size=12),
    steps=st.lists(st.floats(0.02, 0.2), min_size=11, max_size=11),
)
def test_erps_on_a_curved_trajectory_lie_on_the_wall(
    wall_angle: float, offsets: list[float], steps: list[float]
) -> None:
    # Section 4.2.2: the trajectory need not be straight. The robot wanders at distances
    # `offsets` from the wall; each move spans along the wall at least as much as across it.
    count = len(offsets)
    across = np.array(offsets)
    along = np.zeros(count)
    for i in range(1, count):
        least_step = abs(across[i] - across[i - 1]) / math.tan(math.radians(55))
        along[i] = along[i - 1] + max(steps[i - 1], least_step)
    u = np.array([math.cos(wall_angle), math.sin(wall_angle)])
    inward = np.array([-u[1], u[0]])  # from the robot towards the wall
    origin = np.array([0.3, -0.7])
    wall_point = origin + 5.0 * inward
    positions = origin + np.outer(along, u) + np.outer(5.0 - across, inward)
    erps = estimated_reflection_points(positions, math.atan2(inward[1], inward[0]), across)
    assert len(erps) == count - 1
    np.testing.assert_allclose(
        erps.points, foot_of_perpendicular(positions[1:], wall_point, wall_angle), atol=1e-8
    )


def test_nan_ranges_give_no_erp_and_never_nan() -> None:
    positions = straight_drive((0.0, 0.0), 0.0, 10)
    ranges = np.full(10, 1.0)
    ranges[[3, 7]] = np.nan
    ranges[8] = np.inf
    erps = estimated_reflection_points(positions, math.pi / 2, ranges)
    # Pairs touching readings 3, 7 or 8 are lost: the pairs left are (0,1) (1,2) (4,5) (5,6).
    np.testing.assert_array_equal(erps.pair_indices, [0, 1, 4, 5])
    assert np.all(np.isfinite(erps.points))
    all_dropouts = estimated_reflection_points(positions, math.pi / 2, np.full(10, np.nan))
    assert all_dropouts.points.shape == (0, 2)
    assert detect_walls(all_dropouts) == []


@settings(max_examples=60, deadline=None)
@given(
    ranges=st.lists(
        st.one_of(st.floats(0.0, 6.0), st.just(math.nan), st.just(math.inf)),
        min_size=0,
        max_size=40,
    ),
    step=st.floats(0.0, 0.1),
    heading=st.floats(-math.pi, math.pi),
)
def test_any_dropout_pattern_gives_finite_erps_and_walls(
    ranges: list[float], step: float, heading: float
) -> None:
    positions = straight_drive((0.2, -0.1), heading, len(ranges), step)
    erps, walls = detect_walls_from_readings(positions, heading + math.pi / 2, np.array(ranges))
    assert np.all(np.isfinite(erps.points)) and np.all(np.isfinite(erps.reflection_directions_rad))
    assert erps.points.shape == (len(erps), 2)
    for wall in walls:
        assert np.all(np.isfinite(wall.start + wall.end)) and wall.length > 0.0


def test_pairs_no_flat_wall_can_explain_give_no_erp() -> None:
    positions = straight_drive((0.0, 0.0), 0.0, 4)
    # A 30 cm range step over a 3 cm move, and a pair taken without moving.
    ranges = np.array([1.0, 0.7, 0.7, 0.7])
    positions[3] = positions[2]
    erps = estimated_reflection_points(positions, math.pi / 2, ranges)
    np.testing.assert_array_equal(erps.pair_indices, [1])


def test_readings_outside_the_sensing_range_are_dropouts() -> None:
    positions = straight_drive((0.0, 0.0), 0.0, 12)
    ranges = np.full(12, 0.2)  # closer than the 30 cm of section 5
    erps, walls = detect_walls_from_readings(positions, math.pi / 2, ranges)
    assert len(erps) == 0 and walls == []
    erps, walls = detect_walls_from_readings(positions, math.pi / 2, ranges + 0.5)
    assert len(erps) == 11 and len(walls) == 1


@pytest.mark.parametrize(
    ("positions", "directions", "ranges", "name"),
    [
        (np.zeros((5, 3)), 0.0, np.ones(5), "sensor_positions"),
        (np.full((5, 2), np.nan), 0.0, np.ones(5), "sensor_positions"),
        (np.zeros((5, 2)), 0.0, np.ones(4), "ranges_m"),
        (np.zeros((5, 2)), 0.0, -np.ones(5), "ranges_m"),
        (np.zeros((5, 2)), np.zeros(3), np.ones(5), "sensor_directions_rad"),
        (np.zeros((5, 2)), np.nan, np.ones(5), "sensor_directions_rad"),
    ],
)
def test_bad_reading_arguments_raise_naming_the_argument(
    positions: np.ndarray, directions: object, ranges: np.ndarray, name: str
) -> None:
    with pytest.raises(ValueError, match=name):
        estimated_reflection_points(positions, directions, ranges)


# ---------------------------------------------------------------------------------------------
# Wall detection, section 4.2.2-4.2.3
# ---------------------------------------------------------------------------------------------


def test_detect_walls_returns_the_wall_with_the_feet_of_the_end_erps_as_end_points() -> None:
    heading = math.radians(3.0)
    positions = straight_drive((0.0, 0.0), heading, 8)  # 7 ERPs: one group
    ranges = 1.1 - positions[:, 1]
    walls = detect_walls(estimated_reflection_points(positions, heading + math.pi / 2, ranges))
    assert len(walls) == 1
    wall = walls[0]
    np.testing.assert_allclose(wall.start, (positions[1, 0], 1.1), atol=TOL)
    np.testing.assert_allclose(wall.end, (positions[7, 0], 1.1), atol=TOL)
    assert wall.direction_angle == pytest.approx(0.0, abs=TOL)  # occupied (y > 1.1) on the left
    assert wall.residual_variance_m2 == pytest.approx(0.0, abs=1e-18)
    assert wall.point_count == 7


def test_end_points_are_the_projections_of_the_extreme_erps_on_the_fitted_line() -> None:
    # Fig. 6: off-line end ERPs R_s, R_e project perpendicularly on the least-squares line.
    points = np.array([[0.0, 1.0], [0.05, 1.0], [0.10, 1.0], [0.15, 1.0], [0.20, 1.0]])
    points[0, 1] += 0.004
    points[4, 1] -= 0.004
    walls = detect_walls(EstimatedReflectionPoints.from_points(points, math.pi / 2))
    assert len(walls) == 1
    start, end = np.array(walls[0].start), np.array(walls[0].end)
    centroid = points.mean(axis=0)
    u = (end - start) / np.linalg.norm(end - start)
    # T_s, T_e on the line through the centroid, and R_s - T_s perpendicular to it.
    for erp, foot in ((points[0], start), (points[4], end)):
        assert abs((foot - centroid) @ np.array([-u[1], u[0]])) < TOL
        assert abs((erp - foot) @ u) < TOL
    # The least-squares line is the principal axis of the ERPs (orthogonal regression).
    scatter_xy = (points - centroid)[:, 0] @ (points - centroid)[:, 1]
    scatter_xx = np.sum((points - centroid)[:, 0] ** 2)
    scatter_yy = np.sum((points - centroid)[:, 1] ** 2)
    expected_angle = 0.5 * math.atan2(2 * scatter_xy, scatter_xx - scatter_yy)
    assert walls[0].direction_angle == pytest.approx(expected_angle, abs=TOL)


def test_a_right_side_sensor_yields_a_vector_with_the_wall_on_its_left() -> None:
    positions = straight_drive((0.0, 0.0), 0.0, 8)
    erps = estimated_reflection_points(positions, -math.pi / 2, np.full(8, 0.8))
    (wall,) = detect_walls(erps)
    assert abs(angle_difference(wall.direction_angle, math.pi)) < TOL
    np.testing.assert_allclose(wall.start, (positions[7, 0], -0.8), atol=TOL)
    np.testing.assert_allclose(wall.end, (positions[1, 0], -0.8), atol=TOL)


def test_noise_free_grouping_splits_two_separate_walls() -> None:
    walls_map = [
        WallVector((-0.015, 1.0), (0.315, 1.0), "near"),
        WallVector((0.435, 1.2), (0.795, 1.2), "far"),
    ]
    positions = straight_drive((0.0, 0.0), 0.0, 27)  # x = 0 .. 0.78
    ranges = specular_side_ranges(positions, walls_map)
    walls = detect_walls(estimated_reflection_points(positions, math.pi / 2, ranges))
    assert len(walls) == 2
    np.testing.assert_allclose(walls[0].start, (0.03, 1.0), atol=TOL)
    np.testing.assert_allclose(walls[0].end, (0.24, 1.0), atol=TOL)  # 8 ERPs, group closed
    np.testing.assert_allclose(walls[1].start, (0.48, 1.2), atol=TOL)
    np.testing.assert_allclose(walls[1].end, (0.69, 1.2), atol=TOL)
    # The near wall's last ERPs (x = 0.27, 0.30) form a group of 2 and are dropped.


def test_grouping_threshold_is_100_cm2_between_consecutive_erps() -> None:
    def walls_for_gap(gap: float) -> int:
        xs = np.concatenate([np.arange(5) * 0.03, 0.12 + gap + np.arange(5) * 0.03])
        points = np.column_stack([xs, np.ones(10)])
        return len(detect_walls(EstimatedReflectionPoints.from_points(points, math.pi / 2)))

    assert walls_for_gap(0.09) == 1  # 81 cm^2: continuous, one group of 10 -> 8 + 2
    assert walls_for_gap(0.11) == 2  # 121 cm^2: a discontinuity


def test_a_long_wall_is_divided_into_groups_of_at_most_eight_erps() -> None:
    # Section 6: with at most 8 points per group "a long flat wall is divided to 5 detected
    # wall vectors"; 40 ERPs at the 3 cm sampling are 5 groups of 8.
    positions = straight_drive((0.0, 0.0), 0.0, 41)
    erps = estimated_reflection_points(positions, math.pi / 2, np.full(41, 1.0))
    walls = detect_walls(erps)
    assert [w.point_count for w in walls] == [8, 8, 8, 8, 8]
    for k, wall in enumerate(walls):
        np.testing.assert_allclose(wall.start, (0.03 * (8 * k + 1), 1.0), atol=TOL)
        np.testing.assert_allclose(wall.end, (0.03 * (8 * k + 8), 1.0), atol=TOL)


def test_too_small_groups_are_dropped() -> None:
    points = np.column_stack([np.arange(3) * 0.03, np.ones(3)])
    erps = EstimatedReflectionPoints.from_points(points, math.pi / 2)
    assert detect_walls(erps) == []
    assert [fit.status for fit in fit_wall_groups(erps)] == [GROUP_TOO_FEW_POINTS]
    four = EstimatedReflectionPoints.from_points(
        np.column_stack([np.arange(4) * 0.03, np.ones(4)]), math.pi / 2
    )
    assert len(detect_walls(four)) == 1


def test_a_zero_length_group_never_yields_a_wall() -> None:
    erps = EstimatedReflectionPoints.from_points(np.tile([[0.5, 1.0]], (6, 1)), math.pi / 2)
    assert detect_walls(erps) == []
    assert fit_wall_group(erps, range(6)).status == GROUP_ZERO_LENGTH


def test_variance_test_rejects_scattered_erps() -> None:
    xs = np.arange(8) * 0.03
    zigzag = np.array([1.0, -1.0, -1.0, 1.0, 1.0, -1.0, -1.0, 1.0])  # uncorrelated with x
    scattered = np.column_stack([xs, 1.0 + 0.03 * zigzag])  # residual variance ~ (3 cm)^2
    fit = fit_wall_group(EstimatedReflectionPoints.from_points(scattered, math.pi / 2), range(8))
    assert fit.status == GROUP_TOO_MUCH_VARIANCE and fit.wall is None
    tight = np.column_stack([xs, 1.0 + 0.005 * zigzag])  # (5 mm)^2
    fit = fit_wall_group(EstimatedReflectionPoints.from_points(tight, math.pi / 2), range(8))
    assert fit.wall is not None
    assert fit.residual_variance_m2 == pytest.approx(0.005**2, rel=1e-9)


def test_plain_erp_arrays_are_oriented_in_the_order_measured() -> None:
    points = np.column_stack([1.0 - np.arange(5) * 0.03, np.full(5, 2.0)])
    (wall,) = detect_walls(points)
    assert abs(angle_difference(wall.direction_angle, math.pi)) < TOL
    with pytest.raises(ValueError, match="erps"):
        detect_walls(np.array([[0.0, np.nan]]))


def test_detected_wall_refuses_zero_length() -> None:
    with pytest.raises(ValueError, match="start"):
        DetectedWall((0.1, 0.2), (0.1, 0.2), (0, 1, 2, 3), 0.0)


# ---------------------------------------------------------------------------------------------
# Matching, section 4.3
# ---------------------------------------------------------------------------------------------

DETECTED = WallVector((1.0, 1.0), (1.21, 1.0), "detected")


def test_a_single_matching_map_wall_is_matched() -> None:
    wall_map = [
        WallVector((0.0, 1.02), (3.0, 1.02), "north"),
        WallVector((3.0, 0.0), (0.0, 0.0), "south"),
        WallVector((3.0, 1.0), (3.0, 0.0), "east"),
    ]
    result = match_wall(DETECTED, wall_map)
    assert result.status == MATCHED
    assert result.wall_index == 0 and result.wall is wall_map[0]
    assert result.checks[0].endpoint_distance_squared_m2 == pytest.approx(2 * 0.02**2, abs=TOL)
    assert result.checks[0].start_parameter == pytest.approx(1.0 / 3.0, abs=TOL)
    assert result.checks[0].end_parameter == pytest.approx(1.21 / 3.0, abs=TOL)
    assert result.rejections == {1: REJECT_ORIENTATION, 2: REJECT_ORIENTATION}


def test_each_rejected_wall_records_its_reason() -> None:
    wall_map = [
        WallVector((0.0, 1.0), (0.0, 3.0), "turned"),
        WallVector((1.5, 1.0), (3.0, 1.0), "beside"),
        WallVector((0.0, 1.3), (3.0, 1.3), "behind"),
    ]
    result = match_wall(DETECTED, wall_map)
    assert result.status == NO_MATCH and result.wall is None
    assert result.rejections == {0: REJECT_ORIENTATION, 1: REJECT_INCLUSION, 2: REJECT_DISTANCE}
    assert result.checks[2].endpoint_distance_squared_m2 == pytest.approx(2 * 0.3**2, abs=TOL)
    assert result.checks[1].failed_conditions == (REJECT_INCLUSION,)


def test_two_parallel_map_walls_within_the_thresholds_are_ambiguous() -> None:
    wall_map = [WallVector((0.0, 1.0), (3.0, 1.0), "a"), WallVector((0.0, 1.06), (3.0, 1.06), "b")]
    result = match_wall(DETECTED, wall_map)
    assert result.status == AMBIGUOUS and result.wall is None
    assert result.candidate_indices == (0, 1)
    _, correction = correct_with_detected_wall(
        Pose(1.1, 0.0, 0.0), np.eye(3) * 0.01, detected_wall_at(1.0), wall_map, 1e-4, 1e-4
    )
    assert correction.status == AMBIGUOUS and correction.pose is None


def detected_wall_at(y: float) -> DetectedWall:
    return DetectedWall((1.0, y), (1.21, y), tuple(range(8)), 0.0)


@pytest.mark.parametrize(
    ("angle_deg", "status"), [(0.4, MATCHED), (-0.45, MATCHED), (0.6, NO_MATCH)]
)
def test_orientation_tolerance_is_half_a_degree(angle_deg: float, status: str) -> None:
    tilt = math.radians(angle_deg)
    map_wall = WallVector((0.0, 1.0), (3.0 * math.cos(tilt), 1.0 + 3.0 * math.sin(tilt)))
    detected = WallVector((1.0, 1.0), (1.2, 1.0))
    assert match_wall(detected, [map_wall]).status == status


@pytest.mark.parametrize(("offset", "status"), [(0.09, MATCHED), (0.11, NO_MATCH)])
def test_endpoint_distance_threshold_is_200_cm2(offset: float, status: str) -> None:
    # d1 = d2 = offset: 2 * 81 cm^2 = 162 cm^2 passes, 2 * 121 cm^2 = 242 cm^2 fails.
    map_wall = WallVector((0.0, 1.0 + offset), (3.0, 1.0 + offset))
    assert match_wall(DETECTED, [map_wall]).status == status


def test_a_wall_facing_the_other_way_does_not_match() -> None:
    # The far face of a thin wall: same line, opposite orientation.
    result = match_wall(DETECTED, [WallVector((3.0, 1.0), (0.0, 1.0))])
    assert result.status == NO_MATCH and result.rejections == {0: REJECT_ORIENTATION}


def test_match_wall_rejects_bad_arguments() -> None:
    with pytest.raises(ValueError, match="detected"):
        match_wall((0.0, 1.0), [DETECTED])  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"wall_map\[0\]"):
        match_wall(DETECTED, [((0.0, 0.0), (1.0, 0.0))])  # type: ignore[list-item]


# ---------------------------------------------------------------------------------------------
# The experiment of section 6: a corridor wall and the unmapped wall 'B'
# ---------------------------------------------------------------------------------------------

CORRIDOR_MAP = [
    WallVector((-1.0, 1.0), (4.0, 1.0), "corridor_left"),
    WallVector((4.0, -1.0), (-1.0, -1.0), "corridor_right"),
]
WALL_B = WallVector((1.515, 0.7), (2.115, 0.7), "B")  # a board in front of the mapped wall


def corridor_readings() -> tuple[np.ndarray, np.ndarray]:
    positions = straight_drive((0.0, 0.0), 0.0, 101)  # 3 m at 3 cm, left sensor only
    return positions, specular_side_ranges(positions, CORRIDOR_MAP + [WALL_B])


def test_section_6_unmapped_wall_b_is_detected_and_rejected() -> None:
    positions, ranges = corridor_readings()
    _, walls = detect_walls_from_readings(positions, math.pi / 2, ranges)
    results = [match_wall(wall, CORRIDOR_MAP) for wall in walls]
    on_b = [abs(w.start[1] - 0.7) < TOL for w in walls]
    # 50 ERPs before B (6 groups of 8, 2 left over), 19 on B (8 + 8, 3 left over), 29 after
    # B (8 + 8 + 8 + 5): 6 + 2 + 4 wall vectors.
    assert len(walls) == 12 and sum(on_b) == 2
    for wall, result, is_b in zip(walls, results, on_b, strict=True):
        if is_b:
            assert result.status == NO_MATCH
            assert result.rejections == {0: REJECT_DISTANCE, 1: REJECT_ORIENTATION}
            assert result.checks[0].endpoint_distance_squared_m2 == pytest.approx(2 * 0.09, abs=TOL)
        else:
            assert abs(wall.start[1] - 1.0) < TOL
            assert result.status == MATCHED and result.wall_index == 0


def test_section_6_drift_is_corrected_across_the_wall_but_not_along_it() -> None:
    # Odometry drifted by a rigid error: 20 cm along the corridor, 4 cm across, 0.3 deg.
    positions_true, ranges = corridor_readings()
    drift_angle, drift_shift = math.radians(0.3), np.array([0.20, 0.04])
    positions_odometry = positions_true @ rotation(drift_angle).T + drift_shift
    heading_odometry = drift_angle
    erps, walls = detect_walls_from_readings(
        positions_odometry, heading_odometry + math.pi / 2, ranges
    )
    detected = walls[-1]  # the last wall vector, on the mapped wall past B
    last = erps.reading_indices[detected.erp_indices[-1]]
    truth = Pose(*positions_true[last], 0.0)
    estimate = Pose(*positions_odometry[last], heading_odometry)
    match, correction = correct_with_detected_wall(
        estimate,
        np.diag([0.05**2, 0.05**2, math.radians(2.0) ** 2]),
        detected,
        CORRIDOR_MAP,
        1e-8,
        1e-10,
        method="linear",
    )
    assert match.status == MATCHED and correction.ok and correction.pose is not None
    assert abs(correction.pose.y - truth.y) < 1e-3 * abs(estimate.y - truth.y)
    assert abs(correction.pose.theta - truth.theta) < 1e-3 * abs(estimate.theta - truth.theta)
    assert correction.pose.x == pytest.approx(estimate.x, abs=1e-6)  # along the wall: unchanged
    _, paper = correct_with_detected_wall(
        estimate,
        np.diag([0.05**2, 0.05**2, math.radians(2.0) ** 2]),
        detected,
        CORRIDOR_MAP,
        1e-8,
        1e-10,
    )
    assert paper.pose is not None
    assert abs(paper.pose.y - truth.y) < 0.05 * abs(estimate.y - truth.y)
    assert abs(paper.pose.theta - truth.theta) < 0.05 * abs(estimate.theta - truth.theta)


# ---------------------------------------------------------------------------------------------
# Correction, eqs (7)-(14)
# ---------------------------------------------------------------------------------------------

SLANTED_WALL = WallVector((0.0, 2.0), (2.0 * math.cos(0.5), 2.0 + 2.0 * math.sin(0.5)), "slanted")


def wall_frame(wall: WallVector) -> tuple[np.ndarray, np.ndarray]:
    return wall.unit_direction, wall.normal


def exact_observation(wall: WallVector, truth: Pose) -> tuple[float, float]:
    """r and xi from the true pose: distance to the line and bearing of its inward normal."""
    n = wall.normal
    r = float((truth.position - wall.start_point) @ n)
    return r, math.atan2(-n[1], -n[0]) - truth.theta


def isotropic_pose_error(
    wall: WallVector, truth: Pose, along: float, across: float, heading: float
) -> Pose:
    """``truth`` moved by ``along`` / ``across`` (metres, wall frame) and turned by ``heading``."""
    t, n = wall_frame(wall)
    x, y = truth.position + along * t + across * n
    return Pose(x, y, truth.theta + heading)


def test_observe_wall_gives_the_distance_and_the_bearing_of_the_foot() -> None:
    pose = Pose(0.5, -0.2, 0.3)
    # start -> end points -x: the occupied side is y < 1 and the robot (y = -0.2) is in it;
    # the foot of the perpendicular is still straight up.
    observation = observe_wall(WallVector((3.0, 1.0), (-2.0, 1.0)), pose)
    assert observation.r_m == pytest.approx(1.2, abs=TOL)
    assert observation.xi_rad == pytest.approx(math.pi / 2 - 0.3, abs=TOL)
    observation = observe_wall(WallVector((-2.0, 1.0), (3.0, 1.0)), pose)
    assert observation.r_m == pytest.approx(1.2, abs=TOL)
    assert observation.xi_rad == pytest.approx(math.pi / 2 - 0.3, abs=TOL)


@pytest.mark.parametrize("method", ["paper", "linear"])
def test_an_exact_measurement_removes_the_error_across_the_wall_and_in_heading(method: str) -> None:
    truth = Pose(0.8, 0.3, 0.7)
    prior = isotropic_pose_error(SLANTED_WALL, truth, along=0.15, across=0.06, heading=0.02)
    r, xi = exact_observation(SLANTED_WALL, truth)
    result = correct_pose(prior, np.eye(3), SLANTED_WALL, r, xi, 1e-10, 1e-10, method=method)
    assert isinstance(result, CorrectionResult) and isinstance(result, Localization)
    assert result.ok and result.pose is not None
    t, n = wall_frame(SLANTED_WALL)
    error = result.pose.position - truth.position
    # The paper's single step on the squared constraint (10) leaves (bias^2 / 2 d0); the
    # sine constraint (9) leaves tan(e) - e.
    limit = 0.05 if method == "paper" else 1e-6
    assert abs(error @ n) < limit * 0.06
    assert abs(angle_difference(result.pose.theta, truth.theta)) < limit * 0.02
    assert error @ t == pytest.approx(0.15, abs=1e-9)  # nothing is learnt along the wall


def test_linear_update_with_equal_variances_lands_halfway() -> None:
    truth = Pose(0.8, 0.3, 0.7)
    prior = isotropic_pose_error(SLANTED_WALL, truth, along=0.1, across=0.08, heading=-0.05)
    r, xi = exact_observation(SLANTED_WALL, truth)
    variance = 0.01
    result = correct_pose(
        prior, np.eye(3) * variance, SLANTED_WALL, r, xi, variance, variance, method="linear"
    )
    assert result.pose is not None
    t, n = wall_frame(SLANTED_WALL)
    error = result.pose.position - truth.position
    assert error @ n == pytest.approx(0.04, abs=TOL)
    assert error @ t == pytest.approx(0.1, abs=TOL)
    assert angle_difference(result.pose.theta, truth.theta) == pytest.approx(-0.025, abs=TOL)
    basis = np.zeros((3, 3))
    basis[:2, 0], basis[:2, 1], basis[2, 2] = t, n, 1.0
    np.testing.assert_allclose(
        basis.T @ result.covariance @ basis,
        np.diag([variance, variance / 2, variance / 2]),
        atol=1e-15,
    )


def test_paper_step_with_equal_variances_follows_its_closed_form_and_nears_halfway() -> None:
    # One step of eqs (11)-(14) from a prior at distance d0 from the wall, isotropic variance s,
    # measurement r with variance s: the information across the wall is d0^2 / (r^2 s), so
    # the step is d0 (r^2 - d0^2) / (2 (r^2 + d0^2)) and the variance s r^2 / (r^2 + d0^2);
    # in heading the step is tan(e) / 2 and the variance s / 2.
    truth = Pose(0.8, 0.3, 0.7)
    across, heading_error = 0.08, -0.05
    prior = isotropic_pose_error(SLANTED_WALL, truth, 0.1, across, heading_error)
    r, xi = exact_observation(SLANTED_WALL, truth)
    d0 = r + across
    s = 0.01
    result = correct_pose(prior, np.eye(3) * s, SLANTED_WALL, r, xi, s, s)
    assert result.pose is not None
    t, n = wall_frame(SLANTED_WALL)
    moved = result.pose.position - prior.position
    assert moved @ n == pytest.approx(d0 * (r * r - d0 * d0) / (2 * (r * r + d0 * d0)), abs=TOL)
    assert moved @ t == pytest.approx(0.0, abs=TOL)
    assert angle_difference(result.pose.theta, prior.theta) == pytest.approx(
        math.tan(-heading_error) / 2, abs=TOL
    )
    basis = np.zeros((3, 3))
    basis[:2, 0], basis[:2, 1], basis[2, 2] = t, n, 1.0
    np.testing.assert_allclose(
        basis.T @ result.covariance @ basis,
        np.diag([s, s * r * r / (r * r + d0 * d0), s / 2]),
        atol=1e-15,
    )
    # Within 4 % of halfway for an 8 cm bias at r = 1.88 m.
    assert moved @ n == pytest.approx(-across / 2, rel=0.04)


def test_information_across_the_wall_is_one_over_the_range_variance_on_the_measured_line() -> None:
    # Units check of eq. (14) as read: at a prior r from the line, J^T Sigma_su^-1 J is
    # n n^T / sigma_r (1/m^2), whatever the scale of (a, b, c).
    a, b, c = 3.0, -4.0, 10.0  # |(a, b)| = 5
    n = np.array([a, b]) / 5.0
    r = 1.7
    point = -c / 25.0 * np.array([a, b]) + r * n
    information = information_matrix(np.array([*point, 0.3]), (a, b, c), r, 0.04, 0.09)
    np.testing.assert_allclose(information[:2, :2], np.outer(n, n) / 0.04, atol=1e-12)
    assert information[2, 2] == pytest.approx(1 / 0.09)


def test_eqs_13_and_14_are_the_information_of_constraints_9_and_10() -> None:
    # Independent of the printed entries: differentiate eqs (9)-(10) numerically and form
    # J_P^T Sigma_su^-1 P_su and J_P^T Sigma_su^-1 J_P with Sigma_su = J_z diag(s_r, s_xi) J_z^T.
    a, b, c = 0.6, 0.8, -2.0
    prior = np.array([0.4, 0.5, 0.35])
    r, xi, s_r, s_xi = 1.3, 1.1, 2e-4, 3e-4

    def constraints(x: float, y: float, theta: float, r_: float, xi_: float) -> np.ndarray:
        return np.array(
            [
                (a * x + b * y + c) ** 2 - r_**2 * (a * a + b * b),  # eq. (10)
                b * math.cos(theta + xi_) - a * math.sin(theta + xi_),  # eq. (9)
            ]
        )

    h = 1e-6
    args = np.array([*prior, r, xi])
    jacobian = np.column_stack(
        [(constraints(*(args + h * e)) - constraints(*(args - h * e))) / (2 * h) for e in np.eye(5)]
    )
    j_pose, j_measurement = jacobian[:, :3], jacobian[:, 3:]
    weight = np.linalg.inv(j_measurement @ np.diag([s_r, s_xi]) @ j_measurement.T)
    expected_vector = j_pose.T @ weight @ -constraints(*args)
    expected_matrix = j_pose.T @ weight @ j_pose
    np.testing.assert_allclose(
        information_vector(prior, (a, b, c), r, xi, s_r, s_xi), expected_vector, rtol=1e-6
    )
    np.testing.assert_allclose(
        information_matrix(prior, (a, b, c), r, s_r, s_xi), expected_matrix, rtol=1e-6, atol=1e-6
    )


def test_paper_correction_is_eqs_11_and_12_with_eqs_13_and_14() -> None:
    truth = Pose(0.8, 0.3, 0.7)
    prior = isotropic_pose_error(SLANTED_WALL, truth, 0.12, -0.07, 0.04)
    covariance = np.array([[0.02, 0.005, 0.001], [0.005, 0.03, -0.002], [0.001, -0.002, 0.01]])
    r, xi = exact_observation(SLANTED_WALL, truth)
    s_r, s_xi = 4e-4, 1e-3
    result = correct_pose(prior, covariance, SLANTED_WALL, r, xi, s_r, s_xi)
    line = SLANTED_WALL.line_coefficients
    sigma_f = np.linalg.inv(
        np.linalg.inv(covariance) + information_matrix(prior.as_array(), line, r, s_r, s_xi)
    )  # eq. (12)
    pose_f = prior.as_array() + sigma_f @ information_vector(
        prior.as_array(), line, r, xi, s_r, s_xi
    )  # eq. (11)
    assert result.pose is not None
    np.testing.assert_allclose(result.pose.as_array(), pose_f, atol=1e-12)
    np.testing.assert_allclose(result.covariance, sigma_f, atol=1e-12)


covariances = st.builds(
    lambda entries, diagonal: (lambda m: m @ m.T + np.diag(diagonal))(
        np.array(entries).reshape(3, 3)
    ),
    st.lists(st.floats(-0.3, 0.3), min_size=9, max_size=9),
    st.lists(st.floats(1e-4, 0.1), min_size=3, max_size=3),
)


@settings(max_examples=80, deadline=None)
@given(
    covariance=covariances,
    along=st.floats(-0.5, 0.5),
    across=st.floats(-0.2, 0.2),
    heading=st.floats(-0.3, 0.3),
    sigma_r=st.floats(1e-6, 1e-1),
    sigma_xi=st.floats(1e-6, 1e-1),
    method=st.sampled_from(["paper", "linear"]),
)
def test_corrected_covariance_is_symmetric_psd_and_learns_nothing_along_the_wall(
    covariance: np.ndarray,
    along: float,
    across: float,
    heading: float,
    sigma_r: float,
    sigma_xi: float,
    method: str,
) -> None:
    truth = Pose(0.8, 0.3, 0.7)
    prior = isotropic_pose_error(SLANTED_WALL, truth, along, across, heading)
    r, xi = exact_observation(SLANTED_WALL, truth)
    result = correct_pose(prior, covariance, SLANTED_WALL, r, xi, sigma_r, sigma_xi, method=method)
    assert result.ok
    corrected = result.covariance
    scale = float(np.max(np.abs(covariance)))
    assert np.all(np.isfinite(corrected))
    np.testing.assert_array_equal(corrected, corrected.T)
    assert np.min(np.linalg.eigvalsh(corrected)) >= -1e-12 * scale
    assert np.min(np.linalg.eigvalsh(covariance - corrected)) >= -1e-9 * scale  # never grows
    t, n = wall_frame(SLANTED_WALL)
    along_wall = np.array([t[0], t[1], 0.0])
    information_before = along_wall @ np.linalg.solve(covariance, along_wall)
    information_after = along_wall @ np.linalg.solve(corrected, along_wall)
    assert information_after == pytest.approx(information_before, rel=1e-6)
    across_wall = np.array([n[0], n[1], 0.0])
    assert across_wall @ np.linalg.solve(corrected, across_wall) > across_wall @ np.linalg.solve(
        covariance, across_wall
    )


@pytest.mark.parametrize("method", ["paper", "linear"])
def test_with_an_isotropic_prior_the_along_wall_variance_is_unchanged(method: str) -> None:
    truth = Pose(0.8, 0.3, 0.7)
    prior = isotropic_pose_error(SLANTED_WALL, truth, 0.1, 0.03, 0.01)
    r, xi = exact_observation(SLANTED_WALL, truth)
    result = correct_pose(prior, np.eye(3) * 0.02, SLANTED_WALL, r, xi, 1e-4, 1e-5, method=method)
    t, n = wall_frame(SLANTED_WALL)
    assert t @ result.covariance[:2, :2] @ t == pytest.approx(0.02, rel=1e-12)
    assert n @ result.covariance[:2, :2] @ n < 2e-4
    assert result.covariance[2, 2] < 2e-5


def test_degenerate_geometry_gives_a_status_not_nan() -> None:
    wall = WallVector((0.0, 2.0), (3.0, 2.0))
    on_line = correct_pose(Pose(1.0, 2.0, 0.0), np.eye(3), wall, 1.0, 0.0, 1e-4, 1e-4)
    assert on_line.status == PRIOR_ON_WALL_LINE and on_line.pose is None
    np.testing.assert_array_equal(on_line.covariance, np.eye(3))
    # theta + xi along the wall: eq. (9) has no slope.
    sideways = correct_pose(Pose(1.0, 0.0, 0.0), np.eye(3), wall, 2.0, 0.0, 1e-4, 1e-4)
    assert sideways.status == HEADING_DEGENERATE and sideways.pose is None


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"covariance": np.eye(2)}, "covariance"),
        ({"covariance": np.diag([1.0, 1.0, -1.0])}, "covariance"),
        ({"covariance": np.eye(3) + np.diag([0.5, 0.0], k=1)}, "covariance"),  # asymmetric
        ({"r": 0.0}, "^r must"),
        ({"r": -1.0}, "^r must"),
        ({"xi": math.nan}, "^xi must"),
        ({"sigma_r": 0.0}, "sigma_r"),
        ({"sigma_xi": -1e-3}, "sigma_xi"),
        ({"sigma_r": math.inf}, "sigma_r"),
        ({"pose": (0.0, 0.0, 0.0)}, "pose"),
        ({"wall": ((0.0, 2.0), (1.0, 2.0))}, "wall"),
        ({"method": "ekf"}, "method"),
    ],
)
def test_bad_correction_arguments_raise_naming_the_argument(
    kwargs: dict[str, object], name: str
) -> None:
    arguments: dict[str, object] = {
        "pose": Pose(0.0, 0.0, 0.0),
        "covariance": np.eye(3) * 0.01,
        "wall": WallVector((-1.0, 1.0), (1.0, 1.0)),
        "r": 1.0,
        "xi": math.pi / 2,
        "sigma_r": 1e-4,
        "sigma_xi": 1e-4,
    }
    arguments.update(kwargs)
    with pytest.raises(ValueError, match=name):
        correct_pose(**arguments)  # type: ignore[arg-type]
