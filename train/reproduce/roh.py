"""Roh et al. in simulation: Tables II-V, block expansion over two and three areas.

The paper's experiments (Sec. IV): beacons A-E at the Table I coordinates, a robot driving a
parabola and localizing every 40 ms, Areas (A, B, C), (B, C, D) and (B, D, E); over two areas
d1 = 450 mm with six choices of (d2, d3) (Tables II-III), over three areas three choices of
(d1, ..., d6) (Tables IV-V). Each table prints one run's sigma (RMS difference in y between
the localized and the true path) or sigma' (mean distance from the localized points to the
true path).

Here the same setup runs in the ``roh_beacons`` scenario with the environment's sensor
(:func:`sonar_gym.envs.block_expansion.make_ranger`: the one-way ranger of
:mod:`sonar_gym.sonar.ranging` with 1 mm of jitter, a 1 MHz counter, 8 ms between firings)
and the paper's method (:class:`sonar_gym.localization.roh.BlockExpansion`, trilateration by
the centroid reading of Sec. III.A). Every table row is run ``n_runs`` times on the same
measured ranges (one ranging of the path per run, shared by the rows). A run whose
calibration fails (the three spheres miss, or a d is never crossed) is counted and left out of
sigma and sigma', which are the medians over the runs that calibrated every beacon; "differs
by more than 2x" flags where ours / paper leaves [1/2, 2].
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.envs.block_expansion import (
    ENV_ID,
    FIRING_INTERVAL_S,
    PAPER_PATH,
    PAPER_PATH_X_END_M,
    SCENARIO_NAME,
    TEMPERATURE_C,
    BlockExpansionEnvConfig,
    make_ranger,
)
from sonar_gym.localization.result import OK
from sonar_gym.localization.roh import (
    PAPER_THREE_AREAS,
    PAPER_TWO_AREAS,
    TABLE_I_BEACONS_MM,
    TABLE_II_III_D_MM,
    TABLE_II_SIGMA_MM,
    TABLE_III_SIGMA_PRIME_MM,
    TABLE_IV_SIGMA_MM,
    TABLE_IV_V_D_MM,
    TABLE_V_SIGMA_PRIME_MM,
    BlockExpansion,
    BlockExpansionConfig,
    BlockExpansionResult,
    distances_to_polyline,
)
from sonar_gym.pose import FloatArray
from sonar_gym.routes import (
    LOCALIZATION_PERIOD_S,
    PATH_STEP_M,
    ROBOT_SPEED_MPS,
    range_along_route,
)
from sonar_gym.scenario import Scenario, load_scenario
from sonar_gym.world import World
from sonar_gym.train.reproduce.common import FLAG, final_frame_png, parameters_table

SEED = 2009


@dataclass(frozen=True)
class PaperTable:
    """One pair of the paper's tables: the d's (mm) and its sigma and sigma' per row (mm)."""

    name: str
    areas: tuple[tuple[str, str, str], ...]
    distances_mm: tuple[tuple[float, ...], ...]
    sigma_mm: tuple[float, ...]
    sigma_prime_mm: tuple[float, ...]
    printed_average_sigma_mm: float
    printed_average_sigma_prime_mm: float


PAPER_TABLES = (
    PaperTable(
        "two areas (Tables II-III)",
        PAPER_TWO_AREAS,
        TABLE_II_III_D_MM,
        TABLE_II_SIGMA_MM,
        TABLE_III_SIGMA_PRIME_MM,
        33.3,
        21.9,
    ),
    PaperTable(
        "three areas (Tables IV-V)",
        PAPER_THREE_AREAS,
        TABLE_IV_V_D_MM,
        TABLE_IV_SIGMA_MM,
        TABLE_V_SIGMA_PRIME_MM,
        46.5,
        17.3,
    ),
)

UNSTATED_PARAMETERS: tuple[tuple[str, str, str], ...] = (
    ("receiver height", "0.3 m", "roh_beacons.toml; below every beacon"),
    (
        "path",
        "y = 1.45 - 0.9 (x - 1.6)^2 m, x from 2.75 to 1.3 m (two areas) or 0.55 m (three)",
        "parabolic_path; 'a parabolic path' (Sec. IV.A)",
    ),
    (
        "robot speed",
        f"{ROBOT_SPEED_MPS:g} m/s: {PATH_STEP_M * 1000:g} mm per "
        f"{LOCALIZATION_PERIOD_S * 1000:g} ms fix",
        "the 40 ms period is the paper's (Sec. III.C)",
    ),
    ("ranging jitter", "1 mm (as a distance), Gaussian", "BeaconRanger"),
    ("time-of-flight counter", "1 MHz (0.34 mm per count), truncating", "BeaconRanger"),
    (
        "firing interval",
        f"{FIRING_INTERVAL_S * 1000:g} ms (all beacons every {LOCALIZATION_PERIOD_S * 1000:g} ms "
        "for five)",
        "BeaconRanger",
    ),
    ("air temperature", f"{TEMPERATURE_C:g} deg C, known to the sensor", "no speed-of-sound bias"),
    ("beacon range", "5 m (no dropouts in this room)", "BeaconRanger"),
    (
        "trilateration",
        "centroid of the pairwise circle intersections nearest the third circle",
        "Sec. III.A read as in sonar_gym.localization.roh_trilateration",
    ),
    (
        "areas",
        "(A, B, C), (B, C, D), (B, D, E)",
        "Fig. 3 prints Area 2 as (A, B, D); see roh_block_expansion",
    ),
    ("statistic", "median over the runs that calibrated every beacon", "the paper shows one run"),
)


@dataclass
class RowResult:
    """All runs of one table row."""

    distances_mm: tuple[float, ...]
    paper_sigma_mm: float
    paper_sigma_prime_mm: float
    sigma_mm: list[float] = field(default_factory=list)
    sigma_prime_mm: list[float] = field(default_factory=list)
    calibration_errors_mm: dict[str, list[float]] = field(default_factory=dict)
    conditions: dict[str, list[float]] = field(default_factory=dict)
    failures: Counter[str] = field(default_factory=Counter)
    runs: list[BlockExpansionResult] = field(default_factory=list)

    @property
    def successes(self) -> int:
        """Runs that calibrated and passed every boundary."""
        return len(self.sigma_mm)

    def median(self, values: Sequence[float]) -> float:
        """Median in mm, NaN when no run succeeded (printed as a dash)."""
        return float(np.median(values)) if len(values) else math.nan


@dataclass
class Setup:
    """The simulated Table I world and path for one number of areas."""

    table: PaperTable
    scenario: Scenario
    world: World
    beacons_m: dict[str, tuple[float, float, float]]
    path: FloatArray
    sensor_height_m: float
    config: BlockExpansionEnvConfig

    def runner_config(self, distances_mm: Sequence[float]) -> BlockExpansionConfig:
        """The block expansion with the row's d's (mm, as printed)."""
        values = [d / 1000.0 for d in distances_mm]
        triples = tuple(tuple(values[i : i + 3]) for i in range(0, len(values), 3))
        return BlockExpansionConfig(
            beacons_m=self.beacons_m,
            areas=self.table.areas,
            calibration_distances_m=triples,  # type: ignore[arg-type]
            sensor_height_m=self.sensor_height_m,
            range_noise_std_m=0.0,
        )


def make_setup(table: PaperTable) -> Setup:
    """World, beacons (Table I via ``roh_beacons``), paper-like path and sensor for a table."""
    scenario = load_scenario(SCENARIO_NAME)
    names = tuple(dict.fromkeys(name for area in table.areas for name in area))
    beacons = {name: scenario.emitter(name).position for name in names}
    n_areas = len(table.areas)
    path = paper_path(n_areas)
    return Setup(
        table=table,
        scenario=scenario,
        world=World(scenario, temperature_c=TEMPERATURE_C),
        beacons_m=beacons,
        path=path,
        sensor_height_m=scenario.robot.sensor_height,
        config=BlockExpansionEnvConfig(n_areas=n_areas),
    )


def paper_path(n_areas: int) -> FloatArray:
    """The paper-like parabola sampled every :data:`PATH_STEP_M`, ending in the last area."""
    return replace(PAPER_PATH, x_end_m=PAPER_PATH_X_END_M[n_areas]).sample()


def run_table(setup: Setup, n_runs: int, seed: int) -> list[RowResult]:
    """Every row of a paper table, ``n_runs`` times on shared measured ranges."""
    table = setup.table
    rows = [
        RowResult(d, s, sp)
        for d, s, sp in zip(table.distances_mm, table.sigma_mm, table.sigma_prime_mm, strict=True)
    ]
    ranger = make_ranger(setup.config, setup.sensor_height_m)
    for run in range(n_runs):
        rng = np.random.default_rng([seed, len(table.areas), run])
        names = setup.runner_config(table.distances_mm[0]).beacon_names
        ranges, _ = range_along_route(ranger, setup.world, setup.path, names, rng)
        for row in rows:
            result = BlockExpansion(setup.runner_config(row.distances_mm)).run(
                setup.path, distance_table=ranges
            )
            row.runs.append(result)
            for calibration in result.calibrations:
                if calibration.error_m is not None:
                    row.calibration_errors_mm.setdefault(calibration.new_beacon, []).append(
                        1000.0 * calibration.error_m
                    )
                if calibration.calibration is not None and math.isfinite(
                    calibration.calibration.condition
                ):
                    row.conditions.setdefault(calibration.new_beacon, []).append(
                        calibration.calibration.condition
                    )
            failed = [c for c in result.calibrations if c.status != OK]
            if failed:
                row.failures[f"{failed[0].new_beacon}: {failed[0].status}"] += 1
                continue
            sigma, sigma_prime = result.path_errors(setup.path)
            row.sigma_mm.append(1000.0 * sigma)
            row.sigma_prime_mm.append(1000.0 * sigma_prime)
    return rows


# --------------------------------------------------------------------------------------------
# Tables


NO_RUN = "no run calibrated every beacon"


def ratio_flag(ours: float, paper: float) -> str:
    """``FLAG`` when ``ours / paper`` lies outside [1/2, 2], :data:`NO_RUN` when ours is
    missing (NaN), else ``""``."""
    if not math.isfinite(ours):
        return NO_RUN
    if not (ours > 0.0 and paper > 0.0):
        return FLAG
    ratio = ours / paper
    return FLAG if ratio > 2.0 or ratio < 0.5 else ""


def _mm(value: float) -> str:
    return f"{value:.1f}" if math.isfinite(value) else "-"


def comparison_table(table: PaperTable, rows: Sequence[RowResult], n_runs: int) -> Table:
    """The paper's sigma and sigma' per row beside ours (median over successful runs)."""
    view = Table(
        title=f"{table.name}: paper | ours (median over the runs that calibrated, of {n_runs})",
        title_justify="left",
        header_style="bold",
    )
    count = len(table.distances_mm[0])
    for k in range(count):
        view.add_column(f"d{k + 1}", justify="right")
    for header in ("σ paper", "σ ours", "flag", "σ' paper", "σ' ours", "flag", "calibrated"):
        view.add_column(header, justify="right" if "flag" not in header else "left")
    new_beacons = sorted({name for row in rows for name in row.calibration_errors_mm})
    for name in new_beacons:
        view.add_column(f"{name} error", justify="right")
    for row in rows:
        sigma, sigma_prime = row.median(row.sigma_mm), row.median(row.sigma_prime_mm)
        errors = [_mm(row.median(row.calibration_errors_mm.get(n, []))) for n in new_beacons]
        view.add_row(
            *(f"{d:g}" for d in row.distances_mm),
            f"{row.paper_sigma_mm:.1f}",
            _mm(sigma),
            ratio_flag(sigma, row.paper_sigma_mm),
            f"{row.paper_sigma_prime_mm:.1f}",
            _mm(sigma_prime),
            ratio_flag(sigma_prime, row.paper_sigma_prime_mm),
            f"{row.successes}/{n_runs}",
            *errors,
        )
    averages = average_row(rows)
    view.add_row(
        "Average",
        *("" for _ in range(count - 1)),
        f"{table.printed_average_sigma_mm:.1f}",
        _mm(averages["sigma_mm"]),
        ratio_flag(averages["sigma_mm"], table.printed_average_sigma_mm),
        f"{table.printed_average_sigma_prime_mm:.1f}",
        _mm(averages["sigma_prime_mm"]),
        ratio_flag(averages["sigma_prime_mm"], table.printed_average_sigma_prime_mm),
        f"{sum(r.successes for r in rows)}/{n_runs * len(rows)}",
        *("" for _ in new_beacons),
        style="bold",
    )
    return view


def average_row(rows: Sequence[RowResult]) -> dict[str, float]:
    """Mean over the rows (that had a successful run) of our medians, mm."""
    sigmas = [row.median(row.sigma_mm) for row in rows if row.successes]
    primes = [row.median(row.sigma_prime_mm) for row in rows if row.successes]
    return {
        "sigma_mm": float(np.mean(sigmas)) if sigmas else math.nan,
        "sigma_prime_mm": float(np.mean(primes)) if primes else math.nan,
    }


def _counts(counter: Counter[str]) -> str:
    return ", ".join(f"{key} x{count}" for key, count in counter.items())


def differences(results: dict[str, list[RowResult]], n_runs: int) -> list[str]:
    """Plain statements, from the numbers, of where ours differs from the paper and why."""
    lines = []
    two, three = (results[t.name] for t in PAPER_TABLES)
    conditions = [c for row in two for c in row.conditions.get("D", [])]
    d_errors = [e for row in two for e in row.calibration_errors_mm.get("D", [])]
    if conditions and d_errors:
        lines.append(
            "Calibration of D is badly conditioned: the three saved positions lie on "
            f"{PATH_STEP_M * 1000:g} mm steps of a gently curved path (median condition number "
            f"{np.median(conditions):.0f}), so 1 mm of range jitter moves the calibrated D by "
            f"{np.median(d_errors):.0f} mm (median over the two-area rows); the localized path "
            "stays close to the true one because the fixes made with a displaced D still fit the "
            "ranges near the boundary."
        )
    failed = sum(n_runs - row.successes for row in two)
    if failed:
        lines.append(
            f"{failed} of {n_runs * len(two)} two-area runs did not calibrate D "
            f"({_counts(sum((r.failures for r in two), Counter()))}); "
            "the paper reports only runs that worked."
        )
    first = three[0]
    if first.successes == 0:
        lines.append(
            "Table IV's first row (d4 = d5 = d6 = 200 mm, Figs. 6-7) never calibrates E here "
            f"({_counts(first.failures)}): a path that "
            "crosses the boundary BD once crosses 200 mm only twice (approaching and leaving), "
            "and the extraction of Sec. III.C saves the third point only when the distance "
            "crosses 200 mm a third time; when the robot's noisy fixes do, the three points "
            "bunch together and the spheres miss. The paper's robot must have wavered near "
            "the boundary."
        )
    e_errors = [e for row in three for e in row.calibration_errors_mm.get("E", [])]
    if e_errors:
        failures = sum((r.failures for r in three[1:]), Counter())
        lines.append(
            "Over three areas E is calibrated from the robot's own fixes in Area 2, which rest "
            f"on the calibrated D: median E error {np.median(e_errors):.0f} mm; Table IV's "
            f"second and third rows fail in {sum(failures.values())} of "
            f"{n_runs * (len(three) - 1)} runs "
            f"({_counts(failures)})."
        )
    lines.append(
        "sigma against sigma': sigma measures the difference in y at equal x, which grows where "
        "the parabola is steep (an offset e normal to the path shows as e sqrt(1 + f'(x)^2)); "
        "the paper's sigma / sigma' ratio is 1.5 over two areas and 2.7 over three."
    )
    return lines


# --------------------------------------------------------------------------------------------
# Plots


def _representative(row: RowResult, path: FloatArray) -> BlockExpansionResult:
    """The successful run with the median sigma' (the first run if none succeeded)."""
    good = [run for run in row.runs if run.ok]
    if not good:
        return row.runs[0]
    primes = [run.path_errors(path)[1] for run in good]
    return good[int(np.argsort(primes)[len(primes) // 2])]


def plot_scene(setup: Setup, row: RowResult, out_dir: Path, name: str) -> Path:
    """Beacons, areas, the true and localized paths, calibration positions, calibrated beacons."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    run = _representative(row, setup.path)
    figure = Figure(figsize=(11.0, 6.0), dpi=100)
    ax = figure.add_axes((0.07, 0.1, 0.62, 0.8))
    colours = ("#1f77b4", "#ff7f0e", "#2ca02c")
    for number, area in enumerate(setup.table.areas):
        corners = np.array([setup.beacons_m[n][:2] for n in area])
        ax.fill(*corners.T, color=colours[number], alpha=0.12, label=f"Area {number + 1} {area}")
    for beacon, (x, y, z) in setup.beacons_m.items():
        ax.plot(x, y, "k^", markersize=9)
        ax.annotate(
            f"{beacon} (z {z * 1000:.0f} mm)", (x, y), textcoords="offset points", xytext=(6, 6)
        )
    ax.plot(*setup.path.T, "k-", linewidth=1.2, label="true path")
    for number in range(len(setup.table.areas)):
        fixes = run.estimated_xy[run.area_indices[run.estimated_indices] == number]
        if len(fixes):
            ax.plot(
                *fixes.T,
                ".",
                color=colours[number],
                markersize=2.5,
                label=f"localized (Area {number + 1} beacons)",
            )
    for calibration in run.calibrations:
        points = calibration.calibration_points_xy
        if len(points):
            ax.plot(*points.T, "o", markerfacecolor="none", markeredgecolor="m", markersize=8)
        if calibration.calibration is not None and calibration.calibration.position is not None:
            estimate = calibration.calibration.position
            truth = calibration.true_position_m
            ax.plot(estimate[0], estimate[1], "rx", markersize=10, markeredgewidth=2)
            ax.plot([truth[0], estimate[0]], [truth[1], estimate[1]], "r--", linewidth=1)
            error_mm = 1000.0 * (calibration.error_m or 0.0)
            ax.annotate(
                f"{calibration.new_beacon}' ({error_mm:.0f} mm off)",
                (estimate[0], estimate[1]),
                textcoords="offset points",
                xytext=(6, -14),
                color="r",
            )
    ax.plot([], [], "o", markerfacecolor="none", markeredgecolor="m", label="calibration positions")
    ax.plot([], [], "rx", label="calibrated beacon")
    sigma, sigma_prime = run.path_errors(setup.path) if len(run.estimated_xy) else (0.0, 0.0)
    ax.set_title(
        f"{setup.table.name}: d = {', '.join(f'{d:g}' for d in row.distances_mm)} mm; "
        f"σ = {1000 * sigma:.1f} mm, σ' = {1000 * sigma_prime:.1f} mm ({run.status})",
        fontsize=9,
    )
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    path = out_dir / f"roh_scene_{name}.png"
    figure.savefig(path)
    return path


def plot_path_errors(
    setups: dict[str, Setup], results: dict[str, list[RowResult]], out_dir: Path
) -> Path:
    """Figs. 5, 7 and 8: distance of each fix to the true path against the distance driven."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    figure = Figure(figsize=(9.0, 4.0), dpi=100)
    ax = figure.add_subplot(1, 1, 1)
    picks = (
        (PAPER_TABLES[0].name, (450.0, 320.0, 100.0), "two areas, 450/320/100 (Fig. 5)"),
        (PAPER_TABLES[0].name, (450.0, 250.0, 20.0), "two areas, 450/250/20 (Fig. 8)"),
        (
            PAPER_TABLES[1].name,
            (450.0, 250.0, 20.0, 300.0, 400.0, 700.0),
            "three areas, 450/250/20/300/400/700 (Fig. 8)",
        ),
    )
    for table_name, distances, label in picks:
        setup = setups[table_name]
        row = next(r for r in results[table_name] if r.distances_mm == distances)
        run = _representative(row, setup.path)
        if not len(run.estimated_xy):
            continue
        travelled = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(setup.path, axis=0).T))])[
            run.estimated_indices
        ]
        errors = distances_to_polyline(run.estimated_xy, setup.path)
        ax.plot(1000 * travelled, 1000 * errors, linewidth=1, label=f"{label}: {run.status}")
    ax.set_xlabel("distance driven [mm]")
    ax.set_ylabel("path error [mm]")
    ax.set_title("Path error along the path (median run of each row)", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    path = out_dir / "roh_path_error.png"
    figure.savefig(path)
    return path


def render_env(out_dir: Path, seed: int = 0) -> Path:
    """The environment's picture after an episode with the paper agent (three areas)."""
    import gymnasium as gym

    from sonar_gym.agents.block_expansion import PaperAgent

    env = gym.make(ENV_ID, n_areas=3, render_mode="rgb_array")
    agent = PaperAgent(env)
    return final_frame_png(env, agent, seed, out_dir / "roh_env.png")


# --------------------------------------------------------------------------------------------
# Entry point


def run(out_dir: Path, console: Console, *, n_runs: int = 20, seed: int = SEED) -> None:
    """Re-run Roh et al.'s Tables II-V; print them beside ours and write plots into ``out_dir``.

    Args:
        out_dir: where the PNGs and the JSON go (created if missing).
        console: where the tables go.
        n_runs: runs (independent ranging noise) per table row.
        seed: seed of the ranging noise.

    Writes ``roh_scene_two_areas.png``, ``roh_scene_three_areas.png``, ``roh_path_error.png``,
    ``roh_env.png`` and ``roh_results.json`` (the numbers behind the tables, mm).
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    beacons = ", ".join(f"{n} ({x:g}, {y:g}, {z:g})" for n, (x, y, z) in TABLE_I_BEACONS_MM.items())
    console.print(
        f"Roh et al., Table I beacons [mm]: {beacons}. A parabolic path across Areas (A, B, C), "
        "(B, C, D) and (B, D, E); a fix every 40 ms; the d's of Tables II-V.",
        markup=False,
    )
    setups = {table.name: make_setup(table) for table in PAPER_TABLES}
    results = {name: run_table(setup, n_runs, seed) for name, setup in setups.items()}
    for table in PAPER_TABLES:
        console.print(comparison_table(table, results[table.name], n_runs))
    console.print("Differences from the paper:", style="bold")
    for line in differences(results, n_runs):
        console.print(f"- {line}", markup=False)
    console.print(parameters_table(UNSTATED_PARAMETERS))

    two, three = PAPER_TABLES
    three_rows = results[three.name]
    scene_three = max(three_rows, key=lambda r: r.successes)
    paths = [
        plot_scene(setups[two.name], results[two.name][0], out_dir, "two_areas"),
        plot_scene(setups[three.name], scene_three, out_dir, "three_areas"),
        plot_path_errors(setups, results, out_dir),
        render_env(out_dir),
    ]
    numbers: dict[str, Any] = {"n_runs": n_runs, "seed": seed, "units": "mm", "tables": {}}
    for table in PAPER_TABLES:
        rows = results[table.name]
        numbers["tables"][table.name] = {
            "paper_average_sigma_mm": table.printed_average_sigma_mm,
            "paper_average_sigma_prime_mm": table.printed_average_sigma_prime_mm,
            "ours_average": average_row(rows),
            "rows": [
                {
                    "distances_mm": list(row.distances_mm),
                    "paper_sigma_mm": row.paper_sigma_mm,
                    "paper_sigma_prime_mm": row.paper_sigma_prime_mm,
                    "ours_sigma_mm": row.median(row.sigma_mm),
                    "ours_sigma_prime_mm": row.median(row.sigma_prime_mm),
                    "successes": row.successes,
                    "failures": dict(row.failures),
                    "calibration_error_median_mm": {
                        name: float(np.median(values))
                        for name, values in row.calibration_errors_mm.items()
                    },
                }
                for row in rows
            ],
        }
    json_path = out_dir / "roh_results.json"
    json_path.write_text(json.dumps(numbers, indent=2, allow_nan=True) + "\n")
    console.print("Wrote " + ", ".join(str(p) for p in [*paths, json_path]), markup=False)
