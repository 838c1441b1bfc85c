"""The readings of all sweeps, gathered in one pass, are each sweep's own end points (sec. 3.3)."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.localization import kim
from sonar_gym.localization.kim import Sweep, sweep_end_points
from sonar_gym.pose import Pose
from tests.localization.test_kim import (
    MOVES,
    noisy_sweeps,
)


def _noisy_sweeps(truth: Pose, count: int, seed: int) -> list[Sweep]:
    return noisy_sweeps(truth, MOVES[:count], np.random.default_rng(seed), dropout_fraction=0.1)


@pytest.mark.parametrize("count", [1, 3])
@pytest.mark.parametrize("max_range_m", [None, 1.2])
def test_readings_of_all_sweeps_are_each_sweeps_end_points(
    count: int, max_range_m: float | None
) -> None:
    sweeps = _noisy_sweeps(Pose(0.93, 0.71, 0.4), count, seed=count)
    readings = kim._gather_readings(sweeps, max_range_m)
    sensors, ends, beams = zip(
        *(sweep_end_points(sweep, sweep.odometry, max_range_m) for sweep in sweeps), strict=True
    )
    expected_ends = np.concatenate(ends)
    assert np.array_equal(readings.end_xy, expected_ends)
    assert np.array_equal(readings.beam_rad, np.concatenate(beams))
    expected_ranges = np.linalg.norm(expected_ends - np.concatenate(sensors), axis=1)
    assert np.array_equal(readings.range_m, expected_ranges)


def test_an_unchecked_sweep_is_the_checked_one() -> None:
    angles = np.radians(np.arange(-45.0, 46.0, 1.0))
    ranges = np.where(np.arange(angles.size) % 7 == 0, np.nan, 0.3 + 0.01 * np.arange(angles.size))
    odometry = Pose(0.1, -0.05, 0.3)
    checked = Sweep(angles, ranges, (0.04, 0.0), odometry)
    unchecked = Sweep.unchecked(angles, ranges, (0.04, 0.0), odometry)
    assert np.array_equal(unchecked.angles, checked.angles)
    assert np.array_equal(unchecked.ranges, checked.ranges, equal_nan=True)
    assert unchecked.sensor_offset == checked.sensor_offset == (0.04, 0.0)
    assert unchecked.odometry == checked.odometry
    for array, source in ((unchecked.angles, angles), (unchecked.ranges, ranges)):
        assert not array.flags.writeable
        assert not np.shares_memory(array, source)  # a copy: the caller's array stays its own


def test_a_handed_over_sweep_is_the_checked_one_on_the_given_arrays() -> None:
    angles = np.radians(np.arange(-45.0, 46.0, 1.0))
    angles.setflags(write=False)  # as a sweep grid's angles are
    readings = np.empty((2, angles.size))  # ranges come as a row of the readings, as pinged
    readings[0] = np.where(
        np.arange(angles.size) % 7 == 0, np.nan, 0.3 + 0.01 * np.arange(angles.size)
    )
    ranges = readings[0]
    odometry = Pose(0.1, -0.05, 0.3)
    checked = Sweep(angles, ranges.copy(), (0.04, 0.0), odometry)
    handed = Sweep.handed_over(angles, ranges, np.array((0.04, 0.0)), odometry)
    assert handed.angles is angles and handed.ranges is ranges
    assert np.array_equal(handed.angles, checked.angles)
    assert np.array_equal(handed.ranges, checked.ranges, equal_nan=True)
    assert type(handed.sensor_offset[0]) is float
    assert handed.sensor_offset == checked.sensor_offset == (0.04, 0.0)
    assert handed.odometry == checked.odometry
    assert not handed.angles.flags.writeable and not handed.ranges.flags.writeable
    readings[1] = 1.0  # the other row stays the caller's
    sweeps = [handed, Sweep.unchecked(angles, ranges, (0.04, 0.0), Pose(0.2, 0.0, 0.1))]
    gathered = kim._gather_readings(sweeps, 0.7)
    expected = kim._gather_readings([checked, sweeps[1]], 0.7)
    for name in ("end_x", "end_y", "beam_rad", "range_m"):
        assert getattr(gathered, name).tobytes() == getattr(expected, name).tobytes()
