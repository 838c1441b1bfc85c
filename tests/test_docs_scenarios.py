"""docs/scenarios.md stays true: its worked example loads, and its table lists every section."""

from __future__ import annotations

import math
import re
from pathlib import Path

import gymnasium as gym
import pytest

import sonar_gym
from sonar_gym.scenario import _TOP_LEVEL_KEYS, ScenarioError, load_scenario

DOC = Path(__file__).resolve().parents[1] / "docs" / "scenarios.md"


def example_toml() -> str:
    text = DOC.read_text(encoding="utf-8")
    block = re.search(
        r"<!-- scenario-example:start -->\s*```toml\n(.*?)```\s*<!-- scenario-example:end -->",
        text,
        re.DOTALL,
    )
    assert block is not None, "the worked example block is missing from docs/scenarios.md"
    return block.group(1)


@pytest.fixture
def example_path(tmp_path: Path) -> Path:
    path = tmp_path / "my_lab.toml"
    path.write_text(example_toml(), encoding="utf-8")
    return path


def test_worked_example_loads_with_the_values_the_doc_states(example_path: Path) -> None:
    lab = load_scenario(example_path)
    assert lab.name == "my_lab"
    assert lab.room is not None and lab.room.size == (4.0, 3.0)
    (partition,) = lab.walls
    assert partition.mapped is False
    (table,) = lab.boxes
    assert table.size == (1.2, 0.6) and table.angle_deg == 10.0
    assert lab.beacon("small_beacon").radius == 0.0191
    assert lab.beacon("large_beacon").radius == 0.07
    assert [c.role for c in lab.cylinders].count("clutter") == 1
    assert lab.sensor.preset == "polaroid-6500" and math.isclose(lab.reflector.distance, 0.515)


def test_worked_example_runs_in_beacon_scan(example_path: Path) -> None:
    env = gym.make("SonarGym/BeaconScan-v0", scenario=str(example_path))
    observation, _ = env.reset(seed=0)
    assert env.observation_space.contains(observation)
    env.close()


def test_every_section_of_the_format_is_documented() -> None:
    text = DOC.read_text(encoding="utf-8")
    for key in _TOP_LEVEL_KEYS:
        assert f"`[{key}]`" in text or f"`[[{key}]]`" in text, key
    assert set(sonar_gym.builtin_names()) <= set(re.findall(r"`(\w+)`", text))


def test_the_documented_error_message_is_the_real_one(tmp_path: Path) -> None:
    path = tmp_path / "my_lab.toml"
    path.write_text(example_toml().replace('role = "small_beacon"', 'role = "beacon"'))
    with pytest.raises(ScenarioError) as error:
        load_scenario(path)
    documented = re.search(r"my_lab\.toml: (field 'cylinders\[0\]\.role'.*)", DOC.read_text())
    assert documented is not None
    assert str(error.value) == f"{path}: {documented.group(1)}"


def test_output_folder_examples_in_docs_are_what_the_command_line_writes() -> None:
    """Every example row of docs/outputs.md names the folder its command writes to."""
    import shlex

    from sonar_gym.train import cli, evaluation

    text = (DOC.parent / "outputs.md").read_text(encoding="utf-8")
    rows = re.findall(
        r"^\| `sonar-gym (evaluate[^`]*)`[^|]*\| `results/evaluate/([^`]+)/` \|", text, re.M
    )
    assert len(rows) == 4
    for command, folder in rows:
        arguments = cli.build_parser().parse_args(shlex.split(command))
        out_dir = cli.evaluate_output_dir(arguments, evaluation.parse_env_args(arguments.env_arg))
        assert out_dir.as_posix() == f"results/evaluate/{folder}", command
