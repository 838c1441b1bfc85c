"""The compiled readings of Kim, Lee & Jeong's voting (sec. 3.3) against the array forms they
replaced: the same end points, ranges, beams and direction indices, bit for bit."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
import pytest

from sonar_gym.localization import kim
from sonar_gym.localization.kim import Sweep
from sonar_gym.pose import FloatArray, Pose
from tests.localization.test_kim import MOVES, noisy_sweeps


def reference_readings(sweeps: Sequence[Sweep], max_range_m: float | None) -> kim._Readings:
    """The array form: all sweeps' readings concatenated, masked, then moved in one pass."""
    angles = np.concatenate([sweep.angles for sweep in sweeps])
    ranges = np.concatenate([sweep.ranges for sweep in sweeps])
    counts = [sweep.ranges.size for sweep in sweeps]
    per_sweep = []
    for sweep in sweeps:
        pose = sweep.odometry
        offset_x, offset_y = sweep.sensor_offset
        c, s = math.cos(pose.theta), math.sin(pose.theta)
        per_sweep.append(
            (pose.theta, pose.x + c * offset_x - s * offset_y, pose.y + s * offset_x + c * offset_y)
        )
    valid = np.isfinite(ranges)
    if max_range_m is not None:
        valid &= ranges < max_range_m
    keep = np.flatnonzero(valid)
    ranges = ranges.take(keep)
    theta, from_x, from_y = np.repeat(np.array(per_sweep).T, counts, axis=1).take(keep, axis=1)
    beam = theta + angles.take(keep)
    end_x = from_x + ranges * np.cos(beam)
    end_y = from_y + ranges * np.sin(beam)
    run_x, run_y = end_x - from_x, end_y - from_y
    length = np.sqrt(run_x * run_x + run_y * run_y)
    return kim._Readings(end_x, end_y, beam, length)


def reference_direction_index(
    headings: FloatArray, beams: FloatArray, direction_bins: int
) -> npt.NDArray[np.intp]:
    """The array form of :func:`kim._direction_index`."""
    turns = (headings[:, None] + beams[None, :]) * (direction_bins / (2.0 * np.pi))
    return np.rint(turns).astype(np.intp) % direction_bins


def _same_bits(a: FloatArray, b: FloatArray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def _assert_same_readings(readings: kim._Readings, expected: kim._Readings) -> None:
    for name in ("end_x", "end_y", "beam_rad", "range_m"):
        assert _same_bits(getattr(readings, name), getattr(expected, name)), name


@pytest.mark.parametrize("count", [1, 2, 4])
@pytest.mark.parametrize("max_range_m", [None, 1.2, 0.8])
@pytest.mark.parametrize("seed", [0, 1])
def test_compiled_readings_are_the_array_forms(
    count: int, max_range_m: float | None, seed: int
) -> None:
    truth = Pose(0.93, 0.71, 0.4 + seed)
    sweeps = noisy_sweeps(truth, MOVES[:count], np.random.default_rng(seed), dropout_fraction=0.2)
    sweeps = [
        Sweep(sweep.angles, sweep.ranges, (0.04 * index, -0.01), sweep.odometry)
        for index, sweep in enumerate(sweeps)
    ]
    readings = kim._gather_readings(sweeps, max_range_m)
    _assert_same_readings(readings, reference_readings(sweeps, max_range_m))
    assert readings.range_m.size > 0


def test_readings_without_echoes_sweeps_of_one_reading_and_ranges_at_the_limit() -> None:
    angles = np.array([0.3])
    silent = Sweep(np.array([0.1, 0.2]), np.array([np.nan, np.inf]))
    at_limit = Sweep(angles, np.array([1.5]), (0.02, 0.0), Pose(0.1, 0.0, 0.2))
    below = Sweep(angles, np.array([math.nextafter(1.5, 0.0)]), (0.02, 0.0), Pose(0.1, 0.0, 0.2))
    empty = Sweep(np.array([]), np.array([]), (0.0, 0.0), Pose(0.2, 0.1, -0.3))
    for sweeps in ([silent], [silent, at_limit], [silent, below, empty], [empty, below]):
        for max_range_m in (None, 1.5):
            readings = kim._gather_readings(sweeps, max_range_m)
            _assert_same_readings(readings, reference_readings(sweeps, max_range_m))
    assert kim._gather_readings([silent, at_limit], 1.5).range_m.size == 0
    assert kim._gather_readings([silent, below], 1.5).range_m.size == 1


def test_compiled_direction_indices_are_the_array_forms() -> None:
    rng = np.random.default_rng(3)
    headings = kim.heading_candidates_around(3.1, math.radians(20.0), math.radians(1.0))
    beams = rng.uniform(-2.0 * np.pi, 2.0 * np.pi, 200)
    for bins in (8, 360, 361, 1000):
        expected = reference_direction_index(headings, beams, bins)
        readings = kim._Readings(beams, beams, beams, beams)
        assert np.array_equal(kim._direction_index(headings, readings, bins), expected)


def test_direction_indices_of_beams_several_turns_out_are_the_array_forms() -> None:
    rng = np.random.default_rng(4)
    headings = rng.uniform(-np.pi, np.pi, 7)
    beams = np.concatenate(
        [rng.uniform(-6.0 * np.pi, 6.0 * np.pi, 300), [-4.0 * np.pi, 2.0 * np.pi]]
    )
    for bins in (8, 360, 361):
        expected = reference_direction_index(headings, beams, bins)
        readings = kim._Readings(beams, beams, beams, beams)
        assert np.array_equal(kim._direction_index(headings, readings, bins), expected)


def test_direction_indices_round_half_to_even_and_wrap_negative_turns() -> None:
    bins = 8
    per_bin = 2.0 * np.pi / bins
    # turns of exactly k + 1/2 round to the even neighbour; negative turns wrap to [0, bins)
    beams = np.array([0.5, 1.5, 2.5, -0.5, -1.5, -7.5, 7.5, 0.0, -0.0]) * per_bin
    headings = np.array([0.0, -3.0 * per_bin])
    expected = reference_direction_index(headings, beams, bins)
    readings = kim._Readings(beams, beams, beams, beams)
    assert np.array_equal(kim._direction_index(headings, readings, bins), expected)
    empty = kim._Readings(*(np.array([]),) * 4)
    assert kim._direction_index(headings, empty, bins).shape == (2, 0)
