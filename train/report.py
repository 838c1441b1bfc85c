"""Reports of evaluations, trainings and benchmarks: rich tables, JSON/CSV files and plots.

Inside, results keep SI units (metres, radians, seconds); tables and plots show E_xy in
centimetres and E_theta in degrees, the units the papers print (Beom & Cho eq. (16)).
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console, RenderableType
from rich.table import Table
from rich.text import Text

from sonar_gym.train.bench_room import RoomReset
from sonar_gym.train.benchmark import BenchmarkReport
from sonar_gym.train.evaluation import AgentResult, AgentSummary

MISSING = "–"
CSV_FIELDS = (
    "env_id",
    "agent",
    "seed",
    "reward",
    "position_error_m",
    "heading_error_rad",
    "sensing_time_s",
    "status",
    "steps",
)


# --------------------------------------------------------------------------------------------
# evaluation


def _format(value: float | None, scale: float = 1.0, digits: int = 1) -> str:
    return MISSING if value is None else f"{value * scale:.{digits}f}"


def _format_reward(summary: AgentSummary) -> str:
    reward = summary.reward
    if reward.half_width is None:
        return f"{reward.mean:.3f}"
    return f"{reward.mean:.3f} ± {reward.half_width:.3f}"


def summary_table(env_id: str, results: Sequence[AgentResult]) -> Table:
    """One row per agent of ``env_id``: success, E_xy [cm], E_theta [deg], time, reward CI."""
    confidence = results[0].summary.reward.confidence if results else 0.95
    table = Table(title=env_id, title_justify="left", header_style="bold")
    table.add_column("agent", no_wrap=True)
    for header in (
        "episodes",
        "success [%]",
        "E_xy median [cm]",
        "E_xy p95 [cm]",
        "E_θ median [deg]",
        "E_θ p95 [deg]",
        "sensing time [s]",
        f"reward (mean ± {confidence:.0%} CI)",
    ):
        table.add_column(Text(header), justify="right")
    for result in results:
        summary = result.summary
        table.add_row(
            Text(result.agent),
            str(summary.episodes),
            f"{100.0 * summary.success_rate:.1f}",
            _format(summary.position_error_median_m, 100.0),
            _format(summary.position_error_p95_m, 100.0),
            _format(summary.heading_error_median_rad, 180.0 / math.pi, 2),
            _format(summary.heading_error_p95_rad, 180.0 / math.pi, 2),
            _format(summary.sensing_time_mean_s, 1.0, 2),
            _format_reward(summary),
        )
    return table


def group_by_env(results: Sequence[AgentResult]) -> dict[str, list[AgentResult]]:
    """Results grouped per env id, in order of first appearance."""
    grouped: dict[str, list[AgentResult]] = {}
    for result in results:
        grouped.setdefault(result.env_id, []).append(result)
    return grouped


def print_summary(results: Sequence[AgentResult], console: Console) -> None:
    """Print one table per env (see :func:`summary_table`)."""
    for env_id, env_results in group_by_env(results).items():
        console.print(summary_table(env_id, env_results))
    console.print(
        'E_xy, E_θ: over successful episodes (status "ok"); sensing time and reward: over all '
        "episodes; CI: Student-t interval of the mean.",
        style="dim",
    )


def summary_to_dict(summary: AgentSummary) -> dict[str, Any]:
    """A JSON-ready dict of ``summary`` (SI units in the key names)."""
    data = asdict(summary)
    reward = data.pop("reward")
    data.update(
        reward_mean=reward["mean"],
        reward_ci_half_width=reward["half_width"],
        reward_ci_low=summary.reward.low,
        reward_ci_high=summary.reward.high,
        confidence=reward["confidence"],
    )
    return data


def results_to_dict(
    results: Sequence[AgentResult], meta: Mapping[str, Any] | None = None
) -> dict[str, Any]:
    """Everything of an evaluation as a JSON-ready dict: ``meta`` and per (env, agent) the
    summary and every episode record."""
    return {
        "meta": dict(meta or {}),
        "results": [
            {
                "env_id": result.env_id,
                "agent": result.agent,
                "summary": summary_to_dict(result.summary),
                "episodes": [asdict(record) for record in result.records],
            }
            for result in results
        ],
    }


def write_json(
    results: Sequence[AgentResult], path: str | Path, meta: Mapping[str, Any] | None = None
) -> Path:
    """Write :func:`results_to_dict` to ``path`` (parent directories created)."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(json.dumps(results_to_dict(results, meta), indent=2) + "\n")
    return target


def write_csv(results: Sequence[AgentResult], path: str | Path) -> Path:
    """Write one row per episode (columns :data:`CSV_FIELDS`; empty cell = not reported)."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    with target.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=CSV_FIELDS)
        writer.writeheader()
        for result in results:
            for record in result.records:
                row = {"env_id": result.env_id, "agent": result.agent, **asdict(record)}
                writer.writerow({k: "" if v is None else v for k, v in row.items()})
    return target


def _value_or_nan(value: float | None, scale: float = 1.0) -> float:
    return math.nan if value is None else value * scale


def short_agent_label(agent: str) -> str:
    """An agent name short enough for a plot axis: saved models by their last two path parts."""
    parts = Path(agent).parts
    return str(Path(*parts[-2:])) if len(parts) > 2 else agent


def _use_log_scale_for_wide_ranges(axis: Any, values: Sequence[float]) -> None:
    """A log axis when the positive values span more than two decades (errors often do)."""
    positive = [v for v in values if v > 0 and math.isfinite(v)]
    if len(positive) >= 2 and max(positive) / min(positive) > 100.0:
        axis.set_yscale("log")


THIN_SAMPLE = 10
"""Error statistics from fewer successful episodes than this are marked ``n=...`` in plots."""

ERROR_PANELS = (
    ("E_xy [cm]", 100.0, "position_error_median_m", "position_error_p95_m"),
    ("E_θ [deg]", 180.0 / math.pi, "heading_error_median_rad", "heading_error_p95_rad"),
)
SENSING_PANEL = "mean sensing time [s]"
REWARD_PANEL = "episode reward (mean, 95% CI)"


def evaluation_panels(env_results: Sequence[AgentResult]) -> list[str]:
    """The panels of one env's row of :func:`plot_results`, left to right: E_xy, E_theta (only
    when some agent has a heading error: tasks without a heading get no empty panel), mean
    sensing time, episode reward."""
    panels = [ERROR_PANELS[0][0]]
    if any(result.summary.heading_error_median_rad is not None for result in env_results):
        panels.append(ERROR_PANELS[1][0])
    return [*panels, SENSING_PANEL, REWARD_PANEL]


def sample_note(successes: int) -> str:
    """``"n=3"`` for error statistics from fewer than :data:`THIN_SAMPLE` episodes, else ``""``."""
    return f"n={successes}" if 0 < successes < THIN_SAMPLE else ""


def evaluation_figure(results: Sequence[AgentResult]) -> Any:
    """The matplotlib figure of :func:`plot_results` (Agg; the caller closes it)."""
    from matplotlib.figure import Figure

    grouped = group_by_env(results)
    columns = max(len(evaluation_panels(env_results)) for env_results in grouped.values())
    figure = Figure(figsize=(4.2 * columns, 3.6 * len(grouped)), layout="constrained")
    axes = figure.subplots(len(grouped), columns, squeeze=False)
    width = 0.38
    for row, (env_id, env_results) in enumerate(grouped.items()):
        summaries = [result.summary for result in env_results]
        names = [
            f"{short_agent_label(result.agent)}\n{100 * result.summary.success_rate:.0f}% ok"
            for result in env_results
        ]
        # error statistics from few episodes say so under their bars
        thin_names = [
            f"{name} ({note})" if (note := sample_note(result.summary.successes)) else name
            for name, result in zip(names, env_results, strict=True)
        ]
        positions = np.arange(len(names))
        panels = evaluation_panels(env_results)
        for column, panel in enumerate(panels):
            axis = axes[row][column]
            errors = [entry for entry in ERROR_PANELS if entry[0] == panel]
            if errors:
                _, scale, median_key, p95_key = errors[0]
                medians = [_value_or_nan(getattr(s, median_key), scale) for s in summaries]
                p95s = [_value_or_nan(getattr(s, p95_key), scale) for s in summaries]
                for offset, values, name in (
                    (-width / 2, medians, "median"),
                    (width / 2, p95s, "95th percentile"),
                ):
                    bars = axis.bar(positions + offset, values, width, label=name)
                    axis.bar_label(bars, fmt="%.3g", fontsize="x-small")
                _use_log_scale_for_wide_ranges(axis, medians + p95s)
                axis.legend(fontsize="small")
            elif panel == SENSING_PANEL:
                times = [_value_or_nan(s.sensing_time_mean_s) for s in summaries]
                bars = axis.bar(positions, times, 0.6)
                axis.bar_label(bars, fmt="%.3g", fontsize="x-small")
            else:
                means = [s.reward.mean for s in summaries]
                half = [
                    math.nan if s.reward.half_width is None else s.reward.half_width
                    for s in summaries
                ]
                axis.errorbar(positions, means, yerr=half, fmt="o", capsize=4)
                axis.axhline(0.0, color="#999999", linewidth=0.8)
            axis.set_ylabel(panel)
            axis.margins(y=0.12)
            axis.set_xticks(positions, thin_names if errors else names, rotation=20, ha="right")
            axis.set_title(env_id if column == 0 else "", loc="left")
            axis.set_xlim(-0.6, len(names) - 0.4)
        for column in range(len(panels), columns):
            figure.delaxes(axes[row][column])
    if any(0 < r.summary.successes < THIN_SAMPLE for r in results):
        figure.supxlabel(
            f"n=...: error statistics from fewer than {THIN_SAMPLE} successful episodes",
            fontsize="small",
            color="#b22222",
        )
    return figure


def plot_results(results: Sequence[AgentResult], path: str | Path) -> Path:
    """One figure, one row of charts per env (panels: :func:`evaluation_panels`): E_xy median
    and p95 [cm], E_theta median and p95 [deg] where the task has a heading (log axes when
    they span more than two decades; ``n=...`` over agents whose statistics rest on fewer than
    :data:`THIN_SAMPLE` successful episodes), mean sensing time [s], and the mean episode
    reward with its 95 % Student-t confidence interval. One group per agent, labelled with its
    success rate. Missing values leave no bar."""
    figure = evaluation_figure(results)
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(target, dpi=110)
    return target


# --------------------------------------------------------------------------------------------
# training


def moving_average(values: Sequence[float], window: int) -> np.ndarray:
    """Trailing moving average; the first ``window - 1`` points average what exists so far."""
    data = np.asarray(values, dtype=float)
    if data.size == 0:
        return data
    window = max(1, min(window, data.size))
    cumulative = np.concatenate(([0.0], np.cumsum(data)))
    ends = np.arange(1, data.size + 1)
    counts = np.minimum(ends, window)
    return (cumulative[ends] - cumulative[ends - counts]) / counts


def plot_learning_curve(
    timesteps: Sequence[float], rewards: Sequence[float], path: str | Path, title: str
) -> Path:
    """Episode reward against training timesteps: raw points and a moving average."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axis = plt.subplots(figsize=(7, 4), layout="constrained")
    if len(rewards):
        window = max(1, len(rewards) // 20)
        axis.plot(timesteps, rewards, ".", alpha=0.25, markersize=3, label="episode")
        axis.plot(timesteps, moving_average(rewards, window), label=f"moving average ({window})")
        axis.legend()
    else:
        axis.text(0.5, 0.5, "no finished episode", ha="center", transform=axis.transAxes)
    axis.set_xlabel("timesteps")
    axis.set_ylabel("episode reward")
    axis.set_title(title)
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(target, dpi=110)
    plt.close(figure)
    return target


# --------------------------------------------------------------------------------------------
# benchmark


def _format_cell(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}" if abs(value) < 1e4 else f"{value:,.0f}"
    return MISSING if value is None else str(value)


def pan_table(rows: Sequence[Mapping[str, Any]]) -> Table:
    """The rows of the pan-throughput benchmark, one column per key."""
    table = Table(title="sonar pan throughput", title_justify="left", header_style="bold")
    columns = list(dict.fromkeys(key for row in rows for key in row))
    for index, column in enumerate(columns):
        table.add_column(Text(column), justify="left" if index == 0 else "right")
    for row in rows:
        table.add_row(*(Text(_format_cell(row.get(column))) for column in columns))
    return table


def room_reset_line(room: RoomReset) -> str:
    """One line: the make and reset times of the large-room measurement."""
    return (
        f"{room.env_id} in a room of {room.walls} walls ({room.extra_walls} extra): "
        f"gym.make {room.make_seconds:.2f} s, {room.resets} resets {room.reset_seconds:.3f} s "
        f"in all"
    )


def _shares_text(shares: Mapping[str, float]) -> str:
    return " · ".join(f"{phase} {100 * share:.0f}%" for phase, share in shares.items()) or MISSING


def speed_table(report: BenchmarkReport) -> Table:
    """Per env: random-action steps/s, PPO env-steps/s and its ratio to PPO on CartPole-v1
    beside it (the two runs around the env), the ceiling (the ratio on a free stand-in with the
    env's spaces), the env's own time per PPO step, and the share of wall time per phase of
    both runs."""
    reference = report.reference_steps_per_s
    table = Table(
        title=f"env steps per second (PPO on CartPole-v1: {len(report.references)} runs, "
        f"mean {reference:.0f} steps/s, last/first {report.reference_drift:.2f}, "
        f"fastest/slowest {report.reference_spread:.2f})",
        title_justify="left",
        header_style="bold",
    )
    table.add_column("env", no_wrap=True)
    for column in (
        "random steps/s",
        "episodes",
        "PPO steps/s",
        "CartPole PPO steps/s beside it",
        "PPO vs CartPole",
        "ceiling vs CartPole",
        "env ms per PPO step",
    ):
        table.add_column(column, justify="right")
    table.add_column("random: time share")
    table.add_column("PPO: time share")
    for speed in report.envs:
        table.add_row(
            speed.env_id,
            f"{speed.random.steps_per_s:.1f}",
            str(speed.random.episodes),
            f"{speed.ppo.steps_per_s:.1f}",
            f"{speed.reference_steps_per_s:.0f}",
            f"{speed.ppo_over_reference:.3f}",
            f"{speed.ceiling_over_reference:.3f}",
            f"{1e3 * speed.env_seconds_per_step:.2f}",
            _shares_text(speed.random.phase_shares),
            _shares_text(speed.ppo.phase_shares),
        )
    return table


def vector_table(report: BenchmarkReport) -> Table:
    """Per env with a native vector env: env-steps per second of its sub-envs under random
    actions through ``SyncVectorEnv`` and through the native vector env, and their ratio."""
    table = Table(
        title="vector env steps per second (random actions, alternating runs)",
        title_justify="left",
        header_style="bold",
    )
    table.add_column("env", no_wrap=True)
    for column in ("envs", "runs", "sync env-steps/s", "native env-steps/s", "native vs sync"):
        table.add_column(column, justify="right")
    for speed in report.vectors:
        table.add_row(
            speed.env_id,
            str(speed.num_envs),
            str(len(speed.runs)),
            f"{speed.env_steps_per_s('sync'):.0f}",
            f"{speed.env_steps_per_s('vector_entry_point'):.0f}",
            f"{speed.native_over_sync:.3f}",
        )
    return table


# --------------------------------------------------------------------------------------------
# reproductions


class CompactConsole(Console):
    """A console that prints everything but tables (all of it with ``compact=False``), and
    keeps every object, tables included, for :meth:`full_text` (the complete report, for a
    file).

    The papers' reproductions print wide tables; by default the command line shows their
    prose (setup, verdicts, one line per finding) and files the tables.
    """

    def __init__(self, *, compact: bool = True, full_width: int = 160, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.compact = compact
        self.full = Console(file=io.StringIO(), width=full_width, record=True, color_system=None)
        self.tables_filed = 0

    def print(self, *objects: RenderableType | Any, **kwargs: Any) -> None:  # type: ignore[override]
        self.full.print(*objects, **kwargs)
        if self.compact and any(isinstance(item, Table) for item in objects):
            self.tables_filed += 1
            return
        super().print(*objects, **kwargs)

    def full_text(self) -> str:
        """Everything printed so far, tables included, as plain text."""
        return self.full.export_text()
