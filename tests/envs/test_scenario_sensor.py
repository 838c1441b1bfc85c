"""Every pulse-echo env takes its sonar from the scenario's ``[sensor]`` when the file sets one,
and keeps its paper's preset when it does not."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.scenario import load_scenario
from sonar_gym.sonar.presets import preset as transducer_preset
from sonar_gym.sonar.swept import SideSonars

SCENARIOS = Path(sonar_gym.__file__).parent / "scenarios"

# (env id, built-in scenario, the preset its paper uses, another preset)
CASES = [
    ("SonarGym/BeaconScan-v0", "beom_cho_lab", "polaroid-6500", "srf04"),
    ("SonarGym/SweepLocalization-v0", "kim_arena", "srf04", "polaroid-6500"),
    ("SonarGym/WallCorrection-v0", "apcs_corridor", "ma40b8", "srf04"),
]


def scenario_file(tmp_path: Path, builtin: str, preset: str | None) -> Path:
    """The built-in scenario with its ``[sensor]`` preset set to ``preset`` (None: no table)."""
    lines = (SCENARIOS / f"{builtin}.toml").read_text().splitlines()
    start = lines.index("[sensor]")
    assert lines[start + 1].startswith("preset = ")
    sensor = [] if preset is None else ["[sensor]", f'preset = "{preset}"']
    path = tmp_path / f"{builtin}_{preset}.toml"
    path.write_text("\n".join(lines[:start] + sensor + lines[start + 2 :]) + "\n")
    return path


def transducer_of(env: gym.Env) -> object:
    """The transducer the env pings with (after a reset)."""
    task = env.unwrapped
    task.reset(seed=0)
    if hasattr(task, "sonars"):
        return task.sonars.transducer
    if hasattr(task, "sonar"):
        return task.sonar.transducer
    return task._require_episode().sonar.transducer


@pytest.mark.parametrize(("env_id", "builtin", "paper", "other"), CASES)
def test_a_scenario_sensor_replaces_the_papers_preset(
    tmp_path: Path, env_id: str, builtin: str, paper: str, other: str
) -> None:
    default = transducer_of(gym.make(env_id))
    chosen = transducer_of(gym.make(env_id, scenario=str(scenario_file(tmp_path, builtin, other))))
    expected = transducer_preset(other)
    assert chosen != default
    assert chosen.frequency_hz == expected.frequency_hz  # type: ignore[attr-defined]
    assert chosen.max_range_m == expected.max_range_m  # type: ignore[attr-defined]


@pytest.mark.parametrize(("env_id", "builtin", "paper", "other"), CASES)
def test_a_scenario_without_sensor_keeps_the_papers_preset(
    tmp_path: Path, env_id: str, builtin: str, paper: str, other: str
) -> None:
    default = transducer_of(gym.make(env_id))
    without = transducer_of(gym.make(env_id, scenario=str(scenario_file(tmp_path, builtin, None))))
    assert without == default
    assert default.frequency_hz == transducer_preset(paper).frequency_hz  # type: ignore[attr-defined]


def test_a_chosen_sensor_changes_what_the_sweeps_see(tmp_path: Path) -> None:
    path = scenario_file(tmp_path, "kim_arena", "polaroid-6500")
    default, chosen = (
        gym.make("SonarGym/SweepLocalization-v0"),
        gym.make("SonarGym/SweepLocalization-v0", scenario=str(path)),
    )
    action = np.array([2, 0], dtype=default.action_space.dtype)
    default.reset(seed=1)
    chosen.reset(seed=1)
    assert default.step(action)[0].tobytes() != chosen.step(action)[0].tobytes()


def test_wall_correction_keeps_its_timing_jitter_on_a_chosen_sensor(tmp_path: Path) -> None:
    path = scenario_file(tmp_path, "apcs_corridor", "srf04")
    sonars = gym.make("SonarGym/WallCorrection-v0", scenario=str(path)).unwrapped.sonars
    assert isinstance(sonars, SideSonars)
    assert sonars.transducer.range_noise_std_m == 0.001
    assert transducer_preset("srf04").range_noise_std_m != 0.001


def test_the_loader_records_whether_the_file_chose_a_preset(tmp_path: Path) -> None:
    assert load_scenario("kim_arena").sensor.given
    without = load_scenario(scenario_file(tmp_path, "kim_arena", None)).sensor
    assert not without.given
    assert without.preset_or("srf04") == "srf04"
    assert load_scenario("kim_arena").sensor.preset_or("ma40b8") == "srf04"
