"""The ``sonar-gym`` command line: ``evaluate``, ``train``, ``benchmark``, ``reproduce``,
``baselines``.

Parsing only; the work happens in :mod:`sonar_gym.train.evaluation`,
:mod:`sonar_gym.train.training`, :mod:`sonar_gym.train.benchmark`,
:mod:`sonar_gym.train.baselines` and :mod:`sonar_gym.train.report`. A request the user can
fix (unknown env or agent, bad ``--env-arg``, an algorithm the action space does not allow, an
output path a file or folder is in the way of) prints one line naming the allowed values and
exits with status 2, before any work runs. ``python -m sonar_gym`` runs the same command line.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import json
import os
import shlex
import shutil
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rich.console import Console

from sonar_gym.train import UsageError, output_paths

PROGRAM = "sonar-gym"
DEFAULT_EPISODES = 50
DEFAULT_EVALUATE_ROOT = Path("results/evaluate")
DEFAULT_BENCHMARK_ROOT = Path("results/benchmark")
DEFAULT_BENCHMARK_SECONDS = 20.0
DEFAULT_REPRODUCE_DIR = Path("results/reproduce")
DEFAULT_BASELINES_DIR = Path("results/baselines")
REPRODUCIBLE_PAPERS = ("beom-cho", "beom-cho-map", "kim", "wu-tsai", "roh", "apcs")
PIPED_WIDTH = 160


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``sonar-gym`` and its subcommands."""
    parser = argparse.ArgumentParser(
        prog=PROGRAM,
        description="Sonar localization environments: evaluate agents, train policies, "
        "benchmark the simulation, reproduce the papers.",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")
    commands.required = True

    evaluate = commands.add_parser(
        "evaluate",
        help="run agents on envs over seeds; table, JSON/CSV and plot",
        description="Evaluate agents on envs over seeds (episode i uses seed S + i for every "
        "agent, so comparisons are paired).",
    )
    evaluate.add_argument(
        "--env",
        nargs="+",
        metavar="ID",
        help="env ids, or 'all' for every SonarGym/ env (default: SonarGym/BeaconScan-v0)",
    )
    evaluate.add_argument(
        "--agent",
        nargs="+",
        metavar="NAME|PATH",
        help="agent names or saved models (.zip / run dir); default: every agent of the env",
    )
    evaluate.add_argument(
        "--episodes",
        type=_positive_int,
        default=DEFAULT_EPISODES,
        metavar="N",
        help=f"episodes per agent and env (default {DEFAULT_EPISODES})",
    )
    evaluate.add_argument(
        "--seed",
        type=_non_negative_int,
        default=0,
        metavar="S",
        help="episode i uses seed S + i (default 0)",
    )
    evaluate.add_argument(
        "--out",
        type=Path,
        default=None,
        metavar="DIR",
        help=f"output folder (default {DEFAULT_EVALUATE_ROOT}/<name from the arguments>, e.g. "
        f"{DEFAULT_EVALUATE_ROOT}/BeaconScan-v0_all-agents_50ep_seed0)",
    )
    evaluate.add_argument(
        "--json",
        type=Path,
        default=None,
        metavar="PATH",
        help="summaries and every episode (default <out>/evaluate.json)",
    )
    evaluate.add_argument(
        "--csv", type=Path, default=None, metavar="PATH", help="one row per episode (default: none)"
    )
    evaluate.add_argument(
        "--plot",
        type=Path,
        default=None,
        metavar="PATH",
        help="bar charts per env (default <out>/evaluate.png)",
    )
    evaluate.add_argument(
        "--ray",
        action="store_true",
        help="spread the episodes over a Ray cluster (extra [ray]); same numbers as locally",
    )
    evaluate.add_argument(
        "--address",
        default=None,
        metavar="ADDR",
        help="Ray cluster for --ray and --backend rllib ('auto', 'ray://host:10001'); "
        "default: start Ray on this machine",
    )
    _add_env_arg(evaluate)
    evaluate.set_defaults(handler=_evaluate)

    train = commands.add_parser(
        "train",
        help="train a stable-baselines3 policy",
        description="Train PPO, SAC, DQN or A2C on an env with tuned hyper-parameters.",
    )
    train.add_argument("--env", metavar="ID", help="env id (optional with --resume)")
    train.add_argument("--algo", metavar="ALGO", help="ppo | sac | dqn | a2c")
    train.add_argument(
        "--timesteps",
        type=_positive_int,
        required=True,
        metavar="N",
        help="env steps to train (more steps with --resume)",
    )
    train.add_argument(
        "--out",
        type=Path,
        metavar="DIR",
        help="run directory (default runs/<env-short>-<algo>-<seed>)",
    )
    train.add_argument("--seed", type=_non_negative_int, default=0, metavar="S", help="default 0")
    train.add_argument(
        "--n-envs",
        type=_positive_int,
        metavar="K",
        help="vector-env workers (default from the config)",
    )
    train.add_argument(
        "--config",
        type=Path,
        metavar="PATH",
        help="hyper-parameter TOML (default train/configs/<env>.<algo>.toml)",
    )
    train.add_argument(
        "--resume",
        type=Path,
        metavar="CHECKPOINT",
        help="model or checkpoint .zip to continue (its VecNormalize stats too)",
    )
    train.add_argument("--subproc", action="store_true", help="SubprocVecEnv workers")
    train.add_argument(
        "--eval-episodes",
        type=_non_negative_int,
        metavar="N",
        help="episodes of the evaluation after training (0: none)",
    )
    train.add_argument(
        "--overwrite",
        action="store_true",
        help="start afresh in a run directory that holds a model",
    )
    train.add_argument("--no-progress", action="store_true", help="no progress bar")
    train.add_argument(
        "--backend",
        choices=("sb3", "rllib"),
        default="sb3",
        help="stable-baselines3 in this process (default), or RLlib PPO on Ray (extra [ray])",
    )
    train.add_argument(
        "--num-env-runners",
        type=_non_negative_int,
        default=1,
        metavar="N",
        help="RLlib remote env runners (--backend rllib; default 1)",
    )
    train.add_argument(
        "--address",
        default=None,
        metavar="ADDR",
        help="Ray cluster for --backend rllib ('auto', 'ray://host:10001'); default: local Ray",
    )
    _add_env_arg(train)
    train.set_defaults(handler=_train)

    benchmark = commands.add_parser(
        "benchmark",
        help="steps per second a user gets: random actions, PPO training, sonar pans",
        description="Measure, in one run: sonar pan throughput; per env random-action steps/s "
        "and SB3 PPO env-steps/s (n_steps 512, batch 64, 4 epochs, one env, torch on one "
        "thread) against PPO on CartPole-v1 (measured before the first env and after each, "
        "every env's ratio to the two runs around it); the ceiling (PPO on a free stand-in "
        "with the env's spaces); the share of time per phase; for envs with a native vector "
        "env (BeaconScan), env-steps/s of 8 sub-envs through it against SyncVectorEnv. The "
        "whole run takes about (0.5 + 2.5 x envs) x SECONDS plus the pan rows and 0.4 x "
        "SECONDS per vector env (about 6 min for every env at the default).",
    )
    benchmark.add_argument(
        "--env", nargs="+", default=["all"], metavar="ID", help="env ids or 'all' (default)"
    )
    benchmark.add_argument(
        "--seconds",
        type=_positive_float,
        default=DEFAULT_BENCHMARK_SECONDS,
        metavar="S",
        help=f"PPO wall-time budget per env; random actions, the free stand-in and each "
        f"CartPole run get half of it "
        f"(default {DEFAULT_BENCHMARK_SECONDS:g})",
    )
    benchmark.add_argument(
        "--no-pan",
        action="store_true",
        help="skip the sonar pan throughput rows and the large-room reset",
    )
    benchmark.add_argument(
        "--no-vector",
        action="store_true",
        help="skip the vector throughput (native vector env against SyncVectorEnv)",
    )
    benchmark.add_argument(
        "--json",
        type=Path,
        default=None,
        metavar="PATH",
        help=f"default {DEFAULT_BENCHMARK_ROOT}/<envs>_<seconds>s.json, e.g. "
        f"{DEFAULT_BENCHMARK_ROOT}/all_20s.json",
    )
    _add_env_arg(benchmark)
    benchmark.set_defaults(handler=_benchmark)

    reproduce = commands.add_parser(
        "reproduce",
        help="reproduce a paper's tables and figures",
        description=f"Reproduce a paper: one of {', '.join(REPRODUCIBLE_PAPERS)}, or all.",
    )
    reproduce.add_argument("names", nargs="+", metavar="NAME", help="paper name or 'all'")
    reproduce.add_argument(
        "--out",
        type=Path,
        default=DEFAULT_REPRODUCE_DIR,
        metavar="DIR",
        help="output directory (one subdirectory per paper)",
    )
    reproduce.add_argument(
        "--verbose",
        action="store_true",
        help="print every table (by default only the findings; the tables go to "
        "<out>/<paper>/report.txt either way)",
    )
    reproduce.set_defaults(handler=_reproduce)
    _add_baselines_parser(commands)
    return parser


def _add_baselines_parser(commands: Any) -> None:
    from sonar_gym import pretrained

    baselines = commands.add_parser(
        "baselines",
        help="learned policies against the paper, the heuristic and random: table and plots",
        description="Evaluate, per env, the learned policy, the paper's procedure, the env's "
        "heuristic and random actions on the same evaluation seeds (from "
        f"{pretrained.EVALUATION_SEED_START}), in the rooms the policy trained in and in "
        "held-out random rooms; paired differences with 95% Student-t intervals. Writes "
        "baselines.md, baselines.json and plots. Without --pretrained the policies are "
        "trained first (the budget is printed before).",
    )
    baselines.add_argument(
        "--pretrained",
        action="store_true",
        help="evaluate the shipped policies (sonar_gym/pretrained/, or $"
        f"{pretrained.ROOT_VARIABLE}) instead of training new ones",
    )
    baselines.add_argument(
        "--env", nargs="+", default=["all"], metavar="ID", help="env ids or 'all' (default)"
    )
    baselines.add_argument(
        "--episodes",
        type=_positive_int,
        default=pretrained.DEFAULT_EVALUATION_EPISODES,
        metavar="N",
        help=f"episodes per agent, env and kind of room "
        f"(default {pretrained.DEFAULT_EVALUATION_EPISODES})",
    )
    baselines.add_argument(
        "--out",
        type=Path,
        default=None,
        metavar="DIR",
        help=f"output directory (default {DEFAULT_BASELINES_DIR}/<envs>_<N>ep_<pretrained|"
        f"trained>, e.g. {DEFAULT_BASELINES_DIR}/all_200ep_pretrained); trained policies go "
        "to DIR/policies",
    )
    baselines.add_argument(
        "--update-readme",
        action="store_true",
        help="put the table between the baselines markers of README.md (see --readme)",
    )
    baselines.add_argument(
        "--readme",
        type=Path,
        default=Path("README.md"),
        metavar="PATH",
        help="the file --update-readme edits (default README.md)",
    )
    baselines.set_defaults(handler=_baselines)


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``sonar-gym``; returns the exit status (2 for a request the user can fix)."""
    parser = build_parser()
    arguments = parser.parse_args(argv)
    arguments.command_line = [PROGRAM, *(sys.argv[1:] if argv is None else argv)]
    console = make_console()
    try:
        arguments.handler(arguments, console)
    except UsageError as error:
        make_console(stderr=True).print(
            f"{PROGRAM} {arguments.command}: error: {error}",
            style="red",
            markup=False,
            highlight=False,
            soft_wrap=True,
        )
        return 2
    except KeyboardInterrupt:
        make_console(stderr=True).print(f"{PROGRAM} {arguments.command}: interrupted")
        return 130
    return 0


def runnable_program() -> str:
    """How the user's shell can call this command line: ``sonar-gym`` when that name on PATH
    is this installation's script, else the script's path beside the running Python
    (relative when under the working directory, e.g. ``.venv/bin/sonar-gym``), else
    ``<python> -m sonar_gym``."""
    script = Path(sys.executable).with_name(PROGRAM)
    found = shutil.which(PROGRAM)
    if found is not None and (not script.exists() or Path(found).resolve() == script.resolve()):
        return PROGRAM
    if script.exists():
        try:
            return shlex.quote(str(script.relative_to(Path.cwd())))
        except ValueError:
            return shlex.quote(str(script))
    return f"{shlex.quote(sys.executable)} -m sonar_gym"


def runnable_command(command: str) -> str:
    """``command`` (a ``sonar-gym ...`` line) with the program as :func:`runnable_program`."""
    if command == PROGRAM or command.startswith(PROGRAM + " "):
        return runnable_program() + command[len(PROGRAM) :]
    return command


def make_console(stderr: bool = False) -> Console:
    """A rich console; 160 columns wide when writing to a file or pipe (unless COLUMNS is set),
    so the tables do not wrap in logs."""
    stream = sys.stderr if stderr else sys.stdout
    interactive = hasattr(stream, "isatty") and stream.isatty()
    width = None if interactive or "COLUMNS" in os.environ else PIPED_WIDTH
    return Console(stderr=stderr, width=width)


# --------------------------------------------------------------------------------------------
# argument types


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text}")
    return value


def _positive_float(text: str) -> float:
    value = float(text)
    if not value > 0.0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text}")
    return value


def _non_negative_int(text: str) -> int:
    value = int(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be zero or more, got {text}")
    return value


def _add_env_arg(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--env-arg",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="keyword argument for gym.make (numbers, true/false, none, JSON lists, strings); "
        "repeatable",
    )


# --------------------------------------------------------------------------------------------
# handlers


def _evaluate(arguments: argparse.Namespace, console: Console) -> None:
    from sonar_gym.train import evaluation, report
    from sonar_gym.train.progress import episode_progress

    env_kwargs = evaluation.parse_env_args(arguments.env_arg)
    out_dir = evaluate_output_dir(arguments, env_kwargs)
    json_path = arguments.json or out_dir / "evaluate.json"
    plot_path = arguments.plot or out_dir / "evaluate.png"
    # report mistakes before anything runs
    output_paths.check_output_dir("--out", out_dir)
    output_paths.check_output_file("--json" if arguments.json else "--out", json_path)
    if arguments.csv is not None:
        output_paths.check_output_file("--csv", arguments.csv)
    output_paths.check_plot_file("--plot" if arguments.plot else "--out", plot_path)
    env_ids = evaluation.resolve_env_ids(arguments.env or [evaluation.DEFAULT_ENV_ID])
    plan = evaluation.resolve_agent_names(env_ids, arguments.agent)
    evaluation.validate_plan(plan, env_kwargs)
    total = evaluation.count_episodes(plan, arguments.episodes)
    last_seed = arguments.seed + arguments.episodes - 1
    console.print(
        f"Evaluating {total} episodes (seeds {arguments.seed}..{last_seed} for every agent) "
        f"on {', '.join(env_ids)}",
        markup=False,
    )
    started = time.perf_counter()
    with episode_progress(console, total) as advance:
        results = evaluation.evaluate_agents(
            env_ids,
            plan,
            arguments.episodes,
            arguments.seed,
            env_kwargs,
            on_episode=advance,
            ray=arguments.ray,
            ray_address=arguments.address,
        )
    elapsed_s = time.perf_counter() - started
    report.print_summary(results, console)
    meta = {
        "command": arguments.command_line,
        "env_ids": env_ids,
        "agents": plan,
        "episodes": arguments.episodes,
        "seed": arguments.seed,
        "env_kwargs": env_kwargs,
        "elapsed_s": round(elapsed_s, 3),
        "versions": evaluation.software_versions(),
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }
    written = [report.write_json(results, json_path, meta)]
    if arguments.csv is not None:
        written.append(report.write_csv(results, arguments.csv))
    written.append(report.plot_results(results, plot_path))
    console.print(
        f"{total} episodes in {elapsed_s:.1f} s. Wrote " + ", ".join(map(str, written)),
        markup=False,
    )


def evaluate_output_dir(arguments: argparse.Namespace, env_kwargs: dict[str, object]) -> Path:
    """``--out``, else ``results/evaluate/<name>`` with the name made of the arguments
    (:func:`sonar_gym.train.evaluation.output_folder_name`; docs/outputs.md)."""
    from sonar_gym.train import evaluation

    if arguments.out is not None:
        return Path(arguments.out)
    return DEFAULT_EVALUATE_ROOT / evaluation.output_folder_name(
        arguments.env or [evaluation.DEFAULT_ENV_ID],
        arguments.agent,
        arguments.episodes,
        arguments.seed,
        env_kwargs,
    )


def _train(arguments: argparse.Namespace, console: Console) -> None:
    from sonar_gym.train import evaluation
    from sonar_gym.train.training import evaluate_command, train

    env_kwargs = evaluation.parse_env_args(arguments.env_arg)
    if arguments.out is not None:
        output_paths.check_output_dir("--out", arguments.out)
    if arguments.backend == "rllib":
        _train_rllib(arguments, env_kwargs, console)
        return
    result = train(
        env_id=arguments.env,
        algo=arguments.algo.lower() if arguments.algo else None,
        timesteps=arguments.timesteps,
        out_dir=arguments.out,
        seed=arguments.seed,
        n_envs=arguments.n_envs,
        config_path=arguments.config,
        resume=arguments.resume,
        env_kwargs=env_kwargs,
        subproc=arguments.subproc,
        progress_bar=not arguments.no_progress,
        eval_episodes=arguments.eval_episodes,
        overwrite=arguments.overwrite,
    )
    console.print(
        f"Trained {result.algo.upper()} on {result.env_id}: {result.total_timesteps} timesteps "
        f"in total. Run directory {result.out_dir}:"
    )
    for label, path in (
        ("model", result.model_path),
        ("VecNormalize statistics", result.vecnormalize_path),
        ("run info", result.run_file),
        ("learning curve", result.learning_curve_path),
        ("TensorBoard", result.out_dir / "tb"),
    ):
        console.print(f"  {label}: {path}", highlight=False, markup=False)
    if result.eval_mean_reward is not None:
        console.print(
            f"Evaluation (evaluate_policy, {result.eval_episodes} episodes, deterministic): "
            f"episode reward {result.eval_mean_reward:.3f} ± {result.eval_std_reward:.3f} (std)"
        )
    console.print("Evaluate it against the baselines with:")
    console.print(
        f"  {runnable_command(evaluate_command(result))}",
        highlight=False,
        markup=False,
        soft_wrap=True,
    )


def _train_rllib(
    arguments: argparse.Namespace, env_kwargs: dict[str, Any], console: Console
) -> None:
    from sonar_gym.train.rllib_backend import train_rllib

    if arguments.env is None:
        raise UsageError("--backend rllib needs --env ID")
    if arguments.resume is not None:
        raise UsageError("--resume continues stable-baselines3 runs only")
    algo = (arguments.algo or "ppo").lower()
    out_dir = arguments.out or Path("runs") / f"{arguments.env.split('/')[-1]}-rllib-{algo}"
    console.print(
        f"Training RLlib {algo.upper()} on {arguments.env} for {arguments.timesteps} env steps "
        f"with {arguments.num_env_runners} env runner(s)",
        markup=False,
    )
    result = train_rllib(
        arguments.env,
        arguments.timesteps,
        out_dir,
        algo=algo,
        seed=arguments.seed,
        num_env_runners=arguments.num_env_runners,
        address=arguments.address,
        env_kwargs=env_kwargs,
        overwrite=arguments.overwrite,
        on_iteration=lambda steps, total: console.print(f"  {steps}/{total} env steps"),
    )
    console.print(
        f"{result.timesteps} env steps in {result.iterations} iterations, {result.seconds:.1f} s. "
        f"Checkpoint and run info in {result.run_dir}. Evaluate it with:",
        markup=False,
    )
    evaluate = f"sonar-gym evaluate --env {arguments.env} --agent paper {result.run_dir}"
    console.print(
        f"  {runnable_command(evaluate)}",
        highlight=False,
        markup=False,
        soft_wrap=True,
    )


def _benchmark(arguments: argparse.Namespace, console: Console) -> None:
    from sonar_gym.train import benchmark, evaluation, report

    env_kwargs = evaluation.parse_env_args(arguments.env_arg)
    env_ids = evaluation.resolve_env_ids(arguments.env)
    json_path = arguments.json or DEFAULT_BENCHMARK_ROOT / benchmark_file_name(
        arguments.env, arguments.seconds, env_kwargs
    )
    output_paths.check_output_file("--json", json_path)
    started = time.perf_counter()
    with console.status("benchmark") as status:
        results = benchmark.run_benchmark(
            env_ids,
            arguments.seconds,
            env_kwargs,
            on_stage=lambda text: status.update(f"measuring {text}"),
            measure_pan=not arguments.no_pan,
            measure_vector=not arguments.no_vector,
        )
    elapsed_s = time.perf_counter() - started
    for note in results.notes:
        console.print(note, style="yellow", markup=False)
    if results.pan_rows:
        console.print(report.pan_table(results.pan_rows))
    if results.room_reset is not None:
        console.print(report.room_reset_line(results.room_reset), markup=False)
    if results.envs:
        console.print(report.speed_table(results))
    if results.vectors:
        console.print(report.vector_table(results))
    for env_id, failure in results.failures.items():
        console.print(f"{env_id} could not run: {failure}", style="red", markup=False)
    meta = {
        "command": arguments.command_line,
        "env_kwargs": env_kwargs,
        "elapsed_s": round(elapsed_s, 3),
        "versions": evaluation.software_versions(),
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }
    json_path.parent.mkdir(parents=True, exist_ok=True)
    json_path.write_text(json.dumps(results.to_dict(meta), indent=2) + "\n")
    console.print(f"Benchmark took {elapsed_s:.0f} s. Wrote {json_path}", markup=False)


def benchmark_file_name(
    env_selection: Sequence[str], seconds: float, env_kwargs: dict[str, object]
) -> str:
    """``<envs>_<seconds>s[_<key=value>...].json``, named after the arguments like the
    evaluation folders (:func:`sonar_gym.train.evaluation.output_folder_name`)."""
    from sonar_gym.train.evaluation import env_selection_label, name_from_arguments

    return (
        name_from_arguments([env_selection_label(env_selection), f"{seconds:g}s"], env_kwargs)
        + ".json"
    )


def _baselines(arguments: argparse.Namespace, console: Console) -> None:
    from sonar_gym.train import baselines
    from sonar_gym.train.progress import episode_progress

    started = time.perf_counter()
    env_ids = baselines.resolve_baseline_envs(arguments.env)
    out_dir = arguments.out or DEFAULT_BASELINES_DIR / baselines.output_folder_name(
        arguments.env, arguments.episodes, arguments.pretrained
    )
    output_paths.check_output_dir("--out", out_dir)
    if arguments.update_readme:  # a missing marker should stop the run before it starts
        baselines.check_readme_markers(arguments.readme)
    if arguments.pretrained:
        policy_dirs = baselines.shipped_policy_dirs(env_ids)
    else:
        policy_dirs = baselines.train_policies(
            env_ids,
            out_dir / "policies",
            progress=True,
            on_budget=lambda budget: console.print(f"Training budget: {budget}", markup=False),
        )
    total = baselines.count_baseline_episodes(policy_dirs, arguments.episodes)
    console.print(
        f"Evaluating {total} episodes (seeds {pretrained_seed_range(arguments.episodes)} for "
        f"every agent) on {', '.join(env_ids)}",
        markup=False,
    )
    with episode_progress(console, total) as advance:
        report = baselines.run_baselines(policy_dirs, arguments.episodes, on_episode=advance)
    table = baselines.markdown_table(report)
    console.print(table, markup=False, highlight=False, soft_wrap=True)
    meta = {
        "command": arguments.command_line,
        "pretrained": arguments.pretrained,
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }
    written = baselines.write_outputs(report, out_dir, meta)
    if arguments.update_readme:
        baselines.replace_readme_block(arguments.readme, table)
        written.append(arguments.readme)
    console.print(
        f"{total} episodes; total time {time.perf_counter() - started:.1f} s. Wrote "
        + ", ".join(map(str, written)),
        markup=False,
        soft_wrap=True,
    )


def pretrained_seed_range(episodes: int) -> str:
    """``first..last`` of the evaluation seeds of ``episodes`` episodes."""
    from sonar_gym import pretrained

    start = pretrained.EVALUATION_SEED_START
    return f"{start}..{start + episodes - 1}"


def reproduce_module_name(name: str) -> str:
    """``"beom-cho"`` -> ``"sonar_gym.train.reproduce.beom_cho"``."""
    return f"sonar_gym.train.reproduce.{name.replace('-', '_')}"


def available_reproductions() -> list[str]:
    """Papers (command-line names) whose ``sonar_gym.train.reproduce`` module exists."""
    available = []
    for name in REPRODUCIBLE_PAPERS:
        try:
            found = importlib.util.find_spec(reproduce_module_name(name)) is not None
        except ModuleNotFoundError:
            found = False
        if found:
            available.append(name)
    return available


def _reproduce(arguments: argparse.Namespace, console: Console) -> None:
    available = available_reproductions()
    requested: list[str] = []
    for name in arguments.names:
        name = name.lower().replace("_", "-")
        if name == "all":
            requested.extend(available)
            missing = [paper for paper in REPRODUCIBLE_PAPERS if paper not in available]
            if missing:
                console.print(f"not available yet, skipped: {', '.join(missing)}", style="yellow")
        elif name not in REPRODUCIBLE_PAPERS:
            raise UsageError(
                f"unknown paper {name!r}; choose one of {list(REPRODUCIBLE_PAPERS)} or 'all' "
                f"(available now: {available or 'none'})"
            )
        elif name not in available:
            raise UsageError(
                f"the reproduction of {name!r} is not available yet "
                f"(available now: {available or 'none'})"
            )
        else:
            requested.append(name)
    if not requested:
        raise UsageError(
            f"no reproduction is available yet; the papers are {list(REPRODUCIBLE_PAPERS)}"
        )
    for name in dict.fromkeys(requested):  # every paper's folder, before the first one runs
        output_paths.check_output_dir("--out", arguments.out / name.replace("-", "_"))
    from sonar_gym.train.report import CompactConsole

    for name in dict.fromkeys(requested):
        module = importlib.import_module(reproduce_module_name(name))
        out_dir = arguments.out / name.replace("-", "_")
        out_dir.mkdir(parents=True, exist_ok=True)
        console.rule(f"reproduce {name} -> {out_dir}")
        paper_console = CompactConsole(
            compact=not arguments.verbose,
            file=console.file,
            width=console.width,
            color_system=console.color_system,
        )
        module.run(out_dir, paper_console)
        report_path = out_dir / "report.txt"
        report_path.write_text(paper_console.full_text())
        if arguments.verbose:
            line = f"full report: {report_path}"
        else:
            line = f"{paper_console.tables_filed} tables in {report_path} (--verbose prints them)"
        console.print(line, style="dim", markup=False)


if __name__ == "__main__":
    sys.exit(main())
