"""Checks every registered ``SonarGym/`` id must pass, the way Gymnasium tests its own envs."""

from __future__ import annotations

import doctest
import importlib
import importlib.metadata
import math
import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import EnvSpec
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.registration import DEFAULT_EPISODE_STEPS, ENVIRONMENTS

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


# --------------------------------------------------------------------------------------------
# Gymnasium conventions: version, episode limits, spec round trip

# The argument (and the largest value it may take) behind each registered limit, and the
# smallest invalid value just past it.
LIMIT_ARGUMENTS = {
    "SonarGym/BeaconScan-v0": ({"max_steps": 1000}, {"max_steps": 1001}),
    "SonarGym/ActiveBeaconScan-v0": ({"max_steps": 1000}, {"max_steps": 1001}),
    "SonarGym/SweepLocalization-v0": (
        {"route_length_m": 50.0, "decision_spacing_m": 0.05},
        {"decision_spacing_m": 0.049},
    ),
    "SonarGym/Trilateration-v0": ({"n_decision_points": 200}, {"n_decision_points": 201}),
    "SonarGym/BlockExpansion-v0": ({"n_areas": 3}, {"n_areas": 4}),
    "SonarGym/WallCorrection-v0": ({"n_legs": 100, "transition_m": 0.05}, {"n_legs": 101}),
}
LONGEST_EPISODE = {
    "SonarGym/BeaconScan-v0": 1000,
    "SonarGym/ActiveBeaconScan-v0": 1000,
    "SonarGym/SweepLocalization-v0": math.ceil(50.0 / 0.05),
    "SonarGym/Trilateration-v0": 200,
    "SonarGym/BlockExpansion-v0": 3 - 1,
    "SonarGym/WallCorrection-v0": 100,
}


def test_version_comes_from_the_package_metadata() -> None:
    assert isinstance(sonar_gym.__version__, str) and sonar_gym.__version__
    try:
        expected = importlib.metadata.version("sonar-gym")
    except importlib.metadata.PackageNotFoundError:
        expected = "0.0.0+unknown"
    assert sonar_gym.__version__ == expected


def test_every_id_has_a_limit_argument_table_entry() -> None:
    assert set(LIMIT_ARGUMENTS) == set(ENV_IDS) == set(LONGEST_EPISODE)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_registered_limit_is_the_longest_episode_valid_arguments_allow(env_id: str) -> None:
    assert gym.spec(env_id).max_episode_steps == LONGEST_EPISODE[env_id] + 1
    largest, beyond = LIMIT_ARGUMENTS[env_id]
    gym.make(env_id, **largest).close()  # the bound itself is valid
    with pytest.raises(ValueError):
        gym.make(env_id, **beyond)


@pytest.mark.parametrize(
    "env_id",
    [
        "SonarGym/Trilateration-v0",
        "SonarGym/BlockExpansion-v0",
        "SonarGym/WallCorrection-v0",
        "SonarGym/SweepLocalization-v0",
    ],
)
def test_the_longest_episode_ends_terminated_and_not_truncated(env_id: str) -> None:
    """At the largest arguments the env's last step terminates, and TimeLimit leaves it so."""
    largest, _ = LIMIT_ARGUMENTS[env_id]
    env = gym.make(env_id, **largest)
    env.reset(seed=0)
    env.action_space.seed(0)
    steps, terminated, truncated = 0, False, False
    while not (terminated or truncated):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        steps += 1
    assert (terminated, truncated) == (True, False)
    assert steps <= LONGEST_EPISODE[env_id]


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_the_env_ends_its_own_episodes_within_the_default_length(env_id: str) -> None:
    env = gym.make(env_id)
    limit = DEFAULT_EPISODE_STEPS[env_id]
    assert limit < gym.spec(env_id).max_episode_steps or env_id.endswith("BlockExpansion-v0")
    for seed in range(3):
        env.reset(seed=seed)
        env.action_space.seed(seed)
        for _ in range(limit):
            _, _, terminated, truncated, info = env.step(env.action_space.sample())
            if terminated or truncated:
                break
        assert terminated or truncated, f"episode still running after {limit} steps"
        # a truncation comes from the env itself (its status says so), never from TimeLimit
        assert not truncated or info["status"] == "truncated"


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_spec_survives_a_json_round_trip(env_id: str) -> None:
    spec = gym.spec(env_id)
    rebuilt = EnvSpec.from_json(spec.to_json())
    assert rebuilt == spec
    env = gym.make(rebuilt)
    observation, _ = env.reset(seed=0)
    assert env.observation_space.contains(observation)
    assert env.spec is not None and env.spec.max_episode_steps == spec.max_episode_steps
    env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_spec_of_a_configured_env_survives_a_json_round_trip(env_id: str) -> None:
    """The kwargs recorded in ``env.spec`` (JSON turns tuples into lists) rebuild the env."""
    largest, _ = LIMIT_ARGUMENTS[env_id]
    env = gym.make(env_id, **largest)
    assert env.spec is not None
    rebuilt = EnvSpec.from_json(env.spec.to_json())
    again = gym.make(rebuilt)
    assert again.unwrapped.config == env.unwrapped.config
    env.close()
    again.close()


# tuple-valued arguments come back from JSON as lists
TUPLE_ARGUMENTS = {
    "SonarGym/BeaconScan-v0": {"temperature_range_c": (10.0, 30.0), "increments_deg": (1, 5)},
    "SonarGym/Trilateration-v0": {"fix_counts": (0, 1, 5)},
}


@pytest.mark.parametrize("env_id", sorted(TUPLE_ARGUMENTS))
def test_spec_with_tuple_arguments_rebuilds_an_env_that_acts_the_same(env_id: str) -> None:
    env = gym.make(env_id, **TUPLE_ARGUMENTS[env_id])
    assert env.spec is not None
    again = gym.make(EnvSpec.from_json(env.spec.to_json()))
    assert env.action_space == again.action_space
    assert env.observation_space == again.observation_space
    first, second = _rollout(env, seed=3, steps=6), _rollout(again, seed=3, steps=6)
    assert len(first) == len(second)
    for a, b in zip(first, second, strict=True):
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:] == b[1:]
