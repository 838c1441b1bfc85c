"""The route hands the APCS tracker only arguments its checked :meth:`APCSTracker.run` accepts,
so calling :meth:`APCSTracker.run_unchecked` directly skips no error."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import sonar_gym  # noqa: F401  (registers the environments)
from sonar_gym.localization.apcs_online import APCSTracker, RunResult
from sonar_gym.localization.apcs_walls import WallMap, WallVector
from sonar_gym.pose import Pose


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


def _state(tracker: APCSTracker) -> dict[str, Any]:
    """Every attribute of ``tracker`` and of its streams, arrays as (dtype, bytes)."""
    state: dict[str, Any] = {}
    for name, value in vars(tracker).items():
        if name == "streams":
            value = {side: vars(stream) for side, stream in value.items()}
        elif isinstance(value, np.ndarray):
            value = (value.dtype, value.shape, value.tobytes(), value.flags.writeable)
        state[name] = (type(value), value)
    return state


def test_the_unchecked_tracker_is_the_checked_one_for_the_env_arguments(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Whichever constructor the env uses, its arguments pass the checked one, and the
    unchecked one makes the same tracker of them (a copy of the covariance)."""
    checked_init, unchecked = APCSTracker.__init__, APCSTracker.unchecked
    calls: list[tuple[tuple[Any, ...], dict[str, Any]]] = []

    def recording_init(self: APCSTracker, *arguments: Any, **keywords: Any) -> None:
        calls.append((arguments, keywords))
        checked_init(self, *arguments, **keywords)

    def recording_unchecked(
        cls: type[APCSTracker], *arguments: Any, **keywords: Any
    ) -> APCSTracker:
        calls.append((arguments, keywords))
        return unchecked(*arguments, **keywords)

    monkeypatch.setattr(APCSTracker, "__init__", recording_init)
    monkeypatch.setattr(APCSTracker, "unchecked", classmethod(recording_unchecked))
    env = gym.make("SonarGym/WallCorrection-v0")
    for seed in range(4):
        env.reset(seed=seed)
    env.close()
    monkeypatch.undo()
    assert len(calls) >= 4
    for arguments, keywords in calls:
        reference = APCSTracker(*arguments, **keywords)
        tracker = APCSTracker.unchecked(*arguments, **keywords)
        assert _state(tracker) == _state(reference)
        assert not np.shares_memory(tracker.covariance, arguments[2])


def test_the_unchecked_tracker_runs_as_the_checked_one() -> None:
    walls = WallMap(
        (
            WallVector((-1.0, 1.0), (10.0, 1.0), name="left"),
            WallVector((10.0, -1.0), (-1.0, -1.0), name="right"),
        )
    )
    arguments = (walls, Pose(0.0, 0.02, 0.01), np.diag([4e-4, 4e-4, 1e-4]))
    keywords: dict[str, Any] = {
        "wheel_base_m": 0.3,
        "variance_per_m": 1e-6,
        "range_variance_m2": 1e-4,
        "bearing_variance_rad2": 3e-4,
        "measurement_variances": "fit",
    }
    count = 120
    increments = np.full(count, 0.03)
    samples = np.arange(0, count, 2)
    rng = np.random.default_rng(5)
    readings = {
        "left": 0.98 + rng.normal(0.0, 0.002, len(samples)),
        "right": 1.02 + rng.normal(0.0, 0.002, len(samples)),
    }
    results = [
        tracker.run(increments, increments, samples, readings, stops=(40, 80))
        for tracker in (
            APCSTracker(*arguments, **keywords),
            APCSTracker.unchecked(*arguments, **keywords),
        )
    ]
    reference, got = results
    assert reference.walls and reference.consumed < count  # a correction was made
    np.testing.assert_array_equal(got.estimated_path, reference.estimated_path)
    assert (got.consumed, got.erps, got.dropped) == (
        reference.consumed,
        reference.erps,
        reference.dropped,
    )
    assert [wall.pose_after for wall in got.walls] == [wall.pose_after for wall in reference.walls]
