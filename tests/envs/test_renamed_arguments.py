"""Renamed ``gym.make`` arguments: the old name still works, warns with the new one, and gives
the same env; the old and new name together are refused."""

from __future__ import annotations

import dataclasses
import warnings

import gymnasium as gym
import pytest

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.envs.config import renamed_arguments
from sonar_gym.registration import ENVIRONMENTS

# (env id, old name, new name, a non-default value); written out here rather than read from
# the configs' tables, so that dropping a rename from a table fails this test.
RENAMES = [
    ("SonarGym/BeaconScan-v0", "n_bins", "n_range_bins", 36),
    ("SonarGym/ActiveBeaconScan-v0", "n_bins", "n_range_bins", 36),
    ("SonarGym/ActiveBeaconScan-v0", "linear_speed_mps", "robot_speed_mps", 0.3),
    (
        "SonarGym/SweepLocalization-v0",
        "encoder_noise_std_m_per_sqrt_m",
        "encoder_std_m_per_sqrt_m",
        0.002,
    ),
    ("SonarGym/SweepLocalization-v0", "wheel_scale_error", "wheel_scale_error_bound", 0.02),
    ("SonarGym/Trilateration-v0", "measurement_cost_per_s", "sensing_cost_per_s", 0.3),
    ("SonarGym/Trilateration-v0", "max_error_score", "max_error_loss", 30.0),
    ("SonarGym/WallCorrection-v0", "encoder_noise_m_per_sqrt_m", "encoder_std_m_per_sqrt_m", 0.001),
]


@pytest.mark.parametrize(("env_id", "old", "new", "value"), RENAMES)
def test_old_name_warns_naming_the_new_one_and_gives_the_same_env(
    env_id: str, old: str, new: str, value: float
) -> None:
    with pytest.warns(DeprecationWarning, match=f"'{old}' is deprecated; use '{new}'") as record:
        old_env = gym.make(env_id, **{old: value})
    assert [w.filename for w in record] == [__file__]  # points at the caller's gym.make line
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        new_env = gym.make(env_id, **{new: value})
    assert old_env.unwrapped.config == new_env.unwrapped.config
    assert getattr(new_env.unwrapped.config, new) == value
    assert new_env.unwrapped.config != gym.make(env_id).unwrapped.config
    old_obs, _ = old_env.reset(seed=4)
    new_obs, _ = new_env.reset(seed=4)
    assert old_obs.tobytes() == new_obs.tobytes()


@pytest.mark.parametrize(("env_id", "old", "new", "value"), RENAMES)
def test_old_and_new_name_together_are_refused_naming_both(
    env_id: str, old: str, new: str, value: float
) -> None:
    with pytest.raises(ValueError, match=f"'{old}' and '{new}' are the same setting"):
        gym.make(env_id, **{old: value, new: value})


@pytest.mark.parametrize("env_id", sorted(ENVIRONMENTS))
def test_rename_tables_hold_exactly_the_renames_and_map_old_names_to_fields(env_id: str) -> None:
    config_type = type(gym.make(env_id).unwrapped.config)
    table = renamed_arguments(config_type)
    fields = {f.name for f in dataclasses.fields(config_type)}
    assert dict(table) == {old: new for e, old, new, _ in RENAMES if e == env_id}
    assert set(table.values()) <= fields
    assert not set(table) & fields


def test_one_name_per_concept_across_the_envs() -> None:
    fields = {
        name
        for env_id in ENVIRONMENTS
        for name in (f.name for f in dataclasses.fields(gym.make(env_id).unwrapped.config))
    }
    assert not fields & {old for _, old, _, _ in RENAMES}
    assert {"sensing_cost_per_s", "max_error_loss", "encoder_std_m_per_sqrt_m"} <= fields
    assert {"robot_speed_mps", "n_range_bins", "wheel_scale_error_bound"} <= fields
