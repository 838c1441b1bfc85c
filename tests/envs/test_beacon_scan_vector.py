"""The native vector ``SonarGym/BeaconScan-v0`` against ``make_vec(..., "sync")``, and its
contract as a Gymnasium ``VectorEnv``."""

from __future__ import annotations

import doctest
import warnings
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.envs import beacon_scan_vector
from sonar_gym.envs.beacon_scan_vector import BeaconScanVectorEnv, batch_infos

ENV_ID = "SonarGym/BeaconScan-v0"
NATIVE = "vector_entry_point"
STEPS = 60

Transition = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]


def _make(mode: str, num_envs: int, **kwargs: Any) -> gym.vector.VectorEnv:
    return gym.make_vec(ENV_ID, num_envs=num_envs, vectorization_mode=mode, **kwargs)


def _rollout(envs: gym.vector.VectorEnv, seed: int, steps: int) -> list[Transition]:
    """The reset and ``steps`` steps of seeded random actions (the same for either mode)."""
    observations, infos = envs.reset(seed=seed)
    empty = np.zeros(envs.num_envs)
    trace: list[Transition] = [(observations, empty, empty > 0, empty > 0, infos)]
    envs.action_space.seed(seed)
    for _ in range(steps):
        trace.append(envs.step(envs.action_space.sample()))
    envs.close()
    return trace


def _assert_same_arrays(native: np.ndarray, sync: np.ndarray, where: str) -> None:
    assert native.dtype == sync.dtype and native.shape == sync.shape, where
    if native.dtype == object:
        assert native.tolist() == sync.tolist(), where
    else:
        assert native.tobytes() == sync.tobytes(), where


def _assert_same_infos(native: dict[str, Any], sync: dict[str, Any], where: str) -> None:
    assert list(native) == list(sync), where
    for key, value in sync.items():
        if isinstance(value, dict):
            _assert_same_infos(native[key], value, f"{where} [{key}]")
        else:
            _assert_same_arrays(native[key], value, f"{where} [{key}]")


@pytest.mark.parametrize(
    ("kwargs", "num_envs", "seed"),
    [
        ({}, 4, 0),
        ({}, 3, 21),
        ({"action_type": "discrete"}, 4, 5),
        ({"scenario": "random"}, 3, 2),
        ({"start_pose": "any", "max_steps": 4}, 4, 9),
        ({"max_episode_steps": 3}, 3, 1),
    ],
)
def test_native_steps_bit_for_bit_as_sync(kwargs: dict[str, Any], num_envs: int, seed: int) -> None:
    native = _rollout(_make(NATIVE, num_envs, **kwargs), seed, STEPS)
    sync = _rollout(_make("sync", num_envs, **kwargs), seed, STEPS)
    autoresets = 0
    for step, (mine, theirs) in enumerate(zip(native, sync, strict=True)):
        names = ("obs", "reward", "terminated", "truncated")
        for name, a, b in zip(names, mine[:4], theirs[:4], strict=True):
            _assert_same_arrays(np.asarray(a), np.asarray(b), f"step {step} {name}")
        _assert_same_infos(mine[4], theirs[4], f"step {step} info")
        autoresets += int(np.sum(mine[2] | mine[3]))
    assert autoresets > 0  # the rollout crossed episode ends


def test_partial_reset_and_seed_lists_match_sync() -> None:
    mask = np.array([True, False, True])
    traces: list[list[Any]] = []
    for mode in (NATIVE, "sync"):
        envs: Any = _make(mode, 3)  # both take a list of seeds
        first = envs.reset(seed=[4, None, 6])
        envs.action_space.seed(0)
        stepped = envs.step(envs.action_space.sample())
        again = envs.reset(seed=[7, 8, 9], options={"reset_mask": mask.copy()})
        traces.append([first, stepped, again])
        envs.close()
    native, sync = traces
    for index in (0, 2):  # the seeded parts: the unseeded sub-env draws its own seed
        for mine, theirs in zip(native, sync, strict=True):
            _assert_same_arrays(mine[0][index], theirs[0][index], "observation")
    _assert_same_infos(native[2][1], sync[2][1], "masked reset info")


def test_follows_the_vector_env_contract() -> None:
    envs = _make(NATIVE, 3, action_type="discrete")
    single = gym.make(ENV_ID, action_type="discrete")
    assert isinstance(envs, BeaconScanVectorEnv)
    assert envs.num_envs == 3
    assert envs.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP
    assert envs.single_observation_space == single.observation_space
    assert envs.single_action_space == single.action_space
    assert envs.observation_space == gym.vector.utils.batch_space(single.observation_space, 3)
    assert envs.action_space == gym.vector.utils.batch_space(single.action_space, 3)
    observations, _ = envs.reset(seed=1)
    assert observations in envs.observation_space
    observations, rewards, terminated, truncated, _ = envs.step(envs.action_space.sample())
    assert observations in envs.observation_space
    assert rewards.dtype == np.float64 and terminated.dtype == truncated.dtype == np.bool_
    assert envs.spec is not None and envs.spec.id == ENV_ID
    assert envs.call("encode_action", "localize") == (1, 1, 1)
    envs.close()
    assert envs.closed
    envs.close()  # a second close is harmless


def test_default_make_vec_mode_is_native() -> None:
    envs = gym.make_vec(ENV_ID, num_envs=2)
    assert isinstance(envs, BeaconScanVectorEnv)
    assert envs.max_episode_steps == gym.spec(ENV_ID).max_episode_steps
    envs.close()


def test_returned_arrays_are_not_reused() -> None:
    envs = BeaconScanVectorEnv(num_envs=2)
    observations, _ = envs.reset(seed=0)
    kept = observations.copy()
    envs.step(np.array([[0, 0, 4, 0], [1, 0, 0, 0]]))
    np.testing.assert_array_equal(observations, kept)
    envs.close()


@pytest.mark.parametrize("num_envs", [0, -2, 2.5, "3", True, None])
def test_bad_num_envs_is_refused_by_name(num_envs: Any) -> None:
    with pytest.raises(ValueError, match=r"argument 'num_envs' must be a whole number >= 1; got"):
        BeaconScanVectorEnv(num_envs=num_envs)


def test_bad_env_argument_is_refused_by_the_env() -> None:
    with pytest.raises(ValueError, match="max_steps"):
        _make(NATIVE, 2, max_steps=0)


@pytest.mark.parametrize(
    ("actions", "message"),
    [
        (np.zeros((3, 4), dtype=np.int64), r"shape \(2, 4\).*got shape \(3, 4\)"),
        (np.zeros((2, 4)), r"integer array .*dtype float64"),
        (
            np.array([[0, 0, 0, 0], [3, 0, 0, 0]]),
            r"MultiDiscrete.* from \[0, 0, 0, 0\] to \[2, 35, 4, 2\]; env\(s\) \[1\] out",
        ),
        (np.array([[0, -1, 0, 0], [0, 0, 0, 0]]), r"env\(s\) \[0\] out of range"),
    ],
)
def test_bad_actions_are_refused_by_name(actions: np.ndarray, message: str) -> None:
    envs = BeaconScanVectorEnv(num_envs=2)
    envs.reset(seed=0)
    with pytest.raises(ValueError, match=r"argument 'actions' must .*" + message):
        envs.step(actions)
    envs.close()


def test_bad_discrete_actions_are_refused_by_name() -> None:
    envs = BeaconScanVectorEnv(num_envs=2, action_type="discrete")
    envs.reset(seed=0)
    assert isinstance(envs.single_action_space, gym.spaces.Discrete)
    n = int(envs.single_action_space.n)
    expected = rf"Discrete\({n}\) per env, from 0 to {n - 1}; env\(s\) \[1\]"
    with pytest.raises(ValueError, match=expected):
        envs.step(np.array([0, n]))
    envs.close()


def test_step_before_reset_is_refused() -> None:
    envs = BeaconScanVectorEnv(num_envs=2)
    with pytest.raises(RuntimeError, match="reset"):
        envs.step(np.zeros((2, 4), dtype=np.int64))


def test_bad_seed_list_is_refused_by_name() -> None:
    envs = BeaconScanVectorEnv(num_envs=2)
    with pytest.raises(ValueError, match="argument 'seed' must be .* num_envs=2 .*list of 3"):
        envs.reset(seed=[1, 2, 3])


def test_renders_one_frame_per_robot() -> None:
    envs = BeaconScanVectorEnv(num_envs=2, render_mode="rgb_array")
    envs.reset(seed=0)
    frames = envs.render()
    assert len(frames) == 2
    assert all(frame.ndim == 3 and frame.dtype == np.uint8 for frame in frames)
    envs.close()


def test_batch_infos_merges_as_gymnasium_does() -> None:
    entries = [
        (0, {"a": 1, "b": np.float32(2.0), "c": "x", "d": {"e": 1.5}, "f": np.bool_(True)}),
        (2, {"a": 2.7, "c": "y", "d": {"e": 2.5, "g": True}, "h": np.arange(2)}),
    ]
    merged: dict[str, Any] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # gymnasium's merge of 2.7 into an int array
        reference = BeaconScanVectorEnv.__new__(BeaconScanVectorEnv)
        reference.num_envs = 3
        for index, info in entries:
            merged = reference._add_info(merged, info, index)
        batched = batch_infos(entries, 3)
    assert batched is not None
    _assert_same_infos(batched, merged, "infos")


def test_batch_infos_leaves_mixed_nesting_to_gymnasium() -> None:
    assert batch_infos([(0, {"a": {"b": 1}}), (1, {"a": 2})], 2) is None


def test_docstring_examples_run() -> None:
    failures, _ = doctest.testmod(beacon_scan_vector, optionflags=doctest.ELLIPSIS)
    assert failures == 0
