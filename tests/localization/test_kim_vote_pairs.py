"""The search-circle pre-selection of (reading, anchor) pairs changes no vote of sec. 3.3."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization import kim, kim_kernels
from sonar_gym.localization.kim import OccupancyGrid, vote_localize
from sonar_gym.pose import Pose
from tests.localization.test_kim import (
    MOVES,
    _sweep,
    noisy_sweeps,
)


_PRE_SELECTED_PAIRS = kim._candidate_pairs


def _all_pairs(readings, anchors, center, radius, headings):  # type: ignore[no-untyped-def]
    """The slow reference: every reading with every anchor (the full product)."""
    return _PRE_SELECTED_PAIRS(readings, anchors, None, None, headings)


@pytest.mark.parametrize("anchor", ["cell_center", "obstacle_point"])
@pytest.mark.parametrize("radius", [0.1, 0.25, 0.6])
@pytest.mark.parametrize("count", [1, 4])
def test_pre_selected_pairs_give_the_same_result_as_the_full_product(
    arena_grid: OccupancyGrid,
    monkeypatch: pytest.MonkeyPatch,
    anchor: str,
    radius: float,
    count: int,
) -> None:
    truth = Pose(0.93, 0.71, 0.4)
    sweeps = noisy_sweeps(truth, MOVES[:count], np.random.default_rng(7))
    prior = Pose(truth.x + 0.04, truth.y - 0.03, truth.theta + math.radians(2.0))
    # the raw maximum: its pairs come from _candidate_pairs (the smoothed selection selects
    # its pairs inside one compiled call, checked in test_kim_smoothed_fix.py)
    arguments = dict(
        search_center=prior,
        search_radius=radius,
        heading_window_rad=math.radians(10.0),
        anchor=anchor,
        selection="max",
    )
    fast = vote_localize(arena_grid, sweeps, **arguments)  # type: ignore[arg-type]
    monkeypatch.setattr(kim, "_candidate_pairs", _all_pairs)
    slow = vote_localize(arena_grid, sweeps, **arguments)  # type: ignore[arg-type]
    assert fast.status == slow.status == "ok"
    assert fast.pose == slow.pose
    assert fast.votes == slow.votes
    assert np.array_equal(fast.vote_map, slow.vote_map)


def test_pairs_keep_every_pair_that_can_vote_inside_the_circle(arena_grid: OccupancyGrid) -> None:
    truth = Pose(0.93, 0.71, 0.4)
    readings = kim._gather_readings([_sweep(truth)], None)
    anchors = arena_grid.occupied_obstacle_points()
    centre, radius = np.array([1.0, 0.7]), 0.2
    headings = np.radians(np.arange(-180.0, 180.0, 2.0))
    pair_j, pair_k = kim._candidate_pairs(readings, anchors, centre, radius, headings)
    kept = set(zip(pair_j.tolist(), pair_k.tolist(), strict=True))
    for heading in headings:
        c, s = math.cos(heading), math.sin(heading)
        ends = readings.end_xy @ np.array([[c, s], [-s, c]])
        votes = anchors[None, :, :] - ends[:, None, :]
        inside = np.argwhere(np.hypot(*(votes - centre).transpose(2, 0, 1)) <= radius)
        assert {(int(j), int(k)) for j, k in inside} <= kept
    assert len(kept) < readings.range_m.size * anchors.shape[0] / 2


def test_binomial_smoothing_matches_the_padded_reference() -> None:
    volume = np.random.default_rng(5).integers(0, 9, size=(4, 7, 5))
    padded = np.pad(volume, ((0, 0), (1, 1), (1, 1)))
    kernel = np.outer([1, 2, 1], [1, 2, 1])
    expected = np.zeros_like(volume)
    for dx in range(3):
        for dy in range(3):
            expected += kernel[dx, dy] * padded[:, dx : dx + 7, dy : dy + 5]
    assert np.array_equal(kim_kernels.binomial_smooth(volume), expected)
