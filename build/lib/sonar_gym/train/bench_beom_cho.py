"""Benchmark: Beom & Cho's closed-form pose (eqs (8)-(15)) against its least-squares refinement.

Synthetic pans in the paper's setup (small beacon r = 0.0191 m at (2.85, -0.6) m, large beacon
r = 0.07 m at (0.3, -1.5) m, full 360 deg pan at 1 deg): each beacon is an arc of constant
range (the distance to its surface plus Gaussian noise, quantised to the 32 us timer period of
section III.A), with angular extents near the 22 and 24 deg of Table II whose edges jitter by up
to +-0.7 deg; the rest of the pan is clutter that forms no RCD. Both methods run on the same
RCDs. Prints the median and 95th percentile of E_xy (cm) and E_theta (deg) of eq. (16), the
success rate, and the time per ``localize_rcds`` call.

Run: ``python train/bench_beom_cho.py [--cases N] [--seed S]``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

try:
    import sonar_gym  # noqa: F401
except ImportError:  # run from a checkout without installing the package
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from sonar_gym.localization.beom_cho import (
    METHODS,
    BeomChoParameters,
    extract_rcds,
    localize_rcds,
)
from sonar_gym.metrics import heading_error_rad, position_error_m
from sonar_gym.pose import Pose, wrap_angles

SMALL_CENTER = (2.85, -0.6)
LARGE_CENTER = (0.3, -1.5)
SMALL_RADIUS_M = 0.0191
LARGE_RADIUS_M = 0.07
PAN_ANGLES_RAD = np.deg2rad(np.arange(-180.0, 180.0, 1.0))
RANGE_SIGMA_M = 0.003
TIMER_PERIOD_S = 32e-6
SPEED_OF_SOUND_MPS = 343.2
RANGE_STEP_M = SPEED_OF_SOUND_MPS * TIMER_PERIOD_S / 2.0
HALF_EXTENTS_DEG = {"small": 11.0, "large": 12.0}
EDGE_JITTER_DEG = 0.7


def random_sensor_pose(rng: np.random.Generator) -> Pose:
    """A pose 0.5-3.9 m from both beacons, uniform over a patch of the lab."""
    while True:
        x, y = rng.uniform(-1.5, 3.5), rng.uniform(-1.2, 2.2)
        distances = (math.dist((x, y), SMALL_CENTER), math.dist((x, y), LARGE_CENTER))
        if all(0.5 <= d <= 3.9 for d in distances):
            return Pose(x, y, rng.uniform(-math.pi, math.pi))


def synthetic_pan(sensor: Pose, rng: np.random.Generator) -> np.ndarray:
    """Ranges of one pan (metres, NaN = dropout) seen from ``sensor``."""
    ranges = np.where(np.arange(len(PAN_ANGLES_RAD)) % 2 == 0, 1.0, 1.5)
    ranges[rng.random(len(ranges)) < 0.3] = np.nan
    for center, radius, name in (
        (SMALL_CENTER, SMALL_RADIUS_M, "small"),
        (LARGE_CENTER, LARGE_RADIUS_M, "large"),
    ):
        bearing = math.atan2(center[1] - sensor.y, center[0] - sensor.x) - sensor.theta
        offsets_deg = np.degrees(wrap_angles(PAN_ANGLES_RAD - bearing))
        lower, upper = HALF_EXTENTS_DEG[name] + rng.uniform(-EDGE_JITTER_DEG, EDGE_JITTER_DEG, 2)
        inside = (offsets_deg >= -lower) & (offsets_deg <= upper)
        true_range = math.dist((sensor.x, sensor.y), center) - radius
        noisy = true_range + rng.normal(0.0, RANGE_SIGMA_M, int(inside.sum()))
        ranges[inside] = np.round(noisy / RANGE_STEP_M) * RANGE_STEP_M
    return ranges


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", type=int, default=2000, help="number of random poses")
    parser.add_argument("--seed", type=int, default=1995, help="seed of the numpy Generator")
    args = parser.parse_args()
    if args.cases < 1:
        parser.error("--cases must be >= 1")

    rng = np.random.default_rng(args.seed)
    quantisation_sigma_m = RANGE_STEP_M / math.sqrt(12.0)
    params = BeomChoParameters(range_sigma_m=math.hypot(RANGE_SIGMA_M, quantisation_sigma_m))
    errors: dict[str, list[tuple[float, float]]] = {method: [] for method in METHODS}
    failures: dict[str, dict[str, int]] = {method: {} for method in METHODS}
    seconds: dict[str, float] = {method: 0.0 for method in METHODS}
    for _ in range(args.cases):
        truth = random_sensor_pose(rng)
        rcds = extract_rcds(PAN_ANGLES_RAD, synthetic_pan(truth, rng), eps=params.eps_m)
        for method in METHODS:
            start = time.perf_counter()
            result = localize_rcds(
                rcds,
                SMALL_CENTER,
                SMALL_RADIUS_M,
                LARGE_CENTER,
                LARGE_RADIUS_M,
                params=params,
                method=method,
            )
            seconds[method] += time.perf_counter() - start
            if result.pose is None:
                failures[method][result.status] = failures[method].get(result.status, 0) + 1
                continue
            errors[method].append(
                (position_error_m(result.pose, truth), heading_error_rad(result.pose, truth))
            )

    print(
        f"Beom & Cho benchmark: {args.cases} poses, seed {args.seed}, 1 deg pan, "
        f"range noise {RANGE_SIGMA_M * 1e3:.1f} mm, range step {RANGE_STEP_M * 1e3:.2f} mm, "
        f"edge jitter +-{EDGE_JITTER_DEG} deg"
    )
    header = (
        f"{'method':<14} {'ok':>6} {'E_xy med':>9} {'E_xy p95':>9} "
        f"{'E_th med':>9} {'E_th p95':>9} {'us/call':>8}  failures"
    )
    print(header)
    print(f"{'':<14} {'':>6} {'[cm]':>9} {'[cm]':>9} {'[deg]':>9} {'[deg]':>9}")
    for method in METHODS:
        table = np.array(errors[method]).reshape(-1, 2)
        position_cm = table[:, 0] * 100.0
        heading_deg = np.degrees(table[:, 1])
        ok_share = len(table) / args.cases
        print(
            f"{method:<14} {ok_share:>6.1%} "
            f"{np.median(position_cm):>9.3f} {np.percentile(position_cm, 95):>9.3f} "
            f"{np.median(heading_deg):>9.3f} {np.percentile(heading_deg, 95):>9.3f} "
            f"{seconds[method] / args.cases * 1e6:>8.1f}  {failures[method] or '-'}"
        )
    paper_s, refined_s = seconds["paper"], seconds["least_squares"]
    print(f"time ratio least_squares / paper: {refined_s / paper_s:.2f}")


if __name__ == "__main__":
    main()
