"""Figures of the baselines: rewards and paired differences per env, and learning curves.

Rewards are episode rewards (sums over an episode, unitless, higher is better); intervals are
two-sided 95 % Student-t intervals of a mean. Matplotlib's object API (no pyplot), Agg.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from sonar_gym import pretrained
from sonar_gym.train.evaluation import ConfidenceInterval, t_confidence_interval

if TYPE_CHECKING:
    from sonar_gym.train.baselines import BaselinesReport

ROOM_STYLES = {"trained": ("o", "#1f77b4"), "held-out random": ("s", "#d62728")}
LEVEL_COLOURS = ("#2ca02c", "#ff7f0e", "#d62728", "#9467bd")


@dataclass(frozen=True)
class LearningCurves:
    """The validation curves of one shipped policy: per training seed, ``(timesteps,
    mean_reward)`` points in order, and the scripted agents' levels on the same seeds."""

    env_id: str
    by_seed: dict[int, list[tuple[int, float]]]
    levels: dict[str, float]


def read_learning_curves(policy_dir: Path, env_id: str) -> LearningCurves | None:
    """The curves of ``policy_dir`` (``learning_curve.csv``, levels from ``training.json``),
    or None when the policy has no ``learning_curve.csv``.

    Raises:
        ValueError: the CSV lacks a column of
            :data:`sonar_gym.pretrained.LEARNING_CURVE_COLUMNS` or holds a non-number.
    """
    path = policy_dir / pretrained.LEARNING_CURVE_FILE
    if not path.is_file():
        return None
    by_seed: dict[int, list[tuple[int, float]]] = {}
    with path.open(newline="") as handle:
        reader = csv.DictReader(handle)
        missing = [
            c for c in pretrained.LEARNING_CURVE_COLUMNS if c not in (reader.fieldnames or [])
        ]
        if missing:
            raise ValueError(f"{path} lacks the columns {missing}; it has {reader.fieldnames}")
        for line, row in enumerate(reader, start=2):
            try:
                seed = int(row["training_seed"])
                point = (int(float(row["timesteps"])), float(row["mean_reward"]))
            except ValueError as error:
                raise ValueError(f"{path} line {line}: {error}") from error
            by_seed.setdefault(seed, []).append(point)
    levels: dict[str, float] = {}
    training_file = policy_dir / pretrained.TRAINING_FILE
    if training_file.is_file():
        raw_levels = json.loads(training_file.read_text()).get("levels") or {}
        levels = {str(name): float(value) for name, value in raw_levels.items()}
    return LearningCurves(
        env_id=env_id,
        by_seed={seed: sorted(points) for seed, points in sorted(by_seed.items())},
        levels=levels,
    )


def load_learning_curves(policy_dirs: Mapping[str, Path]) -> list[LearningCurves]:
    """The curves of every policy that has them, in the order of ``policy_dirs``."""
    curves = [read_learning_curves(path, env_id) for env_id, path in policy_dirs.items()]
    return [curve for curve in curves if curve is not None]


def mean_over_seeds(
    curves: LearningCurves,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Timesteps where every training seed has a point, the mean reward over the seeds there,
    and its 95 % Student-t interval (low, high; the mean itself where only one seed exists)."""
    common = sorted(set.intersection(*(set(t for t, _ in p) for p in curves.by_seed.values())))
    values = {seed: dict(points) for seed, points in curves.by_seed.items()}
    means, lows, highs = [], [], []
    for timesteps in common:
        interval: ConfidenceInterval = t_confidence_interval(
            [values[seed][timesteps] for seed in values]
        )
        means.append(interval.mean)
        lows.append(interval.mean if interval.low is None else interval.low)
        highs.append(interval.mean if interval.high is None else interval.high)
    return np.asarray(common), np.asarray(means), np.asarray(lows), np.asarray(highs)


def _save(figure: Any, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=110)
    return path


def _half_width(interval: ConfidenceInterval | None) -> float:
    return math.nan if interval is None or interval.half_width is None else interval.half_width


def plot_rewards(report: BaselinesReport, path: Path) -> Path:
    """One row per env: the mean episode reward of every agent with its 95 % CI, and the
    paired per-seed difference to the paper's procedure with its 95 % CI and the zero line;
    trained and held-out rooms side by side (legend)."""
    from matplotlib.figure import Figure

    env_ids = list(dict.fromkeys(row.env_id for row in report.rows))
    figure = Figure(figsize=(11, 3.4 * max(1, len(env_ids))), layout="constrained")
    axes = figure.subplots(max(1, len(env_ids)), 2, squeeze=False)
    for index, env_id in enumerate(env_ids):
        rows = [row for row in report.rows if row.env_id == env_id]
        agents = list(dict.fromkeys(row.agent for row in rows))
        rooms = list(dict.fromkeys(row.rooms for row in rows))
        reward_axis, difference_axis = axes[index]
        compared = [agent for agent in agents if agent != "paper"]
        for position, room in enumerate(rooms):
            marker, colour = ROOM_STYLES.get(room, ("^", "#333333"))
            offset = (position - (len(rooms) - 1) / 2) * 0.2
            in_room = {row.agent: row for row in rows if row.rooms == room}
            reward_axis.errorbar(
                np.arange(len(agents)) + offset,
                [in_room[a].result.summary.reward.mean for a in agents],
                yerr=[_half_width(in_room[a].result.summary.reward) for a in agents],
                fmt=marker,
                color=colour,
                capsize=4,
                label=f"{room} rooms",
            )
            difference_axis.errorbar(
                np.arange(len(compared)) + offset,
                [_mean(in_room[a].versus_paper) for a in compared],
                yerr=[_half_width(in_room[a].versus_paper) for a in compared],
                fmt=marker,
                color=colour,
                capsize=4,
                label=f"{room} rooms",
            )
        reward_axis.set_xticks(np.arange(len(agents)), agents)
        reward_axis.set_ylabel("episode reward\n(mean, 95% CI)")
        reward_axis.set_title(env_id, loc="left")
        difference_axis.axhline(0.0, color="#555555", linewidth=1.0, linestyle="--")
        difference_axis.set_xticks(np.arange(len(compared)), compared)
        difference_axis.set_ylabel("reward − paper's, same seed\n(mean, 95% CI)")
        difference_axis.set_title("paired difference to the paper", loc="left")
        for axis in (reward_axis, difference_axis):
            axis.set_xlabel("agent")
            axis.margins(x=0.15, y=0.12)
            axis.legend(fontsize="small")
    return _save(figure, path)


def _mean(interval: ConfidenceInterval | None) -> float:
    return math.nan if interval is None else interval.mean


def reward_axis_limits(curve: LearningCurves, margin: float = 0.25) -> tuple[float, float] | None:
    """Reward-axis limits that show the curves and every scripted level but ``random``, padded
    by ``margin`` of their span (at least 0.5 in all): the random level usually lies so far
    below that on a shared axis the learned, paper and heuristic levels merge into one line.
    None when there is nothing to frame."""
    values = [reward for points in curve.by_seed.values() for _, reward in points]
    values += [level for name, level in curve.levels.items() if name != "random"]
    values = [value for value in values if math.isfinite(value)]
    if not values:
        return None
    low, high = min(values), max(values)
    pad = max(margin * (high - low), 0.25)
    return low - pad, high + pad


def plot_learning_curves(curves: Sequence[LearningCurves], path: Path) -> Path:
    """One panel per env: mean validation reward against training timesteps, every training
    seed thin, their mean thick with a 95 % Student-t band over seeds, and the scripted
    agents' levels on the same validation seeds as horizontal lines."""
    from matplotlib.figure import Figure

    columns = min(3, max(1, len(curves)))
    rows = max(1, math.ceil(len(curves) / columns))
    figure = Figure(figsize=(5.2 * columns, 3.8 * rows), layout="constrained")
    axes = figure.subplots(rows, columns, squeeze=False)
    for index, curve in enumerate(curves):
        axis = axes[index // columns][index % columns]
        for number, points in enumerate(curve.by_seed.values()):
            timesteps, rewards = zip(*points, strict=True) if points else ((), ())
            label = "each training seed" if number == 0 else None
            axis.plot(timesteps, rewards, color="#888888", linewidth=0.8, label=label)
        if curve.by_seed:
            timesteps_common, means, lows, highs = mean_over_seeds(curve)
            axis.plot(
                timesteps_common, means, color="black", linewidth=2.0, label="mean over seeds"
            )
            if len(curve.by_seed) > 1:
                axis.fill_between(
                    timesteps_common, lows, highs, color="black", alpha=0.15, label="95% CI"
                )
        limits = reward_axis_limits(curve)
        for colour, (name, level) in zip(LEVEL_COLOURS, curve.levels.items(), strict=False):
            label = f"{name} level"
            if limits is not None and not limits[0] <= level <= limits[1]:
                label += f" ({level:.1f}, off the axis)"
            axis.axhline(level, color=colour, linestyle="--", linewidth=1.2, label=label)
        if limits is not None:
            axis.set_ylim(*limits)
        axis.set_title(curve.env_id, loc="left")
        axis.set_xlabel("training timesteps")
        axis.set_ylabel("mean validation reward\n(deterministic policy)")
        axis.legend(fontsize="x-small")
    for index in range(len(curves), rows * columns):
        figure.delaxes(axes[index // columns][index % columns])
    return _save(figure, path)
