"""The rotating pan: the phenomena Beom & Cho work with, and the readout conventions."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from sonar_gym.pose import Pose
from sonar_gym.sonar.acoustics import (
    absorption_amplitude_factor,
    speed_of_sound_mps,
    two_way_pattern,
)
from sonar_gym.sonar.echoes import plane_echo_amplitude
from sonar_gym.sonar.presets import polaroid_6500
from sonar_gym.sonar.pulse_echo import IDEAL_READOUT, Readout
from sonar_gym.sonar.rotating import RotatingSonar, pan_angles
from tests.sonar.worlds import beom_cho_room, cluttered_room, degrees, world

FULL_PAN = (-math.pi, math.pi, math.radians(1.0))


def polaroid(**options) -> RotatingSonar:
    return RotatingSonar.preset("polaroid-6500", **options)


def constant_gain_piston(**options) -> RotatingSonar:
    """The Polaroid as an ideal piston with constant receiver gain (same threshold)."""
    return RotatingSonar(polaroid_6500(time_varying_gain=False, side_lobe_leakage=0.0), **options)


def rcd_extent_deg(scan, echo_range: float, tolerance: float = 0.03) -> float:
    """eta = beta_e - beta_s over the consecutive pings reading ``echo_range`` (Beom & Cho)."""
    on = np.flatnonzero(np.abs(scan.ranges - echo_range) < tolerance)
    assert len(on) > 0 and np.all(np.diff(on) == 1), "the RCD must be one run of pings"
    return float(np.degrees(scan.angles[on[-1]] - scan.angles[on[0]]))


def test_full_pan_has_360_pings_from_minus_180_to_179_degrees() -> None:
    angles = pan_angles(*FULL_PAN)
    assert len(angles) == 360
    assert degrees(angles)[0] == -180 and degrees(angles)[-1] == 179


def test_sector_pan_includes_start_and_excludes_stop() -> None:
    np.testing.assert_array_equal(
        degrees(pan_angles(math.radians(-30), math.radians(30), math.radians(1))),
        np.arange(-30, 30),
    )
    np.testing.assert_array_equal(
        degrees(pan_angles(0.0, math.radians(10.5), math.radians(2))), [0, 2, 4, 6, 8, 10]
    )


@pytest.mark.parametrize(
    ("start", "stop", "increment", "name"),
    [
        (0.0, 1.0, 0.0, "increment"),
        (0.0, 1.0, -0.1, "increment"),
        (1.0, 1.0, 0.1, "start"),
        (1.0, 0.0, 0.1, "start"),
        (-4.0, 4.0, 0.1, "stop"),
        (math.nan, 1.0, 0.1, "start"),
    ],
)
def test_bad_pan_arguments_raise_naming_the_argument(start, stop, increment, name) -> None:
    with pytest.raises(ValueError, match=name):
        polaroid().pan(
            beom_cho_room(), Pose(0, 0), start, stop, increment, np.random.default_rng(0)
        )


def test_unknown_preset_raises() -> None:
    with pytest.raises(ValueError, match="name"):
        RotatingSonar.preset("sonar-9000")


def test_pan_duration_is_motion_plus_listening() -> None:
    sonar = polaroid()
    scan = sonar.pan(beom_cho_room(), Pose(0, 0), *FULL_PAN, np.random.default_rng(0))
    t = sonar.transducer
    assert scan.duration_s == pytest.approx(
        359 * math.radians(1) / t.pan_speed_rad_s + 360 * t.listen_time_s
    )


def test_walls_are_seen_only_near_normal_incidence_at_their_perpendicular_distance() -> None:
    test_world = world(room={"min": [-3.1, -2.5], "max": [3.1, 2.5]})
    sonar = polaroid(readout=IDEAL_READOUT)
    scan = sonar.pan(test_world, Pose(0.4, -0.3, 0.0), *FULL_PAN, np.random.default_rng(0))
    t = sonar.transducer
    ka = t.wavenumber_ka(speed_of_sound_mps(20.0))
    # (normal direction, perpendicular distance) of each wall from (0.4, -0.3).
    walls = [(0.0, 2.7), (90.0, 2.8), (180.0, 3.5), (-90.0, 2.2)]
    for normal_deg, distance in walls:
        on_axis = (
            plane_echo_amplitude(distance)
            * absorption_amplitude_factor(2 * distance, t.absorption_db_per_m)
            * t.time_varying_gain.gain(distance)
        )
        half_window = brentq(
            lambda x, amplitude=on_axis: (
                amplitude
                * two_way_pattern(x, ka, side_lobes=False, side_lobe_leakage=t.side_lobe_leakage)
                - t.detection_threshold
            ),
            0.0,
            math.pi / 2 - 1e-9,
        )
        # Heard through the leakage beyond the first null (12.6 deg), never beyond 30 deg.
        assert 26.0 < 2 * math.degrees(half_window) < 60.0
        off_axis = np.abs((np.degrees(scan.angles) - normal_deg + 180.0) % 360.0 - 180.0)
        inside = off_axis < math.degrees(half_window) - 0.01
        np.testing.assert_allclose(scan.ranges[inside], distance, atol=1e-9)
        reads_wall = np.abs(scan.ranges - distance) < 1e-9
        assert not np.any(reads_wall & (off_axis > math.degrees(half_window) + 0.01))


def test_ranges_are_the_perpendicular_distance_within_a_quantum_and_noise() -> None:
    test_world = world(room={"min": [-3.1, -2.5], "max": [3.1, 2.5]})
    scan = polaroid().pan(
        test_world,
        Pose(0.0, 0.0, 0.0),
        math.radians(-5),
        math.radians(6),
        math.radians(1),
        np.random.default_rng(4),
    )
    quantum = polaroid().transducer.range_quantum_m(343.2)
    assert np.all(np.abs(scan.ranges - 3.1) < quantum + 4 * 0.002)


def test_beacon_rcds_have_the_angular_extents_of_table_2() -> None:
    scan = polaroid().pan(beom_cho_room(), Pose(0.0, 0.0, 0.0), *FULL_PAN, np.random.default_rng(1))
    small = rcd_extent_deg(scan, math.hypot(2.85, -0.6) - 0.0191)
    large = rcd_extent_deg(scan, math.hypot(0.3, -1.5) - 0.07)
    assert small == pytest.approx(22.0, abs=1e-9)  # Table II: 22.0
    assert large == pytest.approx(24.0, abs=2.0)  # Table II: 24.0
    assert 18.0 <= small < large <= 26.0


@settings(max_examples=20, deadline=None)
@given(st.floats(0.0, 1.0))
def test_small_beacon_spans_22_degrees_at_any_phase_of_the_ping_grid(phase_deg: float) -> None:
    scan = polaroid().pan(
        beom_cho_room(),
        Pose(0.0, 0.0, math.radians(phase_deg)),
        *FULL_PAN,
        np.random.default_rng(2),
    )
    assert rcd_extent_deg(scan, math.hypot(2.85, -0.6) - 0.0191) == pytest.approx(22.0, abs=1e-9)


def test_rcd_edges_read_long_with_the_threshold_crossing_delay() -> None:
    sonar = polaroid(readout=Readout(range_noise=False, quantisation=False))
    scan = sonar.pan(beom_cho_room(), Pose(0.0, 0.0, 0.0), *FULL_PAN, np.random.default_rng(0))
    echo_range = math.hypot(2.85, -0.6) - 0.0191
    on = np.flatnonzero(np.abs(scan.ranges - echo_range) < 0.03)
    excess = scan.ranges[on] - echo_range
    assert np.all(excess > 0)
    centre = int(np.argmin(excess))
    assert excess[0] > excess[centre] and excess[-1] > excess[centre]
    assert excess.max() <= sonar.transducer.echo_rise_time_s * 343.3 / 2


def test_a_box_in_front_of_a_cylinder_removes_its_echo_from_the_scan() -> None:
    cylinder = {"center": [2.0, 0.0], "radius": 0.05}
    room = {"min": [-3, -3], "max": [3, 3]}
    clear = polaroid(readout=IDEAL_READOUT).pan(
        world(room=room, cylinders=[cylinder]), Pose(0, 0), *FULL_PAN, None
    )
    hidden = polaroid(readout=IDEAL_READOUT).pan(
        world(room=room, cylinders=[cylinder], boxes=[{"center": [1.0, 0.0], "size": [0.1, 0.5]}]),
        Pose(0, 0),
        *FULL_PAN,
        None,
    )
    assert np.any(np.abs(clear.ranges - 1.95) < 1e-9)
    assert not np.any(np.abs(hidden.ranges - 1.95) < 1e-9)


CORNER_WORLD = {"walls": [{"a": [2.0, -2.0], "b": [2.0, 0.0]}, {"a": [2.0, 0.0], "b": [0.0, 0.0]}]}
EDGE_BOX = {"center": [2.0 + 0.2 * math.sqrt(2), 0.0], "size": [0.4, 0.4], "angle_deg": 45.0}


@pytest.mark.parametrize(
    "sonar", [polaroid(readout=IDEAL_READOUT), constant_gain_piston(readout=IDEAL_READOUT)]
)
def test_a_corner_echoes_like_a_wall(sonar: RotatingSonar) -> None:
    pose = Pose(1.6, -0.4, 0.0)  # looking at the corner (2, 0) from inside its wedge
    bearing = math.atan2(0.4, 0.4)
    corner = sonar.pan(
        world(**CORNER_WORLD), pose, bearing - 0.5, bearing + 0.5, math.radians(0.25), None
    )
    r = math.hypot(0.4, 0.4)
    t = sonar.transducer
    gain = 1.0 if t.time_varying_gain is None else float(t.time_varying_gain.gain(r))
    expected = plane_echo_amplitude(r) * absorption_amplitude_factor(2 * r, t.absorption_db_per_m)
    assert corner.amplitudes.max() == pytest.approx(expected * gain, rel=1e-3)


def test_with_constant_gain_an_edge_is_weak_and_narrower_than_a_corner() -> None:
    corner_world = world(**CORNER_WORLD)
    edge_world = world(boxes=[EDGE_BOX])
    sonar = constant_gain_piston(readout=IDEAL_READOUT)
    pose = Pose(1.6, -0.4, 0.0)  # looking at the corner (2, 0) from inside its wedge
    bearing = math.atan2(0.4, 0.4)
    corner = sonar.pan(corner_world, pose, bearing - 0.5, bearing + 0.5, math.radians(0.25), None)
    r = math.hypot(0.4, 0.4)
    edge_pose = Pose(2.0 - r, 0.0, 0.0)  # the box's corner (2, 0) at the same distance
    edge = sonar.pan(edge_world, edge_pose, -0.5, 0.5, math.radians(0.25), None)
    assert edge.amplitudes.max() < corner.amplitudes.max() / 1000  # over 60 dB weaker
    corner_width = np.count_nonzero(np.abs(corner.ranges - r) < 1e-9)
    edge_width = np.count_nonzero(np.abs(edge.ranges - r) < 1e-9)
    assert 0 < edge_width < corner_width


def test_a_hot_room_reads_short_by_the_ratio_of_the_speeds() -> None:
    sonar = polaroid(readout=IDEAL_READOUT)  # assumes 20 deg C
    cold = sonar.pan(beom_cho_room(20.0), Pose(0, 0), *FULL_PAN, None)
    hot = sonar.pan(beom_cho_room(40.0), Pose(0, 0), *FULL_PAN, None)
    # The middles of the two beacons' RCDs (the beam widens a little in warmer air, so the
    # RCD ends may move by a ping).
    middles = np.r_[180 - 20 : 180 - 4, 180 - 86 : 180 - 71]
    ratio = speed_of_sound_mps(20.0) / speed_of_sound_mps(40.0)
    np.testing.assert_allclose(hot.ranges[middles] / cold.ranges[middles], ratio, rtol=1e-12)


def test_calibration_estimates_the_speed_within_half_a_percent_and_removes_the_bias() -> None:
    rng = np.random.default_rng(11)
    hot = beom_cho_room(40.0)
    sonar = polaroid()
    result = sonar.calibrate(hot, Pose(0, 0), rng)
    assert result.estimated_speed_mps == pytest.approx(speed_of_sound_mps(40.0), rel=0.005)
    assert result.tof_s == pytest.approx(2 * 0.515 / result.estimated_speed_mps, rel=1e-12)
    assert result.duration_s > 5 * sonar.transducer.listen_time_s

    quantum = sonar.transducer.range_quantum_m(speed_of_sound_mps(40.0))
    truth = math.hypot(2.85, -0.6) - 0.0191
    biased = sonar.pan(hot, Pose(0, 0), *FULL_PAN, rng)
    calibrated = sonar.with_assumed_speed(result.estimated_speed_mps).pan(
        hot, Pose(0, 0), *FULL_PAN, rng
    )
    on_beacon = slice(180 - 20, 180 - 4)  # -20 ... -5 deg, the middle of the small beacon's RCD
    assert truth - np.mean(biased.ranges[on_beacon]) > 0.08  # about 3 % short
    assert abs(np.mean(calibrated.ranges[on_beacon]) - truth) < quantum + 0.004


def test_plain_count_reading_of_the_calibration_is_biased_by_half_a_period() -> None:
    sonar = polaroid(readout=Readout(range_noise=False, crossing_delay=False))
    test_world = beom_cho_room(25.0)
    centred = sonar.calibrate(test_world, Pose(0, 0), None, n_pings=3)
    floor = sonar.calibrate(test_world, Pose(0, 0), None, n_pings=3, count_reading="floor")
    assert centred.tof_s - floor.tof_s == pytest.approx(
        sonar.transducer.timer_period_s / 2, rel=1e-9
    )
    true_tof = 2 * 0.515 / speed_of_sound_mps(25.0)
    assert abs(centred.tof_s - true_tof) <= sonar.transducer.timer_period_s / 2


def test_bad_calibration_arguments_raise() -> None:
    with pytest.raises(ValueError, match="n_pings"):
        polaroid().calibrate(beom_cho_room(), Pose(0, 0), np.random.default_rng(0), n_pings=0)
    with pytest.raises(ValueError, match="count_reading"):
        polaroid().calibrate(
            beom_cho_room(), Pose(0, 0), np.random.default_rng(0), count_reading="round"
        )


@pytest.mark.parametrize("readout", [Readout(range_noise=False), Readout()])
def test_ranges_are_whole_counts_of_the_range_quantum(readout: Readout) -> None:
    sonar = polaroid(readout=readout)
    scan = sonar.pan(cluttered_room(), Pose(0.3, 0.2, 0.1), *FULL_PAN, np.random.default_rng(5))
    counts = scan.ranges[scan.detected] / sonar.transducer.range_quantum_m(
        sonar.assumed_speed_of_sound_mps
    )
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-6)


def test_same_seed_same_scan_and_nan_only_in_ranges() -> None:
    sonar = polaroid()
    first = sonar.pan(cluttered_room(), Pose(0.3, 0.2, 0.1), *FULL_PAN, np.random.default_rng(9))
    second = sonar.pan(cluttered_room(), Pose(0.3, 0.2, 0.1), *FULL_PAN, np.random.default_rng(9))
    np.testing.assert_array_equal(first.ranges, second.ranges)
    np.testing.assert_array_equal(first.amplitudes, second.amplitudes)
    assert not np.any(np.isnan(first.amplitudes)) and not np.any(np.isnan(first.angles))
    assert np.all(first.amplitudes[~first.detected] == 0.0)
    assert np.all(first.amplitudes[first.detected] >= sonar.transducer.detection_threshold)
    assert 0 < first.detected.sum() < 360
    assert np.all(first.ranges[first.detected] <= sonar.transducer.max_range_m)


def test_echoes_beyond_the_maximum_range_are_dropouts() -> None:
    far = world(walls=[{"a": [4.5, -3.0], "b": [4.5, 3.0]}])
    scan = polaroid().pan(far, Pose(0, 0), -0.2, 0.2, math.radians(1), np.random.default_rng(0))
    assert np.all(np.isnan(scan.ranges))


def test_sensor_offset_moves_the_pan_axis() -> None:
    test_world = world(
        walls=[{"a": [2.0, -3.0], "b": [2.0, 3.0]}],
        robot={"radius": 0.3, "sensor_offset": [0.2, 0.0]},
    )
    scan = polaroid(readout=IDEAL_READOUT).pan(
        test_world, Pose(0.0, 0.0, 0.0), -0.01, 0.01, 0.01, None
    )
    np.testing.assert_allclose(scan.ranges, 1.8, atol=1e-12)


def test_a_noisy_pan_without_a_random_generator_raises() -> None:
    with pytest.raises(ValueError, match="rng"):
        polaroid().pan(beom_cho_room(), Pose(0, 0), *FULL_PAN, None)


def test_with_constant_gain_an_edge_at_the_minimum_range_spans_less_than_the_18_degree_filter() -> (
    None
):
    box = world(
        boxes=[{"center": [0.3 + 0.2 * math.sqrt(2), 0.0], "size": [0.4, 0.4], "angle_deg": 45.0}]
    )
    sonar = constant_gain_piston(readout=IDEAL_READOUT)
    scan = sonar.pan(box, Pose(0.0, 0.0, 0.0), -0.5, 0.5, math.radians(0.1), None)
    on_edge = np.flatnonzero(np.abs(scan.ranges - 0.3) < 1e-9)
    assert 0 < np.degrees(scan.angles[on_edge[-1]] - scan.angles[on_edge[0]]) < 18.0


def test_sonars_pickle_and_compare_equal() -> None:
    sonar = polaroid().with_assumed_speed(350.0)
    assert pickle.loads(pickle.dumps(sonar)) == sonar
    scan = sonar.pan(beom_cho_room(), Pose(0, 0), *FULL_PAN, np.random.default_rng(0))
    again = pickle.loads(pickle.dumps(sonar)).pan(
        beom_cho_room(), Pose(0, 0), *FULL_PAN, np.random.default_rng(0)
    )
    np.testing.assert_array_equal(scan.ranges, again.ranges)
