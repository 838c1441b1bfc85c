"""The tracker's loop over a run gives exactly what its reference form gives: the same result
(path, ERPs, walls, dropped groups, consumed commands) and the same state afterwards."""

from __future__ import annotations

import copy
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import sonar_gym  # noqa: F401  (registers the environments)
from sonar_gym.localization.apcs_online import APCSTracker, RunResult
from tests.localization.apcs_tracker_run_reference import run_unchecked_reference


def _assert_same_results(got: RunResult, expected: RunResult) -> None:
    np.testing.assert_array_equal(got.estimated_path, expected.estimated_path)
    assert got.consumed == expected.consumed
    assert got.erps == expected.erps
    assert got.dropped == expected.dropped
    assert len(got.walls) == len(expected.walls)
    for wall, reference in zip(got.walls, expected.walls, strict=True):
        assert (wall.side, wall.match, wall.reason, wall.command_index) == (
            reference.side,
            reference.match,
            reference.reason,
            reference.command_index,
        )
        assert (wall.pose_before, wall.pose_after) == (reference.pose_before, reference.pose_after)
        assert wall.group.fit == reference.group.fit
        np.testing.assert_array_equal(wall.group.points, reference.group.points)
        assert (wall.correction.status, wall.correction.pose, wall.correction.message) == (
            reference.correction.status,
            reference.correction.pose,
            reference.correction.message,
        )
        np.testing.assert_array_equal(wall.correction.covariance, reference.correction.covariance)


def _assert_same_trackers(got: APCSTracker, expected: APCSTracker) -> None:
    assert got.estimate == expected.estimate
    np.testing.assert_array_equal(got.covariance, expected.covariance)
    for side, stream in got.streams.items():
        reference = expected.streams[side]
        np.testing.assert_equal(stream._previous, reference._previous)  # NaN: a dropout
        assert stream._group_points == reference._group_points
        assert stream._group_directions == reference._group_directions


@pytest.mark.parametrize("seed", [3, 11])
def test_the_runs_of_an_episode_are_those_of_the_reference_loop(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    unchecked = APCSTracker.run_unchecked
    totals = {"runs": 0, "walls": 0, "dropped": 0, "corrections": 0}

    def against_reference(self: APCSTracker, *arguments: Any, **keywords: Any) -> RunResult:
        reference_tracker = copy.deepcopy(self)
        expected = run_unchecked_reference(reference_tracker, *arguments, **keywords)
        got = unchecked(self, *arguments, **keywords)
        _assert_same_results(got, expected)
        _assert_same_trackers(self, reference_tracker)
        totals["runs"] += 1
        totals["walls"] += len(got.walls)
        totals["dropped"] += sum(got.dropped.values())
        totals["corrections"] += sum(wall.pose_after is not wall.pose_before for wall in got.walls)
        return got

    monkeypatch.setattr(APCSTracker, "run_unchecked", against_reference)
    env = gym.make("SonarGym/WallCorrection-v0")
    env.reset(seed=seed)
    env.action_space.seed(seed)
    for _ in range(80):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            env.reset()
    env.close()
    # the episode exercises every branch: dropped groups, walls and corrections
    assert totals["runs"] > 40
    assert min(totals["walls"], totals["dropped"], totals["corrections"]) > 5
