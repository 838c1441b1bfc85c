"""RLlib training and Ray evaluation.

The slow tests start a local Ray instance on this machine (no cluster) and need the ``[ray]``
extra (``make test-slow`` installs it); the quick ones check the parts that need no Ray.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import sonar_gym  # noqa: F401
from sonar_gym.train import UsageError
from sonar_gym.train.distributed import chunk_seeds
from sonar_gym.train.evaluation import evaluate_agents, play_seeds
from sonar_gym.agents.rllib_policy import is_rllib_run
from sonar_gym.train.rllib_backend import RUN_FILE, require_ray, train_rllib


def test_chunks_cover_every_seed_once_in_order() -> None:
    chunks = chunk_seeds(5, 11, 4)
    assert chunks == [[5, 6, 7, 8], [9, 10, 11, 12], [13, 14, 15]]


def test_chunk_size_below_one_is_refused() -> None:
    with pytest.raises(ValueError, match="chunk_episodes"):
        chunk_seeds(0, 3, 0)


def test_missing_ray_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # makes ``import ray`` raise ImportError
    with pytest.raises(UsageError, match=r"\.\[ray\]"):
        require_ray()


def test_an_empty_directory_is_not_an_rllib_run(tmp_path: Path) -> None:
    assert not is_rllib_run(tmp_path)


def test_training_refuses_an_algorithm_it_does_not_run(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="--algo"):
        train_rllib("SonarGym/Trilateration-v0", 10, tmp_path / "run", algo="dqn")


@pytest.fixture(scope="module")
def local_ray():
    import ray

    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    ray.shutdown()


@pytest.mark.slow
@pytest.mark.parametrize("env_id", ["SonarGym/Trilateration-v0", "SonarGym/BeaconScan-v0"])
def test_ray_evaluation_equals_the_local_run_seed_for_seed(local_ray, env_id: str) -> None:
    from sonar_gym.train.distributed import evaluate_plan_on_ray

    local = evaluate_agents([env_id], ["paper", "random"], episodes=8, seed=3)
    plan = {env_id: ["paper", "random"]}
    remote = evaluate_plan_on_ray(plan, 8, 3, {}, 10_000, play_seeds, chunk_episodes=3)
    for result in local:
        assert list(result.records) == remote[(env_id, result.agent)]


@pytest.mark.slow
def test_rllib_trains_checkpoints_and_the_policy_acts(local_ray, tmp_path: Path) -> None:
    from sonar_gym.agents.rllib_policy import RLlibPolicyAgent

    run_dir = tmp_path / "tri-rllib"
    result = train_rllib("SonarGym/Trilateration-v0", 1024, run_dir, num_env_runners=1, seed=0)
    assert result.timesteps >= 1024
    assert is_rllib_run(run_dir)
    record = json.loads((run_dir / RUN_FILE).read_text())
    assert record["env_id"] == "SonarGym/Trilateration-v0" and record["backend"] == "rllib"
    env = gym.make("SonarGym/Trilateration-v0")
    agent = RLlibPolicyAgent(run_dir, env)
    observation, _ = env.reset(seed=0)
    for _ in range(5):
        action = agent.act(observation)
        assert env.action_space.contains(action)
        observation, reward, terminated, truncated, _ = env.step(action)
        assert np.isfinite(reward)
        if terminated or truncated:
            break
    with pytest.raises(ValueError, match="action space|observations"):
        RLlibPolicyAgent(run_dir, gym.make("SonarGym/BeaconScan-v0"))
