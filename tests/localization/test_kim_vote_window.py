"""Counting votes only in the search circle's window of cells changes no result of sec. 3.3."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization import kim
from sonar_gym.localization.kim import OccupancyGrid, Sweep, vote_localize
from sonar_gym.pose import Pose
from tests.localization.test_kim import ARENA_BOUNDS, ARENA_CIRCLES, ARENA_SEGMENTS, MOVES, _sweep


_CIRCLE_WINDOW = kim._vote_window


def _whole_grid(grid, center, radius):  # type: ignore[no-untyped-def]
    """The slow reference: votes counted over every cell of the grid."""
    return _CIRCLE_WINDOW(grid, None, None)


@pytest.fixture(scope="module")
def grid() -> OccupancyGrid:
    return OccupancyGrid.from_segments(ARENA_SEGMENTS, ARENA_CIRCLES, ARENA_BOUNDS, 0.05)


@pytest.mark.parametrize("selection", ["smoothed", "max"])
@pytest.mark.parametrize("ambiguity_ratio", [None, 0.5])
@pytest.mark.parametrize("radius", [0.1, 0.3, 0.6])
@pytest.mark.parametrize(
    "truth", [Pose(0.93, 0.71, 0.4), Pose(0.2, 0.25, -2.0)], ids=["middle", "near_corner"]
)
def test_windowed_votes_give_the_result_of_the_whole_grid(
    grid: OccupancyGrid,
    monkeypatch: pytest.MonkeyPatch,
    selection: str,
    ambiguity_ratio: float | None,
    radius: float,
    truth: Pose,
) -> None:
    rng = np.random.default_rng(11)
    sweeps = []
    for move in MOVES[:3]:
        exact = _sweep(truth, move)
        noisy = np.abs(exact.ranges + rng.normal(0.0, 0.01, exact.ranges.size))
        sweeps.append(Sweep(exact.angles, noisy, exact.sensor_offset, move))
    prior = Pose(truth.x + 0.04, truth.y - 0.03, truth.theta + math.radians(2.0))
    arguments = dict(
        search_center=prior,
        search_radius=radius,
        heading_window_rad=math.radians(10.0),
        selection=selection,
        ambiguity_ratio=ambiguity_ratio,
        anchor="obstacle_point",
    )
    fast = vote_localize(grid, sweeps, **arguments)  # type: ignore[arg-type]
    monkeypatch.setattr(kim, "_vote_window", _whole_grid)
    slow = vote_localize(grid, sweeps, **arguments)  # type: ignore[arg-type]
    assert fast.status == slow.status
    assert fast.status in ("ok", "ambiguous")
    assert fast.pose == slow.pose
    assert fast.last_sweep_pose == slow.last_sweep_pose
    assert fast.votes == slow.votes
    assert fast.vote_map is not None and slow.vote_map is not None
    assert fast.vote_map.shape == grid.shape
    assert np.array_equal(fast.vote_map, slow.vote_map)


def test_window_covers_the_search_circle_and_is_clipped_to_the_grid(grid: OccupancyGrid) -> None:
    window = kim._vote_window(grid, np.array([0.0, 1.0]), 0.3)
    (low_x, low_y), (wx, wy) = window.low, window.shape
    assert low_x == 0
    nx, ny = grid.shape
    assert 0 < wx < nx and 0 < wy < ny
    inside = grid.world_to_cell(np.array([[0.3, 1.0], [0.0, 0.7], [0.0, 1.3], [0.05, 1.0]]))
    assert np.all(inside[:, 0] >= low_x) and np.all(inside[:, 0] < low_x + wx)
    assert np.all(inside[:, 1] >= low_y) and np.all(inside[:, 1] < low_y + wy)
    assert kim._vote_window(grid, None, None).shape == grid.shape
