"""The ``sonar-gym`` command line: parsing, error messages, outputs (fake env), end to end."""

from __future__ import annotations

import importlib.machinery
import json
import subprocess
import sys
import types
from pathlib import Path

import gymnasium as gym
import pytest
import torch

from tests.cli_fakes import BOX_ID, DISCRETE_ID, MAX_EPISODE_STEPS, MULTI_DISCRETE_ID
from sonar_gym.train import cli

torch.set_num_threads(1)  # the trainings here use tiny networks: more threads only contend

REPOSITORY = Path(__file__).resolve().parents[1]
SCRIPT = Path(sys.executable).with_name("sonar-gym")


@pytest.fixture(autouse=True)
def wide_console(monkeypatch):
    """Tables wide enough not to wrap, whatever terminal the tests run in."""
    monkeypatch.setenv("COLUMNS", "250")


def run_cli(capsys, *argv: str) -> tuple[int, str, str]:
    code = cli.main(list(argv))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


# --------------------------------------------------------------------------------------------
# parsing


def test_evaluate_defaults_are_the_main_job():
    arguments = cli.build_parser().parse_args(["evaluate"])
    assert arguments.env is None  # SonarGym/BeaconScan-v0, resolved when run
    assert arguments.agent is None  # every agent of the env
    assert arguments.episodes == 50 and arguments.seed == 0
    # outputs go to a folder named after the arguments, resolved when run
    assert arguments.out is None and arguments.json is None and arguments.plot is None
    assert arguments.csv is None and arguments.env_arg == []


def test_repeatable_options_collect_every_value():
    arguments = cli.build_parser().parse_args(
        [
            "evaluate",
            "--env",
            "all",
            "--agent",
            "paper",
            "runs/x/model.zip",
            "--env-arg",
            "a=1",
            "--env-arg",
            "b=x",
        ]
    )
    assert arguments.env == ["all"]
    assert arguments.agent == ["paper", "runs/x/model.zip"]
    assert arguments.env_arg == ["a=1", "b=x"]


@pytest.mark.parametrize(
    "argv",
    [
        ["evaluate", "--episodes", "0"],
        ["evaluate", "--episodes", "many"],
        ["train", "--env", DISCRETE_ID, "--algo", "ppo"],  # --timesteps is required
        ["train", "--timesteps", "-5"],
        ["frobnicate"],
        [],
    ],
)
def test_malformed_command_lines_exit_with_status_2(argv, capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.main(argv)
    assert exit_info.value.code == 2
    assert "usage:" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv",
    [
        ["evaluate", "--seed", "-1"],
        ["train", "--env", DISCRETE_ID, "--algo", "ppo", "--timesteps", "10", "--seed", "-5"],
    ],
)
def test_a_negative_seed_is_a_usage_error_naming_the_option(argv, capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert f"argument --seed: must be zero or more, got {argv[-1]}" in err


def unusable_output_command_lines(tmp_path: Path) -> list[tuple[list[str], str]]:
    """Command lines whose output path is in the way of a file or a folder, with the part of
    the error that names the option and its value."""
    a_file = tmp_path / "a_file"
    a_file.write_text("")
    a_dir = tmp_path / "a_dir"
    a_dir.mkdir()
    evaluate = ["evaluate", "--env", DISCRETE_ID, "--episodes", "2", "--out", str(tmp_path / "e")]
    train = ["train", "--env", DISCRETE_ID, "--algo", "ppo", "--timesteps", "64", "--no-progress"]
    return [
        (["evaluate", "--env", DISCRETE_ID, "--out", f"{a_file}/sub"], f"--out {a_file}/sub"),
        (["evaluate", "--env", DISCRETE_ID, "--out", str(a_file)], f"--out {a_file}: is a file"),
        ([*evaluate, "--json", f"{a_file}/x.json"], f"--json {a_file}/x.json"),
        ([*evaluate, "--csv", str(a_dir)], f"--csv {a_dir}: is a directory"),
        ([*evaluate, "--plot", str(tmp_path / "x.txt")], "cannot write '.txt' files"),
        (["reproduce", "--out", str(a_file), "roh"], f"--out {a_file}/roh"),
        ([*train, "--out", f"{a_file}/r6"], f"--out {a_file}/r6"),
        (
            ["benchmark", "--env", DISCRETE_ID, "--seconds", "0.1", "--json", str(a_dir)],
            f"--json {a_dir}: is a directory",
        ),
    ]


@pytest.mark.parametrize("case", range(8))
def test_an_unusable_output_path_is_a_usage_error_before_anything_runs(
    case, tmp_path, capsys, monkeypatch
):
    argv, fragment = unusable_output_command_lines(tmp_path)[case]
    from sonar_gym.train import evaluation, training

    def must_not_run(*args, **kwargs):
        raise AssertionError("the work started before the output path was checked")

    monkeypatch.setattr(evaluation, "evaluate_agents", must_not_run)
    monkeypatch.setattr(training, "_build_model", must_not_run)
    monkeypatch.setattr("sonar_gym.train.reproduce.roh.run", must_not_run)
    monkeypatch.setattr("sonar_gym.train.benchmark.run_benchmark", must_not_run)
    code, out, err = run_cli(capsys, *argv)
    assert code == 2, err
    assert fragment in err
    assert "Traceback" not in err + out
    assert not (tmp_path / "e").exists()


def test_missing_parents_of_the_outputs_are_made(tmp_path, capsys):
    code, _, err = run_cli(
        capsys,
        "evaluate",
        "--env",
        DISCRETE_ID,
        "--episodes",
        "1",
        "--out",
        str(tmp_path / "a" / "b"),
        "--csv",
        str(tmp_path / "c" / "d" / "e.csv"),
        "--plot",
        str(tmp_path / "f" / "p.svg"),
    )
    assert code == 0, err
    assert (tmp_path / "a" / "b" / "evaluate.json").is_file()
    assert (tmp_path / "c" / "d" / "e.csv").is_file() and (tmp_path / "f" / "p.svg").is_file()


# --------------------------------------------------------------------------------------------
# evaluate


def test_evaluate_prints_a_table_and_writes_json_csv_and_plot(tmp_path, capsys):
    code, out, err = run_cli(
        capsys,
        "evaluate",
        "--env",
        DISCRETE_ID,
        "--agent",
        "scripted",
        "coin",
        "--episodes",
        "4",
        "--seed",
        "7",
        "--json",
        str(tmp_path / "e.json"),
        "--csv",
        str(tmp_path / "e.csv"),
        "--plot",
        str(tmp_path / "e.png"),
    )
    assert code == 0, err
    assert DISCRETE_ID in out and "scripted" in out and "coin" in out
    for header in (
        "success [%]",
        "E_xy median [cm]",
        "E_θ p95 [deg]",
        "sensing time [s]",
        "95% CI",
    ):
        assert header in out
    assert str(tmp_path / "e.json") in out and str(tmp_path / "e.png") in out
    data = json.loads((tmp_path / "e.json").read_text())
    assert data["meta"]["seed"] == 7 and data["meta"]["episodes"] == 4
    assert data["meta"]["command"][:4] == ["sonar-gym", "evaluate", "--env", DISCRETE_ID]
    assert data["meta"]["agents"] == {DISCRETE_ID: ["scripted", "coin"]}
    assert [e["seed"] for e in data["results"][0]["episodes"]] == [7, 8, 9, 10]
    assert len((tmp_path / "e.csv").read_text().splitlines()) == 1 + 8
    assert (tmp_path / "e.png").read_bytes()[:4] == b"\x89PNG"


def test_evaluate_writes_to_a_folder_named_after_its_arguments(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, _ = run_cli(capsys, "evaluate", "--env", DISCRETE_ID, "--episodes", "2")
    assert code == 0
    folder = Path("results/evaluate/CliFake-Locate-v0_all-agents_2ep_seed0")
    assert (tmp_path / folder / "evaluate.json").is_file()
    assert (tmp_path / folder / "evaluate.png").is_file()
    assert str(folder / "evaluate.json") in out and str(folder / "evaluate.png") in out
    data = json.loads((tmp_path / folder / "evaluate.json").read_text())
    assert {"scripted", "coin", "patient", "random"} <= {r["agent"] for r in data["results"]}


def test_evaluations_with_other_arguments_do_not_overwrite_each_other(
    tmp_path, capsys, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    for argv in (
        ["--env", DISCRETE_ID, "--agent", "scripted"],
        ["--env", DISCRETE_ID, "--agent", "coin"],
        ["--env", DISCRETE_ID, "--agent", "coin", "--seed", "4"],
        ["--env", DISCRETE_ID, "--agent", "coin", "--env-arg", "noise_std_m=0.2"],
    ):
        assert run_cli(capsys, "evaluate", "--episodes", "1", *argv)[0] == 0
    folders = sorted(path.name for path in (tmp_path / "results" / "evaluate").iterdir())
    assert folders == [
        "CliFake-Locate-v0_coin_1ep_seed0",
        "CliFake-Locate-v0_coin_1ep_seed0_noise_std_m=0.2",
        "CliFake-Locate-v0_coin_1ep_seed4",
        "CliFake-Locate-v0_scripted_1ep_seed0",
    ]


def test_evaluate_out_names_the_folder(tmp_path, capsys):
    code, _, _ = run_cli(
        capsys, "evaluate", "--env", DISCRETE_ID, "--episodes", "1", "--out", str(tmp_path / "x")
    )
    assert code == 0
    assert (tmp_path / "x" / "evaluate.json").is_file() and (
        tmp_path / "x" / "evaluate.png"
    ).is_file()


def test_benchmark_writes_a_file_named_after_its_arguments(tmp_path, capsys, monkeypatch):
    install_fake_bench_sonar(monkeypatch, rows=[{"name": "pan", "pans_per_s": 10.0}])
    monkeypatch.chdir(tmp_path)
    code, out, _ = run_cli(capsys, "benchmark", "--env", DISCRETE_ID, "--seconds", "0.1")
    assert code == 0
    path = Path("results/benchmark/CliFake-Locate-v0_0.1s.json")
    assert (tmp_path / path).is_file() and str(path) in out


def test_evaluate_passes_env_args(tmp_path, capsys):
    code, _, err = run_cli(
        capsys,
        "evaluate",
        "--env",
        DISCRETE_ID,
        "--agent",
        "scripted",
        "--episodes",
        "2",
        "--env-arg",
        "report_heading=false",
        "--env-arg",
        "noise_std_m=0",
        "--json",
        str(tmp_path / "e.json"),
        "--plot",
        str(tmp_path / "e.png"),
    )
    assert code == 0, err
    data = json.loads((tmp_path / "e.json").read_text())
    assert data["meta"]["env_kwargs"] == {"report_heading": False, "noise_std_m": 0}
    episode = data["results"][0]["episodes"][0]
    assert episode["heading_error_rad"] is None and episode["position_error_m"] == 0.0


def test_unknown_env_exits_2_naming_the_allowed_ids(capsys):
    code, out, err = run_cli(capsys, "evaluate", "--env", "SonarGym/Nope-v0")
    assert code == 2
    assert "unknown env 'SonarGym/Nope-v0'" in err and "'all'" in err
    assert "any other registered Gymnasium id" in err
    assert "SonarGym/BeaconScan-v0" in err
    assert "Traceback" not in err + out


def test_unknown_agent_exits_2_naming_the_agents_of_the_env(capsys, tmp_path):
    code, out, err = run_cli(
        capsys,
        "evaluate",
        "--env",
        DISCRETE_ID,
        "--agent",
        "wizard",
        "--json",
        str(tmp_path / "e.json"),
    )
    assert code == 2
    assert "unknown agent 'wizard'" in err
    for name in ("coin", "patient", "random", "scripted"):
        assert name in err
    assert "Traceback" not in err + out
    assert not (tmp_path / "e.json").exists()


@pytest.mark.parametrize(
    "env_arg, fragment",
    [("bogus=1", "has no argument bogus"), ("noise_std_m=5", "must lie in"), ("oops", "KEY=VALUE")],
)
def test_bad_env_args_exit_2_with_the_reason(capsys, env_arg, fragment):
    code, _, err = run_cli(capsys, "evaluate", "--env", DISCRETE_ID, "--env-arg", env_arg)
    assert code == 2 and fragment in err


# --------------------------------------------------------------------------------------------
# train


def test_train_prints_the_evaluation_and_the_command_to_evaluate(tmp_path, capsys):
    config = tmp_path / "tiny.toml"
    config.write_text(
        "n_envs = 2\neval_episodes = 2\n[hyperparameters]\nn_steps = 32\nbatch_size = 32\n"
        "n_epochs = 1\n[policy_kwargs]\nnet_arch = [8]\n"
    )
    out_dir = tmp_path / "run"
    code, out, err = run_cli(
        capsys,
        "train",
        "--env",
        DISCRETE_ID,
        "--algo",
        "PPO",
        "--timesteps",
        "64",
        "--out",
        str(out_dir),
        "--config",
        str(config),
        "--no-progress",
        "--env-arg",
        "noise_std_m=0.02",
    )
    assert code == 0, err
    assert "64 timesteps" in out and "evaluate_policy, 2 episodes" in out
    assert (
        f"sonar-gym evaluate --env {DISCRETE_ID} --agent {out_dir / 'model.zip'} "
        "--env-arg noise_std_m=0.02"
    ) in out
    assert json.loads((out_dir / "run.json").read_text())["env_kwargs"] == {"noise_std_m": 0.02}


@pytest.mark.parametrize(
    "env_id, algo, fragment",
    [
        (DISCRETE_ID, "sac", "SAC needs a Box action space"),
        (BOX_ID, "dqn", "DQN needs a Discrete action space"),
        (DISCRETE_ID, "trpo", "choose one of ['ppo', 'sac', 'dqn', 'a2c']"),
        ("SonarGym/Nope-v0", "ppo", "unknown env"),
    ],
)
def test_train_refuses_what_cannot_work(capsys, tmp_path, env_id, algo, fragment):
    code, _, err = run_cli(
        capsys,
        "train",
        "--env",
        env_id,
        "--algo",
        algo,
        "--timesteps",
        "10",
        "--out",
        str(tmp_path / "run"),
    )
    assert code == 2 and fragment in err
    assert not (tmp_path / "run").exists()


# --------------------------------------------------------------------------------------------
# benchmark


def install_fake_bench_sonar(monkeypatch, rows=None) -> None:
    """A stand-in ``sonar_gym.train.bench_sonar`` (the real one times the sonar for seconds)."""
    fake = types.ModuleType("sonar_gym.train.bench_sonar")
    if rows is not None:
        fake.pan_throughput = lambda: rows
    monkeypatch.setitem(sys.modules, "sonar_gym.train.bench_sonar", fake)


def test_benchmark_reports_random_and_ppo_rates_against_cartpole(tmp_path, capsys, monkeypatch):
    install_fake_bench_sonar(monkeypatch, rows=[{"name": "pan", "pans_per_s": 10.0}])
    path = tmp_path / "b.json"
    code, out, err = run_cli(
        capsys, "benchmark", "--env", DISCRETE_ID, BOX_ID, "--seconds", "0.2", "--json", str(path)
    )
    assert code == 0, err
    assert "env steps per second" in out and DISCRETE_ID in out and "CartPole-v1" in out
    data = json.loads(path.read_text())
    assert data["meta"]["seconds"] == 0.2 and data["meta"]["ppo"]["n_steps"] == 512
    assert data["meta"]["ppo"]["torch_threads"] == 1
    reference = data["reference"]
    assert reference["env_id"] == "CartPole-v1"
    runs = reference["runs"]
    assert len(runs) == 3  # before the first env and after each of the two
    assert all(run["timesteps"] >= 1 for run in runs)
    rates = [run["steps_per_s"] for run in runs]
    assert reference["before"] == runs[0] and reference["after"] == runs[-1]
    assert reference["ppo_steps_per_s"] == pytest.approx(sum(rates) / 3)
    assert reference["drift_after_over_before"] == pytest.approx(rates[-1] / rates[0])
    assert reference["fastest_over_slowest"] == pytest.approx(max(rates) / min(rates))
    assert [entry["env_id"] for entry in data["envs"]] == [DISCRETE_ID, BOX_ID]
    for index, entry in enumerate(data["envs"]):
        # each env against the two CartPole runs around it
        assert entry["cartpole_ppo_steps_per_s"] == pytest.approx(
            (rates[index] + rates[index + 1]) / 2
        )
        random, ppo = entry["random"], entry["ppo"]
        assert random["steps"] >= 1 and random["episodes"] >= 1
        assert random["steps_per_s"] == pytest.approx(random["steps"] / random["seconds"])
        assert ppo["steps_per_s"] == pytest.approx(ppo["timesteps"] / ppo["seconds"])
        assert entry["ppo_over_cartpole"] == pytest.approx(
            ppo["steps_per_s"] / entry["cartpole_ppo_steps_per_s"]
        )
        ceiling = entry["ceiling"]
        assert ceiling["timesteps"] >= 1
        assert entry["ceiling_over_cartpole"] == pytest.approx(
            ceiling["steps_per_s"] / entry["cartpole_ppo_steps_per_s"]
        )
        assert entry["env_seconds_per_ppo_step"] == pytest.approx(
            1 / ppo["steps_per_s"] - 1 / ceiling["steps_per_s"]
        )
        assert set(random["phase_shares"]) == {"sensing", "localization", "env other"}
        assert set(ppo["phase_shares"]) == {"sensing", "localization", "env other", "learner"}
        assert sum(ppo["phase_shares"].values()) == pytest.approx(1.0)
        assert 0.0 < sum(random["phase_shares"].values()) <= 1.0 + 1e-9
    assert data["pan"] == [{"name": "pan", "pans_per_s": 10.0}] and data["notes"] == []
    room = data["room_reset"]
    assert room["extra_walls"] == 1500 and room["resets"] == 4
    assert room["make_seconds"] > 0 and room["reset_seconds"] > 0
    assert "1500 extra" in out


def test_benchmark_random_run_starts_a_new_episode_whenever_one_ends():
    from sonar_gym.train.benchmark import random_rate

    rate = random_rate(DISCRETE_ID, seconds=0.3)
    # CliFake episodes last at most MAX_EPISODE_STEPS steps, so many episodes fit in the budget
    assert rate.steps > MAX_EPISODE_STEPS
    assert rate.episodes >= rate.steps / MAX_EPISODE_STEPS
    assert rate.env_seconds <= rate.seconds


@pytest.mark.parametrize("env_id", [DISCRETE_ID, BOX_ID, MULTI_DISCRETE_ID])
def test_benchmark_free_stand_in_has_the_env_spaces_and_its_episode_length(env_id):
    from gymnasium.utils.env_checker import check_env

    from sonar_gym.train.benchmark import FreeEnv

    real = gym.make(env_id)
    free = FreeEnv(real.observation_space, real.action_space, episode_steps=3)
    check_env(free, skip_render_check=True)
    assert free.observation_space == real.observation_space
    assert free.action_space == real.action_space
    observation, _ = free.reset(seed=1)
    assert real.observation_space.contains(observation)
    flags = [free.step(free.action_space.sample())[2] for _ in range(3)]
    assert flags == [False, False, True]
    with pytest.raises(ValueError, match="episode_steps"):
        FreeEnv(real.observation_space, real.action_space, episode_steps=0)


def test_benchmark_ceiling_trains_ppo_on_the_free_stand_in():
    from sonar_gym.train.benchmark import ceiling_rate

    rate = ceiling_rate(MULTI_DISCRETE_ID, seconds=0.3, episode_steps=5, n_steps=64)
    assert rate.env_id == MULTI_DISCRETE_ID and rate.timesteps >= 1
    # the stand-in keeps no timing phases: all of its time inside the env is bookkeeping
    assert rate.phase_seconds == {}
    assert rate.env_seconds < rate.seconds


def test_large_room_scenario_adds_the_pieces_inside_the_room():
    from sonar_gym.scenario import load_scenario
    from sonar_gym.train.bench_room import PIECE_LENGTH_M, scenario_with_extra_walls

    base = len(load_scenario("beom_cho_lab").walls)
    scenario = scenario_with_extra_walls(30, seed=3)
    pieces = scenario["walls"][-30:]
    assert len(scenario["walls"]) == base + 30
    (x_min, y_min), (x_max, y_max) = scenario["room"]["min"], scenario["room"]["max"]
    for piece in pieces:
        (ax, ay), (bx, by) = piece["a"], piece["b"]
        assert ay == by and bx - ax == pytest.approx(PIECE_LENGTH_M)
        assert x_min < ax < bx < x_max and y_min < ay < y_max
    assert scenario == scenario_with_extra_walls(30, seed=3)
    with pytest.raises(ValueError, match="extra_walls"):
        scenario_with_extra_walls(-1)


def test_benchmark_phase_shares_split_the_wall_time():
    from sonar_gym.train.benchmark import phase_shares

    shares = phase_shares(10.0, 6.0, {"sensing": 3.0, "localization": 1.0}, outside="learner")
    assert shares == pytest.approx(
        {"sensing": 0.3, "localization": 0.1, "env other": 0.2, "learner": 0.4}
    )
    assert phase_shares(0.0, 0.0, {}) == {}


def test_benchmark_vector_speed_alternates_sync_and_native_runs():
    """The code path only (a tiny budget): no speed is asserted."""
    from sonar_gym.train.benchmark import vector_speed

    speed = vector_speed("SonarGym/BeaconScan-v0", 0.01, num_envs=2, pairs=2)
    assert [run.mode for run in speed.runs] == ["sync", "vector_entry_point"] * 2
    assert all(run.steps >= 1 and run.num_envs == 2 for run in speed.runs)
    sync = [run for run in speed.runs if run.mode == "sync"]
    assert speed.env_steps_per_s("sync") == pytest.approx(
        sum(2 * run.steps for run in sync) / sum(run.seconds for run in sync)
    )
    data = speed.to_dict()
    assert data["native_over_sync"] == pytest.approx(
        data["native_env_steps_per_s"] / data["sync_env_steps_per_s"]
    )
    assert len(data["runs"]) == 4 and data["runs"][0]["env_steps_per_s"] > 0


def test_benchmark_measures_vector_throughput_of_envs_with_a_native_vector_env(monkeypatch):
    from sonar_gym.train import benchmark, report

    monkeypatch.setattr(
        benchmark, "ppo_rate", lambda env_id, *a, **k: benchmark.PPORate(env_id, 9, 1, 1.0, 0.0)
    )
    monkeypatch.setattr(
        benchmark,
        "random_rate",
        lambda env_id, *a, **k: benchmark.RandomRate(env_id, 9, 2, 1.0, 0.5),
    )
    monkeypatch.setattr(
        benchmark, "ceiling_rate", lambda env_id, *a, **k: benchmark.PPORate(env_id, 9, 1, 1.0, 0.0)
    )
    monkeypatch.setattr(benchmark, "VECTOR_SHARE_OF_BUDGET", 0.01)
    ids = ["SonarGym/BeaconScan-v0", "SonarGym/Trilateration-v0"]  # only the first has one
    measured = benchmark.run_benchmark(ids, 1.0, measure_pan=False)
    assert [speed.env_id for speed in measured.vectors] == ids[:1]
    assert len(measured.vectors[0].runs) == 2 * benchmark.VECTOR_PAIRS
    data = measured.to_dict()
    assert [entry["env_id"] for entry in data["vector"]] == ids[:1]
    assert report.vector_table(measured).row_count == 1
    skipped = benchmark.run_benchmark(ids[:1], 1.0, measure_pan=False, measure_vector=False)
    assert skipped.vectors == () and "vector throughput skipped: not requested" in skipped.notes


def test_benchmark_rates_each_env_against_the_cartpole_runs_around_it(monkeypatch):
    """CartPole runs before the first env and after every env, a failed one too; each env's
    ratios use the mean of the two runs around it, not of the whole run's."""
    from sonar_gym.train import benchmark

    cartpole_rates = iter([100.0, 300.0, 500.0, 900.0])
    order: list[str] = []

    def fake_ppo_rate(env_id, seconds, env_kwargs=None, seed=0, n_steps=512):
        order.append(f"ppo {env_id}")
        rate = next(cartpole_rates) if env_id == benchmark.REFERENCE_ENV_ID else 60.0
        return benchmark.PPORate(env_id, int(rate), 1, 1.0, 0.0)

    def fake_random_rate(env_id, seconds, env_kwargs=None, seed=0):
        order.append(f"random {env_id}")
        if env_id == "Broken-v0":
            raise RuntimeError("broken")
        return benchmark.RandomRate(env_id, 10, 2, 1.0, 0.5)

    def fake_ceiling_rate(env_id, seconds, episode_steps, env_kwargs=None, seed=0, n_steps=512):
        order.append(f"ceiling {env_id}")
        return benchmark.PPORate(env_id, 150, 1, 1.0, 0.0)

    monkeypatch.setattr(benchmark, "ppo_rate", fake_ppo_rate)
    monkeypatch.setattr(benchmark, "random_rate", fake_random_rate)
    monkeypatch.setattr(benchmark, "ceiling_rate", fake_ceiling_rate)
    monkeypatch.setattr(benchmark, "check_env_kwargs", lambda env_id, kwargs: None)
    report = benchmark.run_benchmark(["A-v0", "Broken-v0", "B-v0"], 1.0, measure_pan=False)
    cartpole = f"ppo {benchmark.REFERENCE_ENV_ID}"
    assert order == [
        cartpole,
        "random A-v0", "ppo A-v0", "ceiling A-v0", cartpole,
        "random Broken-v0", cartpole,
        "random B-v0", "ppo B-v0", "ceiling B-v0", cartpole,
    ]  # fmt: skip
    assert list(report.failures) == ["Broken-v0"]
    first, second = report.envs
    assert first.reference_steps_per_s == pytest.approx(200.0)  # (100 + 300) / 2
    assert second.reference_steps_per_s == pytest.approx(700.0)  # (500 + 900) / 2
    assert first.ppo_over_reference == pytest.approx(0.3)
    assert second.ceiling_over_reference == pytest.approx(150.0 / 700.0)
    assert report.reference_steps_per_s == pytest.approx(450.0)
    assert report.reference_drift == pytest.approx(9.0)
    assert report.reference_spread == pytest.approx(9.0)


@pytest.mark.parametrize("seconds", ["0", "-1", "inf", "soon"])
def test_benchmark_rejects_a_budget_that_is_not_a_positive_number(seconds, capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["benchmark", "--seconds", seconds])
    assert exit_info.value.code == 2
    assert "--seconds" in capsys.readouterr().err


def test_benchmark_pan_throughput_uses_bench_sonar_when_present(tmp_path, capsys, monkeypatch):
    install_fake_bench_sonar(monkeypatch, [{"name": "polaroid 360 pings", "pans_per_s": 123.0}])
    code, out, _ = run_cli(
        capsys,
        "benchmark",
        "--env",
        DISCRETE_ID,
        "--seconds",
        "0.1",
        "--json",
        str(tmp_path / "b.json"),
    )
    assert code == 0
    assert "sonar pan throughput" in out and "polaroid 360 pings" in out
    assert json.loads((tmp_path / "b.json").read_text())["pan"][0]["pans_per_s"] == 123.0


def test_benchmark_skips_pan_throughput_with_a_note_when_unavailable(tmp_path, capsys, monkeypatch):
    install_fake_bench_sonar(monkeypatch)
    code, out, _ = run_cli(
        capsys,
        "benchmark",
        "--env",
        DISCRETE_ID,
        "--seconds",
        "0.1",
        "--json",
        str(tmp_path / "b.json"),
    )
    assert code == 0 and "pan throughput skipped" in out


# --------------------------------------------------------------------------------------------
# reproduce


def install_fake_reproduction(monkeypatch, name: str, calls: list) -> None:
    module_name = f"sonar_gym.train.reproduce.{name}"
    module = types.ModuleType(module_name)
    module.__spec__ = importlib.machinery.ModuleSpec(module_name, None)
    module.run = lambda out_dir, console: calls.append((name, out_dir))
    monkeypatch.setitem(sys.modules, module_name, module)


def test_reproduce_dispatches_to_the_module_of_the_paper(tmp_path, capsys, monkeypatch):
    calls: list = []
    install_fake_reproduction(monkeypatch, "wu_tsai", calls)
    assert "wu-tsai" in cli.available_reproductions()
    code, _, err = run_cli(capsys, "reproduce", "wu-tsai", "--out", str(tmp_path))
    assert code == 0, err
    assert calls == [("wu_tsai", tmp_path / "wu_tsai")]
    assert (tmp_path / "wu_tsai").is_dir()


def test_reproduce_all_runs_what_exists(tmp_path, capsys, monkeypatch):
    calls: list = []
    install_fake_reproduction(monkeypatch, "beom_cho", calls)
    monkeypatch.setattr(cli, "available_reproductions", lambda: ["beom-cho"])
    code, out, _ = run_cli(capsys, "reproduce", "all", "--out", str(tmp_path))
    assert code == 0
    assert calls == [("beom_cho", tmp_path / "beom_cho")]
    assert "not available yet, skipped: beom-cho-map, kim, wu-tsai, roh, apcs" in out


def install_talking_reproduction(monkeypatch, name: str) -> None:
    """A reproduction that prints a finding and a wide table, as the real ones do."""
    from rich.table import Table

    def run(out_dir, console):
        table = Table(title="Table IX")
        table.add_column("column")
        table.add_row("a table cell")
        console.print(table)
        console.print("Finding: within the paper's bound.")

    module_name = f"sonar_gym.train.reproduce.{name}"
    module = types.ModuleType(module_name)
    module.__spec__ = importlib.machinery.ModuleSpec(module_name, None)
    module.run = run
    monkeypatch.setitem(sys.modules, module_name, module)


def test_reproduce_prints_findings_and_files_the_tables_by_default(tmp_path, capsys, monkeypatch):
    install_talking_reproduction(monkeypatch, "kim")
    code, out, _ = run_cli(capsys, "reproduce", "kim", "--out", str(tmp_path))
    assert code == 0
    assert "Finding: within the paper's bound." in out
    assert "a table cell" not in out and "1 tables in" in out and "--verbose" in out
    report = (tmp_path / "kim" / "report.txt").read_text()
    assert "Table IX" in report and "a table cell" in report
    assert "Finding: within the paper's bound." in report


def test_reproduce_verbose_prints_every_table(tmp_path, capsys, monkeypatch):
    install_talking_reproduction(monkeypatch, "kim")
    code, out, _ = run_cli(capsys, "reproduce", "kim", "--verbose", "--out", str(tmp_path))
    assert code == 0
    assert "a table cell" in out and "Finding: within the paper's bound." in out
    assert "a table cell" in (tmp_path / "kim" / "report.txt").read_text()


def test_reproduce_unknown_or_missing_paper_exits_2_listing_the_papers(capsys, monkeypatch):
    monkeypatch.setattr(cli, "available_reproductions", lambda: ["kim"])
    code, _, err = run_cli(capsys, "reproduce", "smith")
    assert code == 2
    assert "unknown paper 'smith'" in err and "beom-cho" in err and "wu-tsai" in err
    assert "available now: ['kim']" in err
    code, _, err = run_cli(capsys, "reproduce", "roh")
    assert code == 2 and "'roh' is not available yet" in err
    monkeypatch.setattr(cli, "available_reproductions", lambda: [])
    code, _, err = run_cli(capsys, "reproduce", "all")
    assert code == 2 and "no reproduction is available yet" in err


# --------------------------------------------------------------------------------------------
# the installed script


def test_console_script_is_installed_and_reports_errors_without_traceback():
    assert SCRIPT.is_file(), "run `pip install -e . --no-deps` to create the sonar-gym script"
    help_run = subprocess.run(
        [str(SCRIPT), "--help"], capture_output=True, text=True, cwd=REPOSITORY, timeout=60
    )
    assert help_run.returncode == 0
    for command in ("evaluate", "train", "benchmark", "reproduce"):
        assert command in help_run.stdout
    bad = subprocess.run(
        [str(SCRIPT), "evaluate", "--env", "Nope-v0"],
        capture_output=True,
        text=True,
        cwd=REPOSITORY,
        timeout=60,
    )
    assert bad.returncode == 2 and "unknown env" in bad.stderr
    assert "Traceback" not in bad.stderr


# --------------------------------------------------------------------------------------------
# end to end on SonarGym/BeaconScan-v0

BEACON_SCAN = "SonarGym/BeaconScan-v0"


def test_evaluate_without_arguments_runs_every_beacon_scan_agent(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    arguments = cli.build_parser().parse_args(["evaluate"])
    code, out, err = run_cli(capsys, "evaluate", "--episodes", "3")  # all other defaults
    assert code == 0, err
    assert arguments.episodes == 50  # what `make evaluate` runs; 3 here to stay fast
    folder = Path("results/evaluate/BeaconScan-v0_all-agents_3ep_seed0")
    data = json.loads((tmp_path / folder / "evaluate.json").read_text())
    assert data["meta"]["env_ids"] == [BEACON_SCAN]
    # the shipped policy is one of BeaconScan's agents
    assert [r["agent"] for r in data["results"]] == ["learned", "paper", "random", "sector"]
    for result in data["results"]:
        assert [e["seed"] for e in result["episodes"]] == [0, 1, 2]
        assert all(isinstance(e["position_error_m"], float) for e in result["episodes"])
    assert (tmp_path / folder / "evaluate.png").is_file()
    assert "paper" in out and "sector" in out and str(folder / "evaluate.json") in out


@pytest.mark.parametrize(
    "env_id, agent, env_arg, fragment",
    [
        (BEACON_SCAN, "paper", "increments_deg=[5]", "'increments_deg' to include 1"),
        (BEACON_SCAN, "sector", "sector_widths_deg=[60]", "'sector_widths_deg' to include 360"),
        (
            "SonarGym/ActiveBeaconScan-v0",
            "retry",
            "turn_angles_deg=[30,-30]",
            "'turn_angles_deg' to include 90",
        ),
    ],
)
def test_evaluate_refuses_a_built_in_agent_the_env_args_leave_without_its_choices(
    tmp_path, capsys, env_id, agent, env_arg, fragment
):
    code, out, err = run_cli(
        capsys,
        "evaluate",
        "--env",
        env_id,
        "--agent",
        agent,
        "--env-arg",
        env_arg,
        "--out",
        str(tmp_path / "e"),
    )
    assert code == 2
    assert f"agent {agent!r} cannot act in {env_id}" in err and fragment in err
    assert "Traceback" not in err + out
    assert not (tmp_path / "e").exists()


def test_train_on_beacon_scan_then_evaluate_the_policy(tmp_path, capsys):
    from sonar_gym.agents.base import make_agent
    from sonar_gym.agents.learned import PolicyAgent
    from sonar_gym.train.evaluation import make_env

    out_dir = tmp_path / "run"
    code, out, err = run_cli(
        capsys,
        "train",
        "--env",
        BEACON_SCAN,
        "--algo",
        "ppo",
        "--timesteps",
        "512",
        "--out",
        str(out_dir),
        "--eval-episodes",
        "2",
        "--no-progress",
    )
    assert code == 0, err
    assert "512 timesteps" in out
    command = f"sonar-gym evaluate --env {BEACON_SCAN} --agent {out_dir / 'model.zip'}"
    assert command in out
    assert (out_dir / "vecnormalize.pkl").is_file()
    assert json.loads((out_dir / "run.json").read_text())["config_file"].endswith(
        "beacon_scan.ppo.toml"
    )
    agent = make_agent(str(out_dir / "model.zip"), make_env(BEACON_SCAN))
    assert isinstance(agent, PolicyAgent) and agent.normalizer is not None

    code, out, err = run_cli(
        capsys,
        *command.split()[1:],
        "paper",
        "--episodes",
        "2",
        "--json",
        str(tmp_path / "e.json"),
        "--plot",
        str(tmp_path / "e.png"),
    )
    assert code == 0, err
    data = json.loads((tmp_path / "e.json").read_text())
    assert [r["agent"] for r in data["results"]] == [str(out_dir / "model.zip"), "paper"]
    assert all(len(r["episodes"]) == 2 for r in data["results"])


def test_benchmark_beacon_scan_end_to_end(tmp_path, capsys):
    path = tmp_path / "b.json"
    code, out, err = run_cli(
        capsys, "benchmark", "--env", BEACON_SCAN, "--seconds", "0.5", "--json", str(path)
    )
    assert code == 0, err
    assert BEACON_SCAN in out
    data = json.loads(path.read_text())
    assert data["failures"] == {}
    (entry,) = data["envs"]
    assert entry["random"]["steps"] >= 1 and entry["ppo"]["timesteps"] >= 1
    assert entry["ppo"]["phase_seconds"]["sensing"] > 0
    assert data["pan"] and all(row["pans_per_s"] > 0 for row in data["pan"])  # bench_sonar's
    assert "sonar pan throughput" in out


# --------------------------------------------------------------------------------------------
# the closing hints name a command the user's shell can run


def test_hint_uses_the_script_beside_python_when_sonar_gym_is_not_on_path(monkeypatch, tmp_path):
    bin_dir = tmp_path / "venv" / "bin"
    bin_dir.mkdir(parents=True)
    (bin_dir / "sonar-gym").write_text("#!/bin/sh\n")
    monkeypatch.setattr(sys, "executable", str(bin_dir / "python"))
    monkeypatch.setattr(cli.shutil, "which", lambda name: None)
    monkeypatch.chdir(tmp_path)
    assert cli.runnable_command("sonar-gym evaluate --env X") == (
        "venv/bin/sonar-gym evaluate --env X"
    )
    monkeypatch.chdir(tmp_path / "venv")
    assert cli.runnable_program() == "bin/sonar-gym"


def test_hint_falls_back_to_python_dash_m(monkeypatch, tmp_path):
    monkeypatch.setattr(sys, "executable", str(tmp_path / "python"))  # no script beside it
    monkeypatch.setattr(cli.shutil, "which", lambda name: None)
    assert (
        cli.runnable_command("sonar-gym evaluate") == f"{tmp_path / 'python'} -m sonar_gym evaluate"
    )


def test_hint_keeps_sonar_gym_when_it_is_on_path(monkeypatch, tmp_path):
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    (bin_dir / "sonar-gym").write_text("#!/bin/sh\n")
    monkeypatch.setattr(sys, "executable", str(bin_dir / "python"))
    monkeypatch.setattr(cli.shutil, "which", lambda name: str(bin_dir / name))
    assert cli.runnable_command("sonar-gym evaluate") == "sonar-gym evaluate"
    assert cli.runnable_command("other evaluate") == "other evaluate"


def test_python_dash_m_sonar_gym_runs_the_command_line():
    completed = subprocess.run(
        [sys.executable, "-m", "sonar_gym", "--help"],
        capture_output=True,
        text=True,
        cwd=REPOSITORY,
        timeout=120,
    )
    assert completed.returncode == 0 and "evaluate" in completed.stdout
