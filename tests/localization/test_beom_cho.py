"""Tests of the Beom & Cho (1995) method: RCDs, filters, eq. (7), eqs (8)-(15), calibration."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from sonar_gym.localization.beom_cho import (
    RCD,
    BeaconLocalization,
    BeomChoParameters,
    assign_large_and_small,
    extract_rcds,
    heading_from_large_beacon,
    localize_rcds,
    localize_scan,
    localize_scans,
    pair_distance_error,
    range_from_tof,
    solve_two_circles,
    speed_of_sound_from_reflector,
    symmetry_measure,
)
from sonar_gym.metrics import heading_error_rad, position_error_m
from sonar_gym.pose import Pose, angle_difference, wrap_angles
from sonar_gym.sonar.scan import Scan

SMALL_CENTER = (2.85, -0.6)
LARGE_CENTER = (0.3, -1.5)
SMALL_RADIUS = 0.0382 / 2
LARGE_RADIUS = 0.14 / 2
BEACON_DISTANCE = math.dist(SMALL_CENTER, LARGE_CENTER)

TABLE_II = (
    RCD.from_degrees(2.8542, -10.3, 22.0, 0.0027),
    RCD.from_degrees(1.4401, -78.3, 24.0, 0.0012),
    RCD.from_degrees(1.4612, -140.3, 18.0, 0.0074),
    RCD.from_degrees(1.8311, 158.7, 18.0, 0.0021),
)
FULL_TURN_1DEG = np.deg2rad(np.arange(-180.0, 180.0))


def _law_of_cosines(small_m: float, large_m: float, angle_deg: float) -> float:
    return math.sqrt(
        small_m**2 + large_m**2 - 2.0 * small_m * large_m * math.cos(math.radians(angle_deg))
    )


def _circle_intersections(
    center_a: tuple[float, float], radius_a: float, center_b: tuple[float, float], radius_b: float
) -> list[np.ndarray]:
    """Both intersections of two circles, built along and across the line of centres."""
    a, b = np.asarray(center_a), np.asarray(center_b)
    distance = float(np.linalg.norm(b - a))
    along_unit = (b - a) / distance
    across_unit = np.array([-along_unit[1], along_unit[0]])
    along = (radius_a**2 - radius_b**2 + distance**2) / (2.0 * distance)
    half_chord = math.sqrt(radius_a**2 - along**2)
    return [a + along * along_unit + s * half_chord * across_unit for s in (1.0, -1.0)]


# ------------------------------------------------------------------------------------------
# Table II (section V.B)
# ------------------------------------------------------------------------------------------


def test_paper_beacon_distance_is_2_704_m() -> None:
    assert pytest.approx(2.704, abs=5e-4) == BEACON_DISTANCE


def test_table_ii_symmetry_filter_removes_the_third_rcd() -> None:
    result = localize_rcds(TABLE_II, SMALL_CENTER, SMALL_RADIUS, LARGE_CENTER, LARGE_RADIUS)
    assert result.candidates == (TABLE_II[0], TABLE_II[1], TABLE_II[3])


def test_table_ii_first_rcd_is_small_beacon_and_second_is_large() -> None:
    result = localize_rcds(TABLE_II, SMALL_CENTER, SMALL_RADIUS, LARGE_CENTER, LARGE_RADIUS)
    assert result.ok
    assert result.small_rcd is TABLE_II[0]
    assert result.large_rcd is TABLE_II[1]


def test_table_ii_pair_errors_match_the_printed_ones_where_the_table_allows() -> None:
    first, second, _, fourth = TABLE_II
    # Pair (1, 4): RCD 1 (22 deg) is the large beacon, RCD 4 (18 deg) the small one.
    error_14 = pair_distance_error(first, fourth, SMALL_RADIUS, LARGE_RADIUS, BEACON_DISTANCE)
    expected_14 = abs(BEACON_DISTANCE - _law_of_cosines(1.8311 + 0.0191, 2.8542 + 0.07, 169.0))
    assert error_14 == pytest.approx(expected_14, abs=1e-9)
    assert error_14 == pytest.approx(2.049, abs=0.002)  # the paper prints 2.049 m
    # Pair (2, 4): RCD 2 (24 deg) large, RCD 4 small. The paper prints 0.257 m; the rounded
    # Table II gives 0.253 m.
    error_24 = pair_distance_error(second, fourth, SMALL_RADIUS, LARGE_RADIUS, BEACON_DISTANCE)
    expected_24 = abs(BEACON_DISTANCE - _law_of_cosines(1.8311 + 0.0191, 1.4401 + 0.07, 237.0))
    assert error_24 == pytest.approx(expected_24, abs=1e-9)
    assert error_24 == pytest.approx(0.257, abs=0.005)
    # Pair (1, 2): the paper prints 0.031 m; the rounded Table II with the beacon radii added
    # (as eq. (7) says) gives 0.005 m (0.032 m would need the radii left out). Either way it is
    # the smallest error and within the 0.04 m tolerance.
    error_12 = pair_distance_error(first, second, SMALL_RADIUS, LARGE_RADIUS, BEACON_DISTANCE)
    expected_12 = abs(BEACON_DISTANCE - _law_of_cosines(2.8542 + 0.0191, 1.4401 + 0.07, 68.0))
    assert error_12 == pytest.approx(expected_12, abs=1e-9)
    assert error_12 < min(error_14, error_24)
    assert error_12 < 0.031


def test_table_ii_pose_lies_on_both_beacon_circles() -> None:
    result = localize_rcds(TABLE_II, SMALL_CENTER, SMALL_RADIUS, LARGE_CENTER, LARGE_RADIUS)
    assert result.pose is not None
    small_distance = 2.8542 + SMALL_RADIUS
    large_distance = 1.4401 + LARGE_RADIUS
    position = (result.pose.x, result.pose.y)
    assert math.dist(position, SMALL_CENTER) == pytest.approx(small_distance, abs=1e-9)
    assert math.dist(position, LARGE_CENTER) == pytest.approx(large_distance, abs=1e-9)
    # Of the two intersections, the one on the side where the small beacon appears
    # counter-clockwise of the large one (delta-beta = +68 deg).
    expected = max(
        _circle_intersections(SMALL_CENTER, small_distance, LARGE_CENTER, large_distance),
        key=lambda p: angle_difference(
            math.atan2(SMALL_CENTER[1] - p[1], SMALL_CENTER[0] - p[0]),
            math.atan2(LARGE_CENTER[1] - p[1], LARGE_CENTER[0] - p[0]),
        ),
    )
    assert result.pose.x == pytest.approx(expected[0], abs=1e-9)
    assert result.pose.y == pytest.approx(expected[1], abs=1e-9)
    # eq. (10) does not depend on the slip of eq. (11): y_R is the -0.013 m worked from the table
    assert result.pose.y == pytest.approx(-0.013, abs=0.002)
    expected_heading = math.atan2(-1.5 - expected[1], 0.3 - expected[0]) - math.radians(-78.3)
    assert result.pose.theta == pytest.approx(expected_heading, abs=1e-9)
    # the robot stood at the origin with heading 0 (section V.B)
    assert position_error_m(result.pose, Pose(0.0, 0.0, 0.0)) < 0.04
    assert math.degrees(heading_error_rad(result.pose, Pose(0.0, 0.0, 0.0))) < 2.0


def test_eq_11_as_printed_is_a_slip_the_method_does_not_follow() -> None:
    """Eq. (11) prints x_R = y_R tan(psi) + L; eqs (8)-(9) give x_R = L - y_R tan(psi)."""
    (x_s, y_s), (x_l, y_l) = SMALL_CENTER, LARGE_CENTER
    d_s, d_l = 2.8542 + SMALL_RADIUS, 1.4401 + LARGE_RADIUS
    tan_psi = (y_l - y_s) / (x_l - x_s)
    offset = (d_s**2 - d_l**2 + x_l**2 - x_s**2 + y_l**2 - y_s**2) / (2 * (x_l - x_s))
    half_b = x_l * tan_psi - offset * tan_psi - y_l
    discriminant = half_b**2 - (tan_psi**2 + 1) * ((x_l - offset) ** 2 + y_l**2 - d_l**2)
    y_literal = (-half_b + math.sqrt(discriminant)) / (1 + tan_psi**2)
    x_literal = y_literal * tan_psi + offset
    heading_literal = math.atan2(y_l - y_literal, x_l - x_literal) - math.radians(-78.3)
    # The literal reading gives (0.028, -0.013) m and -1.34 deg ...
    assert (x_literal, y_literal) == pytest.approx((0.028, -0.013), abs=0.002)
    assert math.degrees(heading_literal) == pytest.approx(-1.34, abs=0.05)
    # ... a point 8.9 mm off the small beacon's circle, so no solution of eqs (8)-(9).
    assert abs(math.dist((x_literal, y_literal), SMALL_CENTER) - d_s) > 0.008
    result = localize_rcds(TABLE_II, SMALL_CENTER, SMALL_RADIUS, LARGE_CENTER, LARGE_RADIUS)
    assert result.pose is not None
    assert abs(result.pose.x - x_literal) > 0.005
    assert result.discriminant == pytest.approx(discriminant, rel=1e-12)


def test_parameters_override_the_symmetry_and_extent_filters() -> None:
    loose = BeomChoParameters(gamma_threshold_m=0.008)
    result = localize_rcds(
        TABLE_II, SMALL_CENTER, SMALL_RADIUS, LARGE_CENTER, LARGE_RADIUS, params=loose
    )
    assert TABLE_II[2] in result.candidates
    narrow = BeomChoParameters(eta_min_rad=math.radians(23.0))
    result = localize_rcds(
        TABLE_II, SMALL_CENTER, SMALL_RADIUS, LARGE_CENTER, LARGE_RADIUS, params=narrow
    )
    assert result.status == "no_pair"
    assert result.candidates == (TABLE_II[1],)


def test_no_candidates_and_no_pair_statuses_carry_no_pose() -> None:
    none_pass = localize_rcds([TABLE_II[2]], SMALL_CENTER, SMALL_RADIUS, LARGE_CENTER, LARGE_RADIUS)
    assert none_pass.status == "no_candidates" and none_pass.pose is None
    far_apart = localize_rcds(
        [TABLE_II[0], TABLE_II[3]], SMALL_CENTER, SMALL_RADIUS, LARGE_CENTER, LARGE_RADIUS
    )
    assert far_apart.status == "no_pair" and far_apart.pose is None
    assert far_apart.pair_error_m == pytest.approx(2.049, abs=0.002)
    tight = localize_rcds(
        TABLE_II, SMALL_CENTER, SMALL_RADIUS, LARGE_CENTER, LARGE_RADIUS, distance_tolerance=0.004
    )
    assert tight.status == "no_pair"


# ------------------------------------------------------------------------------------------
# Eq. (7): large/small assignment
# ------------------------------------------------------------------------------------------


def test_larger_angular_extent_is_the_large_beacon_whatever_the_range() -> None:
    wide_near = RCD.from_degrees(1.0, 10.0, 24.0)
    narrow_far = RCD.from_degrees(3.0, -50.0, 20.0)
    assert assign_large_and_small(wide_near, narrow_far) == (narrow_far, wide_near)
    assert assign_large_and_small(narrow_far, wide_near) == (narrow_far, wide_near)


def test_equal_angular_extents_make_the_farther_rcd_the_large_beacon() -> None:
    near = RCD.from_degrees(1.2, 30.0, 22.0)
    far = RCD.from_degrees(2.5, -40.0, 22.0)
    assert assign_large_and_small(near, far) == (near, far)
    assert assign_large_and_small(far, near) == (near, far)
    error = pair_distance_error(near, far, 0.02, 0.07, 2.0)
    assert error == pytest.approx(abs(2.0 - _law_of_cosines(1.22, 2.57, 70.0)), abs=1e-12)
    assert pair_distance_error(far, near, 0.02, 0.07, 2.0) == error


# ------------------------------------------------------------------------------------------
# Eqs (3)-(5): RCD extraction
# ------------------------------------------------------------------------------------------


def _clutter(count: int) -> np.ndarray:
    """Ranges that jump by 0.5 m at every step, so they form no RCD."""
    return np.where(np.arange(count) % 2 == 0, 1.0, 1.5)


def test_constant_arc_gives_one_rcd_with_its_centre_and_extent() -> None:
    ranges = _clutter(360)
    arc = np.arange(160, 185)  # -20 deg .. +4 deg, 25 samples
    ranges[arc] = 2.0
    rcds = extract_rcds(FULL_TURN_1DEG, ranges)
    assert len(rcds) == 1
    (rcd,) = rcds
    assert math.degrees(rcd.beta) == pytest.approx(-8.0, abs=1e-9)
    assert math.degrees(rcd.eta) == pytest.approx(24.0, abs=1e-9)
    assert rcd.delta == 2.0
    assert rcd.gamma == 0.0
    assert (rcd.start_index, rcd.end_index) == (160, 184)
    assert rcd.indices == tuple(range(160, 185))


def test_even_sample_count_takes_the_mean_of_the_two_central_ranges() -> None:
    ranges = _clutter(360)
    ranges[100:104] = [2.000, 2.004, 2.010, 2.012]
    (rcd,) = extract_rcds(FULL_TURN_1DEG, ranges)
    assert rcd.delta == pytest.approx(2.007, abs=1e-12)
    assert math.degrees(rcd.beta) == pytest.approx(-80.0 + 1.5, abs=1e-9)
    assert math.degrees(rcd.eta) == pytest.approx(3.0, abs=1e-9)


def test_arc_across_180_deg_of_a_full_turn_is_one_wrapped_rcd() -> None:
    ranges = _clutter(360)
    ranges[350:] = 1.7  # 170 .. 179 deg
    ranges[:11] = 1.7  # -180 .. -170 deg
    rcds = extract_rcds(FULL_TURN_1DEG, ranges)
    assert len(rcds) == 1
    (rcd,) = rcds
    assert abs(angle_difference(rcd.beta, math.pi)) < 1e-9
    assert math.degrees(rcd.eta) == pytest.approx(20.0, abs=1e-9)
    assert rcd.start_index == 350 and rcd.end_index == 10
    assert rcd.start_index > rcd.end_index
    assert rcd.indices == tuple(range(350, 360)) + tuple(range(11))


def test_partial_pan_does_not_wrap() -> None:
    angles = np.deg2rad(np.arange(-90.0, 91.0))
    ranges = _clutter(len(angles))
    ranges[:5] = 1.7
    ranges[-5:] = 1.7
    rcds = extract_rcds(angles, ranges)
    assert [(r.start_index, r.end_index) for r in rcds] == [(0, 4), (176, 180)]


def test_full_turn_of_constant_range_is_one_unwrapped_rcd() -> None:
    (rcd,) = extract_rcds(FULL_TURN_1DEG, np.full(360, 2.5))
    assert (rcd.start_index, rcd.end_index) == (0, 359)
    assert math.degrees(rcd.eta) == pytest.approx(359.0, abs=1e-9)


def test_nan_breaks_an_rcd() -> None:
    ranges = _clutter(360)
    ranges[100:121] = 2.0
    ranges[110] = np.nan
    rcds = extract_rcds(FULL_TURN_1DEG, ranges)
    assert [(r.start_index, r.end_index) for r in rcds] == [(100, 109), (111, 120)]


def test_single_sample_is_no_rcd_but_two_samples_are() -> None:
    ranges = _clutter(360)
    ranges[50] = 3.0
    assert extract_rcds(FULL_TURN_1DEG, ranges) == []
    ranges[51] = 3.0
    (rcd,) = extract_rcds(FULL_TURN_1DEG, ranges)
    assert rcd.indices == (50, 51)
    assert math.degrees(rcd.eta) == pytest.approx(1.0, abs=1e-9)


def test_eps_separates_neighbours_strictly() -> None:
    ranges = _clutter(360)
    ranges[200:210] = 2.0 + 0.019 * np.arange(10)  # steps below eps: one RCD
    ranges[300:310] = 2.0 + 0.021 * np.arange(10)  # steps above eps: single samples only
    rcds = extract_rcds(FULL_TURN_1DEG, ranges, eps=0.02)
    assert [(r.start_index, r.end_index) for r in rcds] == [(200, 209)]
    wider = extract_rcds(FULL_TURN_1DEG, ranges, eps=0.022)
    assert [(r.start_index, r.end_index) for r in wider] == [(200, 209), (300, 309)]
    ranges[250:252] = [2.0, 2.25]  # exactly eps (a binary-exact 0.25) is a break, eq. (3)
    assert all(r.start_index != 250 for r in extract_rcds(FULL_TURN_1DEG, ranges, eps=0.25))


# ------------------------------------------------------------------------------------------
# Eq. (6): symmetry
# ------------------------------------------------------------------------------------------


def test_symmetric_profile_has_zero_gamma() -> None:
    angles = np.deg2rad(np.arange(0.0, 23.0))
    ranges = 2.0 + 0.001 * (np.arange(23) - 11) ** 2
    assert symmetry_measure(angles, ranges, np.arange(23)) == pytest.approx(0.0, abs=1e-15)


def test_linear_ramp_gamma_matches_closed_form_for_odd_count() -> None:
    slope_m = 0.001
    angles = np.deg2rad(np.arange(0.0, 23.0))  # N = 23, M = 11
    ranges = 2.0 + slope_m * np.arange(23)
    # |delta(c + i) - delta(c - i)| = 2 i s, mean over i = 1..M is s (M + 1)
    assert symmetry_measure(angles, ranges, np.arange(23)) == pytest.approx(slope_m * 12, rel=1e-9)


def test_linear_ramp_gamma_matches_closed_form_for_even_count() -> None:
    slope_m = 0.001
    angles = np.deg2rad(np.arange(0.0, 22.0))  # N = 22, M = 11, eta = 21 increments
    ranges = 2.0 + slope_m * np.arange(22)
    # offsets i * 21 / 22 samples: gamma = s * 21 / 11 * (M + 1) / 2
    assert symmetry_measure(angles, ranges, np.arange(22)) == pytest.approx(
        slope_m * 21 / 11 * 6, rel=1e-9
    )


def test_skewed_profile_fails_the_symmetry_threshold_a_symmetric_one_passes() -> None:
    ranges = _clutter(360)
    ranges[100:123] = 2.0 + 0.0005 * np.arange(23)  # gamma = 0.006 m
    ranges[200:223] = 2.0 + 0.0005 * np.abs(np.arange(23) - 11)  # gamma = 0
    skewed, symmetric = extract_rcds(FULL_TURN_1DEG, ranges)
    assert skewed.gamma == pytest.approx(0.006, rel=1e-9)
    assert symmetric.gamma == pytest.approx(0.0, abs=1e-12)


# ------------------------------------------------------------------------------------------
# Eqs (8)-(15): two circles, sign rule, heading
# ------------------------------------------------------------------------------------------


def _exact_rcds(sensor: Pose) -> tuple[RCD, RCD]:
    small_range = math.dist((sensor.x, sensor.y), SMALL_CENTER) - SMALL_RADIUS
    large_range = math.dist((sensor.x, sensor.y), LARGE_CENTER) - LARGE_RADIUS
    small_bearing = math.atan2(SMALL_CENTER[1] - sensor.y, SMALL_CENTER[0] - sensor.x)
    large_bearing = math.atan2(LARGE_CENTER[1] - sensor.y, LARGE_CENTER[0] - sensor.x)
    return (
        RCD(small_range, small_bearing - sensor.theta, math.radians(22.0)),
        RCD(large_range, large_bearing - sensor.theta, math.radians(24.0)),
    )


def _sine_of_subtended_angle(position: tuple[float, float], a: tuple, b: tuple) -> float:
    ax, ay = a[0] - position[0], a[1] - position[1]
    bx, by = b[0] - position[0], b[1] - position[1]
    return (ax * by - ay * bx) / (math.hypot(ax, ay) * math.hypot(bx, by))


@settings(max_examples=150, deadline=None)
@given(
    x=st.floats(-2.0, 4.5),
    y=st.floats(-3.5, 2.0),
    theta=st.floats(-math.pi, math.pi),
)
def test_exact_geometry_recovers_random_sensor_poses(x: float, y: float, theta: float) -> None:
    truth = Pose(x, y, theta)
    for center in (SMALL_CENTER, LARGE_CENTER):
        assume(0.5 <= math.dist((x, y), center) <= 3.9)
    assume(abs(_sine_of_subtended_angle((x, y), SMALL_CENTER, LARGE_CENTER)) > 0.05)
    result = localize_rcds(
        _exact_rcds(truth), SMALL_CENTER, SMALL_RADIUS, LARGE_CENTER, LARGE_RADIUS
    )
    assert result.pose is not None
    assert result.pair_error_m == pytest.approx(0.0, abs=1e-9)
    assert position_error_m(result.pose, truth) < 1e-9
    assert heading_error_rad(result.pose, truth) < 1e-9


@settings(max_examples=150, deadline=None)
@given(
    small=st.tuples(st.floats(-5.0, 5.0), st.floats(-5.0, 5.0)),
    large=st.tuples(st.floats(-5.0, 5.0), st.floats(-5.0, 5.0)),
    position=st.tuples(st.floats(-5.0, 5.0), st.floats(-5.0, 5.0)),
)
def test_two_circles_recover_any_position_for_any_beacon_layout(
    small: tuple[float, float], large: tuple[float, float], position: tuple[float, float]
) -> None:
    assume(math.dist(small, large) > 0.5)
    assume(math.dist(position, small) > 0.3 and math.dist(position, large) > 0.3)
    assume(abs(_sine_of_subtended_angle(position, small, large)) > 0.05)
    bearing_difference = angle_difference(
        math.atan2(small[1] - position[1], small[0] - position[0]),
        math.atan2(large[1] - position[1], large[0] - position[0]),
    )
    solution = solve_two_circles(
        small, math.dist(position, small), large, math.dist(position, large), bearing_difference
    )
    assert solution.position is not None
    assert math.dist(solution.position, position) < 1e-9


def test_sign_rule_picks_each_mirror_image_of_the_line_of_centres() -> None:
    # (1.0, 1.0) and its mirror across the line through the beacon centres
    position = np.array([1.0, 1.0])
    large, small = np.array(LARGE_CENTER), np.array(SMALL_CENTER)
    unit = (small - large) / np.linalg.norm(small - large)
    foot = large + unit * float((position - large) @ unit)
    mirror = 2.0 * foot - position
    chosen = []
    for truth in (position, mirror):
        pose = Pose(float(truth[0]), float(truth[1]), 0.3)
        solution = solve_two_circles(
            SMALL_CENTER,
            float(np.linalg.norm(truth - small)),
            LARGE_CENTER,
            float(np.linalg.norm(truth - large)),
            angle_difference(*(b.beta for b in _exact_rcds(pose))),
        )
        assert solution.position is not None and solution.other_position is not None
        assert np.allclose(solution.position, truth, atol=1e-9)
        assert np.allclose(solution.other_position, 2.0 * foot - truth, atol=1e-9)
        chosen.append(solution.position)
    assert math.dist(*chosen) > 1.0


def test_non_intersecting_circles_give_no_intersection_and_no_nan() -> None:
    solution = solve_two_circles(SMALL_CENTER, 1.0, LARGE_CENTER, 1.0, 0.5)
    assert solution.status == "no_intersection"
    assert solution.position is None
    assert math.isfinite(solution.discriminant) and solution.discriminant < 0.0


def test_collinear_ranges_passing_eq_7_end_in_no_intersection() -> None:
    # Robot beyond the small beacon on the line of centres; the large range 1 cm too long.
    small_distance = 1.0
    large_distance = small_distance + BEACON_DISTANCE + 0.01
    bearing = math.radians(20.0)
    rcds = [
        RCD(small_distance - SMALL_RADIUS, bearing, math.radians(22.0)),
        RCD(large_distance - LARGE_RADIUS, bearing, math.radians(24.0)),
    ]
    params = BeomChoParameters(r_max_m=5.0)
    result = localize_rcds(
        rcds, SMALL_CENTER, SMALL_RADIUS, LARGE_CENTER, LARGE_RADIUS, params=params
    )
    assert isinstance(result, BeaconLocalization)
    assert result.status == "no_intersection"
    assert result.pose is None
    assert result.pair_error_m == pytest.approx(0.01, abs=1e-9)
    assert result.discriminant is not None and result.discriminant < 0.0


def test_beacons_with_equal_x_are_solved() -> None:
    small, large = (1.0, 2.0), (1.0, -1.0)
    truth = (3.0, 0.5)
    bearing_difference = angle_difference(
        math.atan2(small[1] - truth[1], small[0] - truth[0]),
        math.atan2(large[1] - truth[1], large[0] - truth[0]),
    )
    solution = solve_two_circles(
        small, math.dist(truth, small), large, math.dist(truth, large), bearing_difference
    )
    assert not solution.used_paper_formula
    assert solution.position is not None
    assert math.dist(solution.position, truth) < 1e-12
    mirrored = solve_two_circles(
        small, math.dist(truth, small), large, math.dist(truth, large), -bearing_difference
    )
    assert mirrored.position is not None
    assert math.dist(mirrored.position, (-1.0, 0.5)) < 1e-12


def test_heading_is_bearing_of_large_beacon_minus_its_rcd_angle() -> None:
    heading = heading_from_large_beacon((0.0, 0.0), (1.0, 1.0), math.radians(30.0))
    assert heading == pytest.approx(math.radians(15.0), abs=1e-12)
    assert heading_from_large_beacon((0.0, 0.0), (-1.0, 0.0), -math.pi / 2) == pytest.approx(
        -math.pi / 2, abs=1e-12
    )


# ------------------------------------------------------------------------------------------
# The whole chain on a synthetic pan, and the least-squares refinement
# ------------------------------------------------------------------------------------------


def _beacon_pan(
    sensor: Pose,
    rng: np.random.Generator | None = None,
    range_sigma_m: float = 0.0,
) -> Scan:
    """A 1-deg full pan: each beacon an arc of constant range (plus noise), clutter elsewhere."""
    angles = FULL_TURN_1DEG
    ranges = _clutter(len(angles)).astype(np.float64)
    ranges[::3] = np.nan
    for center, radius, half_extent_deg in (
        (SMALL_CENTER, SMALL_RADIUS, 11.0),
        (LARGE_CENTER, LARGE_RADIUS, 12.0),
    ):
        bearing = math.atan2(center[1] - sensor.y, center[0] - sensor.x) - sensor.theta
        if rng is None:
            lower = upper = half_extent_deg
        else:
            lower, upper = half_extent_deg + rng.uniform(-0.7, 0.7, size=2)
        offsets = np.degrees(wrap_angles(angles - bearing))
        inside = (offsets >= -lower) & (offsets <= upper)
        noise = 0.0 if rng is None else rng.normal(0.0, range_sigma_m, inside.sum())
        ranges[inside] = math.dist((sensor.x, sensor.y), center) - radius + noise
    return Scan(angles, ranges, np.ones_like(ranges), duration_s=1.0)


class _StandInScenario:
    def __init__(self, sensor_offset: tuple[float, float]) -> None:
        self._beacons = {
            "small_beacon": SimpleNamespace(center=SMALL_CENTER, radius=SMALL_RADIUS),
            "large_beacon": SimpleNamespace(center=LARGE_CENTER, radius=LARGE_RADIUS),
        }
        self.robot = SimpleNamespace(sensor_offset=sensor_offset)

    def beacon(self, name: str) -> SimpleNamespace:
        return self._beacons[name]


def test_localize_scan_returns_the_robot_centre_not_the_pan_axis() -> None:
    offset = (0.2, -0.05)
    robot = Pose(0.4, 0.3, math.radians(25.0))
    sensor = robot.compose(Pose(*offset, 0.0))
    result = localize_scan(_beacon_pan(sensor), _StandInScenario(offset))
    assert result.ok and result.pose is not None
    # ranges are exact, bearings are quantised to the 1 deg pan: heading within half a step
    assert math.degrees(heading_error_rad(result.pose, robot)) <= 0.5 + 1e-9
    assert position_error_m(result.pose, robot) < 0.21 * math.radians(0.5) + 1e-9
    assert position_error_m(result.pose, sensor) > 0.19
    assert result.small_rcd is not None and result.large_rcd is not None
    # arcs of 22 and 24 deg hold 22-23 and 24-25 samples of the 1 deg pan
    assert 21.0 - 1e-9 <= math.degrees(result.small_rcd.eta) <= 22.0 + 1e-9
    assert 23.0 - 1e-9 <= math.degrees(result.large_rcd.eta) <= 24.0 + 1e-9


def test_localize_scan_drops_readings_beyond_r_max() -> None:
    sensor = Pose(0.0, 0.0, 0.0)
    scan = _beacon_pan(sensor)
    short = BeomChoParameters(r_max_m=2.0)  # the small beacon is 2.9 m away
    result = localize_scan(scan, _StandInScenario((0.0, 0.0)), params=short)
    assert result.status == "no_pair"
    assert all(rcd.delta <= 2.0 for rcd in result.candidates)


def test_least_squares_is_exact_on_exact_data() -> None:
    truth = Pose(0.7, 0.4, -2.0)
    result = localize_rcds(
        _exact_rcds(truth),
        SMALL_CENTER,
        SMALL_RADIUS,
        LARGE_CENTER,
        LARGE_RADIUS,
        method="least_squares",
    )
    assert result.pose is not None
    assert position_error_m(result.pose, truth) < 1e-9
    assert heading_error_rad(result.pose, truth) < 1e-9


def test_least_squares_is_at_least_as_accurate_as_the_paper_on_noisy_pans() -> None:
    rng = np.random.default_rng(1995)
    errors: dict[str, list[tuple[float, float]]] = {"paper": [], "least_squares": []}
    scenario = _StandInScenario((0.0, 0.0))
    while len(errors["paper"]) < 60:
        truth = Pose(rng.uniform(-1.0, 2.5), rng.uniform(-0.5, 2.0), rng.uniform(-math.pi, math.pi))
        scan = _beacon_pan(truth, rng, range_sigma_m=0.003)
        results = {m: localize_scan(scan, scenario, method=m) for m in errors}
        if not all(r.ok for r in results.values()):
            continue
        for method, result in results.items():
            assert result.pose is not None
            errors[method].append(
                (position_error_m(result.pose, truth), heading_error_rad(result.pose, truth))
            )
    paper = np.median(np.array(errors["paper"]), axis=0)
    refined = np.median(np.array(errors["least_squares"]), axis=0)
    assert refined[0] <= paper[0]
    assert refined[1] <= paper[1]


# ------------------------------------------------------------------------------------------
# Section II.A: speed of sound
# ------------------------------------------------------------------------------------------


def test_self_calibration_recovers_the_speed_of_sound() -> None:
    speed_mps = 331.3 * math.sqrt(1.0 + 28.0 / 273.15)
    tof_s = 2.0 * 0.515 / speed_mps
    assert speed_of_sound_from_reflector(tof_s) == pytest.approx(speed_mps, rel=1e-12)
    assert speed_of_sound_from_reflector(2.0 * 0.8 / 340.0, 0.8) == pytest.approx(340.0, rel=1e-12)
    assert range_from_tof(2.0 * 1.7 / speed_mps, speed_mps) == pytest.approx(1.7, rel=1e-12)


def test_calibrated_speed_removes_the_range_bias_of_an_assumed_speed() -> None:
    true_speed_mps, assumed_speed_mps = 347.0, 343.2
    tof_s = 2.0 * 2.0 / true_speed_mps
    assert range_from_tof(tof_s, assumed_speed_mps) < 2.0 - 0.02
    calibrated = speed_of_sound_from_reflector(2.0 * 0.515 / true_speed_mps)
    assert range_from_tof(tof_s, calibrated) == pytest.approx(2.0, rel=1e-12)


# ------------------------------------------------------------------------------------------
# Bad arguments
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: speed_of_sound_from_reflector(0.0), "round_trip_tof_s"),
        (lambda: speed_of_sound_from_reflector(0.003, -0.5), "reflector_distance_m"),
        (lambda: range_from_tof(-1e-3, 343.0), "tof_s"),
        (lambda: range_from_tof(1e-3, 0.0), "speed_of_sound_mps"),
        (lambda: extract_rcds(FULL_TURN_1DEG, np.ones(10)), "ranges"),
        (lambda: extract_rcds(FULL_TURN_1DEG[::-1], np.ones(360)), "angles"),
        (lambda: extract_rcds(FULL_TURN_1DEG, np.ones(360), eps=0.0), "eps"),
        (lambda: symmetry_measure(FULL_TURN_1DEG, np.ones(360), [3]), "rcd_indices"),
        (
            lambda: localize_rcds(TABLE_II, SMALL_CENTER, -0.02, LARGE_CENTER, 0.07),
            "small_radius",
        ),
        (
            lambda: localize_rcds(TABLE_II, SMALL_CENTER, 0.02, (1.0,), 0.07),
            "large_center",
        ),
        (
            lambda: localize_rcds(TABLE_II, SMALL_CENTER, 0.02, LARGE_CENTER, 0.07, method="x"),
            "method",
        ),
        (
            lambda: localize_rcds(
                TABLE_II, SMALL_CENTER, 0.02, LARGE_CENTER, 0.07, distance_tolerance=0.0
            ),
            "distance_tolerance",
        ),
        (lambda: solve_two_circles(SMALL_CENTER, 1.0, SMALL_CENTER, 2.0, 0.1), "distinct"),
        (lambda: BeomChoParameters(eps_m=-0.01), "eps_m"),
        (lambda: BeomChoParameters(r_min_m=5.0), "r_min_m"),
        (lambda: RCD(delta=-1.0, beta=0.0, eta=0.3), "RCD.delta"),
    ],
)
def test_bad_arguments_raise_value_error_naming_the_argument(call, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        call()


# ------------------------------------------------------------------------------------------
# Options beside the paper: pair assignment by best fit, the odometry-prior gate
# ------------------------------------------------------------------------------------------


def _rcd_of_beacon(sensor: Pose, center: tuple[float, float], radius: float, eta_deg: float) -> RCD:
    delta = math.dist(center, (sensor.x, sensor.y)) - radius
    bearing = math.degrees(math.atan2(center[1] - sensor.y, center[0] - sensor.x) - sensor.theta)
    return RCD.from_degrees(delta, bearing, eta_deg, 0.001)


def test_swapped_extents_defeat_the_papers_rule_but_not_best_fit_assignment() -> None:
    sensor = Pose(1.6, -0.4, 0.3)
    # the small beacon is near, so its RCD is the wider one: the paper's rule swaps them
    small = _rcd_of_beacon(sensor, SMALL_CENTER, SMALL_RADIUS, 24.0)
    large = _rcd_of_beacon(sensor, LARGE_CENTER, LARGE_RADIUS, 22.0)
    args = (SMALL_CENTER, SMALL_RADIUS, LARGE_CENTER, LARGE_RADIUS)
    paper = localize_rcds([small, large], *args)
    best_fit = localize_rcds([small, large], *args, params=BeomChoParameters(assignment="best_fit"))
    assert not (paper.ok and position_error_m(paper.pose, sensor) < 0.01)
    assert best_fit.ok
    assert position_error_m(best_fit.pose, sensor) < 1e-9
    assert heading_error_rad(best_fit.pose, sensor) < 1e-9


def test_prior_gate_rejects_a_coincidental_pair_that_matches_eq_7_better() -> None:
    sensor = Pose(-0.5, 0.7, -0.2)
    exact_small = _rcd_of_beacon(sensor, SMALL_CENTER, SMALL_RADIUS, 22.0)
    small = RCD(exact_small.delta + 0.005, exact_small.beta, exact_small.eta, exact_small.gamma)
    large = _rcd_of_beacon(sensor, LARGE_CENTER, LARGE_RADIUS, 24.0)
    true_error = pair_distance_error(small, large, SMALL_RADIUS, LARGE_RADIUS, BEACON_DISTANCE)
    # two wall echoes whose implied distance matches d_0 exactly: eq. (7) prefers them
    decoy_small = RCD.from_degrees(2.0, 10.0, 22.0, 0.001)
    decoy_large_range = 1.0
    chord = BEACON_DISTANCE
    # choose the decoy's bearing so the law of cosines gives exactly d_0
    d_s, d_l = 2.0 + SMALL_RADIUS, decoy_large_range + LARGE_RADIUS
    cos_angle = (d_s**2 + d_l**2 - chord**2) / (2 * d_s * d_l)
    decoy_large = RCD.from_degrees(
        decoy_large_range, 10.0 - math.degrees(math.acos(cos_angle)), 24.0, 0.001
    )
    assert (
        pair_distance_error(decoy_small, decoy_large, SMALL_RADIUS, LARGE_RADIUS, BEACON_DISTANCE)
        < true_error + 1e-12
    )
    rcds = [small, large, decoy_small, decoy_large]
    args = (SMALL_CENTER, SMALL_RADIUS, LARGE_CENTER, LARGE_RADIUS)
    ungated = localize_rcds(rcds, *args)
    prior = Pose(sensor.x + 0.15, sensor.y - 0.1, sensor.theta + 0.05)
    gated = localize_rcds(rcds, *args, prior=prior, prior_gate_m=0.4)
    assert ungated.small_rcd == decoy_small or ungated.small_rcd == decoy_large
    assert gated.ok and gated.small_rcd == small
    assert position_error_m(gated.pose, sensor) < 0.02
    far_prior = Pose(sensor.x + 3.0, sensor.y, sensor.theta)
    assert (
        localize_rcds(rcds, *args, prior=far_prior, prior_gate_m=0.4).status == "no_pair_near_prior"
    )


def test_bad_assignment_name_is_rejected() -> None:
    with pytest.raises(ValueError, match="assignment"):
        BeomChoParameters(assignment="coin_flip")


# ------------------------------------------------------------------------------------------
# solve_two_circles at every magnitude
# ------------------------------------------------------------------------------------------

LAB_SENSOR = (0.4, 0.9)


def _lab_geometry_scaled(scale: float) -> tuple[tuple[float, float], float, tuple, float, float]:
    """The paper lab's beacon pair seen from ``LAB_SENSOR``, every length times ``scale``."""
    small = (SMALL_CENTER[0] * scale, SMALL_CENTER[1] * scale)
    large = (LARGE_CENTER[0] * scale, LARGE_CENTER[1] * scale)
    sensor = (LAB_SENSOR[0] * scale, LAB_SENSOR[1] * scale)
    bearing = angle_difference(
        math.atan2(SMALL_CENTER[1] - LAB_SENSOR[1], SMALL_CENTER[0] - LAB_SENSOR[0]),
        math.atan2(LARGE_CENTER[1] - LAB_SENSOR[1], LARGE_CENTER[0] - LAB_SENSOR[0]),
    )
    d_s = math.dist(SMALL_CENTER, LAB_SENSOR) * scale
    d_l = math.dist(LARGE_CENTER, LAB_SENSOR) * scale
    return small, d_s, large, d_l, bearing, sensor  # type: ignore[return-value]


@pytest.mark.parametrize("scale", [1e-300, 1e-200, 1e-120, 1e120, 1e200, 1e250, 1e300])
def test_two_circles_scale_with_their_lengths_at_extreme_magnitudes(scale: float) -> None:
    small, d_s, large, d_l, bearing, sensor = _lab_geometry_scaled(scale)
    solution = solve_two_circles(small, d_s, large, d_l, bearing)
    assert solution.status == "ok" and solution.position is not None
    np.testing.assert_allclose(solution.position, sensor, rtol=1e-9)
    assert math.isfinite(solution.discriminant) and solution.discriminant >= 0.0


def test_circles_meeting_beyond_the_float_range_say_so() -> None:
    # the circles meet at (2.5e308, 0) and (0.9e308, 0): one point is beyond the largest float
    small, large = (1.7e308, 0.0), (1.7e308, 0.5e308)
    solution = solve_two_circles(small, 0.8e308, large, math.hypot(0.8e308, 0.5e308), 1.0)
    assert solution.status == "out_of_float_range" and solution.position is None
    assert math.isfinite(solution.discriminant)


_ANY_LENGTH = st.floats(min_value=-1.7e308, max_value=1.7e308, allow_nan=False)
_ANY_DISTANCE = st.floats(min_value=5e-324, max_value=1.7e308, allow_nan=False)


@settings(max_examples=300, deadline=None)
@given(
    st.tuples(_ANY_LENGTH, _ANY_LENGTH),
    _ANY_DISTANCE,
    st.tuples(_ANY_LENGTH, _ANY_LENGTH),
    _ANY_DISTANCE,
    st.floats(min_value=-1e300, max_value=1e300, allow_nan=False),
)
def test_every_finite_input_gives_a_status_and_no_nan(
    small: tuple[float, float],
    d_s: float,
    large: tuple[float, float],
    d_l: float,
    bearing: float,
) -> None:
    assume(small != large)
    solution = solve_two_circles(small, d_s, large, d_l, bearing)
    assert solution.status in ("ok", "no_intersection", "out_of_float_range")
    assert not math.isnan(solution.discriminant)
    assert (solution.status == "ok") == (solution.position is not None)
    if solution.position is not None and solution.other_position is not None:
        assert all(math.isfinite(v) for v in (*solution.position, *solution.other_position))


@pytest.mark.parametrize(
    ("arguments", "name"),
    [
        (((math.nan, 0.0), 1.0, (1.0, 0.0), 1.0, 0.1), "small_center"),
        (((0.0, 0.0), 1.0, (1.0, math.inf), 1.0, 0.1), "large_center"),
        (((0.0, 0.0), math.inf, (1.0, 0.0), 1.0, 0.1), "small_distance"),
        (((0.0, 0.0), 1.0, (1.0, 0.0), math.nan, 0.1), "large_distance"),
        (((0.0, 0.0), 1.0, (1.0, 0.0), 1.0, -math.inf), "bearing_difference"),
    ],
)
def test_non_finite_input_is_a_value_error_naming_it(arguments: tuple, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        solve_two_circles(*arguments)


@pytest.mark.parametrize("seed", range(5))
def test_extracted_rcds_equal_ones_built_through_the_checked_constructor(seed: int) -> None:
    rng = np.random.default_rng(seed)
    ranges = np.repeat(rng.uniform(0.5, 4.0, 40), 9) + rng.normal(0.0, 0.004, 360)
    ranges[rng.random(360) < 0.05] = np.nan
    for rcd in extract_rcds(FULL_TURN_1DEG, ranges):
        angles = np.unwrap(FULL_TURN_1DEG[list(rcd.indices)])
        count = len(rcd.indices)
        middle = ranges[list(rcd.indices)][(count - 1) // 2 : count // 2 + 1]
        checked = RCD(
            delta=float(np.mean(middle)) if count % 2 == 0 else float(middle[0]),
            beta=0.5 * (angles[0] + angles[-1]),
            eta=float(angles[-1] - angles[0]),
            gamma=symmetry_measure(FULL_TURN_1DEG, ranges, rcd.indices),
            start_index=rcd.indices[0],
            end_index=rcd.indices[-1],
            indices=rcd.indices,
            sample_ranges=tuple(ranges[list(rcd.indices)]),
        )
        assert rcd == checked


def test_single_ping_pans_add_nothing_but_are_still_checked() -> None:
    scenario = _StandInScenario((0.0, 0.0))
    pan = _beacon_pan(Pose(0.4, 0.3, 0.2))
    alone = localize_scans([pan], scenario)
    singles = [Scan(np.array([a]), np.array([2.0]), np.ones(1), 0.01) for a in (0.1, 0.2)]
    assert localize_scans([singles[0], pan, singles[1]], scenario) == alone
    assert localize_scans(singles, scenario).status == "no_candidates"
    unknown_angle = Scan(np.array([math.nan]), np.array([2.0]), np.ones(1), 0.01)
    with pytest.raises(ValueError, match="angles"):
        localize_scans([pan, unknown_angle], scenario)
