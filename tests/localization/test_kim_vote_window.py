"""Counting votes only in the search circle's window of cells changes no result of sec. 3.3."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization import kim
from sonar_gym.localization.kim import OccupancyGrid, vote_localize
from sonar_gym.pose import Pose
from tests.localization.test_kim import (
    MOVES,
    _sweep,
    noisy_sweeps,
)


_CIRCLE_WINDOW = kim._vote_window


def _whole_grid(arena_grid, center, radius):  # type: ignore[no-untyped-def]
    """The slow reference: votes counted over every cell of the arena_grid."""
    return _CIRCLE_WINDOW(arena_grid, None, None)


@pytest.mark.parametrize("selection", ["smoothed", "max"])
@pytest.mark.parametrize("ambiguity_ratio", [None, 0.5])
@pytest.mark.parametrize("radius", [0.1, 0.3, 0.6])
@pytest.mark.parametrize(
    "truth", [Pose(0.93, 0.71, 0.4), Pose(0.2, 0.25, -2.0)], ids=["middle", "near_corner"]
)
def test_windowed_votes_give_the_result_of_the_whole_grid(
    arena_grid: OccupancyGrid,
    monkeypatch: pytest.MonkeyPatch,
    selection: str,
    ambiguity_ratio: float | None,
    radius: float,
    truth: Pose,
) -> None:
    sweeps = noisy_sweeps(truth, MOVES[:3], np.random.default_rng(11))
    prior = Pose(truth.x + 0.04, truth.y - 0.03, truth.theta + math.radians(2.0))
    arguments = dict(
        search_center=prior,
        search_radius=radius,
        heading_window_rad=math.radians(10.0),
        selection=selection,
        ambiguity_ratio=ambiguity_ratio,
        anchor="obstacle_point",
    )
    fast = vote_localize(arena_grid, sweeps, **arguments)  # type: ignore[arg-type]
    monkeypatch.setattr(kim, "_vote_window", _whole_grid)
    slow = vote_localize(arena_grid, sweeps, **arguments)  # type: ignore[arg-type]
    assert fast.status == slow.status
    assert fast.status in ("ok", "ambiguous")
    assert fast.pose == slow.pose
    assert fast.last_sweep_pose == slow.last_sweep_pose
    assert fast.votes == slow.votes
    assert fast.vote_map is not None and slow.vote_map is not None
    assert fast.vote_map.shape == arena_grid.shape
    assert np.array_equal(fast.vote_map, slow.vote_map)


def test_window_covers_the_search_circle_and_is_clipped_to_the_grid(
    arena_grid: OccupancyGrid,
) -> None:
    window = kim._vote_window(arena_grid, np.array([0.0, 1.0]), 0.3)
    (low_x, low_y), (wx, wy) = window.low, window.shape
    assert low_x == 0
    nx, ny = arena_grid.shape
    assert 0 < wx < nx and 0 < wy < ny
    inside = arena_grid.world_to_cell(np.array([[0.3, 1.0], [0.0, 0.7], [0.0, 1.3], [0.05, 1.0]]))
    assert np.all(inside[:, 0] >= low_x) and np.all(inside[:, 0] < low_x + wx)
    assert np.all(inside[:, 1] >= low_y) and np.all(inside[:, 1] < low_y + wy)
    assert kim._vote_window(arena_grid, None, None).shape == arena_grid.shape


def _no_heading_test(headings):  # type: ignore[no-untyped-def]
    """The slow reference: no pair dropped for its heading."""
    return None


@pytest.mark.parametrize("window_deg", [3.0, 30.0, 180.0])
@pytest.mark.parametrize("radius", [0.1, 0.35, 0.6])
@pytest.mark.parametrize("theta", [0.4, 3.1, -3.1])
def test_pairs_dropped_for_their_heading_never_vote(
    arena_grid: OccupancyGrid,
    monkeypatch: pytest.MonkeyPatch,
    window_deg: float,
    radius: float,
    theta: float,
) -> None:
    rng = np.random.default_rng(int(window_deg * 100 + radius * 10))
    truth = Pose(0.93, 0.71, theta)
    sweeps = noisy_sweeps(truth, MOVES[:2], rng, range_std_m=0.02)
    prior = Pose(truth.x - 0.05, truth.y + 0.04, truth.theta - math.radians(2.5))
    arguments = dict(
        search_center=prior,
        search_radius=radius,
        heading_window_rad=math.radians(window_deg),
        anchor="obstacle_point",
    )
    fast = vote_localize(arena_grid, sweeps, **arguments)  # type: ignore[arg-type]
    monkeypatch.setattr(kim, "_heading_spread", _no_heading_test)
    slow = vote_localize(arena_grid, sweeps, **arguments)  # type: ignore[arg-type]
    assert fast.status == slow.status == "ok"
    assert fast.pose == slow.pose
    assert fast.votes == slow.votes
    assert np.array_equal(fast.vote_map, slow.vote_map)


def test_heading_filter_drops_most_pairs_of_a_narrow_window(arena_grid: OccupancyGrid) -> None:
    truth = Pose(0.93, 0.71, 0.4)
    readings = kim._gather_readings([_sweep(truth)], None)
    anchors = arena_grid.occupied_obstacle_points()
    centre, radius = np.array([0.95, 0.7]), 0.1
    every_heading = np.radians(np.arange(-180.0, 180.0, 1.0))
    pairs = kim._candidate_pairs(readings, anchors, centre, radius, every_heading)
    headings = kim.heading_candidates_around(0.4, math.radians(5.0), math.radians(1.0))
    kept = kim._candidate_pairs(readings, anchors, centre, radius, headings)
    kept_set = set(zip(kept[0].tolist(), kept[1].tolist(), strict=True))
    assert len(kept_set) < pairs[0].size / 2
    for heading in headings:  # every pair whose vote lands inside is kept
        c, s = math.cos(heading), math.sin(heading)
        ends = readings.end_xy[pairs[0]] @ np.array([[c, s], [-s, c]])
        votes = anchors[pairs[1]] - ends
        inside = np.hypot(*(votes - centre).T) <= radius
        assert set(zip(pairs[0][inside].tolist(), pairs[1][inside].tolist(), strict=True)) <= (
            kept_set
        )
