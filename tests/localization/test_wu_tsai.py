"""Tests of the Wu & Tsai (2001) localization: three ceiling transmitters, two receivers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.localization.result import Localization
from sonar_gym.localization.wu_tsai import (
    PAPER_COUNTER_RATE_HZ,
    PAPER_RECEIVER_OFFSETS_M,
    PAPER_REPEATED_FIXES,
    PAPER_TEMPERATURE_C,
    PAPER_TRANSMITTER_SPACING_M,
    SPEED_OF_LIGHT_MPS,
    Fix,
    InconsistentDistances,
    TransmitterLocalization,
    average_fixes,
    distance_from_tof,
    heading_from_receivers,
    heading_observable,
    localize,
    receiver_position,
    receiver_position_least_squares,
    speed_of_sound_from_temperature_mps,
    transmitter_positions,
)
from sonar_gym.pose import angle_difference

A_PAPER = PAPER_TRANSMITTER_SPACING_M
OFFSETS_PAPER = np.array(PAPER_RECEIVER_OFFSETS_M)
COUNTER_TICK_S = 1.0 / PAPER_COUNTER_RATE_HZ

# Tables I-II of the paper (cm and degrees as printed): the robot at [0, 0, z], headings
# 0/45/90/135 deg, estimates from n = 10 fixes by eqs (13)-(16).
PAPER_HEADINGS_DEG = (0.0, 45.0, 90.0, 135.0)
PAPER_TABLES = {
    -190.0: {
        "x_hat_cm": (-3.1, -3.55, -2.87, -1.73),
        "y_hat_cm": (-2.29, -2.92, -1.09, -2.74),
        "z_hat_cm": (-189.02, -188.61, -189.38, -189.3),
        "theta_hat_deg": (0.6, 46.6, 91.2, 136.71),
    },
    -150.0: {
        "x_hat_cm": (-0.94, -1.48, -1.95, -0.92),
        "y_hat_cm": (-0.47, -1.48, -0.97, -0.52),
        "z_hat_cm": (-149.83, -149.36, -149.30, -149.84),
        "theta_hat_deg": (0.5, 46.12, 89.22, 136.08),
    },
}

# Noise model for the paper's rig: each transmitter-receiver TOF gets independent Gaussian
# jitter of 2 us (0.7 mm of range: threshold-detection jitter well below one 25 us carrier
# period), then the 50 kHz counter truncates it to whole 20 us ticks; the distance uses the
# speed of sound at the paper's 27 deg C.
TOF_JITTER_S = 2e-6


def _receivers_xyz(x: float, y: float, z: float, heading: float, offsets: np.ndarray) -> np.ndarray:
    """Receiver positions in {T} for a robot at (x, y, z, heading) with offsets in {AMR}."""
    c, s = math.cos(heading), math.sin(heading)
    rotated = offsets @ np.array([[c, s], [-s, c]])
    return np.column_stack([rotated + [x, y], np.full(len(offsets), z)])


def _distances(receivers: np.ndarray, transmitters: np.ndarray) -> np.ndarray:
    return np.linalg.norm(receivers[:, None, :] - transmitters[None, :, :], axis=2)


def _counter_distances(
    true_distances: np.ndarray, rng: np.random.Generator | None, jitter_s: float
) -> np.ndarray:
    """Distances measured through the paper's 50 kHz counter (truncation), eq. (11)."""
    speed = speed_of_sound_from_temperature_mps(PAPER_TEMPERATURE_C)
    tof = true_distances / speed
    if rng is not None:
        tof = tof + rng.normal(0.0, jitter_s, size=tof.shape)
    ticks = np.floor(tof / COUNTER_TICK_S)
    return np.asarray(distance_from_tof(ticks * COUNTER_TICK_S, speed))


# --------------------------------------------------------------------------------------------
# Ranging, eqs (10)-(11)
# --------------------------------------------------------------------------------------------


def test_speed_of_sound_matches_reference_values() -> None:
    assert speed_of_sound_from_temperature_mps(0.0) == pytest.approx(331.3)
    assert speed_of_sound_from_temperature_mps(20.0) == pytest.approx(343.2, abs=0.05)
    assert speed_of_sound_from_temperature_mps(PAPER_TEMPERATURE_C) == pytest.approx(
        347.3, abs=0.05
    )


def test_distance_from_tof_is_speed_times_time_eq_11() -> None:
    assert distance_from_tof(0.01, 340.0) == pytest.approx(3.4, rel=1e-15)
    np.testing.assert_allclose(distance_from_tof([0.001, 0.002], 340.0), [0.34, 0.68])


def test_distance_from_tof_with_radio_delay_eq_10_is_shorter_by_vu_over_ve() -> None:
    speed = 347.3
    eq_11 = distance_from_tof(0.0055, speed)
    eq_10 = distance_from_tof(0.0055, speed, radio_speed_mps=SPEED_OF_LIGHT_MPS)
    # TOF = d / V_E + d / V_U  =>  d = TOF V_U / (1 + V_U / V_E).
    assert eq_10 == pytest.approx(eq_11 / (1.0 + speed / SPEED_OF_LIGHT_MPS), rel=1e-14)
    assert eq_11 - eq_10 == pytest.approx(eq_11 * speed / SPEED_OF_LIGHT_MPS, rel=1e-5)


@pytest.mark.parametrize("tof", [0.0, -1e-3, math.nan, math.inf, [0.001, -0.001]])
def test_distance_from_tof_rejects_non_positive_tof(tof: object) -> None:
    with pytest.raises(ValueError, match="tof_s"):
        distance_from_tof(tof, 340.0)  # type: ignore[arg-type]


@pytest.mark.parametrize("speed", [0.0, -340.0, math.nan])
def test_distance_from_tof_rejects_non_positive_speed(speed: float) -> None:
    with pytest.raises(ValueError, match="speed_of_sound_mps"):
        distance_from_tof(0.001, speed)
    with pytest.raises(ValueError, match="radio_speed_mps"):
        distance_from_tof(0.001, 340.0, radio_speed_mps=speed)


def test_speed_of_sound_rejects_temperature_below_absolute_zero() -> None:
    with pytest.raises(ValueError, match="temperature_c"):
        speed_of_sound_from_temperature_mps(-300.0)


# --------------------------------------------------------------------------------------------
# Closed form, Theorem 2, eqs (2)-(9)
# --------------------------------------------------------------------------------------------


@settings(max_examples=200, deadline=None)
@given(
    x=st.floats(-3.0, 3.0),
    y=st.floats(-3.0, 3.0),
    z=st.floats(-2.5, -0.5),
    a=st.one_of(st.just(0.2), st.floats(0.05, 2.0)),
)
def test_closed_form_recovers_exact_receiver_position(
    x: float, y: float, z: float, a: float
) -> None:
    truth = np.array([x, y, z])
    d = np.linalg.norm(truth - transmitter_positions(a), axis=1)
    estimate = receiver_position(d, a)
    assert np.linalg.norm(estimate - truth) <= 1e-9 * np.linalg.norm(truth)


def test_closed_form_on_hand_computed_point() -> None:
    # Receiver at (0.3, 0.4, -1.2) with a = 0.5: d0 = 1.3, d1^2 = 0.04 + 0.16 + 1.44,
    # d2^2 = 0.09 + 0.01 + 1.44.
    d = [1.3, math.sqrt(1.64), math.sqrt(1.54)]
    np.testing.assert_allclose(receiver_position(d, 0.5), [0.3, 0.4, -1.2], rtol=1e-12)


def test_z_sign_chooses_the_root_of_eq_9() -> None:
    truth = np.array([0.1, -0.2, 1.3])
    d = np.linalg.norm(truth - transmitter_positions(A_PAPER), axis=1)
    np.testing.assert_allclose(receiver_position(d, A_PAPER, z_sign=1), truth, rtol=1e-12)
    np.testing.assert_allclose(
        receiver_position(d, A_PAPER, z_sign=-1), truth * [1, 1, -1], rtol=1e-12
    )


def test_receiver_in_transmitter_plane_gives_z_zero_not_nan() -> None:
    truth = np.array([0.37, -0.81, 0.0])
    d = np.linalg.norm(truth - transmitter_positions(A_PAPER), axis=1)
    estimate = receiver_position(d, A_PAPER)
    assert np.all(np.isfinite(estimate))
    np.testing.assert_allclose(estimate, truth, atol=1e-6)


def test_inconsistent_distances_raise_dedicated_value_error() -> None:
    # x = y = -0.1, so d0^2 - x^2 - y^2 = 0.01 - 0.02 < 0: no point has these distances.
    with pytest.raises(InconsistentDistances, match="eq. \\(9\\)"):
        receiver_position([0.1, 0.3, 0.3], A_PAPER)
    assert issubclass(InconsistentDistances, ValueError)


# --------------------------------------------------------------------------------------------
# Heading from two receivers (Theorem 2)
# --------------------------------------------------------------------------------------------

NEAR_PI_HEADINGS = [math.pi, -math.pi + 1e-9, math.pi - 1e-9, math.radians(179.99), -3.1415]


@settings(max_examples=200, deadline=None)
@given(
    heading=st.one_of(st.floats(-math.pi, math.pi), st.sampled_from(NEAR_PI_HEADINGS)),
    x=st.floats(-2.0, 2.0),
    y=st.floats(-2.0, 2.0),
)
def test_heading_from_rear_and_front_receivers_on_robot_axis(
    heading: float, x: float, y: float
) -> None:
    front, back = _receivers_xyz(x, y, -1.9, heading, np.array([[0.2, 0.0], [-0.2, 0.0]]))
    assert abs(angle_difference(heading_from_receivers(front, back), heading)) <= 1e-12


@settings(max_examples=200, deadline=None)
@given(
    heading=st.one_of(st.floats(-math.pi, math.pi), st.sampled_from(NEAR_PI_HEADINGS)),
    x=st.floats(-2.0, 2.0),
    y=st.floats(-2.0, 2.0),
    z=st.floats(-2.5, -0.5),
)
def test_localize_recovers_exact_pose_with_paper_receivers(
    heading: float, x: float, y: float, z: float
) -> None:
    receivers = _receivers_xyz(x, y, z, heading, OFFSETS_PAPER)
    result = localize(_distances(receivers, transmitter_positions(A_PAPER)), A_PAPER, OFFSETS_PAPER)
    assert result.status == "ok"
    assert result.pose is not None and result.fix is not None and result.position_3d is not None
    scale = math.hypot(math.hypot(x, y), z)
    assert np.linalg.norm(np.subtract(result.position_3d, [x, y, z])) <= 1e-9 * scale
    assert abs(angle_difference(result.pose.theta, heading)) <= 1e-9
    np.testing.assert_allclose(result.fix.receiver_array, receivers, atol=1e-9 * scale)
    # The paper's rig: receivers at [0, +-0.2, 0] in {AMR}, so the baseline from the -y
    # receiver to the +y receiver points along +y_AMR, pi/2 from the heading.
    p_plus_y, p_minus_y = result.fix.receiver_array
    theorem_2 = heading_from_receivers(p_plus_y, p_minus_y, baseline_angle_in_robot_rad=math.pi / 2)
    assert abs(angle_difference(theorem_2, result.pose.theta)) <= 1e-12


def test_localize_with_offset_receivers_finds_robot_origin() -> None:
    offsets = np.array([[0.35, 0.1], [-0.05, 0.1], [0.15, -0.3]])
    receivers = _receivers_xyz(1.1, -0.4, -1.7, math.radians(-150.0), offsets)
    result = localize(_distances(receivers, transmitter_positions(0.5)), 0.5, offsets)
    assert result.fix is not None
    np.testing.assert_allclose(result.fix.position, [1.1, -0.4, -1.7], atol=1e-12)
    assert result.fix.heading == pytest.approx(math.radians(-150.0), abs=1e-12)


def test_result_is_a_localization_with_planar_pose() -> None:
    receivers = _receivers_xyz(0.3, 0.2, -1.5, 0.4, OFFSETS_PAPER)
    result = localize(_distances(receivers, transmitter_positions(A_PAPER)), A_PAPER, OFFSETS_PAPER)
    assert isinstance(result, Localization) and isinstance(result, TransmitterLocalization)
    assert result.ok and result.pose is not None
    assert (result.pose.x, result.pose.y) == pytest.approx((0.3, 0.2), abs=1e-12)


# --------------------------------------------------------------------------------------------
# Theorem 1: observability
# --------------------------------------------------------------------------------------------


def test_one_receiver_gives_heading_unobservable_with_3d_position() -> None:
    offset = np.array([[0.1, 0.05]])
    results = []
    for heading in (0.3, 2.5):
        # Turn the robot about the vertical through its receiver: every distance is unchanged.
        receiver = np.array([[0.42, -0.17, -1.9]])
        origin = receiver[0, :2] - _receivers_xyz(0.0, 0.0, 0.0, heading, offset)[0, :2]
        moved = _receivers_xyz(origin[0], origin[1], -1.9, heading, offset)
        np.testing.assert_allclose(moved, receiver, atol=1e-15)
        d = _distances(moved, transmitter_positions(A_PAPER))
        results.append(localize(d, A_PAPER, offset))
    for result in results:
        assert result.status == "heading_unobservable"
        assert result.pose is None and result.fix is None
        assert result.position_3d == pytest.approx((0.42, -0.17, -1.9), abs=1e-12)
    assert results[0] == results[1]


def test_receivers_at_one_place_on_robot_are_like_one_receiver() -> None:
    offsets = np.zeros((2, 2))
    receivers = _receivers_xyz(0.2, 0.1, -1.5, 1.0, offsets)
    result = localize(_distances(receivers, transmitter_positions(A_PAPER)), A_PAPER, offsets)
    assert result.status == "heading_unobservable"
    assert result.position_3d == pytest.approx((0.2, 0.1, -1.5), abs=1e-12)


def test_theorem_1_one_transmitter_never_observes_heading() -> None:
    # Proof of Theorem 1: turning the robot about the vertical through a single transmitter
    # keeps every receiver's distance to it, so no number of receivers fixes the heading.
    rng = np.random.default_rng(7)
    offsets = rng.uniform(-0.5, 0.5, size=(6, 2))
    transmitter = np.zeros((1, 3))
    before = _distances(_receivers_xyz(1.0, 0.5, -1.9, 0.2, offsets), transmitter)
    c, s = math.cos(1.1), math.sin(1.1)
    x, y = c * 1.0 - s * 0.5, s * 1.0 + c * 0.5
    after = _distances(_receivers_xyz(x, y, -1.9, 0.2 + 1.1, offsets), transmitter)
    np.testing.assert_allclose(before, after, rtol=1e-12)
    assert not any(heading_observable(1, m) for m in range(1, 20))
    assert not heading_observable(3, 1)
    assert heading_observable(3, 2)


# --------------------------------------------------------------------------------------------
# Averaging n fixes, eqs (12)-(16), with the circular mean for eq. (16)
# --------------------------------------------------------------------------------------------


def _fix(heading_deg: float, x: float = 0.0, y: float = 0.0, z: float = -1.9) -> Fix:
    return Fix(x=x, y=y, z=z, heading=math.radians(heading_deg))


def test_circular_mean_across_180_deg_is_180_not_0() -> None:
    # The literal eq. (16), (179 + (-179)) / 2, gives 0 deg: the opposite direction.
    mean = average_fixes([_fix(179.0), _fix(-179.0)])
    assert abs(angle_difference(mean.heading, math.pi)) < 1e-12


@settings(max_examples=100, deadline=None)
@given(
    centre=st.floats(-math.pi, math.pi),
    spreads=st.lists(st.floats(0.0, 1.0), min_size=1, max_size=6),
)
def test_symmetric_headings_average_to_their_centre(centre: float, spreads: list[float]) -> None:
    headings = [centre + sign * spread for spread in spreads for sign in (1.0, -1.0)]
    mean = average_fixes([Fix(0.0, 0.0, -1.0, heading) for heading in headings])
    assert abs(angle_difference(mean.heading, centre)) < 1e-9


def test_positions_average_arithmetically_eqs_13_to_15() -> None:
    fixes = [
        Fix(0.1, -0.2, -1.90, 0.10, ((0.1, 0.0, -1.90), (0.1, -0.4, -1.90))),
        Fix(0.3, -0.1, -1.86, 0.20, ((0.3, 0.1, -1.86), (0.3, -0.3, -1.86))),
        Fix(0.2, 0.0, -1.88, 0.30, ((0.2, 0.2, -1.88), (0.2, -0.2, -1.88))),
    ]
    mean = average_fixes(fixes)
    assert (mean.x, mean.y, mean.z) == pytest.approx((0.2, -0.1, -1.88), abs=1e-15)
    assert mean.heading == pytest.approx(0.2, abs=1e-15)
    np.testing.assert_allclose(mean.receiver_array, [[0.2, 0.1, -1.88], [0.2, -0.3, -1.88]])


def test_average_fixes_rejects_empty_and_mixed_input() -> None:
    with pytest.raises(ValueError, match="fixes"):
        average_fixes([])
    with pytest.raises(ValueError, match="fixes"):
        average_fixes([_fix(0.0), Fix(0.0, 0.0, -1.0, 0.0, ((0.0, 0.0, -1.0),))])


# --------------------------------------------------------------------------------------------
# The paper's experiments, Tables I-II
# --------------------------------------------------------------------------------------------


def _simulate_table(z_m: float, rng: np.random.Generator, n: int) -> list[list[Fix]]:
    """n fixes per heading of Table I (z = -1.9 m) or II (z = -1.5 m), robot at (0, 0)."""
    transmitters = transmitter_positions(A_PAPER)
    table = []
    for heading_deg in PAPER_HEADINGS_DEG:
        receivers = _receivers_xyz(0.0, 0.0, z_m, math.radians(heading_deg), OFFSETS_PAPER)
        true_distances = _distances(receivers, transmitters)
        fixes = []
        for _ in range(n):
            result = localize(
                _counter_distances(true_distances, rng, TOF_JITTER_S), A_PAPER, OFFSETS_PAPER
            )
            assert result.fix is not None, result
            fixes.append(result.fix)
        table.append(fixes)
    return table


@pytest.mark.parametrize("z_cm", sorted(PAPER_TABLES))
def test_paper_tables_errors_are_of_the_papers_order(z_cm: float) -> None:
    paper = PAPER_TABLES[z_cm]
    paper_horizontal_cm = np.mean(np.abs(np.concatenate([paper["x_hat_cm"], paper["y_hat_cm"]])))
    paper_height_cm = np.mean(np.subtract(paper["z_hat_cm"], z_cm))
    paper_heading_deg = np.mean(np.abs(np.subtract(paper["theta_hat_deg"], PAPER_HEADINGS_DEG)))

    rng = np.random.default_rng(2001)
    table = _simulate_table(z_cm / 100.0, rng, PAPER_REPEATED_FIXES)
    estimates = [average_fixes(fixes) for fixes in table]
    horizontal_cm = np.array([[f.x * 100.0, f.y * 100.0] for f in estimates])
    height_cm = np.array([f.z * 100.0 - z_cm for f in estimates])
    heading_deg = np.array(
        [
            math.degrees(abs(angle_difference(f.heading, math.radians(truth))))
            for f, truth in zip(estimates, PAPER_HEADINGS_DEG, strict=True)
        ]
    )
    # A few cm and a few degrees in every experiment, as in the paper ...
    assert np.all(np.abs(horizontal_cm) <= 5.0)
    assert np.all(np.abs(height_cm) <= 2.0)
    assert np.all(heading_deg <= 10.0)
    # ... the table means within a small factor of the paper's ...
    assert 0.1 <= np.mean(np.abs(horizontal_cm)) / paper_horizontal_cm <= 4.0
    assert 0.1 <= np.mean(np.abs(height_cm)) / paper_height_cm <= 4.0
    assert 0.1 <= np.mean(heading_deg) / paper_heading_deg <= 4.0
    # ... and, as in all eight of the paper's experiments, the robot appears nearer the
    # ceiling than it is: the counter truncates every TOF, so every distance is short.
    assert np.mean(height_cm) > 0.0 and paper_height_cm > 0.0


def test_shorter_distances_give_more_accurate_fixes_section_5() -> None:
    # Section 5: Example 2 (z = -1.5 m) is more accurate than Example 1 (z = -1.9 m) because
    # the distances are shorter; the noise gain of eqs (7)-(8) is about d / a.
    rng = np.random.default_rng(5)
    rms: dict[float, tuple[float, float]] = {}
    for z_m in (-1.9, -1.5):
        fixes_by_heading = _simulate_table(z_m, rng, n=50)
        horizontal = [f.x**2 + f.y**2 for fixes in fixes_by_heading for f in fixes]
        heading = [
            angle_difference(f.heading, math.radians(truth)) ** 2
            for fixes, truth in zip(fixes_by_heading, PAPER_HEADINGS_DEG, strict=True)
            for f in fixes
        ]
        rms[z_m] = (math.sqrt(np.mean(horizontal)), math.sqrt(np.mean(heading)))
    assert rms[-1.5][0] < rms[-1.9][0]
    assert rms[-1.5][1] < rms[-1.9][1]


def test_counter_range_quantum_at_27_c_is_about_7_mm() -> None:
    quantum_m = speed_of_sound_from_temperature_mps(PAPER_TEMPERATURE_C) * COUNTER_TICK_S
    assert quantum_m == pytest.approx(6.946e-3, abs=2e-6)


@settings(max_examples=200, deadline=None)
@given(
    x=st.floats(-1.5, 1.5),
    y=st.floats(-1.5, 1.5),
    z=st.floats(-2.5, -0.5),
    heading=st.floats(-math.pi, math.pi),
)
def test_counter_truncation_alone_gives_bounded_deterministic_error(
    x: float, y: float, z: float, heading: float
) -> None:
    # Truncation makes each distance short by e in (-q, 0], q = c * 20 us. By eq. (7),
    # x_meas - x = [(2 d0 e0 + e0^2) - (2 d1 e1 + e1^2)] / (2a), and 2 d e + e^2 lies in
    # (-(2 d q - q^2), 0], so x_meas - x lies in (-(2 d0 q - q^2), 2 d1 q - q^2) / (2a);
    # likewise y with d2 (eq. (8)).
    q = speed_of_sound_from_temperature_mps(PAPER_TEMPERATURE_C) * COUNTER_TICK_S
    receivers = _receivers_xyz(x, y, z, heading, OFFSETS_PAPER)
    true_distances = _distances(receivers, transmitter_positions(A_PAPER))
    measured = _counter_distances(true_distances, None, 0.0)
    result = localize(measured, A_PAPER, OFFSETS_PAPER)
    assert result == localize(_counter_distances(true_distances, None, 0.0), A_PAPER, OFFSETS_PAPER)
    if result.fix is None:
        # Far off-axis and high up, the x, y errors (up to d q / a each, see below) can shift
        # d0^2 - x^2 - y^2 of eq. (9) by more than the receiver's z^2: then no point exists.
        assert result.status == "inconsistent_distances"
        e = float(true_distances.max()) * q / A_PAPER
        shift = 2 * true_distances[:, 0] * q + 2 * (np.abs(receivers[:, :2]) * e + e * e).sum(1)
        assert np.any(receivers[:, 2] ** 2 <= shift), "eq. (9) lost its root with margin left"
        return
    slack = 1e-12
    for receiver, d, estimate in zip(
        receivers, true_distances, result.fix.receiver_array, strict=True
    ):
        error = estimate - receiver
        lower_x, upper_x = -(2 * d[0] * q - q * q), 2 * d[1] * q - q * q
        lower_y, upper_y = -(2 * d[0] * q - q * q), 2 * d[2] * q - q * q
        assert lower_x / (2 * A_PAPER) - slack <= error[0] <= upper_x / (2 * A_PAPER) + slack
        assert lower_y / (2 * A_PAPER) - slack <= error[1] <= upper_y / (2 * A_PAPER) + slack


def test_counter_truncation_bound_is_nearly_attained() -> None:
    # Over many positions the fractional ticks of d0 and d1 fill the unit square, so the
    # extreme errors approach the bound max(d0, d1) q / a (6.7 cm at the paper's 1.9 m).
    q = speed_of_sound_from_temperature_mps(PAPER_TEMPERATURE_C) * COUNTER_TICK_S
    transmitters = transmitter_positions(A_PAPER)
    ratios = []
    for x in np.linspace(-0.3, 0.3, 61):
        for y in np.linspace(-0.3, 0.3, 61):
            receiver = np.array([[x, y, -1.9]])
            d = _distances(receiver, transmitters)[0]
            estimate = receiver_position(_counter_distances(d[None, :], None, 0.0)[0], A_PAPER)
            bound = (2 * max(d[0], d[1]) * q - q * q) / (2 * A_PAPER)
            ratios.append(abs(estimate[0] - x) / bound)
    assert max(ratios) <= 1.0 + 1e-9
    assert max(ratios) >= 0.9


# --------------------------------------------------------------------------------------------
# Statuses: never NaN
# --------------------------------------------------------------------------------------------


def _assert_no_nan(result: TransmitterLocalization) -> None:
    assert result.pose is None and result.fix is None
    if result.position_3d is not None:
        assert all(math.isfinite(v) for v in result.position_3d)


def test_inconsistent_distances_status() -> None:
    distances = np.array([[0.1, 0.3, 0.3], [1.9, 1.9, 1.9]])
    result = localize(distances, A_PAPER, OFFSETS_PAPER)
    assert result.status == "inconsistent_distances"
    assert result.position_3d is None
    _assert_no_nan(result)


@pytest.mark.parametrize("missing", [math.nan, math.inf])
def test_missing_distance_status(missing: float) -> None:
    receivers = _receivers_xyz(0.0, 0.0, -1.9, 0.0, OFFSETS_PAPER)
    distances = _distances(receivers, transmitter_positions(A_PAPER))
    distances[1, 2] = missing
    result = localize(distances, A_PAPER, OFFSETS_PAPER)
    assert result.status == "missing_distance"
    assert "receiver 1, transmitter 2" in result.message
    _assert_no_nan(result)


# --------------------------------------------------------------------------------------------
# Least squares beside the closed form
# --------------------------------------------------------------------------------------------


@settings(max_examples=50, deadline=None)
@given(
    x=st.floats(-2.0, 2.0),
    y=st.floats(-2.0, 2.0),
    z=st.floats(-2.5, -0.5),
    seed=st.integers(0, 2**32 - 1),
)
def test_least_squares_equals_closed_form_with_three_transmitters(
    x: float, y: float, z: float, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    transmitters = transmitter_positions(A_PAPER)
    d = np.linalg.norm(np.array([x, y, z]) - transmitters, axis=1) + rng.normal(0, 1e-3, 3)
    try:
        closed = receiver_position(d, A_PAPER)
    except InconsistentDistances:
        return
    fitted = receiver_position_least_squares(d, transmitters[:, :2])
    np.testing.assert_allclose(fitted, closed, atol=1e-7)


def test_least_squares_over_more_transmitters_beats_closed_form_on_noise() -> None:
    rng = np.random.default_rng(11)
    extra = np.array([[A_PAPER, A_PAPER], [-A_PAPER, 0.0], [0.0, -A_PAPER]])
    transmitters = np.vstack([transmitter_positions(A_PAPER), np.column_stack([extra, [0, 0, 0]])])
    errors = {"closed_form": [], "least_squares": []}
    for _ in range(200):
        x, y = rng.uniform(-0.5, 0.5, size=2)
        heading = rng.uniform(-math.pi, math.pi)
        receivers = _receivers_xyz(x, y, -1.9, heading, OFFSETS_PAPER)
        noisy = _distances(receivers, transmitters) + rng.normal(0.0, 2e-3, size=(2, 6))
        for solver in errors:
            result = localize(
                noisy, A_PAPER, OFFSETS_PAPER, solver=solver, extra_transmitter_xy=extra
            )
            if result.fix is not None:
                errors[solver].append(np.linalg.norm(result.fix.position - [x, y, -1.9]))
    assert len(errors["least_squares"]) == 200
    rms = {solver: math.sqrt(np.mean(np.square(e))) for solver, e in errors.items()}
    assert rms["least_squares"] < 0.7 * rms["closed_form"]


def test_least_squares_recovers_exact_pose_with_extra_transmitters() -> None:
    extra = np.array([[1.0, 1.0], [-0.5, 0.7]])
    transmitters = np.vstack([transmitter_positions(0.3), np.column_stack([extra, [0, 0]])])
    receivers = _receivers_xyz(0.4, -0.9, -2.1, 2.9, OFFSETS_PAPER)
    result = localize(
        _distances(receivers, transmitters),
        0.3,
        OFFSETS_PAPER,
        solver="least_squares",
        extra_transmitter_xy=extra,
    )
    assert result.fix is not None
    np.testing.assert_allclose(result.fix.position, [0.4, -0.9, -2.1], atol=1e-9)
    assert abs(angle_difference(result.fix.heading, 2.9)) < 1e-9


# --------------------------------------------------------------------------------------------
# Bad arguments
# --------------------------------------------------------------------------------------------

GOOD_DISTANCES = np.full((2, 3), 1.9)


@pytest.mark.parametrize("a", [0.0, -0.2, math.nan, math.inf])
def test_bad_spacing_raises(a: float) -> None:
    with pytest.raises(ValueError, match="^a must"):
        localize(GOOD_DISTANCES, a, OFFSETS_PAPER)
    with pytest.raises(ValueError, match="^a must"):
        receiver_position([1.9, 1.9, 1.9], a)


@pytest.mark.parametrize(
    "distances", [np.full((2, 2), 1.9), np.full(3, 1.9), np.full((0, 3), 1.9), np.full((2, 4), 1.9)]
)
def test_bad_distance_shape_raises(distances: np.ndarray) -> None:
    with pytest.raises(ValueError, match="^distances"):
        localize(distances, A_PAPER, OFFSETS_PAPER[: max(1, len(distances))])


def test_negative_distance_raises() -> None:
    with pytest.raises(ValueError, match="^distances"):
        localize(np.array([[1.9, -1.9, 1.9], [1.9, 1.9, 1.9]]), A_PAPER, OFFSETS_PAPER)
    with pytest.raises(ValueError, match="^d must"):
        receiver_position([1.9, -1.9, 1.9], A_PAPER)


@pytest.mark.parametrize(
    "offsets", [np.zeros((3, 2)), np.zeros((2, 3)), [[0.0, math.nan], [0.0, 0.1]]]
)
def test_bad_receiver_offsets_raise(offsets: object) -> None:
    with pytest.raises(ValueError, match="^receiver_offsets"):
        localize(GOOD_DISTANCES, A_PAPER, offsets)  # type: ignore[arg-type]


@pytest.mark.parametrize("z_sign", [0, 2, -0.5, True])
def test_bad_z_sign_raises(z_sign: object) -> None:
    with pytest.raises(ValueError, match="^z_sign"):
        localize(GOOD_DISTANCES, A_PAPER, OFFSETS_PAPER, z_sign=z_sign)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="^z_sign"):
        receiver_position([1.9, 1.9, 1.9], A_PAPER, z_sign=z_sign)  # type: ignore[arg-type]


def test_bad_receiver_shape_and_solver_raise() -> None:
    with pytest.raises(ValueError, match="^d must"):
        receiver_position([1.9, 1.9], A_PAPER)
    with pytest.raises(ValueError, match="^solver"):
        localize(GOOD_DISTANCES, A_PAPER, OFFSETS_PAPER, solver="magic")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="^p_front"):
        heading_from_receivers([0.0], [0.0, 0.0])
    with pytest.raises(ValueError, match="p_front and p_back"):
        heading_from_receivers([0.1, 0.2, -1.0], [0.1, 0.2, -1.5])
    with pytest.raises(ValueError, match="^transmitter_xy"):
        receiver_position_least_squares([1.0, 1.0, 1.0], [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
