"""Yamamoto, Maeyama, Ohya & Yuta (APCS) in simulation: the corridor with wall B, Figs 12-15.

The paper's experiment (sec. 6): the robot drives along a corridor at 30 cm/s, its left side
sonar sampling every 3 cm; wall 'B' was put up on purpose and is not in the robot's map. The
paper prints few numbers: the thresholds (100 cm^2 grouping, groups of 4 to 8 ERPs, +-0.5 deg,
d1^2 + d2^2 = 200 cm^2), that "a long flat wall is divided to 5 detected wall vectors", that
the vector of wall B is detected and rejected, and (Fig. 15) that the estimated position
changes when corrected.

Here, with ``SonarGym/WallCorrection-v0`` in ``apcs_corridor`` (wall B, no other unmapped
obstacle) and the ``paper`` agent (left sonar, 3 cm, centre line), over several runs with
drifting odometry:

- the detected wall vectors, how many lie on the first flat stretch of the left wall
  (x = 0.5-2.0 m, from the start to the first pillar) against the paper's 5;
- which were matched and which rejected, with the reason (sec. 4.3), and what became of
  wall B;
- the pose error just before and just after each correction, and at the end of the route for
  plain odometry and for APCS.

Plots: the corridor with the ERPs and the detected vectors coloured matched / rejected
(Figs 12-14), and the true, odometry and corrected paths with the lateral error along the
route (Fig. 15). Every comparison whose ratio ours / paper lies outside [1/2, 2] is flagged
"differs by more than 2x".
"""

from __future__ import annotations

import json
import math
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from rich.console import Console
from rich.table import Table

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.agents.wall_correction import PaperAgent
from sonar_gym.apcs_route import WallDetection
from sonar_gym.envs.wall_correction import WallCorrectionEnv
from sonar_gym.localization.apcs import DEFAULT_PARAMETERS
from sonar_gym.pose import angle_difference
from sonar_gym.train.reproduce.common import parameters_table, ratio_flag

ENV_ID = "SonarGym/WallCorrection-v0"
PAPER_VECTORS_ON_LONG_WALL = 5
"""Sec. 6: "a long flat wall is divided to 5 detected wall vectors"."""
LONG_WALL_X_M = (0.5, 2.0)
"""The first flat stretch of the left wall seen from the route: start to the first pillar."""
LONG_WALL_Y_M = 1.0
WALL_B_X_M = (3.8, 4.7)
WALL_B_Y_M = 0.7
ON_WALL_TOLERANCE_M = 0.05
"""A detected vector lies on a wall when both its end points are this close to the wall's line."""
ENV_KWARGS: dict[str, Any] = {"n_unmapped_obstacles": 0}
PRESET_JITTER_KWARGS: dict[str, Any] = {"n_unmapped_obstacles": 0, "range_noise_std_m": None}

UNSTATED_PARAMETERS: tuple[tuple[str, str, str], ...] = (
    (
        "corridor",
        "10 m x 2 m, pillars 0.4 x 0.15 m on the left at x = 2.0 and 6.0 m and on the right "
        "at x = 4.0 m; wall B a 0.9 m board 0.3 m in front of the left wall (x = 3.8-4.7 m)",
        "scenario apcs_corridor",
    ),
    ("route", "x = 0.5 -> 9.5 m on the centre line, 6 legs", "env defaults"),
    ("robot", "radius 0.2 m, wheel base 0.3 m", "apcs_corridor"),
    (
        "sonar",
        "MA40B8 preset, +-17.5 deg beam, 0.3-5 m; timing jitter 1 mm (the preset's 3 mm "
        "shown beside)",
        "env range_noise_std_m",
    ),
    ("variance threshold of a wall fit", "(2 cm)^2 of perpendicular residual", "APCSParameters"),
    ("line fit", "total least squares through the centroid", "fit_wall_group"),
    (
        "sigma_r, sigma_xi of eqs (13)-(14)",
        "(1 cm)^2, (1 deg)^2",
        "env range_variance_m2, bearing_std_deg",
    ),
    (
        "odometry drift",
        "wheel radius errors N(0, 0.05 %), encoder 0.5 mm / sqrt(m), rare slips",
        "env",
    ),
    ("odometry covariance", "each wheel's variance grows 5e-7 m^2 per metre rolled", "env"),
    ("start uncertainty", "5 mm, 0.1 deg", "env"),
)


@dataclass
class RunResult:
    """One drive along the corridor."""

    detections: list[WallDetection]
    vectors_on_long_wall: int
    wall_b_vectors: int
    wall_b_rejected: int
    wall_b_reasons: Counter[str]
    odometry_final_error_m: float
    apcs_final_error_m: float
    correction_errors: list[tuple[float, float, float, float]] = field(default_factory=list)
    """(lateral before, lateral after, heading before, heading after), metres and radians."""


def _on_wall(detection: WallDetection, y_m: float, x_range: tuple[float, float]) -> bool:
    (x0, y0), (x1, y1) = detection.wall.start, detection.wall.end
    near_line = abs(y0 - y_m) < ON_WALL_TOLERANCE_M and abs(y1 - y_m) < ON_WALL_TOLERANCE_M
    middle = 0.5 * (x0 + x1)
    return (
        near_line and x_range[0] - ON_WALL_TOLERANCE_M <= middle <= x_range[1] + ON_WALL_TOLERANCE_M
    )


def drive_corridor(
    seed: int, env_kwargs: dict[str, Any] | None = None
) -> tuple[RunResult, WallCorrectionEnv]:
    """Drive the corridor once with the paper agent; return what APCS did."""
    env = gym.make(ENV_ID, **(ENV_KWARGS if env_kwargs is None else env_kwargs))
    unwrapped: WallCorrectionEnv = env.unwrapped  # type: ignore[assignment]
    agent = PaperAgent(env)
    agent.reset(seed)
    observation, info = env.reset(seed=seed)
    while True:
        observation, _, terminated, truncated, info = env.step(agent.act(observation))
        if terminated or truncated:
            break
    detections = list(unwrapped.trace.detections)
    wall_b = [d for d in detections if _on_wall(d, WALL_B_Y_M, WALL_B_X_M)]
    corrections = []
    for true_pose, before, after in unwrapped.trace.corrections:
        corrections.append(
            (
                abs(before.y - true_pose.y),
                abs(after.y - true_pose.y),
                abs(angle_difference(before.theta, true_pose.theta)),
                abs(angle_difference(after.theta, true_pose.theta)),
            )
        )
    result = RunResult(
        detections=detections,
        vectors_on_long_wall=sum(_on_wall(d, LONG_WALL_Y_M, LONG_WALL_X_M) for d in detections),
        wall_b_vectors=len(wall_b),
        wall_b_rejected=sum(not d.matched for d in wall_b),
        wall_b_reasons=Counter(d.reason or "matched" for d in wall_b),
        odometry_final_error_m=float(info["odometry_position_error_m"]),
        apcs_final_error_m=float(info["position_error_m"]),
        correction_errors=corrections,
    )
    return result, unwrapped


@dataclass
class Study:
    """Runs of the corridor and their statistics."""

    runs: list[RunResult]

    def vectors_on_long_wall(self) -> float:
        return float(np.mean([r.vectors_on_long_wall for r in self.runs]))

    def matched_share_on_mapped_walls(self) -> float:
        on_map = [
            d for r in self.runs for d in r.detections if not _on_wall(d, WALL_B_Y_M, WALL_B_X_M)
        ]
        return float(np.mean([d.matched for d in on_map])) if on_map else math.nan

    def reasons(self) -> Counter[str]:
        return Counter(d.reason or "matched" for r in self.runs for d in r.detections)

    def wall_b_detected_share(self) -> float:
        return float(np.mean([r.wall_b_vectors > 0 for r in self.runs]))

    def wall_b_rejected_share(self) -> float:
        total = sum(r.wall_b_vectors for r in self.runs)
        return sum(r.wall_b_rejected for r in self.runs) / total if total else math.nan

    def wall_b_reasons(self) -> Counter[str]:
        total: Counter[str] = Counter()
        for r in self.runs:
            total.update(r.wall_b_reasons)
        return total

    def correction_means(self) -> tuple[float, float, float, float]:
        rows = np.array([c for r in self.runs for c in r.correction_errors]).reshape(-1, 4)
        if rows.size == 0:
            return (math.nan,) * 4
        return tuple(float(v) for v in rows.mean(axis=0))  # type: ignore[return-value]

    def final_errors(self) -> tuple[float, float]:
        return (
            float(np.mean([r.odometry_final_error_m for r in self.runs])),
            float(np.mean([r.apcs_final_error_m for r in self.runs])),
        )


def statements_table(study: Study, preset: Study) -> Table:
    """The paper's statements (sec. 6, Figs 13-15) beside ours."""
    table = Table(title=f"APCS sec. 6 beside ours ({len(study.runs)} runs of the corridor)")
    for header in ("statement", "paper", "ours", "preset 3 mm jitter", "check"):
        table.add_column(header)
    params = DEFAULT_PARAMETERS
    table.add_row(
        "ERP grouping threshold",
        "100 cm^2",
        f"{params.grouping_distance_squared_m2 * 1e4:.0f} cm^2",
        "same",
        "same",
    )
    table.add_row(
        "group size",
        "ignore < 4, at most 8",
        f"ignore < {params.min_group_size}, at most {params.max_group_size}",
        "same",
        "same",
    )
    table.add_row(
        "orientation threshold",
        "+-0.5 deg",
        f"+-{math.degrees(params.orientation_tolerance_rad):.1f} deg",
        "same",
        "same",
    )
    table.add_row(
        "map matching d1^2 + d2^2",
        "200 cm^2",
        f"{params.endpoint_distance_squared_m2 * 1e4:.0f} cm^2",
        "same",
        "same",
    )
    table.add_row(
        "sampling", "every 3 cm at 30 cm/s, left side", "every 3 cm, left side", "same", "same"
    )
    ours_long, preset_long = study.vectors_on_long_wall(), preset.vectors_on_long_wall()
    table.add_row(
        "vectors on a long flat wall (Fig. 13)",
        str(PAPER_VECTORS_ON_LONG_WALL),
        f"{ours_long:.1f} on x = 0.5-2.0 m",
        f"{preset_long:.1f} {ratio_flag(preset_long, PAPER_VECTORS_ON_LONG_WALL)}".strip(),
        ratio_flag(ours_long, PAPER_VECTORS_ON_LONG_WALL) or "within 2x",
    )
    table.add_row(
        "wall B detected (Fig. 13)",
        "yes",
        f"in {100 * study.wall_b_detected_share():.0f} % of runs",
        f"{100 * preset.wall_b_detected_share():.0f} %",
        "",
    )
    reasons = ", ".join(f"{k} {v}" for k, v in study.wall_b_reasons().most_common())
    table.add_row(
        "wall B rejected (Fig. 14)",
        "yes (not in the map)",
        f"{100 * study.wall_b_rejected_share():.0f} % of its vectors ({reasons})",
        f"{100 * preset.wall_b_rejected_share():.0f} %",
        "",
    )
    table.add_row(
        "vectors on mapped walls matched (Fig. 14)",
        "drawn as matched",
        f"{100 * study.matched_share_on_mapped_walls():.0f} %",
        f"{100 * preset.matched_share_on_mapped_walls():.0f} %",
        "",
    )
    before_y, after_y, before_h, after_h = study.correction_means()
    table.add_row(
        "position corrected (Fig. 15)",
        "estimate changed",
        f"lateral |e| {100 * before_y:.2f} -> {100 * after_y:.2f} cm, heading "
        f"{math.degrees(before_h):.2f} -> {math.degrees(after_h):.2f} deg per correction",
        "",
        "",
    )
    odometry, apcs = study.final_errors()
    preset_odometry, preset_apcs = preset.final_errors()
    table.add_row(
        "error at the end of the route",
        "not given",
        f"odometry {100 * odometry:.1f} cm, APCS {100 * apcs:.1f} cm",
        f"odometry {100 * preset_odometry:.1f} cm, APCS {100 * preset_apcs:.1f} cm",
        "",
    )
    return table


def reasons_table(study: Study) -> Table:
    """How every detected vector fared in the matching (sec. 4.3)."""
    table = Table(
        title="Detected vectors by outcome (first failed condition of the nearest map wall)"
    )
    table.add_column("outcome")
    table.add_column("vectors per run", justify="right")
    for reason, count in study.reasons().most_common():
        table.add_row(reason, f"{count / len(study.runs):.1f}")
    return table


def plot_walls(run: RunResult, env: WallCorrectionEnv, out_dir: Path) -> Path:
    """Figs 12-14: the corridor, the ERPs, the detected vectors matched / rejected.

    The lower panel stretches the strip along the left wall (y from 0.6 m to 1.05 m).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, (whole, strip) = plt.subplots(
        2, 1, figsize=(13, 6.5), gridspec_kw={"height_ratios": [1.2, 1]}
    )
    erps = np.array([(x, y) for x, y, side in env.trace.erps if side == "left"]).reshape(-1, 2)
    true_path = np.array(env.trace.true_path)
    for axis in (whole, strip):
        _draw_corridor(axis, env)
        axis.plot(erps[:, 0], erps[:, 1], ".", color="#ff7f0e", markersize=2.5, label="ERP")
        for label, matched, colour in (
            ("matched", True, "#2ca02c"),
            ("rejected", False, "#d62728"),
        ):
            axis.plot([], [], color=colour, label=f"detected vector, {label}")
            for detection in run.detections:
                if detection.matched != matched:
                    continue
                (x0, y0), (x1, y1) = detection.wall.start, detection.wall.end
                axis.annotate(
                    "",
                    xy=(x1, y1),
                    xytext=(x0, y0),
                    arrowprops={"arrowstyle": "->", "color": colour, "lw": 1.6},
                )
    whole.plot(true_path[:, 0], true_path[:, 1], color="#145214", lw=1.0, label="trajectory A")
    whole.set_aspect("equal")
    whole.set_title("APCS corridor: ERPs and detected wall vectors (cf. Figs 12-14)")
    whole.legend(loc="lower right", fontsize=7, ncol=4)
    reasons = ", ".join(f"{k} x{v}" for k, v in run.wall_b_reasons.most_common())
    strip.text(
        0.5 * sum(WALL_B_X_M),
        WALL_B_Y_M - 0.06,
        f"B: {reasons}",
        color="#d62728",
        ha="center",
        fontsize=8,
    )
    strip.set_ylim(0.6, 1.05)
    strip.set_title("Strip along the left wall (stretched)", fontsize=9)
    path = out_dir / "apcs_walls.png"
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


def plot_paths(env: WallCorrectionEnv, out_dir: Path) -> Path:
    """Fig. 15: lateral and heading errors of odometry and of APCS along the route."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    trace = env.trace
    true_path = np.array(trace.true_path)
    odometry = np.array(trace.odometry_path)
    estimate = np.array(trace.estimated_path)

    def heading_error_deg(path: np.ndarray) -> np.ndarray:
        return np.degrees(np.angle(np.exp(1j * (path[:, 2] - true_path[:, 2]))))

    figure, (lateral, heading) = plt.subplots(2, 1, figsize=(13, 5.5), sharex=True)
    lateral.plot(
        true_path[:, 0],
        100 * (odometry[:, 1] - true_path[:, 1]),
        color="#7f7f7f",
        ls="--",
        label="odometry",
    )
    lateral.plot(
        true_path[:, 0],
        100 * (estimate[:, 1] - true_path[:, 1]),
        color="#d81b9c",
        label="APCS estimate",
    )
    heading.plot(
        true_path[:, 0], heading_error_deg(odometry), color="#7f7f7f", ls="--", label="odometry"
    )
    heading.plot(
        true_path[:, 0], heading_error_deg(estimate), color="#d81b9c", label="APCS estimate"
    )
    for true_pose, _, _ in trace.corrections:
        for axis in (lateral, heading):
            axis.axvline(true_pose.x, color="#2ca02c", lw=0.4, alpha=0.6)
    for axis in (lateral, heading):
        axis.axhline(0.0, color="black", lw=0.5)
        axis.legend(fontsize=7)
    lateral.set_ylabel("lateral error (cm)")
    heading.set_ylabel("heading error (deg)")
    heading.set_xlabel("x (m); green lines: corrections")
    lateral.set_title("The estimate changes at each correction (cf. Fig. 15)")
    path = out_dir / "apcs_paths.png"
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


def _draw_corridor(axis: Any, env: WallCorrectionEnv) -> None:
    scenario = env.world_scenario
    for vector in env.wall_map:
        (x0, y0), (x1, y1) = vector.start, vector.end
        axis.plot([x0, x1], [y0, y1], color="#222222", lw=1.5)
    for wall in scenario.walls:
        if not wall.mapped:
            axis.plot(
                [wall.a[0], wall.b[0]], [wall.a[1], wall.b[1]], color="#b5651d", lw=2.0, ls="--"
            )
            axis.text(
                0.5 * (wall.a[0] + wall.b[0]),
                wall.a[1] - 0.045,
                "B (not in map)",
                color="#b5651d",
                ha="center",
                fontsize=8,
            )
    axis.set_xlabel("x (m)")
    axis.set_ylabel("y (m)")


def run(out_dir: Path, console: Console, *, n_runs: int = 30, seed: int = 0) -> None:
    """Re-run the APCS corridor experiment; print the tables, write the plots into ``out_dir``.

    Args:
        out_dir: where the PNGs and ``apcs_results.json`` go (created if missing).
        console: where the tables go.
        n_runs: drives of the corridor (seeds ``seed`` ... ``seed + n_runs - 1``).
        seed: the first seed. The run where APCS gains most over odometry is plotted.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    console.print(
        "Yamamoto et al. sec. 6: corridor with an unmapped wall B, left side sonar every 3 cm, "
        "APCS thresholds of sec. 6, drifting odometry.",
        markup=False,
    )
    runs, plotted, plotted_env = [], None, None
    for index in range(n_runs):
        result, env = drive_corridor(seed + index)
        runs.append(result)
        gain = result.odometry_final_error_m - result.apcs_final_error_m
        if plotted is None or gain > plotted.odometry_final_error_m - plotted.apcs_final_error_m:
            plotted, plotted_env = result, env
    preset_runs = [drive_corridor(seed + index, PRESET_JITTER_KWARGS)[0] for index in range(n_runs)]
    study, preset = Study(runs), Study(preset_runs)
    console.print(statements_table(study, preset))
    console.print(reasons_table(study))
    console.print(parameters_table(UNSTATED_PARAMETERS))
    assert plotted is not None and plotted_env is not None
    paths = [plot_walls(plotted, plotted_env, out_dir), plot_paths(plotted_env, out_dir)]
    before_y, after_y, before_h, after_h = study.correction_means()
    odometry, apcs = study.final_errors()
    numbers = {
        "n_runs": n_runs,
        "paper_vectors_on_long_wall": PAPER_VECTORS_ON_LONG_WALL,
        "vectors_on_long_wall": study.vectors_on_long_wall(),
        "vectors_on_long_wall_preset_jitter": preset.vectors_on_long_wall(),
        "wall_b_detected_share": study.wall_b_detected_share(),
        "wall_b_rejected_share": study.wall_b_rejected_share(),
        "wall_b_reasons": dict(study.wall_b_reasons()),
        "matched_share_on_mapped_walls": study.matched_share_on_mapped_walls(),
        "matched_share_on_mapped_walls_preset_jitter": preset.matched_share_on_mapped_walls(),
        "outcomes_per_run": {k: v / n_runs for k, v in study.reasons().items()},
        "correction_lateral_error_before_m": before_y,
        "correction_lateral_error_after_m": after_y,
        "correction_heading_error_before_rad": before_h,
        "correction_heading_error_after_rad": after_h,
        "final_error_odometry_m": odometry,
        "final_error_apcs_m": apcs,
        "plots": [str(p) for p in paths],
    }
    (out_dir / "apcs_results.json").write_text(json.dumps(numbers, indent=2) + "\n")
    for path in paths:
        console.print(f"wrote {path}", markup=False)
