"""The baselines table: shipped (or freshly trained) policies against the scripted agents.

For every env, four agents play the same evaluation episodes (episode ``i`` uses seed
``EVALUATION_SEED_START + i`` for every agent, :mod:`sonar_gym.pretrained`), once in the rooms
the policy was trained in (the env arguments of its ``run.json``) and once in rooms it never
saw, where the env offers a randomised variant (:data:`HELD_OUT_ROOMS`):

- ``learned``: the policy, deterministic actions;
- ``paper``: the paper's own procedure with the paper's parameters;
- the env's heuristic (:func:`heuristic_agent`: sector, retry, covariance, adaptive, spread,
  both_walls);
- ``random``: uniform random actions.

Episodes come from :func:`sonar_gym.train.evaluation.evaluate_agents`. Because the episodes
are paired by seed, an agent is compared with the paper (and with the heuristic) by the
per-seed reward difference ``d_i = R_agent(seed_i) - R_other(seed_i)``: its mean with a
two-sided 95 % Student-t interval ``mean(d) +- t_{0.975, n-1} s_d / sqrt(n)``. An agent
"beats" the other when that whole interval lies above zero.

The table (:func:`markdown_table`), every number and every episode (:func:`report_to_dict`)
and the figures (:mod:`sonar_gym.train.baselines_plots`) are written by
:func:`write_outputs`; :func:`replace_readme_block` puts the table into README.md.
"""

from __future__ import annotations

import importlib
import json
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from sonar_gym import pretrained
from sonar_gym.agents.builtin import BUILTIN_AGENTS
from sonar_gym.train import UsageError
from sonar_gym.train.evaluation import (
    AgentResult,
    ConfidenceInterval,
    EpisodeCallback,
    EpisodeRecord,
    env_selection_label,
    evaluate_agents,
    name_from_arguments,
    resolve_env_ids,
    t_confidence_interval,
)
from sonar_gym.train.report import summary_to_dict

LEARNED = "learned"
PAPER = "paper"
RANDOM = "random"
TRAINED_ROOMS = "trained"
HELD_OUT_LABEL = "held-out random"
NO_HELD_OUT = "none"
CONFIDENCE = 0.95
README_START = "<!-- baselines:start -->"
README_END = "<!-- baselines:end -->"
TABLE_FILE = "baselines.md"
JSON_FILE = "baselines.json"
REWARDS_PLOT_FILE = "baselines_rewards.png"
LEARNING_CURVES_PLOT_FILE = "baselines_learning_curves.png"
MISSING = "–"
TRAINING_MODULE = "sonar_gym.train.baseline_training"

HELD_OUT_ROOMS: dict[str, dict[str, Any] | None] = {
    "SonarGym/BeaconScan-v0": {"scenario": "random"},
    "SonarGym/ActiveBeaconScan-v0": {"scenario": "random"},
    "SonarGym/SweepLocalization-v0": {"route": "random"},
    "SonarGym/BlockExpansion-v0": {"layout": "random", "path": "random"},
    "SonarGym/Trilateration-v0": None,
    "SonarGym/WallCorrection-v0": None,
}
"""Env arguments that put an episode in a room the policy never trained on, drawn from the
episode's seed (so a fixed set of evaluation seeds is a fixed set of held-out rooms); None
where the env offers no randomised room. BeaconScan / ActiveBeaconScan: a seeded random room
(``scenario="random"``); SweepLocalization: a random route through the arena; BlockExpansion:
jittered Table I beacons and a random path. Trilateration draws its route per episode already
and has one room; WallCorrection places its unmapped obstacles per episode already and has
one corridor."""

Trainer = Callable[[list[str], Path, bool], dict[str, Path]]
"""``train_baselines(env_ids, out_dir, progress) -> {env id: policy directory}``."""


@dataclass(frozen=True)
class BaselineRow:
    """One agent in one kind of room of one env.

    ``versus_paper`` / ``versus_heuristic``: the paired per-seed reward difference (this agent
    minus the other) with its Student-t interval; None for the agent itself.
    """

    env_id: str
    rooms: str
    env_kwargs: dict[str, Any]
    agent: str
    result: AgentResult
    versus_paper: ConfidenceInterval | None
    versus_heuristic: ConfidenceInterval | None

    @property
    def beats_paper(self) -> bool | None:
        """Whether the paired difference to the paper lies entirely above zero."""
        return beats(self.versus_paper)

    @property
    def beats_heuristic(self) -> bool | None:
        """Whether the paired difference to the heuristic lies entirely above zero."""
        return beats(self.versus_heuristic)


@dataclass
class BaselinesReport:
    """Every row of a baselines run, and what it was run on."""

    rows: list[BaselineRow]
    episodes: int
    seed: int
    policy_dirs: dict[str, Path]
    heuristics: dict[str, str]
    no_held_out: list[str] = field(default_factory=list)
    elapsed_s: float = 0.0


# --------------------------------------------------------------------------------------------
# statistics


def paired_difference(
    records: Sequence[EpisodeRecord],
    reference: Sequence[EpisodeRecord],
    confidence: float = CONFIDENCE,
) -> ConfidenceInterval:
    """Mean per-seed reward difference ``records - reference`` with its Student-t interval.

    Raises:
        ValueError: the two runs did not play the same seeds in the same order.
    """
    seeds = [record.seed for record in records]
    reference_seeds = [record.seed for record in reference]
    if seeds != reference_seeds:
        raise ValueError(
            "paired differences need the same seeds in the same order; got "
            f"{seeds[:5]}... and {reference_seeds[:5]}..."
        )
    differences = [a.reward - b.reward for a, b in zip(records, reference, strict=True)]
    return t_confidence_interval(differences, confidence)


def beats(difference: ConfidenceInterval | None) -> bool | None:
    """True when the interval lies entirely above zero; None when there is none (the agent
    itself, or a single episode)."""
    if difference is None or difference.low is None:
        return None
    return difference.low > 0.0


# --------------------------------------------------------------------------------------------
# what runs


def heuristic_agent(env_id: str) -> str:
    """The env's scripted agent that is neither the paper's procedure nor random.

    Raises:
        UsageError: the env has no such agent, or more than one.
    """
    names = [name for name in BUILTIN_AGENTS.get(env_id, {}) if name not in (PAPER, RANDOM)]
    if len(names) != 1:
        raise UsageError(
            f"{env_id} needs exactly one heuristic agent for the baselines; has {names}"
        )
    return names[0]


def held_out_kwargs(env_id: str, trained_kwargs: Mapping[str, Any]) -> dict[str, Any] | None:
    """The env arguments of the held-out rooms (over the trained ones), or None if none exist."""
    variant = HELD_OUT_ROOMS.get(env_id)
    return None if variant is None else {**trained_kwargs, **variant}


def trained_env_kwargs(policy_dir: Path) -> dict[str, Any]:
    """The ``gym.make`` arguments the policy in ``policy_dir`` was trained with (``run.json``)."""
    run_file = policy_dir / pretrained.RUN_FILE
    if not run_file.is_file():
        return {}
    kwargs: dict[str, Any] = json.loads(run_file.read_text()).get("env_kwargs") or {}
    return dict(kwargs)


def shipped_policy_dirs(env_ids: Sequence[str]) -> dict[str, Path]:
    """The shipped policy of every env in ``env_ids``.

    Raises:
        UsageError: some env has no shipped policy (the message names them).
    """
    missing = [env_id for env_id in env_ids if not pretrained.has_policy(env_id)]
    if missing:
        raise UsageError(
            f"no shipped policy for {missing} in {pretrained.pretrained_root()}; policies ship "
            f"for {pretrained.shipped_env_ids() or 'no env'} (leave out --pretrained to train)"
        )
    return {env_id: pretrained.find_policy(env_id) for env_id in env_ids}


def train_policies(
    env_ids: Sequence[str],
    out_dir: Path,
    progress: bool,
    trainer: Trainer | None = None,
    on_budget: Callable[[str], None] | None = None,
) -> dict[str, Path]:
    """Train a policy per env with ``trainer`` (default:
    :func:`sonar_gym.train.baseline_training.train_baselines`) into ``out_dir``; the default
    trainer's budget is passed to ``on_budget`` before training starts.

    Raises:
        UsageError: the trainer returned no policy for some env.
    """
    if trainer is None:
        # imported by name, lazily: training pulls in torch and is not needed for --pretrained
        try:
            baseline_training = importlib.import_module(TRAINING_MODULE)
        except ModuleNotFoundError as error:
            if error.name != TRAINING_MODULE:
                raise
            raise UsageError(
                f"training the baselines needs {TRAINING_MODULE}, which this installation "
                "lacks; evaluate the shipped policies with --pretrained"
            ) from error
        if on_budget is not None:
            on_budget(baseline_training.training_budget(list(env_ids)))
        trainer = baseline_training.train_baselines
    policy_dirs = trainer(list(env_ids), out_dir, progress)
    missing = [env_id for env_id in env_ids if env_id not in policy_dirs]
    if missing:
        raise UsageError(f"training gave no policy for {missing}")
    return {env_id: Path(policy_dirs[env_id]) for env_id in env_ids}


def room_settings(env_id: str, policy_dir: Path) -> list[tuple[str, dict[str, Any]]]:
    """``(rooms label, env arguments)`` pairs an env is evaluated in: trained, then held out."""
    trained = trained_env_kwargs(policy_dir)
    settings = [(TRAINED_ROOMS, trained)]
    held_out = held_out_kwargs(env_id, trained)
    if held_out is not None:
        settings.append((HELD_OUT_LABEL, held_out))
    return settings


def count_baseline_episodes(policy_dirs: Mapping[str, Path], episodes: int) -> int:
    """Episodes :func:`run_baselines` plays: four agents per env and kind of room."""
    settings = sum(len(room_settings(env_id, path)) for env_id, path in policy_dirs.items())
    return 4 * episodes * settings


# --------------------------------------------------------------------------------------------
# running


def run_baselines(
    policy_dirs: Mapping[str, Path],
    episodes: int = pretrained.DEFAULT_EVALUATION_EPISODES,
    seed: int = pretrained.EVALUATION_SEED_START,
    on_episode: EpisodeCallback | None = None,
) -> BaselinesReport:
    """Evaluate learned, paper, heuristic and random on every env of ``policy_dirs`` (env id
    -> policy directory) in trained and held-out rooms; episode ``i`` uses seed ``seed + i``.

    Raises:
        UsageError: an env's policy does not fit it, or the env has no heuristic.
        ValueError: ``episodes`` < 1.
    """
    started = time.perf_counter()
    rows: list[BaselineRow] = []
    heuristics = {env_id: heuristic_agent(env_id) for env_id in policy_dirs}
    no_held_out: list[str] = []
    for env_id, policy_dir in policy_dirs.items():
        heuristic = heuristics[env_id]
        settings = room_settings(env_id, policy_dir)
        if len(settings) == 1:
            no_held_out.append(env_id)
        for rooms, env_kwargs in settings:
            agents = [str(policy_dir), PAPER, heuristic, RANDOM]
            results = evaluate_agents(
                [env_id],
                {env_id: agents},
                episodes,
                seed,
                env_kwargs,
                on_episode=_relabel(on_episode, str(policy_dir)),
            )
            by_agent = dict(zip([LEARNED, PAPER, heuristic, RANDOM], results, strict=True))
            for agent, result in by_agent.items():
                rows.append(
                    BaselineRow(
                        env_id=env_id,
                        rooms=rooms,
                        env_kwargs=dict(env_kwargs),
                        agent=agent,
                        result=result,
                        versus_paper=None
                        if agent == PAPER
                        else paired_difference(result.records, by_agent[PAPER].records),
                        versus_heuristic=None
                        if agent == heuristic
                        else paired_difference(result.records, by_agent[heuristic].records),
                    )
                )
    return BaselinesReport(
        rows=rows,
        episodes=episodes,
        seed=seed,
        policy_dirs=dict(policy_dirs),
        heuristics=heuristics,
        no_held_out=no_held_out,
        elapsed_s=time.perf_counter() - started,
    )


def _relabel(on_episode: EpisodeCallback | None, policy_path: str) -> EpisodeCallback | None:
    if on_episode is None:
        return None
    callback = on_episode

    def relabelled(env_id: str, agent: str, record: EpisodeRecord) -> None:
        callback(env_id, LEARNED if agent == policy_path else agent, record)

    return relabelled


# --------------------------------------------------------------------------------------------
# the table


def _number(value: float | None, scale: float = 1.0, digits: int = 1) -> str:
    return MISSING if value is None else f"{value * scale:.{digits}f}"


def format_interval(interval: ConfidenceInterval | None, digits: int = 2) -> str:
    """``mean [low, high]``, the mean alone for a single value, or ``–`` for none."""
    if interval is None:
        return MISSING
    if interval.low is None or interval.high is None:
        return f"{interval.mean:+.{digits}f}"
    return f"{interval.mean:+.{digits}f} [{interval.low:+.{digits}f}, {interval.high:+.{digits}f}]"


def _verdict(value: bool | None) -> str:
    return MISSING if value is None else ("yes" if value else "no")


def _reward_cell(reward: ConfidenceInterval) -> str:
    if reward.half_width is None:
        return f"{reward.mean:.2f}"
    return f"{reward.mean:.2f} ± {reward.half_width:.2f}"


TABLE_COLUMNS = (
    "env",
    "rooms",
    "agent",
    "reward (mean ± 95% CI)",
    "Δ vs paper [95% CI]",
    "beats paper",
    "Δ vs heuristic [95% CI]",
    "beats heuristic",
    "success [%]",
    "E_xy median / p95 [cm]",
    "E_θ median / p95 [deg]",
    "sensing time [s]",
)


def table_rows(report: BaselinesReport) -> list[list[str]]:
    """The cells of :func:`markdown_table`, one list per row (columns :data:`TABLE_COLUMNS`)."""
    cells: list[list[str]] = []
    for index, row in enumerate(report.rows):
        summary = row.result.summary
        agent = row.agent
        if agent not in (LEARNED, PAPER, RANDOM):
            agent = f"{agent} (heuristic)"
        cells.append(
            [
                row.env_id.rpartition("/")[2],
                row.rooms,
                agent,
                _reward_cell(summary.reward),
                format_interval(row.versus_paper),
                _verdict(row.beats_paper),
                format_interval(row.versus_heuristic),
                _verdict(row.beats_heuristic),
                f"{100.0 * summary.success_rate:.0f}",
                f"{_number(summary.position_error_median_m, 100.0)} / "
                f"{_number(summary.position_error_p95_m, 100.0)}",
                f"{_number(summary.heading_error_median_rad, 180.0 / math.pi, 2)} / "
                f"{_number(summary.heading_error_p95_rad, 180.0 / math.pi, 2)}",
                _number(summary.sensing_time_mean_s, 1.0, 2),
            ]
        )
        last_of_env = index + 1 == len(report.rows) or report.rows[index + 1].env_id != row.env_id
        if last_of_env and row.env_id in report.no_held_out:
            cells.append(
                [row.env_id.rpartition("/")[2], NO_HELD_OUT, *[MISSING] * (len(TABLE_COLUMNS) - 2)]
            )
    return cells


def markdown_table(report: BaselinesReport) -> str:
    """The baselines as a markdown table with a line on seeds and a legend below it."""
    header = "| " + " | ".join(TABLE_COLUMNS) + " |"
    rule = "|" + "|".join("---" if i < 3 else "---:" for i in range(len(TABLE_COLUMNS))) + "|"
    body = ["| " + " | ".join(cells) + " |" for cells in table_rows(report)]
    last_seed = report.seed + report.episodes - 1
    notes = [
        "",
        f"{report.episodes} episodes per agent and row, seeds {report.seed}..{last_seed}, the "
        "same for every agent (paired). Δ: mean per-seed reward difference to the paper's "
        "procedure / the env's heuristic with its 95 % Student-t interval; *beats*: the whole "
        "interval above zero. E_xy, E_θ over successful episodes; reward and sensing time over "
        "all. *held-out random*: rooms drawn from the episode seed that the policy never "
        "trained in (`"
        + "`, `".join(
            f"{env_id.rpartition('/')[2]}: "
            + ", ".join(f"{key}={value}" for key, value in variant.items())
            for env_id, variant in HELD_OUT_ROOMS.items()
            if variant is not None and env_id in report.policy_dirs
        )
        + "`); *none*: the env offers no randomised room.",
    ]
    seen = {
        env_id.rpartition("/")[2]: variants
        for env_id, directory in report.policy_dirs.items()
        if (variants := demonstrated_variants(directory))
    }
    if seen:
        notes.append(
            "Teachers that also played random rooms of their own seeds during the warm start "
            "(so these held-out rooms are new rooms of a kind the policy saw): "
            + "; ".join(
                f"{name}: `"
                + "`, `".join(
                    ", ".join(f"{k}={v}" for k, v in variant.items()) for variant in variants
                )
                + "`"
                for name, variants in seen.items()
            )
            + "."
        )
    return "\n".join([header, rule, *body, *notes]) + "\n"


def demonstrated_variants(policy_dir: Path) -> list[dict[str, Any]]:
    """The non-default room settings a policy's teacher played during its warm start, from
    its ``training.json`` (none for a policy without one)."""
    training_file = policy_dir / pretrained.TRAINING_FILE
    if not training_file.is_file():
        return []
    recipe = json.loads(training_file.read_text()).get("recipe", {})
    return [dict(variant) for variant in recipe.get("demo_variants", []) if variant]


# --------------------------------------------------------------------------------------------
# files


def interval_to_dict(interval: ConfidenceInterval | None) -> dict[str, Any] | None:
    """A JSON-ready dict of a paired difference (None stays None)."""
    if interval is None:
        return None
    return {
        "mean": interval.mean,
        "ci_low": interval.low,
        "ci_high": interval.high,
        "half_width": interval.half_width,
        "confidence": interval.confidence,
        "n": interval.n,
    }


def report_to_dict(
    report: BaselinesReport, meta: Mapping[str, Any] | None = None
) -> dict[str, Any]:
    """Every number of ``report`` and every episode of every row, JSON-ready (SI units)."""
    return {
        "meta": {
            **dict(meta or {}),
            "episodes": report.episodes,
            "seed": report.seed,
            "policy_dirs": {env_id: str(path) for env_id, path in report.policy_dirs.items()},
            "heuristics": report.heuristics,
            "no_held_out_rooms": report.no_held_out,
            "elapsed_s": round(report.elapsed_s, 3),
        },
        "rows": [
            {
                "env_id": row.env_id,
                "rooms": row.rooms,
                "env_kwargs": row.env_kwargs,
                "agent": row.agent,
                "summary": summary_to_dict(row.result.summary),
                "versus_paper": interval_to_dict(row.versus_paper),
                "beats_paper": row.beats_paper,
                "versus_heuristic": interval_to_dict(row.versus_heuristic),
                "beats_heuristic": row.beats_heuristic,
                "episodes": [asdict(record) for record in row.result.records],
            }
            for row in report.rows
        ],
    }


def write_outputs(
    report: BaselinesReport, out_dir: Path, meta: Mapping[str, Any] | None = None
) -> list[Path]:
    """Write ``baselines.md``, ``baselines.json`` and the figures into ``out_dir``."""
    from sonar_gym.train import baselines_plots

    out_dir.mkdir(parents=True, exist_ok=True)
    table_path = out_dir / TABLE_FILE
    table_path.write_text(f"# Baselines\n\n{markdown_table(report)}")
    json_path = out_dir / JSON_FILE
    json_path.write_text(json.dumps(report_to_dict(report, meta), indent=2) + "\n")
    written = [table_path, json_path]
    written.append(baselines_plots.plot_rewards(report, out_dir / REWARDS_PLOT_FILE))
    curves = baselines_plots.load_learning_curves(report.policy_dirs)
    if curves:
        written.append(
            baselines_plots.plot_learning_curves(curves, out_dir / LEARNING_CURVES_PLOT_FILE)
        )
    return written


def _block_span(readme: Path) -> tuple[str, int, int]:
    """The text of ``readme`` and where the baselines block starts (after the start marker)
    and ends (at the end marker)."""
    if not readme.is_file():
        raise UsageError(f"--update-readme: no file {readme}")
    text = readme.read_text()
    start = text.find(README_START)
    end = text.find(README_END)
    if start < 0 or end < start or text.count(README_START) != 1 or text.count(README_END) != 1:
        raise UsageError(
            f"--update-readme: {readme} needs one {README_START!r} and, after it, one "
            f"{README_END!r} around the baselines table"
        )
    return text, start + len(README_START), end


def check_readme_markers(readme: Path) -> None:
    """Check that :func:`replace_readme_block` can edit ``readme``.

    Raises:
        UsageError: the file is missing, or lacks either marker (or has them out of order).
    """
    _block_span(readme)


def replace_readme_block(readme: Path, table: str) -> None:
    """Replace the text between :data:`README_START` and :data:`README_END` in ``readme``
    with ``table`` (the markers and everything outside them stay).

    Raises:
        UsageError: as :func:`check_readme_markers`.
    """
    text, start, end = _block_span(readme)
    readme.write_text(f"{text[:start]}\n{table.strip()}\n{text[end:]}")


def resolve_baseline_envs(selection: Sequence[str] | None) -> list[str]:
    """The env ids of ``--env`` (default and ``"all"``: every registered SonarGym/ id)."""
    return resolve_env_ids(list(selection or ["all"]))


def output_folder_name(
    env_selection: Sequence[str], episodes: int, pretrained_policies: bool
) -> str:
    """``<envs>_<episodes>ep_<pretrained|trained>``: the default folder of a baselines run,
    named after its arguments (envs as given, without the ``SonarGym/`` namespace).

    >>> output_folder_name(["all"], 200, True)
    'all_200ep_pretrained'
    """
    source = "pretrained" if pretrained_policies else "trained"
    return name_from_arguments([env_selection_label(env_selection), f"{episodes}ep", source])
