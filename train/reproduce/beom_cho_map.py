"""Where in Beom & Cho's lab their method gives a pose: an outcome map over robot positions.

The paper reports its errors along three straight paths (Figs 9-11); it does not say from how
much of the lab the method works. Here every cell of a square grid over ``beom_cho_lab`` whose
centre is a free robot position is one trial at 20 C: a heading drawn per cell, the reflector
calibration of sec. II.A, a full pan at 1 deg, and the pose from the paper's method
(eqs (3)-(15), Table I defaults, no prior) and, beside it, from the occlusion-aware retry
(:mod:`sonar_gym.localization.beom_cho_occlusion`). Each trial gets one outcome:

* within the paper's bounds (E_xy <= 3 cm and E_theta <= 2 deg, sec. V.C);
* a pose outside those bounds but within 10 cm;
* a wrong pose (more than 10 cm off);
* no pair (eq. (7) found none within 0.04 m, too few RCDs passed the filters, or the retry's
  pairs disagreed on the place);
* no intersection (D < 0 in eq. (12): the robot near the line through the beacons);
* beacons not visible (out of range or out of sight; no trial, left out of the shares).

Writes ``beom_cho_map.png`` (the two maps side by side) and ``beom_cho_map.json``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

from sonar_gym.beacon_visibility import beacons_visible
from sonar_gym.localization.beom_cho import BeomChoParameters, localize_scans
from sonar_gym.metrics import heading_error_rad, position_error_m
from sonar_gym.pose import Pose
from sonar_gym.scenario import Scenario, load_scenario
from sonar_gym.sonar.rotating import RotatingSonar
from sonar_gym.world import World
from sonar_gym.train.progress import task_progress
from sonar_gym.train.reproduce.beom_cho import (
    PAN_INCREMENT_RAD,
    PAN_START_RAD,
    PAN_STOP_RAD,
    SCENARIO_NAME,
    SENSOR_PRESET,
    calibrated_sonar,
)

TEMPERATURE_C = 20.0
WRONG_POSE_M = 0.10
START_CLEARANCE_M = 0.05  # as the BeaconScan env keeps from walls at the start
POSITION_BOUND_M = 0.03
HEADING_BOUND_RAD = math.radians(2.0)

WITHIN_BOUNDS = "within 3 cm / 2 deg"
OUTSIDE_BOUNDS = "pose 3-10 cm or > 2 deg off"
WRONG_POSE = "wrong pose (> 10 cm)"
NO_PAIR = "no pair"
NO_INTERSECTION = "no intersection (D < 0)"
NOT_VISIBLE = "beacons not visible"
OUTCOMES = (WITHIN_BOUNDS, OUTSIDE_BOUNDS, WRONG_POSE, NO_PAIR, NO_INTERSECTION)
OUTCOME_COLOURS = {
    WITHIN_BOUNDS: "#2e7d32",
    OUTSIDE_BOUNDS: "#9ccc65",
    WRONG_POSE: "#c62828",
    NO_PAIR: "#ffb300",
    NO_INTERSECTION: "#6a1b9a",
    NOT_VISIBLE: "#e0e0e0",
}
EXTRACTIONS = {"paper": "paper's RCDs", "occlusion_aware": "occlusion-aware retry"}


@dataclass
class OutcomeMap:
    """Outcomes per grid cell. ``xs``, ``ys``: cell centres in metres in {W}; ``outcomes``:
    per extraction, one outcome name per cell (row = y, column = x), ``""`` off the floor."""

    xs: np.ndarray
    ys: np.ndarray
    outcomes: dict[str, list[list[str]]] = field(default_factory=dict)

    def shares(self, extraction: str) -> dict[str, float]:
        """Share of each outcome among the cells with both beacons visible."""
        cells = [o for row in self.outcomes[extraction] for o in row if o in OUTCOMES]
        return {o: cells.count(o) / max(len(cells), 1) for o in OUTCOMES}

    def trials(self) -> int:
        """Cells with a trial (free, both beacons visible)."""
        first = next(iter(self.outcomes.values()))
        return sum(o in OUTCOMES for row in first for o in row)


def outcome_of(status: str, estimate: Pose | None, truth: Pose) -> str:
    """The outcome name of one localization (see the module docstring)."""
    if estimate is None:
        return NO_INTERSECTION if status == "no_intersection" else NO_PAIR
    position = position_error_m(estimate, truth)
    if position > WRONG_POSE_M:
        return WRONG_POSE
    if position <= POSITION_BOUND_M and heading_error_rad(estimate, truth) <= HEADING_BOUND_RAD:
        return WITHIN_BOUNDS
    return OUTSIDE_BOUNDS


def outcome_map(seed: int, spacing_m: float) -> OutcomeMap:
    """Run one trial per free cell of a ``spacing_m`` grid (see the module docstring)."""
    if not (isinstance(spacing_m, (int, float)) and 0.02 <= spacing_m <= 1.0):
        raise ValueError(f"spacing_m must be a number of metres in [0.02, 1.0], got {spacing_m!r}")
    scenario = load_scenario(SCENARIO_NAME)
    (x_min, y_min), (x_max, y_max) = scenario.bounds
    xs = np.arange(x_min + spacing_m / 2, x_max, spacing_m)
    ys = np.arange(y_min + spacing_m / 2, y_max, spacing_m)
    rng = np.random.default_rng(seed)
    world = World(scenario, temperature_c=TEMPERATURE_C)
    probe = RotatingSonar.preset(SENSOR_PRESET)
    result = OutcomeMap(xs, ys, {name: [] for name in EXTRACTIONS})
    with task_progress("outcome map", len(xs) * len(ys)) as advance:
        for y in ys:
            rows: dict[str, list[Any]] = {name: [] for name in EXTRACTIONS}
            for x in xs:
                pose = Pose(x, y, float(rng.uniform(-math.pi, math.pi)))
                for name, outcome in cell_outcomes(world, scenario, probe, pose, rng).items():
                    rows[name].append(outcome)
                advance()
            for name in EXTRACTIONS:
                result.outcomes[name].append(rows[name])
    return result


def cell_outcomes(
    world: World, scenario: Scenario, probe: RotatingSonar, pose: Pose, rng: np.random.Generator
) -> dict[str, str]:
    """The outcome per extraction of one trial with the robot at ``pose`` ({W}, metres and
    radians): ``""`` when the robot does not fit there, :data:`NOT_VISIBLE` when a beacon is
    out of range or sight of ``probe``."""
    if not world.is_free((pose.x, pose.y), radius=world.robot_radius + START_CLEARANCE_M):
        return dict.fromkeys(EXTRACTIONS, "")
    if not beacons_visible(world, probe, pose):
        return dict.fromkeys(EXTRACTIONS, NOT_VISIBLE)
    world.set_robot_pose(pose)
    sonar = calibrated_sonar(world, rng)
    scan = sonar.pan(world, pose, PAN_START_RAD, PAN_STOP_RAD, PAN_INCREMENT_RAD, rng)
    outcomes = {}
    for name in EXTRACTIONS:
        found = localize_scans([scan], scenario, BeomChoParameters(extraction=name))
        outcomes[name] = outcome_of(found.status, found.pose, pose)
    return outcomes


def shares_table(result: OutcomeMap, spacing_m: float) -> Table:
    """Outcome shares per extraction, over the cells with both beacons visible."""
    table = Table(
        title=f"Outcomes over {result.trials()} lab positions ({spacing_m} m grid, both beacons "
        "visible, 20 C, one heading per cell)"
    )
    table.add_column("outcome")
    for label in EXTRACTIONS.values():
        table.add_column(label, justify="right")
    shares = {name: result.shares(name) for name in EXTRACTIONS}
    for outcome in OUTCOMES:
        table.add_row(outcome, *(f"{100 * shares[name][outcome]:.1f} %" for name in EXTRACTIONS))
    return table


def plot_map(result: OutcomeMap, scenario: Scenario, path: Path) -> Path:
    """The two outcome maps side by side, with the beacons and the room's shapes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    names = [*OUTCOMES, NOT_VISIBLE]
    colours = ListedColormap([OUTCOME_COLOURS[n] for n in names])
    spacing = float(result.xs[1] - result.xs[0]) if len(result.xs) > 1 else 1.0
    extent = (
        result.xs[0] - spacing / 2,
        result.xs[-1] + spacing / 2,
        result.ys[0] - spacing / 2,
        result.ys[-1] + spacing / 2,
    )
    figure, axes = plt.subplots(1, 2, figsize=(13, 5.4), constrained_layout=True)
    for axis, (name, label) in zip(axes, EXTRACTIONS.items(), strict=True):
        codes = np.array(
            [[names.index(o) if o else np.nan for o in row] for row in result.outcomes[name]]
        )
        axis.imshow(
            np.ma.masked_invalid(codes),
            origin="lower",
            extent=extent,
            cmap=colours,
            vmin=-0.5,
            vmax=len(names) - 0.5,
            interpolation="nearest",
        )
        for segment in scenario_segments(scenario):
            axis.plot(*segment.T, color="black", linewidth=1.0)
        for role, marker in (("small_beacon", 40), ("large_beacon", 120)):
            beacon = scenario.beacon(role)
            axis.scatter(*beacon.center, s=marker, color="black", zorder=3)
        within = 100 * result.shares(name)[WITHIN_BOUNDS]
        axis.set_title(f"{label}: {within:.1f} % within bounds")
        axis.set_xlabel("x [m]")
        axis.set_ylabel("y [m]")
        axis.set_aspect("equal")
    figure.legend(
        handles=[Patch(color=OUTCOME_COLOURS[n], label=n) for n in names],
        loc="outside lower center",
        ncols=len(names),
    )
    figure.suptitle("Beom & Cho in beom_cho_lab: outcome by robot position (black dots: beacons)")
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


def scenario_segments(scenario: Scenario) -> list[np.ndarray]:
    """The room, walls, boxes and cylinders as closed or open polylines, metres in {W}."""
    (x0, y0), (x1, y1) = scenario.bounds
    segments = [np.array([(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)])]
    segments += [np.array([wall.a, wall.b]) for wall in scenario.walls]
    segments += [np.array([*box.corners, box.corners[0]]) for box in scenario.boxes]
    circle = np.linspace(0.0, 2.0 * math.pi, 25)
    segments += [
        np.column_stack(
            (c.center[0] + c.radius * np.cos(circle), c.center[1] + c.radius * np.sin(circle))
        )
        for c in scenario.cylinders
    ]
    return segments


def run(
    out_dir: Path, console: Console, *, seed: int = 0, spacing_m: float = 0.1
) -> dict[str, Any]:
    """Build the map, print the shares, write ``beom_cho_map.png`` and ``beom_cho_map.json``."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    result = outcome_map(seed, spacing_m)
    console.print(shares_table(result, spacing_m))
    scenario = load_scenario(SCENARIO_NAME)
    png = plot_map(result, scenario, out_dir / "beom_cho_map.png")
    numbers = {
        "seed": seed,
        "spacing_m": spacing_m,
        "temperature_c": TEMPERATURE_C,
        "trials": result.trials(),
        "shares": {name: result.shares(name) for name in EXTRACTIONS},
        "xs_m": result.xs.tolist(),
        "ys_m": result.ys.tolist(),
        "outcomes": result.outcomes,
    }
    json_path = out_dir / "beom_cho_map.json"
    json_path.write_text(json.dumps(numbers, indent=2) + "\n")
    for path in (png, json_path):
        console.print(f"wrote {path}", markup=False)
    return numbers
