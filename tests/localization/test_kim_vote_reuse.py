"""The vote's shortcuts of sec. 3.3 give bit for bit what their slow references give."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization import kim
from sonar_gym.localization.kim import OccupancyGrid, Sweep, sweep_end_points, vote_localize
from sonar_gym.pose import Pose
from tests.localization.test_kim import (
    ARENA_BOUNDS,
    ARENA_CIRCLES,
    ARENA_SEGMENTS,
    MOVES,
    noisy_sweeps,
)


@pytest.fixture(scope="module")
def grid() -> OccupancyGrid:
    return OccupancyGrid.from_segments(ARENA_SEGMENTS, ARENA_CIRCLES, ARENA_BOUNDS, 0.05)


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


@pytest.mark.parametrize("anchor", ["cell_center", "obstacle_point"])
@pytest.mark.parametrize("radius", [None, 0.15, 0.5])
@pytest.mark.parametrize(
    "truth", [Pose(0.93, 0.71, 0.4), Pose(0.2, 0.25, -2.0)], ids=["middle", "near_corner"]
)
def test_mean_from_the_counted_votes_is_the_mean_of_the_votes_cast_again(
    grid: OccupancyGrid,
    monkeypatch: pytest.MonkeyPatch,
    anchor: str,
    radius: float | None,
    truth: Pose,
) -> None:
    """One block of headings reuses the chosen heading's counted votes for the mean position;
    with many blocks the chosen heading's votes are cast again (the reference)."""
    sweeps = _noisy_sweeps(truth, 2, seed=5)
    prior = Pose(truth.x + 0.04, truth.y - 0.03, truth.theta + math.radians(2.0))
    arguments = dict(
        search_center=prior,
        search_radius=radius,
        heading_window_rad=math.radians(8.0),
        anchor=anchor,
    )
    fast = vote_localize(grid, sweeps, **arguments)  # type: ignore[arg-type]
    recast: list[float] = []
    reference_mean = kim._mean_vote_position

    def counting_mean(*args, **kwargs):  # type: ignore[no-untyped-def]
        recast.append(1.0)
        return reference_mean(*args, **kwargs)

    monkeypatch.setattr(kim, "_mean_vote_position", counting_mean)
    monkeypatch.setattr(kim, "_CHUNK_ELEMENTS", 1)  # one heading per block
    slow = vote_localize(grid, sweeps, **arguments)  # type: ignore[arg-type]
    assert recast, "the reference path was not taken"
    assert fast.status == slow.status == "ok"
    assert fast.pose == slow.pose
    assert fast.votes == slow.votes
    assert fast.vote_map is not None and slow.vote_map is not None
    assert np.array_equal(fast.vote_map, slow.vote_map)
