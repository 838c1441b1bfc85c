"""The ``learned`` agent, the shipped-policy locator and ``sonar-gym baselines`` (tiny policies)."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch

from sonar_gym import pretrained
from sonar_gym.agents.base import agent_names, make_agent
from sonar_gym.agents.learned import PolicyAgent
from sonar_gym.train import UsageError, baselines, baselines_plots, cli
from sonar_gym.train.evaluation import EpisodeRecord
from sonar_gym.train.training import train
from tests.cli_fakes import BOX_ID, DISCRETE_ID
from tests.test_training import tiny_config, tiny_ppo_run

torch.set_num_threads(1)  # tiny networks: more threads only contend

BEACON_SCAN = "SonarGym/BeaconScan-v0"
TRILATERATION = "SonarGym/Trilateration-v0"
T_975_DF4 = 2.7764451051977987
"""Student-t quantile t_{0.975} with 4 degrees of freedom (statistical tables)."""


@pytest.fixture(autouse=True)
def wide_console(monkeypatch):
    """Tables wide enough not to wrap, whatever terminal the tests run in."""
    monkeypatch.setenv("COLUMNS", "250")


@pytest.fixture(scope="module")
def fake_env_policy(tmp_path_factory) -> Path:
    """The shared tiny PPO run on ``CliFake/Locate-v0``."""
    return tiny_ppo_run(tmp_path_factory.mktemp("fake_policy"))


@pytest.fixture(scope="module")
def sonar_policies(tmp_path_factory) -> Path:
    """A pretrained root with tiny (barely trained) PPO policies for BeaconScan and
    Trilateration, in the shipped format (a learning curve and levels included)."""
    work = tmp_path_factory.mktemp("sonar_policies")
    root = work / "pretrained"
    for env_id in (BEACON_SCAN, TRILATERATION):
        out = root / pretrained.policy_name(env_id)
        train(
            env_id,
            "ppo",
            64,
            out_dir=out,
            config_path=tiny_config(work, "ppo"),
            progress_bar=False,
            eval_episodes=0,
        )
        (out / pretrained.LEARNING_CURVE_FILE).write_text(
            "training_seed,timesteps,wall_time_s,mean_reward,ci95\n"
            "0,0,0.0,-15.0,1.0\n0,64,1.0,-12.0,1.0\n1,0,0.0,-16.0,1.0\n1,64,1.0,-11.0,1.0\n"
        )
        (out / pretrained.TRAINING_FILE).write_text(
            json.dumps({"env_id": env_id, "levels": {"paper": -11.0, "random": -20.0}})
        )
    return root


def shipped_root(tmp_path: Path, policy: Path, *env_ids: str) -> Path:
    """A pretrained root holding ``policy`` as the shipped policy of each of ``env_ids``."""
    root = tmp_path / "pretrained"
    for env_id in env_ids:
        shutil.copytree(policy, root / pretrained.policy_name(env_id))
    return root


def records(rewards: list[float], first_seed: int = 0) -> list[EpisodeRecord]:
    return [
        EpisodeRecord(first_seed + i, reward, 0.01, None, 1.0, "ok", 1)
        for i, reward in enumerate(rewards)
    ]


# --------------------------------------------------------------------------------------------
# the learned agent


def test_learned_agent_loads_the_policy_shipped_for_the_env_id_and_acts(
    tmp_path, monkeypatch, fake_env_policy
):
    monkeypatch.setenv(
        pretrained.ROOT_VARIABLE, str(shipped_root(tmp_path, fake_env_policy, DISCRETE_ID))
    )
    env = gym.make(DISCRETE_ID)
    agent = make_agent("learned", env)
    assert isinstance(agent, PolicyAgent) and agent.name == "learned"
    observation, _ = env.reset(seed=3)
    action = agent.act(observation)
    assert env.action_space.contains(action)
    assert agent.act(observation) == action  # deterministic
    assert "learned" in agent_names(DISCRETE_ID)
    assert "learned" not in agent_names(BOX_ID)  # no policy ships for that id


def test_learned_agent_without_a_shipped_policy_says_so(tmp_path, monkeypatch):
    monkeypatch.setenv(pretrained.ROOT_VARIABLE, str(tmp_path / "empty"))
    with pytest.raises(ValueError, match=r"no shipped policy for env 'CliFake/Locate-v0'"):
        make_agent("learned", gym.make(DISCRETE_ID))
    assert "learned" not in agent_names(DISCRETE_ID)


def test_learned_agent_refuses_a_policy_of_other_spaces(tmp_path, monkeypatch, fake_env_policy):
    monkeypatch.setenv(
        pretrained.ROOT_VARIABLE, str(shipped_root(tmp_path, fake_env_policy, BOX_ID))
    )
    with pytest.raises(ValueError, match="action space"):
        make_agent("learned", gym.make(BOX_ID))


def test_without_the_variable_the_locator_looks_in_the_package(monkeypatch):
    monkeypatch.delenv(pretrained.ROOT_VARIABLE, raising=False)
    assert pretrained.pretrained_root() == Path(pretrained.__file__).resolve().parent
    assert pretrained.policy_dir(BEACON_SCAN).name == "BeaconScan-v0"


def test_evaluate_runs_the_learned_agent_beside_a_scripted_one(
    tmp_path, monkeypatch, capsys, fake_env_policy
):
    monkeypatch.setenv(
        pretrained.ROOT_VARIABLE, str(shipped_root(tmp_path, fake_env_policy, DISCRETE_ID))
    )
    out = tmp_path / "evaluation"
    argv = ["evaluate", "--env", DISCRETE_ID, "--agent", "scripted", "learned"]
    assert cli.main([*argv, "--episodes", "2", "--out", str(out)]) == 0
    results = json.loads((out / "evaluate.json").read_text())["results"]
    assert [result["agent"] for result in results] == ["scripted", "learned"]
    assert all(len(result["episodes"]) == 2 for result in results)


def test_evaluate_with_no_shipped_policy_exits_with_the_reason(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv(pretrained.ROOT_VARIABLE, str(tmp_path / "empty"))
    argv = ["evaluate", "--env", DISCRETE_ID, "--agent", "learned", "--out", str(tmp_path / "o")]
    assert cli.main(argv) == 2
    assert "no shipped policy for env 'CliFake/Locate-v0'" in capsys.readouterr().err


# --------------------------------------------------------------------------------------------
# statistics and selection


def test_paired_difference_is_the_student_t_interval_of_the_per_seed_differences():
    agent = records([1.0, 2.0, 3.0, 4.0, 6.0])
    paper = records([0.5, 2.5, 1.0, 3.0, 4.0])
    # differences 0.5, -0.5, 2, 1, 2: mean 1, sample variance 4.5 / 4
    half_width = T_975_DF4 * math.sqrt(4.5 / 4) / math.sqrt(5)
    difference = baselines.paired_difference(agent, paper)
    assert difference.mean == pytest.approx(1.0)
    assert difference.half_width == pytest.approx(half_width, rel=1e-9)
    assert difference.low == pytest.approx(1.0 - half_width, rel=1e-9)
    assert half_width == pytest.approx(1.316984, abs=1e-6)  # 2.776445 * 0.474342
    assert baselines.beats(difference) is False  # the interval reaches below zero
    clearly_better = baselines.paired_difference(records([2.0, 3.1, 4.0, 5.2, 6.0]), paper)
    assert baselines.beats(clearly_better) is True


def test_paired_difference_needs_the_same_seeds():
    with pytest.raises(ValueError, match="same seeds"):
        baselines.paired_difference(records([1.0, 2.0]), records([1.0, 2.0], first_seed=5))


def test_every_registered_env_has_one_heuristic_and_a_held_out_rooms_entry():
    expected = {
        "SonarGym/BeaconScan-v0": "sector",
        "SonarGym/ActiveBeaconScan-v0": "retry",
        "SonarGym/SweepLocalization-v0": "covariance",
        "SonarGym/Trilateration-v0": "adaptive",
        "SonarGym/BlockExpansion-v0": "spread",
        "SonarGym/WallCorrection-v0": "both_walls",
    }
    registered = baselines.resolve_baseline_envs(["all"])
    assert sorted(registered) == sorted(expected)
    for env_id in registered:
        assert baselines.heuristic_agent(env_id) == expected[env_id]
        assert env_id in baselines.HELD_OUT_ROOMS


def test_held_out_rooms_come_from_the_episode_seed():
    env = gym.make(BEACON_SCAN, scenario="random")
    first, _ = env.reset(seed=1_000_000)
    again, _ = env.reset(seed=1_000_000)
    other, _ = env.reset(seed=1_000_001)
    np.testing.assert_array_equal(first, again)
    assert not np.array_equal(first, other)


def test_retraining_evaluates_what_the_trainer_returns(tmp_path):
    calls = []

    def fake_trainer(env_ids, out_dir, progress):
        calls.append((env_ids, out_dir, progress))
        return {env_id: out_dir / pretrained.policy_name(env_id) for env_id in env_ids}

    dirs = baselines.train_policies([BEACON_SCAN], tmp_path, progress=False, trainer=fake_trainer)
    assert calls == [([BEACON_SCAN], tmp_path, False)]
    assert dirs == {BEACON_SCAN: tmp_path / "BeaconScan-v0"}
    with pytest.raises(UsageError, match="no policy for"):
        baselines.train_policies([BEACON_SCAN], tmp_path, False, trainer=lambda *_: {})


# --------------------------------------------------------------------------------------------
# the command


README_BEFORE = "# Title\n\nintro\n\n<!-- baselines:start -->\n"
README_AFTER = "<!-- baselines:end -->\n\n## Later\n\ntext\n"


def test_baselines_pretrained_writes_table_json_plots_and_the_readme_block(
    tmp_path, monkeypatch, capsys, sonar_policies
):
    monkeypatch.setenv(pretrained.ROOT_VARIABLE, str(sonar_policies))
    readme = tmp_path / "README.md"
    readme.write_text(README_BEFORE + "old table\n" + README_AFTER)
    out = tmp_path / "baselines"
    argv = ["baselines", "--pretrained", "--env", BEACON_SCAN, TRILATERATION, "--episodes", "3"]
    argv += ["--out", str(out), "--update-readme", "--readme", str(readme)]
    assert cli.main(argv) == 0
    printed = capsys.readouterr().out
    assert "total time" in printed

    table_lines = [
        line for line in (out / "baselines.md").read_text().splitlines() if line.startswith("| ")
    ]
    cells = [[cell.strip() for cell in line.strip("|").split("|")] for line in table_lines[1:]]
    assert [(row[0], row[1], row[2]) for row in cells] == [
        ("BeaconScan-v0", "trained", "learned"),
        ("BeaconScan-v0", "trained", "paper"),
        ("BeaconScan-v0", "trained", "sector (heuristic)"),
        ("BeaconScan-v0", "trained", "random"),
        ("BeaconScan-v0", "held-out random", "learned"),
        ("BeaconScan-v0", "held-out random", "paper"),
        ("BeaconScan-v0", "held-out random", "sector (heuristic)"),
        ("BeaconScan-v0", "held-out random", "random"),
        ("Trilateration-v0", "trained", "learned"),
        ("Trilateration-v0", "trained", "paper"),
        ("Trilateration-v0", "trained", "adaptive (heuristic)"),
        ("Trilateration-v0", "trained", "random"),
        ("Trilateration-v0", "none", "–"),
    ]

    data = json.loads((out / "baselines.json").read_text())
    rows = data["rows"]
    assert len(rows) == 12
    seeds = [pretrained.EVALUATION_SEED_START + i for i in range(3)]
    for row in rows:
        assert [episode["seed"] for episode in row["episodes"]] == seeds
    held_out = [row for row in rows if row["rooms"] == "held-out random"]
    assert {json.dumps(row["env_kwargs"]) for row in held_out} == {'{"scenario": "random"}'}
    # the paired difference is over the per-seed rewards the file lists
    key = {(row["env_id"], row["rooms"], row["agent"]): row for row in rows}
    learned = key[(BEACON_SCAN, "trained", "learned")]
    paper = key[(BEACON_SCAN, "trained", "paper")]
    differences = [
        a["reward"] - b["reward"]
        for a, b in zip(learned["episodes"], paper["episodes"], strict=True)
    ]
    assert learned["versus_paper"]["mean"] == pytest.approx(np.mean(differences))
    assert paper["versus_paper"] is None and paper["beats_paper"] is None
    assert learned["summary"]["reward_mean"] == pytest.approx(
        np.mean([episode["reward"] for episode in learned["episodes"]])
    )

    for name in (baselines.REWARDS_PLOT_FILE, baselines.LEARNING_CURVES_PLOT_FILE):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    text = readme.read_text()
    assert text.startswith(README_BEFORE) and text.endswith(README_AFTER)
    block = text[len(README_BEFORE) : -len(README_AFTER)]
    assert "old table" not in block
    assert block.strip() == (out / "baselines.md").read_text().removeprefix("# Baselines").strip()


def test_update_readme_replaces_exactly_the_block(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(README_BEFORE + "line one\nline two\n" + README_AFTER)
    baselines.replace_readme_block(readme, "| a | b |\n|---|---|\n")
    assert readme.read_text() == README_BEFORE + "| a | b |\n|---|---|\n" + README_AFTER


@pytest.mark.parametrize(
    "text", ["no markers\n", README_BEFORE + "x\n", "x\n" + README_AFTER + README_BEFORE]
)
def test_update_readme_without_its_markers_stops_before_running(
    tmp_path, monkeypatch, capsys, sonar_policies, text
):
    monkeypatch.setenv(pretrained.ROOT_VARIABLE, str(sonar_policies))
    readme = tmp_path / "README.md"
    readme.write_text(text)
    out = tmp_path / "baselines"
    argv = ["baselines", "--pretrained", "--env", BEACON_SCAN, "--episodes", "1", "--out", str(out)]
    assert cli.main([*argv, "--update-readme", "--readme", str(readme)]) == 2
    assert "<!-- baselines:start -->" in capsys.readouterr().err
    assert not out.exists()
    assert readme.read_text() == text


def test_baselines_pretrained_names_the_envs_without_a_shipped_policy(
    tmp_path, monkeypatch, capsys, sonar_policies
):
    monkeypatch.setenv(pretrained.ROOT_VARIABLE, str(sonar_policies))
    argv = ["baselines", "--pretrained", "--env", BEACON_SCAN, "SonarGym/WallCorrection-v0"]
    assert cli.main([*argv, "--out", str(tmp_path / "o")]) == 2
    assert "no shipped policy for ['SonarGym/WallCorrection-v0']" in capsys.readouterr().err


def test_the_default_folder_is_named_after_the_arguments():
    assert baselines.output_folder_name([BEACON_SCAN], 3, True) == "BeaconScan-v0_3ep_pretrained"
    assert baselines.output_folder_name(["all"], 200, False) == "all_200ep_trained"


def test_retraining_without_the_training_module_points_to_pretrained(tmp_path, monkeypatch):
    import importlib

    real_import = importlib.import_module

    def without_training(name, *args):
        if name == baselines.TRAINING_MODULE:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return real_import(name, *args)

    monkeypatch.setattr(importlib, "import_module", without_training)
    with pytest.raises(UsageError, match="--pretrained"):
        baselines.train_policies([BEACON_SCAN], tmp_path, progress=False)


T_975_DF1 = 12.706204736174698
"""Student-t quantile t_{0.975} with 1 degree of freedom (statistical tables)."""


def test_learning_curve_band_is_the_student_t_interval_over_training_seeds(tmp_path):
    (tmp_path / pretrained.LEARNING_CURVE_FILE).write_text(
        "training_seed,timesteps,wall_time_s,mean_reward,ci95\n"
        "1,64,2.0,-11.0,0.5\n0,0,0.0,-15.0,1.0\n0,64,1.0,-12.0,1.0\n1,0,0.0,-16.0,1.0\n"
        "0,128,3.0,-10.0,1.0\n"  # only seed 0 reached 128 steps: not in the mean
    )
    (tmp_path / pretrained.TRAINING_FILE).write_text(json.dumps({"levels": {"paper": -11}}))
    curves = baselines_plots.read_learning_curves(tmp_path, BEACON_SCAN)
    assert curves is not None and curves.levels == {"paper": -11.0}
    assert curves.by_seed == {
        0: [(0, -15.0), (64, -12.0), (128, -10.0)],
        1: [(0, -16.0), (64, -11.0)],
    }
    timesteps, means, lows, highs = baselines_plots.mean_over_seeds(curves)
    assert timesteps.tolist() == [0, 64]
    assert means.tolist() == [-15.5, -11.5]
    half_width = T_975_DF1 * math.sqrt(0.5) / math.sqrt(2)  # s of two values 1 apart
    np.testing.assert_allclose(highs - means, [half_width, half_width], rtol=1e-9)
    np.testing.assert_allclose(means - lows, [half_width, half_width], rtol=1e-9)


def test_the_reward_axis_frames_the_curves_and_levels_but_not_random():
    curves = baselines_plots.LearningCurves(
        BEACON_SCAN,
        {0: [(0, -4.36), (4096, -4.31)], 1: [(0, -4.38)]},
        {"paper": -4.51, "sector": -4.37, "random": -19.2},
    )
    low, high = baselines_plots.reward_axis_limits(curves)
    # span 0.20 (-4.51 .. -4.31): padded by the 0.25 floor on each side, random left out
    assert (low, high) == pytest.approx((-4.76, -4.06))
    only_random = baselines_plots.LearningCurves(BEACON_SCAN, {}, {"random": -19.2})
    assert baselines_plots.reward_axis_limits(only_random) is None


def test_a_learning_curve_without_its_columns_is_refused(tmp_path):
    (tmp_path / pretrained.LEARNING_CURVE_FILE).write_text("timesteps,mean_reward\n0,1\n")
    with pytest.raises(ValueError, match="lacks the columns"):
        baselines_plots.read_learning_curves(tmp_path, BEACON_SCAN)
    assert baselines_plots.read_learning_curves(tmp_path / "none", BEACON_SCAN) is None
