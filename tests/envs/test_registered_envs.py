"""Checks every registered ``SonarGym/`` id must pass, the way Gymnasium tests its own envs."""

from __future__ import annotations

import doctest
import importlib
import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.registration import ENVIRONMENTS

ENV_IDS = sorted(ENVIRONMENTS)


def _rollout(env: gym.Env, seed: int, steps: int) -> list[tuple]:
    observation, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    trace = [(observation.copy(), 0.0, False, False)]
    for _ in range(steps):
        observation, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        trace.append((observation.copy(), reward, terminated, truncated))
        if terminated or truncated:
            observation, _ = env.reset()
            trace.append((observation.copy(), 0.0, False, False))
    return trace


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_gymnasium_checker_passes_without_warnings(env_id: str) -> None:
    env = gym.make(env_id)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gym_check_env(env.unwrapped, skip_render_check=False)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_sb3_checker_passes_without_warnings(env_id: str) -> None:
    env = gym.make(env_id)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sb3_check_env(env.unwrapped, warn=True)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_same_seed_gives_the_same_rollout(env_id: str) -> None:
    first = _rollout(gym.make(env_id), seed=11, steps=25)
    second = _rollout(gym.make(env_id), seed=11, steps=25)
    assert len(first) == len(second)
    for a, b in zip(first, second, strict=True):
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:] == b[1:]


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_different_seeds_give_different_episodes(env_id: str) -> None:
    first, _ = gym.make(env_id).reset(seed=1)
    second, _ = gym.make(env_id).reset(seed=2)
    assert not np.array_equal(first, second)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_random_rollout_stays_in_space_and_finite(env_id: str) -> None:
    env = gym.make(env_id)
    observation, info = env.reset(seed=5)
    env.action_space.seed(5)
    for key in ("position_error_m", "sensing_time_s", "status"):
        assert key in info
    for _ in range(60):
        assert env.observation_space.contains(observation)
        observation, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert np.isfinite(reward)
        assert np.all(np.isfinite(observation))
        assert np.isfinite(info["position_error_m"]) and np.isfinite(info["sensing_time_s"])
        if terminated or truncated:
            observation, info = env.reset()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_env_pickles_mid_episode_and_continues_identically(env_id: str) -> None:
    env = gym.make(env_id)
    env.reset(seed=3)
    env.action_space.seed(3)
    action = env.action_space.sample()
    clone = pickle.loads(pickle.dumps(env))
    original_step = env.step(action)
    clone_step = clone.step(action)
    np.testing.assert_array_equal(original_step[0], clone_step[0])
    assert original_step[1:4] == clone_step[1:4]


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_runs_in_async_vector_env(env_id: str) -> None:
    vector_env = gym.vector.AsyncVectorEnv([lambda: gym.make(env_id)] * 2)
    try:
        observations, _ = vector_env.reset(seed=[0, 1])
        assert observations.shape == (2, *vector_env.single_observation_space.shape)
        vector_env.action_space.seed(0)
        observations, rewards, *_ = vector_env.step(vector_env.action_space.sample())
        assert np.all(np.isfinite(observations)) and np.all(np.isfinite(rewards))
    finally:
        vector_env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_render_returns_an_rgb_image(env_id: str) -> None:
    env = gym.make(env_id, render_mode="rgb_array")
    env.reset(seed=0)
    image = env.render()
    assert isinstance(image, np.ndarray)
    assert image.ndim == 3 and image.shape[2] == 3 and image.dtype == np.uint8
    assert image.shape[0] >= 100 and image.shape[1] >= 100
    assert image.std() > 0  # not a blank canvas


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_unknown_argument_is_named_in_the_error(env_id: str) -> None:
    with pytest.raises(ValueError, match="no_such_argument"):
        gym.make(env_id, no_such_argument=1)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_action_outside_the_space_is_rejected(env_id: str) -> None:
    env = gym.make(env_id)
    env.reset(seed=0)
    space = env.action_space
    if isinstance(space, gym.spaces.Box):
        bad = np.full(space.shape, 10.0, dtype=space.dtype)
    elif isinstance(space, gym.spaces.Discrete):
        bad = int(space.n) + 5
    else:
        bad = np.asarray(space.nvec) + 5
    with pytest.raises(ValueError, match="action"):
        env.unwrapped.step(bad)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_docstring_example_runs_as_written(env_id: str) -> None:
    module = importlib.import_module(ENVIRONMENTS[env_id].split(":")[0])
    env_class = getattr(module, ENVIRONMENTS[env_id].split(":")[1])
    finder = doctest.DocTestFinder()
    examples = [test for test in finder.find(env_class) if test.examples]
    assert examples, f"{env_class.__name__} has no >>> example in its docstring"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in examples:
        runner.run(test)
    assert runner.failures == 0
