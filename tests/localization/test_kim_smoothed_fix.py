"""Kim, Lee & Jeong's vote of one fix in one compiled call (sec. 3.3, smoothed selection)
against the loops it chains, called one by one from Python, bit for bit.

The reference takes every (reading, anchor) pair (the full product), so the pre-selection of
pairs inside the compiled call is checked too; the clamping of the chosen cells to the arena_grid
is that of the array form the call replaced.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization import kim, kim_kernels
from sonar_gym.localization.kim import OccupancyGrid
from sonar_gym.pose import Pose
from tests.localization.test_kim import (
    MOVES,
    noisy_sweeps,
)


def reference_fix(
    arena_grid: OccupancyGrid, arguments: tuple, window: kim._VoteWindow
) -> tuple[np.ndarray, int, int, int, int, int, float, float]:
    """The loops one at a time: every pair, the volume, its smoothed peak, the mean of the
    peak's heading over the peak cell +- 1 clamped to the arena_grid."""
    end_x, end_y, range_m, anchors, direction_index, table, cos_h, sin_h, _, *layout = arguments
    n_anchors = anchors.shape[0]
    pairs = np.divmod(np.arange(end_x.size * n_anchors), n_anchors)
    votes_of = (table, range_m, end_x, end_y, anchors)
    volume = kim_kernels.vote_volume(*pairs, direction_index, *votes_of, cos_h, sin_h, *layout)
    score = kim_kernels.binomial_smooth(volume)
    heading, x, y = np.unravel_index(int(np.argmax(score)), score.shape)
    peak = int(score[heading, x, y])
    if peak == 0:
        return volume, peak, heading, x, y, 0, 0.0, 0.0
    nx, ny = arena_grid.shape
    best_x, best_y = x + window.low[0], y + window.low[1]
    cells = (
        max(best_x - 1, 0),
        max(best_y - 1, 0),
        min(best_x + 1, nx - 1),
        min(best_y + 1, ny - 1),
    )
    count, mean_x, mean_y = kim_kernels.vote_mean(
        *pairs, direction_index[heading], *votes_of, float(cos_h[heading]),
        float(sin_h[heading]), *layout, cells,
    )  # fmt: skip
    return volume, peak, heading, x, y, count, mean_x, mean_y


def _arguments(
    arena_grid: OccupancyGrid,
    truth: Pose,
    prior: Pose,
    count: int,
    radius: float | None,
    window_deg: float,
    anchor: str,
    seed: int,
) -> tuple[tuple, kim._VoteWindow]:
    rng = np.random.default_rng(seed)
    sweeps = noisy_sweeps(truth, MOVES[:count], rng, 0.02, 0.1)
    center = None if radius is None else prior.position
    headings = kim.heading_candidates_around(
        prior.theta, math.radians(window_deg), math.radians(1.0)
    )
    readings = kim._gather_readings(sweeps, None)
    table_cache = kim._free_distance_table(arena_grid, 360, arena_grid.cell_size_m)
    anchors = table_cache.anchors(anchor)  # type: ignore[arg-type]
    window = kim._vote_window(arena_grid, center, radius)
    direction_index = kim._direction_index(headings, readings, 360)
    table = table_cache.columns(direction_index.ravel())
    arguments = (
        readings.end_x, readings.end_y, readings.range_m, anchors, direction_index, table,
        np.cos(headings), np.sin(headings), kim._pair_test(center, radius, headings)[1],
        *kim._vote_layout(arena_grid, window, center, radius),
    )  # fmt: skip
    return arguments, window


def _assert_same_bits(found: tuple, expected: tuple) -> None:
    assert np.array_equal(found[0], expected[0])
    assert found[1:6] == expected[1:6]
    assert np.array(found[6:]).tobytes() == np.array(expected[6:]).tobytes()


@pytest.mark.parametrize("anchor", ["cell_center", "obstacle_point"])
@pytest.mark.parametrize("radius", [None, 0.1, 0.3, 0.6])
@pytest.mark.parametrize("count", [1, 2, 4])
def test_smoothed_fix_is_the_loops_one_by_one(
    arena_grid: OccupancyGrid, anchor: str, radius: float | None, count: int
) -> None:
    for seed in range(8):
        rng = np.random.default_rng(100 + seed)
        truth = Pose(rng.uniform(0.3, 1.7), rng.uniform(0.3, 1.7), rng.uniform(-math.pi, math.pi))
        prior = Pose(
            truth.x + rng.normal(0.0, 0.05),
            truth.y + rng.normal(0.0, 0.05),
            truth.theta + rng.normal(0.0, 0.05),
        )
        window_deg = float(rng.choice([0.0, 3.0, 10.0, 30.0, 200.0]))
        arguments, window = _arguments(
            arena_grid, truth, prior, count, radius, window_deg, anchor, seed
        )
        found = kim_kernels.smoothed_fix(*arguments)
        _assert_same_bits(found, reference_fix(arena_grid, arguments, window))


def test_smoothed_fix_with_every_ray_obstructed_finds_nothing(arena_grid: OccupancyGrid) -> None:
    truth = Pose(0.93, 0.71, 0.4)
    arguments, window = _arguments(arena_grid, truth, truth, 2, 0.3, 10.0, "cell_center", 0)
    blocked = list(arguments)
    blocked[5] = np.zeros_like(arguments[5])  # no free distance behind any occupied cell
    found = kim_kernels.smoothed_fix(*blocked)
    _assert_same_bits(found, reference_fix(arena_grid, tuple(blocked), window))
    assert not found[0].any() and found[5:] == (0, 0.0, 0.0)


@pytest.mark.parametrize("selection", ["smoothed", "max"])
def test_vote_localize_with_and_without_the_vote_map_agree(
    arena_grid: OccupancyGrid, selection: str
) -> None:
    truth = Pose(0.93, 0.71, 0.4)
    sweeps = noisy_sweeps(truth, MOVES[:3], np.random.default_rng(3))
    prior = Pose(truth.x + 0.04, truth.y - 0.03, truth.theta + math.radians(2.0))
    results = [
        kim.vote_localize(
            arena_grid,
            sweeps,
            search_center=prior,
            search_radius=0.3,
            selection=selection,
            return_vote_map=with_map,  # type: ignore[arg-type]
        )  # fmt: skip
        for with_map in (True, False)
    ]
    assert results[0].status == results[1].status == "ok"
    assert results[0].pose == results[1].pose
    assert results[0].last_sweep_pose == results[1].last_sweep_pose
    assert results[0].votes == results[1].votes
