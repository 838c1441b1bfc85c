"""Fuzzed ``gym.make`` arguments of every env: a clean ``ValueError`` or an env that runs.

Each example changes one to three arguments of the env's config (chosen among its fields)
to a value near the default, an edge number (``-0.0``, denormals, ``10**400``, NaN), a numpy
scalar or a value of the wrong type. ``gym.make`` must then either raise a ``ValueError``
(a ``ScenarioError`` is one) whose message names one of the changed arguments, or give an
env that resets and steps with finite observations and rewards inside its spaces.
"""

from __future__ import annotations

import dataclasses
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
from tests.fuzzing import fuzz_settings, value_like


@cache
def defaults(env_id: str) -> dict[str, Any]:
    """The env's config fields and their default values."""
    config = gym.make(env_id).unwrapped.config
    return {f.name: getattr(config, f.name) for f in dataclasses.fields(config)}


def changed_arguments(env_id: str) -> st.SearchStrategy[dict[str, Any]]:
    fields = defaults(env_id)
    names = st.lists(st.sampled_from(sorted(fields)), min_size=1, max_size=3, unique=True)
    return names.flatmap(
        lambda chosen: st.fixed_dictionaries({name: value_like(fields[name]) for name in chosen})
    )


def check_runs(env: gym.Env, seed: int) -> None:
    observation, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    assert env.observation_space.contains(observation), observation
    for _ in range(2):
        observation, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        assert np.all(np.isfinite(observation)), observation
        assert env.observation_space.contains(observation), observation
        assert math.isfinite(float(reward)), reward
        if terminated or truncated:
            break


@pytest.mark.parametrize("env_id", sorted(ENVIRONMENTS))
@fuzz_settings(300)
@given(data=st.data(), seed=st.integers(0, 2**16))
def test_make_arguments_give_a_clean_error_or_a_working_env(
    env_id: str, data: st.DataObject, seed: int
) -> None:
    kwargs = data.draw(changed_arguments(env_id), label="kwargs")
    try:
        env = gym.make(env_id, **kwargs)
    except ValueError as error:
        message = str(error)
        assert any(name in message for name in kwargs), message
        event("clean ValueError")
        return
    hash(env.unwrapped.config)
    check_runs(env, seed)
    env.close()
    event("accepted and ran")
