"""The servo-swept sonar of Kim et al. and the side sonars of APCS."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.pose import Pose
from sonar_gym.sonar import pulse_echo
from sonar_gym.sonar.acoustics import PistonBeam
from sonar_gym.sonar.presets import PRESET_NAMES, preset
from sonar_gym.sonar.pulse_echo import IDEAL_READOUT, FirstEchoes
from sonar_gym.sonar.rotating import RotatingSonar
from sonar_gym.sonar.swept import (
    APCS_SAMPLE_SPACING_M,
    APCS_SPEED_MPS,
    SideSonars,
    SweptSonar,
)
from tests.sonar.worlds import cluttered_room, degrees, world


def corridor(**tables):
    return world(room={"min": [0.0, -0.9], "max": [10.0, 1.3]}, robot={"radius": 0.2}, **tables)


def test_kim_sweep_covers_plus_minus_45_degrees_inclusive() -> None:
    sweep = SweptSonar.kim()
    np.testing.assert_array_equal(degrees(sweep.sweep_angles()), np.arange(-45, 46, 5))
    np.testing.assert_array_equal(
        degrees(SweptSonar.kim(wide=True).sweep_angles()), np.arange(-90, 91, 5)
    )
    np.testing.assert_array_equal(
        degrees(sweep.sweep_angles(math.radians(30))), np.arange(-15, 76, 5)
    )
    assert sweep.transducer.name == "srf04"


def test_sweep_matches_a_pan_over_the_same_angles() -> None:
    test_world = cluttered_room()
    sweep = SweptSonar.kim(readout=IDEAL_READOUT)
    pose = Pose(0.3, 0.4, 1.0)
    scan = sweep.sweep(test_world, pose, None)
    pan = RotatingSonar(sweep.transducer, readout=IDEAL_READOUT).pan(
        test_world, pose, -math.pi / 4, math.pi / 4 + 1e-9, math.radians(5), None
    )
    np.testing.assert_allclose(scan.ranges, pan.ranges, atol=1e-12)
    t = sweep.transducer
    assert scan.duration_s == pytest.approx(
        math.radians(90) / t.pan_speed_rad_s + 19 * t.listen_time_s
    )


@pytest.mark.parametrize("sector", [0.0, math.pi / 2.0, -math.pi / 2.0, math.pi])
def test_sweep_readings_are_the_sweep_without_its_scan(sector: float) -> None:
    test_world = cluttered_room()
    sweep = SweptSonar.kim()
    grid = sweep.sweep_grid(sector)
    for seed, pose in enumerate([Pose(0.3, 0.4, 1.0), Pose(-0.2, 0.1, -2.5), Pose(0.0, 0.0, 0.0)]):
        scan = sweep.sweep(test_world, pose, np.random.default_rng(seed), sector)
        angles, ranges, amplitudes, duration = sweep.sweep_readings(
            test_world, pose, np.random.default_rng(seed), grid
        )
        assert angles is grid[0] and not angles.flags.writeable
        np.testing.assert_array_equal(angles, scan.angles)
        np.testing.assert_array_equal(ranges, scan.ranges)
        np.testing.assert_array_equal(amplitudes, scan.amplitudes)
        assert duration == scan.duration_s
    with pytest.raises(ValueError, match="sector_center"):
        sweep.sweep_grid(math.nan)


def test_a_sensor_point_as_floats_pings_as_the_same_point_as_an_array() -> None:
    """The sweep and the pan hand ``ping`` their sensor point as a pair of floats; an array of
    it (the form they handed before) gives the same candidates and readings, bit for bit."""
    test_world = cluttered_room()
    sweep = SweptSonar.kim()
    directions = sweep.sweep_grid(0.3)[1]
    for seed, pose in enumerate([Pose(0.3, 0.4, 1.0), Pose(-0.2, 0.1, -2.5)]):
        c, s = math.cos(pose.theta), math.sin(pose.theta)
        point = (pose.x + c * 0.05 - s * 0.01, pose.y + s * 0.05 + c * 0.01)
        readings = []
        for sensor_xy in (point, np.array(point)):
            pulse_echo._LAST_CANDIDATES.clear()  # search afresh for each form
            readings.append(
                sweep.ping(test_world, pose, sensor_xy, directions, np.random.default_rng(seed))
            )
        for got, want in zip(readings[0], readings[1], strict=True):
            assert got.tobytes() == want.tobytes()


def test_sweep_sees_the_wall_ahead_at_its_perpendicular_distance() -> None:
    test_world = world(room={"min": [-1.0, -1.0], "max": [1.5, 1.0]}, robot={"radius": 0.1})
    scan = SweptSonar.kim(readout=IDEAL_READOUT).sweep(test_world, Pose(0.0, 0.0, 0.0), None)
    assert scan.ranges[9] == pytest.approx(1.5, abs=1e-12)


def test_bad_sweep_arguments_raise() -> None:
    sweep = SweptSonar.kim()
    with pytest.raises(ValueError, match="step_rad"):
        SweptSonar(sweep.transducer, step_rad=0.0)
    with pytest.raises(ValueError, match="half_sweep_rad"):
        SweptSonar(sweep.transducer, half_sweep_rad=4.0)


def test_side_sonars_read_the_perpendicular_distance_to_parallel_walls() -> None:
    sonars = SideSonars.apcs(readout=IDEAL_READOUT)
    left, right = sonars.read(corridor(), Pose(3.0, 0.0, 0.0), None)
    assert (left, right) == (pytest.approx(1.3, abs=1e-12), pytest.approx(0.9, abs=1e-12))
    left, right = sonars.read(corridor(), Pose(3.0, 0.2, math.pi), None)
    assert (left, right) == (pytest.approx(1.1, abs=1e-12), pytest.approx(1.1, abs=1e-12))


def test_side_sonars_mounted_off_centre_measure_from_the_sensor() -> None:
    sonars = SideSonars.apcs(readout=IDEAL_READOUT, lateral_offset_m=0.15)
    left, right = sonars.read(corridor(), Pose(3.0, 0.0, 0.0), None)
    assert (left, right) == (pytest.approx(1.15, abs=1e-12), pytest.approx(0.75, abs=1e-12))


def test_sampling_along_a_path_every_3_cm_at_30_cm_per_second() -> None:
    assert pytest.approx(0.1) == APCS_SAMPLE_SPACING_M / APCS_SPEED_MPS
    sonars = SideSonars.apcs(readout=IDEAL_READOUT)
    test_world = corridor(walls=[{"a": [4.0, 0.8], "b": [5.0, 0.8]}])
    poses = [Pose(x, 0.0, 0.0) for x in np.arange(3.0, 6.0, APCS_SAMPLE_SPACING_M)]
    samples = sonars.sample_along(test_world, poses, None)
    np.testing.assert_allclose(samples.right_m, 0.9, atol=1e-12)
    on_board = np.array([4.0 < pose.x < 5.0 for pose in poses])
    np.testing.assert_allclose(samples.left_m[on_board], 0.8, atol=1e-12)
    for pose, left, right in zip(poses, samples.left_m, samples.right_m, strict=True):
        assert (left, right) == pytest.approx(sonars.read(test_world, pose, None), nan_ok=True)


def test_side_samples_are_seeded_noisy_and_quantised() -> None:
    sonars = SideSonars.apcs()
    poses = [Pose(x, 0.0, 0.0) for x in np.arange(3.0, 4.0, 0.03)]
    first = sonars.sample_along(corridor(), poses, np.random.default_rng(2))
    again = sonars.sample_along(corridor(), poses, np.random.default_rng(2))
    np.testing.assert_array_equal(first.left_m, again.left_m)
    assert np.std(first.right_m) > 0
    quantum = sonars.transducer.range_quantum_m(sonars.assumed_speed_of_sound_mps)
    counts = first.right_m / quantum
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-6)
    assert np.all(np.abs(first.right_m - 0.9) < 0.02)


def test_no_poses_no_samples() -> None:
    samples = SideSonars.apcs().sample_along(corridor(), [], np.random.default_rng(0))
    assert samples.left_m.shape == (0,) and samples.right_m.shape == (0,)


def test_bad_side_offset_raises() -> None:
    with pytest.raises(ValueError, match="lateral_offset_m"):
        SideSonars.apcs(lateral_offset_m=-0.1)


def test_reading_a_prefix_of_echoes_gives_the_readings_and_draws_of_those_poses() -> None:
    sonars = SideSonars.apcs()
    test_world = corridor(walls=[{"a": [3.2, 0.8], "b": [3.6, 0.8]}])
    poses = np.array([[x, 0.05 * math.sin(x), 0.01 * x] for x in np.arange(3.0, 4.0, 0.03)])
    echoes = sonars.first_echoes_along(test_world, poses)
    kept = 11
    prefix_rng, direct_rng = np.random.default_rng(5), np.random.default_rng(5)
    prefix = sonars.read_echoes(
        test_world,
        FirstEchoes(
            echoes.detected[: 2 * kept],
            echoes.path_lengths[: 2 * kept],
            echoes.amplitudes[: 2 * kept],
        ),
        prefix_rng,
    )
    direct = sonars.sample_along(test_world, poses[:kept], direct_rng)
    np.testing.assert_array_equal(prefix.left_m, direct.left_m)
    np.testing.assert_array_equal(prefix.right_m, direct.right_m)
    assert prefix_rng.random() == direct_rng.random()  # both streams left in the same state


@pytest.mark.parametrize("side", ["left", "right"])
def test_one_named_side_reads_what_it_reads_beside_the_other(side: str) -> None:
    sonars = SideSonars.apcs()
    test_world = corridor(walls=[{"a": [3.2, 0.8], "b": [3.6, 0.8]}])
    poses = np.array([[x, 0.05 * math.sin(x), 0.01 * x] for x in np.arange(3.0, 4.0, 0.03)])
    alone_rng, both_rng = np.random.default_rng(4), np.random.default_rng(4)
    alone = sonars.sample_along(test_world, poses, alone_rng, sides=(side,))
    both = sonars.sample_along(test_world, poses, both_rng)
    other = "right" if side == "left" else "left"
    named = getattr(alone, f"{side}_m")
    assert np.isfinite(named).mean() > 0.9
    np.testing.assert_array_equal(named, getattr(both, f"{side}_m"))
    assert np.all(np.isnan(getattr(alone, f"{other}_m")))
    assert alone_rng.random() == both_rng.random()  # the other side's noise was drawn too
    none = sonars.sample_along(test_world, poses, np.random.default_rng(4), sides=())
    assert np.all(np.isnan(none.left_m)) and np.all(np.isnan(none.right_m))
    with pytest.raises(ValueError, match="sides"):
        sonars.sample_along(test_world, poses, None, sides=("up",))


@pytest.mark.parametrize("name", PRESET_NAMES)
@pytest.mark.parametrize("leakage", [0.0, 0.01])
def test_no_main_lobe_limit_is_wider_than_that_of_the_faintest_level(
    name: str, leakage: float
) -> None:
    transducer = preset(name)
    beam = PistonBeam.for_ka(transducer.wavenumber_ka(343.2), False, leakage)
    levels = np.concatenate([np.geomspace(1e-300, 10.0, 20_001), [1.0, 1.0 + 1e-12]])
    limits = beam.main_lobe_cos_limits(levels)
    widest = beam.widest_main_lobe_cos
    assert 0.0 < widest < 1.0
    assert np.all(limits >= widest)
    order = np.argsort(levels)
    assert np.all(np.diff(limits[order]) >= 0.0)  # the limit grows with the level
