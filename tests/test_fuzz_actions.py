"""Random action sequences in every env: finite observations inside the space, finite rewards.

One env per id (default arguments) is reused across examples; each example resets it with a
drawn seed and plays a short drawn sequence of valid actions, stopping at the episode's end.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import event, given
from hypothesis import strategies as st

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.registration import ENVIRONMENTS
from tests.fuzzing import fuzz_settings

MAX_ACTIONS = 4
"""Longest action sequence per example: short episodes keep the default run quick."""


@cache
def env_for(env_id: str) -> gym.Env:
    return gym.make(env_id)


def action_in(space: gym.Space) -> st.SearchStrategy[Any]:
    """Valid actions of a Discrete, MultiDiscrete or Box action space."""
    if isinstance(space, gym.spaces.Discrete):
        return st.integers(int(space.start), int(space.start + space.n - 1))
    if isinstance(space, gym.spaces.MultiDiscrete):
        return st.tuples(*(st.integers(0, int(n) - 1) for n in space.nvec)).map(
            lambda a: np.asarray(a, dtype=space.dtype)
        )
    if isinstance(space, gym.spaces.Box):
        low, high = space.low.ravel(), space.high.ravel()
        return st.tuples(
            *(
                st.floats(float(lo), float(hi), allow_nan=False, width=32)
                for lo, hi in zip(low, high, strict=True)
            )
        ).map(lambda a: np.asarray(a, dtype=space.dtype).reshape(space.shape))
    raise TypeError(f"no strategy for {space}")


def play(env_id: str, data: st.DataObject, seed: int) -> None:
    env = env_for(env_id)
    actions = data.draw(st.lists(action_in(env.action_space), min_size=1, max_size=MAX_ACTIONS))
    observation, info = env.reset(seed=seed)
    assert env.observation_space.contains(observation), observation
    for action in actions:
        observation, reward, terminated, truncated, info = env.step(action)
        assert np.all(np.isfinite(observation)), observation
        assert env.observation_space.contains(observation), observation
        assert math.isfinite(float(reward)), reward
        if terminated or truncated:
            event("episode ended")
            return
    event("episode still running")


@pytest.mark.parametrize("env_id", sorted(ENVIRONMENTS))
@fuzz_settings(300)
@given(data=st.data(), seed=st.integers(0, 2**31 - 1))
def test_random_actions_keep_observations_and_rewards_finite(
    env_id: str, data: st.DataObject, seed: int
) -> None:
    play(env_id, data, seed)
