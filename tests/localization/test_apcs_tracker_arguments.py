"""The route hands the APCS tracker only arguments its checked :meth:`APCSTracker.run` accepts,
so calling :meth:`APCSTracker.run_unchecked` directly skips no error."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import pytest

import sonar_gym  # noqa: F401  (registers the environments)
from sonar_gym.localization.apcs_online import APCSTracker, RunResult


def test_route_arguments_pass_the_checked_run(monkeypatch: pytest.MonkeyPatch) -> None:
    unchecked = APCSTracker.run_unchecked
    depth = 0
    runs = 0

    def through_checked_run(self: APCSTracker, *arguments: Any, **keywords: Any) -> RunResult:
        nonlocal depth, runs
        if depth:  # run's own delegation
            return unchecked(self, *arguments, **keywords)
        depth, runs = 1, runs + 1
        try:
            return APCSTracker.run(self, *arguments, **keywords)
        finally:
            depth = 0

    monkeypatch.setattr(APCSTracker, "run_unchecked", through_checked_run)
    env = gym.make("SonarGym/WallCorrection-v0")
    env.reset(seed=3)
    env.action_space.seed(3)
    for _ in range(60):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            env.reset()
    env.close()
    assert runs > 20
