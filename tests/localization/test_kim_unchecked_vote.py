"""Kim, Lee & Jeong's vote of sec. 3.3 without the argument checks (the form the EKF loop of
``kim_fix`` calls) against the checked :func:`vote_localize` with the same arguments, field for
field and bit for bit, over random poses, priors, circles, heading windows and sweep counts,
with silent sweeps and circles that miss the arena_grid."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization import kim
from sonar_gym.localization.kim import OccupancyGrid, Sweep, VoteLocalization
from sonar_gym.pose import Pose
from tests.localization.test_kim import (
    MOVES,
    noisy_sweeps,
)


def assert_same_vote(result: VoteLocalization, expected: VoteLocalization) -> None:
    """The same status, message, votes, heading and poses (bit for bit), and no vote map."""
    assert result.status == expected.status
    assert result.message == expected.message
    assert result.votes == expected.votes
    assert result.heading_rad == expected.heading_rad
    assert result.vote_map is None and expected.vote_map is None
    for pose, expected_pose in (
        (result.pose, expected.pose),
        (result.last_sweep_pose, expected.last_sweep_pose),
    ):
        if expected_pose is None:
            assert pose is None
        else:
            assert pose is not None
            assert (pose.x, pose.y, pose.theta) == (
                expected_pose.x,
                expected_pose.y,
                expected_pose.theta,
            )


def _checked_and_unchecked(
    arena_grid: OccupancyGrid,
    sweeps: list[Sweep],
    prior: Pose,
    radius: float,
    step: float,
    window: float,
    max_range: float,
    anchor: kim.Anchor,
) -> tuple[VoteLocalization, VoteLocalization]:
    checked = kim.vote_localize(
        arena_grid,
        sweeps,
        search_center=prior,
        search_radius=radius,
        heading_step_rad=step,
        heading_window_rad=window,
        max_range_m=max_range,
        anchor=anchor,
        return_vote_map=False,
    )
    unchecked = kim.vote_localize_unchecked(
        arena_grid,
        sweeps,
        prior,
        radius,
        heading_step_rad=step,
        heading_window_rad=window,
        max_range_m=max_range,
        anchor=anchor,
    )
    return unchecked, checked


@pytest.mark.parametrize("seed", range(40))
def test_unchecked_vote_is_the_checked_vote(arena_grid: OccupancyGrid, seed: int) -> None:
    rng = np.random.default_rng(seed)
    truth = Pose(rng.uniform(0.3, 1.7), rng.uniform(0.3, 1.7), rng.uniform(-math.pi, math.pi))
    sweeps = noisy_sweeps(truth, MOVES[: int(rng.integers(1, 5))], rng, 0.02, 0.1)
    prior = Pose(
        truth.x + rng.normal(0.0, 0.05),
        truth.y + rng.normal(0.0, 0.05),
        truth.theta + rng.normal(0.0, 0.05),
    )
    unchecked, checked = _checked_and_unchecked(
        arena_grid,
        sweeps,
        prior,
        float(rng.uniform(0.1, 0.6)),
        math.radians(float(rng.choice([0.5, 1.0, 2.0]))),
        float(rng.uniform(0.0, math.radians(30.0))),
        float(rng.uniform(1.0, 3.0)),
        "obstacle_point" if seed % 2 else "cell_center",
    )
    assert checked.status in ("ok", "no_votes")
    assert_same_vote(unchecked, checked)


def test_unchecked_vote_fails_as_the_checked_vote(arena_grid: OccupancyGrid) -> None:
    rng = np.random.default_rng(7)
    truth = Pose(1.0, 1.0, 0.3)
    sweeps = noisy_sweeps(truth, MOVES[:2], rng, 0.02, 0.0)
    silent = [Sweep(s.angles, np.full(s.ranges.size, np.nan), odometry=s.odometry) for s in sweeps]
    cases = [
        (silent, truth, "empty_sweep"),
        (sweeps, Pose(9.0, 9.0, 0.3), "no_votes"),  # the circle misses the arena_grid
    ]
    for sweep_list, prior, status in cases:
        unchecked, checked = _checked_and_unchecked(
            arena_grid,
            sweep_list,
            prior,
            0.3,
            math.radians(1.0),
            math.radians(5.0),
            3.0,
            "cell_center",
        )
        assert checked.status == status
        assert_same_vote(unchecked, checked)
