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
