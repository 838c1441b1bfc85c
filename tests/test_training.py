"""Training with stable-baselines3 on the fake env: files, configs, resume, the policy loader."""

from __future__ import annotations

import json
import pickle
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

from sonar_gym.agents.base import Agent, make_agent
from sonar_gym.agents.learned import (
    PolicyAgent,
    algorithm_class,
    detect_algorithm,
    load_policy_agent,
    vecnormalize_path_for,
)
from tests.cli_fakes import BOX_ID, DISCRETE_ID, MULTI_DISCRETE_ID
from sonar_gym.train import UsageError
from sonar_gym.train.evaluation import evaluate_agents
from sonar_gym.train.report import moving_average
from sonar_gym.train.training import (
    CONFIG_DIR,
    TRAINABLE_ALGORITHMS,
    check_algorithm_allowed,
    config_path_for,
    default_run_dir,
    env_short_name,
    load_config,
    read_episode_log,
    train,
)

torch.set_num_threads(1)  # networks of a few dozen units: more threads only contend

TINY_CONFIGS = {
    "ppo": """
n_envs = 2
checkpoint_every = 128
eval_episodes = 3
[hyperparameters]
n_steps = 64
batch_size = 64
n_epochs = 2
[policy_kwargs]
net_arch = [16, 16]
""",
    "a2c": """
n_envs = 2
eval_episodes = 2
[hyperparameters]
n_steps = 8
[policy_kwargs]
net_arch = [16]
""",
    "sac": """
n_envs = 1
eval_episodes = 2
[hyperparameters]
learning_starts = 32
batch_size = 16
buffer_size = 1000
[policy_kwargs]
net_arch = [16]
""",
    "dqn": """
n_envs = 1
eval_episodes = 2
[hyperparameters]
learning_starts = 32
batch_size = 16
buffer_size = 1000
target_update_interval = 32
[policy_kwargs]
net_arch = [16]
""",
}


def tiny_config(tmp_path: Path, algo: str) -> Path:
    path = tmp_path / f"tiny.{algo}.toml"
    path.write_text(TINY_CONFIGS[algo])
    return path


def tiny_ppo_run(tmp_path: Path) -> Path:
    """A 128-step PPO run on the discrete env with the tiny config, without evaluation."""
    out = tmp_path / "run"
    train(
        DISCRETE_ID,
        "ppo",
        128,
        out_dir=out,
        config_path=tiny_config(tmp_path, "ppo"),
        progress_bar=False,
        eval_episodes=0,
    )
    return out


def test_learning_curve_smoothing_is_a_trailing_moving_average():
    assert moving_average([1.0, 2.0, 3.0, 4.0], 2).tolist() == [1.0, 1.5, 2.5, 3.5]
    assert moving_average([4.0, 2.0, 0.0], 5).tolist() == [4.0, 3.0, 2.0]
    assert moving_average([], 3).size == 0


def test_env_short_names_are_snake_case_without_namespace_or_version():
    assert env_short_name("SonarGym/BeaconScan-v0") == "beacon_scan"
    assert env_short_name("SonarGym/SweepLocalization-v0") == "sweep_localization"
    assert env_short_name("SonarGym/WallCorrection-v12") == "wall_correction"
    assert default_run_dir("SonarGym/BlockExpansion-v0", "ppo", 3) == Path(
        "runs/block_expansion-ppo-3"
    )


def test_config_falls_back_to_the_default_of_the_algorithm():
    assert config_path_for(DISCRETE_ID, "sac") == CONFIG_DIR / "default.sac.toml"


@pytest.mark.parametrize("algo", TRAINABLE_ALGORITHMS)
def test_shipped_default_configs_build_their_algorithm(algo):
    config = load_config(DISCRETE_ID, algo)
    env = gym.make(BOX_ID if algo == "sac" else DISCRETE_ID)
    model = algorithm_class(algo)(
        config.policy, env, policy_kwargs=config.sb3_policy_kwargs(), **config.hyperparameters
    )
    assert model.gamma == config.hyperparameters.get("gamma", 0.99)


@pytest.mark.parametrize("path", sorted(CONFIG_DIR.glob("*.toml")), ids=lambda p: p.name)
def test_every_shipped_config_is_valid_for_its_algorithm(path):
    algo = path.name.split(".")[-2]
    config = load_config("SonarGym/BeaconScan-v0", algo, path)
    assert config.n_envs >= 1 and config.checkpoint_every >= 1


def test_config_with_an_unknown_hyperparameter_names_the_allowed_ones(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("[hyperparameters]\nlearning_rat = 0.1\n")
    with pytest.raises(UsageError) as error:
        load_config(DISCRETE_ID, "ppo", path)
    assert "learning_rat" in str(error.value) and "learning_rate" in str(error.value)


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("n_env = 2\n", "unknown keys"),
        ("n_envs = 0\n", "n_envs"),
        ('[policy_kwargs]\nactivation_fn = "swish"\n', "activation_fn"),
        ("[vec_normalize]\nnorm_ob = true\n", "norm_ob"),
        ("[hyperparameters\n", "bad.toml"),
    ],
)
def test_malformed_configs_are_refused_with_the_field(tmp_path, text, fragment):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(UsageError, match=fragment):
        load_config(DISCRETE_ID, "ppo", path)


def test_algorithms_are_matched_to_action_spaces():
    discrete = gym.spaces.Discrete(3)
    box = gym.spaces.Box(-1.0, 1.0, (2,))
    multi = gym.spaces.MultiDiscrete([2, 3])
    for algo in ("ppo", "a2c", "dqn"):
        check_algorithm_allowed(algo, discrete)
    for algo in ("ppo", "a2c", "sac"):
        check_algorithm_allowed(algo, box)
    with pytest.raises(UsageError, match="SAC needs a Box action space"):
        check_algorithm_allowed("sac", discrete)
    with pytest.raises(UsageError, match="DQN needs a Discrete action space.*'ppo', 'a2c'"):
        check_algorithm_allowed("dqn", multi)
    with pytest.raises(UsageError, match="choose one of"):
        check_algorithm_allowed("trpo", discrete)


def test_ppo_training_saves_a_run_that_loads_and_evaluates(tmp_path):
    out = tmp_path / "run"
    result = train(
        DISCRETE_ID,
        "ppo",
        384,
        out_dir=out,
        seed=1,
        config_path=tiny_config(tmp_path, "ppo"),
        progress_bar=False,
    )
    assert result.total_timesteps == 384
    for name in (
        "model.zip",
        "vecnormalize.pkl",
        "run.json",
        "learning_curve.png",
        "episodes.csv",
        "monitor/0.monitor.csv",
        "monitor/1.monitor.csv",
        "checkpoints/rl_model_256_steps.zip",
        "checkpoints/rl_model_vecnormalize_256_steps.pkl",
    ):
        assert (out / name).is_file(), name
    assert any((out / "tb").rglob("events.out.tfevents*"))
    run_info = json.loads((out / "run.json").read_text())
    assert run_info["env_id"] == DISCRETE_ID and run_info["algo"] == "ppo"
    assert run_info["seed"] == 1 and run_info["total_timesteps"] == 384
    assert run_info["vec_normalize"]["norm_reward"] is True
    assert {"stable-baselines3", "torch", "gymnasium"} <= set(run_info["versions"])
    timesteps, rewards = read_episode_log(out / "episodes.csv")
    assert len(rewards) > 10 and np.all(np.diff(timesteps) >= 0) and timesteps[-1] <= 384
    assert result.eval_episodes == 3 and result.eval_mean_reward is not None

    env = gym.make(DISCRETE_ID)
    agent = make_agent(str(out / "model.zip"), env)
    assert isinstance(agent, PolicyAgent) and isinstance(agent, Agent)
    assert agent.normalizer is not None and agent.normalizer.obs_rms.mean.shape == (3,)
    evaluated = evaluate_agents(DISCRETE_ID, [str(out / "model.zip"), str(out)], episodes=4)
    assert all(len(r.records) == 4 for r in evaluated)
    assert evaluated[0].records == evaluated[1].records  # the run directory means its model.zip


def test_policy_agent_normalises_like_vecnormalize(tmp_path):
    out = tiny_ppo_run(tmp_path)
    env = gym.make(DISCRETE_ID)
    agent = load_policy_agent(out / "model.zip", env)
    reference = VecNormalize.load(str(out / "vecnormalize.pkl"), DummyVecEnv([lambda: env]))
    model = algorithm_class("ppo").load(out / "model.zip")
    rng = np.random.default_rng(0)
    for _ in range(20):
        observation = rng.uniform(-1.0, 2.0, size=3).astype(np.float32)
        expected, _ = model.predict(reference.normalize_obs(observation), deterministic=True)
        assert agent.act(observation) == int(expected)
    normalized = reference.normalize_obs(np.ones(3, dtype=np.float32))
    assert not np.allclose(normalized, 1.0)  # the statistics do change the input


@pytest.mark.parametrize(
    "algo, env_id", [("a2c", MULTI_DISCRETE_ID), ("sac", BOX_ID), ("dqn", DISCRETE_ID)]
)
def test_other_algorithms_train_and_load_on_their_action_spaces(tmp_path, algo, env_id):
    out = tmp_path / algo
    result = train(
        env_id, algo, 64, out_dir=out, config_path=tiny_config(tmp_path, algo), progress_bar=False
    )
    assert result.total_timesteps >= 64
    run_info = json.loads((out / "run.json").read_text())
    assert run_info["vec_normalize"]["norm_reward"] is False  # reward normalisation: PPO only
    (out / "run.json").unlink()  # the loader must tell the algorithm from the zip alone
    assert detect_algorithm(out / "model.zip") == algo
    env = gym.make(env_id)
    agent = make_agent(str(out / "model.zip"), env)
    observation, _ = env.reset(seed=0)
    assert env.action_space.contains(agent.act(observation))


def test_ppo_and_a2c_zips_are_told_apart_without_run_json(tmp_path):
    env = gym.make(DISCRETE_ID)
    for algo in ("ppo", "a2c", "dqn"):
        path = tmp_path / f"{algo}.zip"
        algorithm_class(algo)("MlpPolicy", env).save(path)
        assert detect_algorithm(path) == algo


def test_loader_refuses_a_model_whose_normalisation_statistics_are_missing(tmp_path):
    out = tiny_ppo_run(tmp_path)
    (out / "vecnormalize.pkl").unlink()
    with pytest.raises(ValueError, match="vecnormalize.pkl is missing"):
        load_policy_agent(out / "model.zip", gym.make(DISCRETE_ID))


def test_loader_refuses_an_env_with_other_spaces(tmp_path):
    out = tmp_path / "run"
    train(
        DISCRETE_ID,
        "ppo",
        128,
        out_dir=out,
        config_path=tiny_config(tmp_path, "ppo"),
        progress_bar=False,
        eval_episodes=0,
        env_kwargs={"noise_std_m": 0.02},
    )
    with pytest.raises(ValueError, match="action space.*env arguments {'noise_std_m': 0.02}"):
        load_policy_agent(out, gym.make(BOX_ID))
    with pytest.raises(UsageError, match="cannot act in CliFake/LocateBox-v0"):
        evaluate_agents([DISCRETE_ID, BOX_ID], ["scripted", str(out)], episodes=1)


def test_checkpoint_statistics_sit_beside_the_checkpoint():
    checkpoint = Path("run/checkpoints/rl_model_2048_steps.zip")
    assert vecnormalize_path_for(checkpoint) == Path(
        "run/checkpoints/rl_model_vecnormalize_2048_steps.pkl"
    )
    assert vecnormalize_path_for(Path("run/model.zip")) == Path("run/vecnormalize.pkl")


def test_resume_adds_the_new_timesteps_to_the_counter(tmp_path):
    out = tmp_path / "run"
    config = tiny_config(tmp_path, "ppo")
    first = train(
        DISCRETE_ID,
        "ppo",
        256,
        out_dir=out,
        config_path=config,
        progress_bar=False,
        eval_episodes=0,
    )
    assert first.total_timesteps == 256
    with (out / "vecnormalize.pkl").open("rb") as handle:
        count_before = pickle.load(handle).obs_rms.count
    resumed = train(
        None,
        None,
        128,
        resume=out / "model.zip",
        config_path=config,
        progress_bar=False,
        eval_episodes=0,
    )
    assert resumed.out_dir == out and resumed.algo == "ppo" and resumed.env_id == DISCRETE_ID
    assert resumed.total_timesteps == 384
    assert algorithm_class("ppo").load(out / "model.zip").num_timesteps == 384
    with (out / "vecnormalize.pkl").open("rb") as handle:
        assert pickle.load(handle).obs_rms.count > count_before  # the statistics continued
    run_info = json.loads((out / "run.json").read_text())
    assert run_info["total_timesteps"] == 384
    assert [segment["timesteps"] for segment in run_info["segments"]] == [256, 128]
    assert (out / "checkpoints" / "rl_model_384_steps.zip").is_file()


def test_resume_from_a_checkpoint_uses_its_statistics(tmp_path):
    out = tmp_path / "run"
    config = tiny_config(tmp_path, "ppo")
    train(
        DISCRETE_ID,
        "ppo",
        256,
        out_dir=out,
        config_path=config,
        progress_bar=False,
        eval_episodes=0,
    )
    resumed = train(
        DISCRETE_ID,
        "ppo",
        128,
        out_dir=tmp_path / "branch",
        resume=out / "checkpoints" / "rl_model_128_steps.zip",
        config_path=config,
        progress_bar=False,
        eval_episodes=0,
    )
    assert resumed.total_timesteps == 256
    assert (tmp_path / "branch" / "model.zip").is_file()


def test_resume_refuses_another_algorithm_or_env(tmp_path):
    out = tmp_path / "run"
    config = tiny_config(tmp_path, "ppo")
    train(
        DISCRETE_ID,
        "ppo",
        128,
        out_dir=out,
        config_path=config,
        progress_bar=False,
        eval_episodes=0,
    )
    with pytest.raises(UsageError, match="trained with ppo, not a2c"):
        train(None, "a2c", 128, resume=out / "model.zip")
    with pytest.raises(UsageError, match="trained on CliFake/Locate-v0"):
        train(BOX_ID, None, 128, resume=out / "model.zip")
    (out / "vecnormalize.pkl").unlink()
    with pytest.raises(UsageError, match="VecNormalize statistics"):
        train(None, None, 128, resume=out / "model.zip")


def test_an_existing_run_is_not_overwritten_by_accident(tmp_path):
    out = tmp_path / "run"
    config = tiny_config(tmp_path, "ppo")
    train(
        DISCRETE_ID,
        "ppo",
        128,
        out_dir=out,
        config_path=config,
        progress_bar=False,
        eval_episodes=0,
    )
    with pytest.raises(UsageError, match="already holds a trained model"):
        train(DISCRETE_ID, "ppo", 128, out_dir=out, config_path=config, progress_bar=False)
    again = train(
        DISCRETE_ID,
        "ppo",
        128,
        out_dir=out,
        config_path=config,
        progress_bar=False,
        eval_episodes=0,
        overwrite=True,
    )
    assert again.total_timesteps == 128
    assert not (out / "checkpoints" / "rl_model_256_steps.zip").exists()


def test_training_refuses_an_algorithm_the_action_space_does_not_allow(tmp_path):
    with pytest.raises(UsageError, match="SAC needs a Box"):
        train(DISCRETE_ID, "sac", 64, out_dir=tmp_path / "x")
    assert not (tmp_path / "x").exists()  # nothing half-built


def test_subprocess_workers_train_too(tmp_path):
    out = tmp_path / "run"
    result = train(
        DISCRETE_ID,
        "ppo",
        128,
        out_dir=out,
        config_path=tiny_config(tmp_path, "ppo"),
        subproc=True,
        progress_bar=False,
        eval_episodes=0,
    )
    assert result.total_timesteps == 128
    assert json.loads((out / "run.json").read_text())["segments"][0]["subproc"] is True
