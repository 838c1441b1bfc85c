"""The RL Zoo hyper-parameter files: generated from the command line's configs, read by the zoo."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from sonar_gym.registration import ENVIRONMENTS
from sonar_gym.train.training import TRAINABLE_ALGORITHMS, load_config
from sonar_gym.train.zoo import (
    HYPERPARAMS_DIR,
    ZOO_TIMESTEPS,
    _yaml_value,
    zoo_entries,
    zoo_file_path,
    zoo_file_text,
)

BEACON_SCAN = "SonarGym/BeaconScan-v0"
REPOSITORY = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("algo", TRAINABLE_ALGORITHMS)
def test_checked_in_zoo_file_matches_the_configs(algo: str) -> None:
    path = zoo_file_path(algo)
    assert path.is_file(), f"missing {path}: run python -m sonar_gym.train.zoo"
    assert path.read_text() == zoo_file_text(algo), (
        f"{path} is out of date with train/configs/: run python -m sonar_gym.train.zoo"
    )


def test_every_env_has_a_ppo_entry_and_sac_only_where_actions_are_continuous() -> None:
    assert list(zoo_entries("ppo")) == list(ENVIRONMENTS)
    assert list(zoo_entries("sac")) == ["SonarGym/BlockExpansion-v0"]


def test_a_zoo_entry_carries_the_cli_config_of_its_env() -> None:
    entry = zoo_entries("ppo")[BEACON_SCAN]
    config = load_config(BEACON_SCAN, "ppo")
    assert config.source.name == "beacon_scan.ppo.toml"
    for key, value in config.hyperparameters.items():
        assert entry[key] == value, key
    assert entry["normalize"] == {
        "norm_obs": True,
        "norm_reward": True,
        "gamma": 0.98,
        "clip_obs": 10.0,
    }
    assert entry["policy_kwargs"] == "dict(net_arch=[128, 128], activation_fn=nn.Tanh)"
    assert (entry["n_envs"], entry["n_timesteps"]) == (config.n_envs, ZOO_TIMESTEPS)


def test_yaml_numbers_without_a_dot_are_tagged_as_floats() -> None:
    assert _yaml_value(3e-5) == "!!float 3e-05"
    assert _yaml_value(0.0003) == "0.0003"
    assert _yaml_value([64, 64]) == "[64, 64]"
    assert _yaml_value("it's") == "'it''s'"
    with pytest.raises(ValueError, match="non-finite"):
        _yaml_value(float("inf"))


@pytest.mark.slow
def test_rl_zoo_trains_beacon_scan_with_the_project_entry(tmp_path: Path) -> None:
    import rl_zoo3  # noqa: F401  (the [zoo] extra, which make test-slow installs)
    import yaml
    from stable_baselines3 import PPO

    for algo in TRAINABLE_ALGORITHMS:  # the zoo's own YAML reader gets back what was written
        assert yaml.safe_load(zoo_file_path(algo).read_text()) == zoo_entries(algo)
    command = [
        sys.executable, "-m", "rl_zoo3.train", "--algo", "ppo", "--env", BEACON_SCAN,
        "--gym-packages", "sonar_gym", "-conf", str(HYPERPARAMS_DIR / "ppo.yml"),
        "-n", "2048", "--seed", "0", "-f", str(tmp_path),
    ]  # fmt: skip
    result = subprocess.run(
        command, cwd=REPOSITORY, capture_output=True, text=True, timeout=1800, check=False
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    assert "Hyperparameters not found" not in result.stdout
    (model_path,) = tmp_path.glob("ppo/SonarGym-BeaconScan-v0_*/SonarGym-BeaconScan-v0.zip")
    model = PPO.load(model_path, device="cpu")
    config = load_config(BEACON_SCAN, "ppo")
    for key in ("n_steps", "batch_size", "n_epochs", "gamma", "gae_lambda", "ent_coef"):
        assert getattr(model, key) == config.hyperparameters[key], key
    assert model.n_envs == config.n_envs
    assert model.policy_kwargs["net_arch"] == config.policy_kwargs["net_arch"]
    assert model.policy_kwargs["activation_fn"].__name__ == "Tanh"
    assert model.num_timesteps >= 2048
