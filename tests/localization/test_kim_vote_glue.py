"""Kim's vote glue in its lean form gives the bits of the form first written
(``kim_vote_glue_reference``): the readings gathered in one pass over the sweeps, and the
unchecked vote of the EKF loop, over random sweeps, odometry, offsets, ranges and circles."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization import kim
from sonar_gym.localization.kim import OccupancyGrid, Sweep, VoteLocalization
from sonar_gym.pose import Pose
from tests.localization.kim_vote_glue_reference import (
    gather_readings_reference,
    vote_localize_unchecked_reference,
)
from tests.localization.test_kim import MOVES, noisy_sweeps
from tests.localization.test_kim_unchecked_vote import assert_same_vote


def _random_sweeps(rng: np.random.Generator) -> list[Sweep]:
    """1 to 4 sweeps of different lengths, offsets and odometry, with NaN and inf dropouts,
    the first one's odometry the identity."""
    sweeps = []
    offset = (float(rng.uniform(-0.1, 0.1)), float(rng.uniform(-0.1, 0.1)))
    for index in range(int(rng.integers(1, 5))):
        size = int(rng.integers(0, 60))
        angles = rng.uniform(-math.pi, math.pi, size)
        ranges = rng.uniform(0.0, 3.5, size)
        ranges[rng.random(size) < 0.1] = np.nan
        ranges[rng.random(size) < 0.05] = np.inf
        odometry = (
            Pose(0.0, 0.0, 0.0)
            if index == 0
            else Pose(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-4.0, 4.0))
        )
        sweeps.append(Sweep(angles, ranges, offset, odometry))
    return sweeps


@pytest.mark.parametrize("seed", range(200))
def test_gathered_readings_are_the_reference_bits(seed: int) -> None:
    rng = np.random.default_rng(seed)
    sweeps = _random_sweeps(rng)
    for max_range_m in (None, float(rng.uniform(0.5, 3.0))):
        got = kim._gather_readings(sweeps, max_range_m)
        want = gather_readings_reference(sweeps, max_range_m)
        for name in ("end_x", "end_y", "beam_rad", "range_m"):
            got_field, want_field = getattr(got, name), getattr(want, name)
            assert got_field.dtype == want_field.dtype and got_field.shape == want_field.shape
            assert got_field.tobytes() == want_field.tobytes(), name


def _assert_same(result: VoteLocalization, expected: VoteLocalization) -> None:
    assert type(result) is type(expected)
    assert list(vars(result)) == list(vars(expected))  # every field, in the dataclass's order
    assert_same_vote(result, expected)


@pytest.mark.parametrize("seed", range(60))
def test_unchecked_vote_is_the_reference_vote(arena_grid: OccupancyGrid, seed: int) -> None:
    rng = np.random.default_rng(1000 + seed)
    truth = Pose(rng.uniform(0.2, 1.8), rng.uniform(0.2, 1.8), rng.uniform(-math.pi, math.pi))
    sweeps = noisy_sweeps(truth, MOVES[: int(rng.integers(1, 5))], rng, 0.02, 0.1)
    if seed % 10 == 0:  # no echo at all
        sweeps = [
            Sweep(s.angles, np.full(s.ranges.size, np.nan), odometry=s.odometry) for s in sweeps
        ]
    prior = Pose(
        truth.x + rng.normal(0.0, 0.05 if seed % 7 else 3.0),  # some circles miss the grid
        truth.y + rng.normal(0.0, 0.05),
        truth.theta + rng.normal(0.0, 0.05),
    )
    arguments = {
        "heading_step_rad": math.radians(float(rng.choice([0.5, 1.0, 2.0]))),
        "heading_window_rad": float(rng.uniform(0.0, math.radians(30.0))),
        "max_range_m": float(rng.uniform(1.0, 3.0)),
        "anchor": "obstacle_point" if seed % 2 else "cell_center",
    }
    radius = float(rng.uniform(0.05, 0.6))
    got = kim.vote_localize_unchecked(arena_grid, sweeps, prior, radius, **arguments)  # type: ignore[arg-type]
    want = vote_localize_unchecked_reference(arena_grid, sweeps, prior, radius, **arguments)  # type: ignore[arg-type]
    _assert_same(got, want)
