"""An env keeps one World across episodes: an episode must not depend on the ones before it."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import sonar_gym  # noqa: F401  (registers the ids)


def _rollout(env: gym.Env, seed: int) -> list[tuple[Any, ...]]:
    observation, info = env.reset(seed=seed)
    env.action_space.seed(seed)
    steps: list[tuple[Any, ...]] = [(observation.tolist(), info["true_pose"].tolist())]
    terminated = truncated = False
    while not (terminated or truncated):
        observation, reward, terminated, truncated, info = env.step(env.action_space.sample())
        steps.append(
            (
                observation.tolist(),
                reward,
                info["true_pose"].tolist(),
                info["estimated_pose"].tolist(),
            )
        )
    return steps


@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [
        ("SonarGym/SweepLocalization-v0", {}),
        ("SonarGym/SweepLocalization-v0", {"route": "random"}),
        ("SonarGym/Trilateration-v0", {}),
    ],
)
def test_an_episode_after_others_replays_the_episode_of_a_fresh_env(
    env_id: str, kwargs: dict[str, Any]
) -> None:
    used = gym.make(env_id, **kwargs)
    _rollout(used, seed=1)
    _rollout(used, seed=2)
    fresh = gym.make(env_id, **kwargs)
    replay, first = _rollout(used, seed=5), _rollout(fresh, seed=5)
    assert len(replay) == len(first) > 1
    for again, original in zip(replay, first, strict=True):
        assert np.array_equal(np.asarray(again[0]), np.asarray(original[0]))
        assert again[1:] == original[1:]
