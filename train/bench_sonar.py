"""Benchmark: the vectorised sonar pan against bare pymunk ray casts, in the same process.

The project's speed target: a full 360-ping pan with all the physics (echo candidates,
occlusion, the receiver's gain ramp, the beam pattern with its side-lobe leakage,
threshold-crossing delay, noise, the counter) in the Beom & Cho
lab (``beom_cho_lab``: 37 segments, 5 cylinders) costs at most 0.12 of 360 bare
``space.segment_query_first`` calls from the same point. Consecutive pans come from different
poses, so the sonar's memory of the last sensor position (which spares repeated pans from one
pose their echo search) never helps here. Both are timed interleaved, over the
same random free poses, with the garbage collector off as ``timeit`` does, and the ratio is
taken per round, so a busy machine slows both alike.
Also timed: a 60-ping sector pan, a Kim sweep (19 pings), an APCS side-sonar sample and a
Wu & Tsai ranging round.

Run: ``python train/bench_sonar.py [--rounds N] [--poses P] [--seed S] [--phases]``.
``pan_throughput()`` gives the same numbers as rows for ``train benchmark``. ``--phases``
also splits the full pan into its phases (:func:`phase_times`): the echo search of the
sensor position, the readout of the 360 pings from its candidates, and the rest.
"""

from __future__ import annotations

import argparse
import functools
import gc
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

try:
    import sonar_gym  # noqa: F401
except ImportError:  # run from a checkout without installing the package
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from sonar_gym.pose import Pose
from sonar_gym.scenario import load_scenario
from sonar_gym.sonar import BeaconRanger, RotatingSonar, SideSonars, SweptSonar
from sonar_gym.world import STATIC_ONLY, World

TARGET_RATIO = 0.12
FULL_PAN = (-math.pi, math.pi, math.radians(1.0))
SECTOR_PAN = (math.radians(-30.0), math.radians(30.0), math.radians(1.0))


def _seconds(function: Callable[[], object]) -> float:
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def _cycle(items: list[Any]) -> Callable[[], Any]:
    """A callable returning the items in turn (fresh poses, so nothing is reused between calls)."""
    state = {"i": 0}

    def next_item() -> Any:
        item = items[state["i"] % len(items)]
        state["i"] += 1
        return item

    return next_item


def measure(rounds: int = 15, n_poses: int = 20, seed: int = 0) -> dict[str, float]:
    """Per-call times in seconds, median (``<job>_s``) and minimum (``<job>_min_s``).

    Every job runs once per pose per round, the jobs interleaved, so load from other
    processes falls on all of them alike. ``pan_over_pymunk`` is the median over calls of
    (pan time / time of the 360 ray casts from the same pose right after it);
    ``pan_over_pymunk_min`` the ratio of the two minima (the least disturbed calls).
    """
    rng = np.random.default_rng(seed)
    lab = World(load_scenario("beom_cho_lab"))
    sonar = RotatingSonar.preset("polaroid-6500")
    poses = [lab.sample_free_pose(rng, clearance=0.05) for _ in range(n_poses)]
    max_range = sonar.transducer.max_range_m
    angles = np.arange(*FULL_PAN[:2], FULL_PAN[2])
    casts = []
    for pose in poses:
        origin = tuple(pose.transform_point(lab.scenario.robot.sensor_offset))
        ends = [
            (
                origin[0] + max_range * math.cos(pose.theta + a),
                origin[1] + max_range * math.sin(pose.theta + a),
            )
            for a in angles
        ]
        casts.append((origin, ends))
    space = lab.space

    def pymunk_360(cast: tuple[tuple[float, float], list[tuple[float, float]]]) -> None:
        origin, ends = cast
        for end in ends:
            space.segment_query_first(origin, end, 0.0, STATIC_ONLY)

    kim = World(load_scenario("kim_arena"))
    corridor = World(load_scenario("apcs_corridor"))
    ceiling = World(load_scenario("wu_tsai_room"))
    sweep, sides, ranger = SweptSonar.kim(), SideSonars.apcs(), BeaconRanger.wu_tsai()
    kim_poses = _cycle([kim.sample_free_pose(rng, clearance=0.05) for _ in range(n_poses)])
    corridor_poses = _cycle([Pose(x, 0.0, 0.0) for x in np.linspace(0.5, 9.5, n_poses)])
    ceiling_poses = _cycle([ceiling.sample_free_pose(rng, clearance=0.05) for _ in range(n_poses)])
    next_pose, next_cast = _cycle(poses), _cycle(casts)

    jobs: dict[str, Callable[[], object]] = {
        "pan_360_s": lambda: sonar.pan(lab, next_pose(), *FULL_PAN, rng),
        "pymunk_360_s": lambda: pymunk_360(next_cast()),
        "pan_60_s": lambda: sonar.pan(lab, next_pose(), *SECTOR_PAN, rng),
        "kim_sweep_s": lambda: sweep.sweep(kim, kim_poses(), rng),
        "apcs_side_sample_s": lambda: sides.read(corridor, corridor_poses(), rng),
        "wu_tsai_ranging_s": lambda: ranger.measure(ceiling, ceiling_poses(), rng),
    }
    for job in jobs.values():  # warm caches (geometry tables, beam tables)
        job()
    samples: dict[str, list[float]] = {name: [] for name in jobs}
    gc.collect()
    gc.disable()  # as timeit does: one job's garbage must not bill the next one
    try:
        for _ in range(rounds):
            for _ in range(n_poses):
                for name, job in jobs.items():
                    samples[name].append(_seconds(job))
            gc.collect()
    finally:
        gc.enable()
    result = {}
    for name, values in samples.items():
        result[name] = float(np.median(values))
        result[name[: -len("_s")] + "_min_s"] = float(np.min(values))
    pairs = np.array(samples["pan_360_s"]) / np.array(samples["pymunk_360_s"])
    result["pan_over_pymunk"] = float(np.median(pairs))
    result["pan_over_pymunk_min"] = result["pan_360_min_s"] / result["pymunk_360_min_s"]
    return result


def phase_times(rounds: int = 15, n_poses: int = 20, seed: int = 0) -> dict[str, float]:
    """Where a full pan's time goes: per-call medians in seconds, interleaved as in :func:`measure`.

    ``pan_s`` is the whole pan (a new sensor position each call, as in :func:`measure`);
    ``search_s`` the echo search of that position alone; ``readout_s`` the 360 pings from
    candidates the sonar remembers (beam pattern, detection, crossing delay, noise, counter);
    ``rest_s`` what the pan adds to the two (pan angles, sensor position, the memory's
    bookkeeping, the :class:`~sonar_gym.sonar.scan.Scan`, and caches the pan finds cold).
    """
    rng = np.random.default_rng(seed)
    lab = World(load_scenario("beom_cho_lab"))
    sonar = RotatingSonar.preset("polaroid-6500")
    poses = [lab.sample_free_pose(rng, clearance=0.05) for _ in range(n_poses)]
    sensors = [np.array(pose.transform_point(lab.scenario.robot.sensor_offset)) for pose in poses]
    angles = np.arange(*FULL_PAN[:2], FULL_PAN[2])
    directions = np.column_stack([np.cos(angles), np.sin(angles)])
    samples: dict[str, list[float]] = {"pan_s": [], "search_s": [], "readout_s": []}
    for pose in poses:  # warm caches
        sonar.pan(lab, pose, *FULL_PAN, rng)
    gc.collect()
    gc.disable()
    try:
        for _ in range(rounds):
            for pose, sensor in zip(poses, sensors, strict=True):
                pan = functools.partial(sonar.pan, lab, pose, *FULL_PAN, rng)
                search = functools.partial(sonar._search_candidates, lab, pose, sensor)
                readout = functools.partial(sonar.ping, lab, pose, sensor, directions, rng)
                samples["pan_s"].append(_seconds(pan))
                samples["search_s"].append(_seconds(search))
                samples["readout_s"].append(_seconds(readout))
            gc.collect()
    finally:
        gc.enable()
    result = {name: float(np.median(values)) for name, values in samples.items()}
    result["rest_s"] = result["pan_s"] - result["search_s"] - result["readout_s"]
    return result


def pan_throughput() -> list[dict[str, Any]]:
    """Rows for ``train benchmark``: pans and pings per second of the sonar configurations.

    ``ratio_to_bare_casts`` is each row's median time over that of 360 bare pymunk casts (the
    first row also carries ``pan_over_pymunk``, the median of the per-call ratios).
    """
    timings = measure(rounds=7, n_poses=10)
    rows = []
    for name, key, pings in (
        ("polaroid full pan (360 pings)", "pan_360_s", 360),
        ("polaroid sector pan (60 pings)", "pan_60_s", 60),
        ("srf04 Kim sweep (19 pings)", "kim_sweep_s", 19),
        ("pymunk segment_query_first x 360", "pymunk_360_s", 360),
    ):
        seconds = timings[key]
        rows.append(
            {
                "name": name,
                "median_us": seconds * 1e6,
                "pans_per_s": 1.0 / seconds,
                "pings_per_s": pings / seconds,
                "ratio_to_bare_casts": seconds / timings["pymunk_360_s"],
            }
        )
    rows[0]["pan_over_pymunk"] = timings["pan_over_pymunk"]
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--rounds", type=int, default=15, help="interleaved timing rounds (default 15)"
    )
    parser.add_argument(
        "--poses", type=int, default=20, help="random free poses per round (default 20)"
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--phases", action="store_true", help="also split the full pan into its phases"
    )
    args = parser.parse_args(argv)
    if args.rounds < 1 or args.poses < 1:
        parser.error("--rounds and --poses must be at least 1")
    t = measure(args.rounds, args.poses, args.seed)
    rows = (
        ("full pan, 360 pings, noise on", "pan_360"),
        ("360 x pymunk segment_query_first", "pymunk_360"),
        ("sector pan, 60 pings", "pan_60"),
        ("Kim sweep, 19 pings (kim_arena)", "kim_sweep"),
        ("APCS side-sonar sample (apcs_corridor)", "apcs_side_sample"),
        ("Wu & Tsai ranging round (wu_tsai_room)", "wu_tsai_ranging"),
    )
    print("Sonar benchmark, beom_cho_lab: microseconds per call (median, minimum)")
    for label, key in rows:
        print(f"  {label:42s} {t[key + '_s'] * 1e6:9.1f} {t[key + '_min_s'] * 1e6:9.1f}")
    print(
        f"  ratio pan / pymunk (target <= {TARGET_RATIO})       "
        f"{t['pan_over_pymunk']:9.3f} {t['pan_over_pymunk_min']:9.3f}"
    )
    if args.phases:
        phases = phase_times(args.rounds, args.poses, args.seed)
        print("Full pan by phase: microseconds per call (median)")
        for label, key in (
            ("whole pan", "pan_s"),
            ("echo search of the position", "search_s"),
            ("readout of 360 pings (candidates known)", "readout_s"),
            ("rest (pan minus the two)", "rest_s"),
        ):
            print(f"  {label:42s} {phases[key] * 1e6:9.1f}")
    return 0 if t["pan_over_pymunk"] <= TARGET_RATIO else 1


if __name__ == "__main__":
    raise SystemExit(main())
