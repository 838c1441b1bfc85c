"""A side stream's stored readings and ERPs move with a correction exactly as they did point by
point (Yamamoto et al., Fig. 2): the same bits for every point, direction and range."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from sonar_gym.localization.apcs_online import WallStream
from sonar_gym.pose import Pose
from tests.localization.apcs_move_frame_reference import move_frame_per_point
from tests.localization.float_bits import canonical


def _state(stream: WallStream) -> object:
    previous = stream._previous
    return (
        None if previous is None else canonical((*previous[0], previous[1], previous[2])),
        [canonical(point) for point in stream._group_points],
        [canonical(direction) for direction in stream._group_directions],
    )


def _stream(rng: np.random.Generator) -> WallStream:
    """A stream with a stored reading or none and an open group of 0 to 40 ERPs, at any scale."""
    stream = WallStream(str(rng.choice(["left", "right"])))
    scale = float(rng.choice([1e-3, 1.0, 50.0, 1e6]))
    count = int(rng.choice([0, 1, 2, 7, 40]))
    stream._group_points = [tuple(rng.normal(0.0, scale, 2).tolist()) for _ in range(count)]
    stream._group_directions = rng.uniform(-math.pi, math.pi, count).tolist()
    if rng.random() < 0.8:
        x, y = rng.normal(0.0, scale, 2).tolist()
        range_m = math.nan if rng.random() < 0.2 else float(rng.uniform(0.0, 5.0))
        stream._previous = ((x, y), float(rng.uniform(-4.0, 4.0)), range_m)
    return stream


def _pose(rng: np.random.Generator) -> Pose:
    x, y = rng.normal(0.0, float(rng.choice([1e-3, 1.0, 100.0])), 2).tolist()
    theta = float(rng.choice([rng.uniform(-math.pi, math.pi), 0.0, math.pi, -math.pi / 2]))
    return Pose(x, y, theta)


def test_move_frame_moves_every_stored_point_as_the_per_point_form() -> None:
    rng = np.random.default_rng(20261207)
    for _ in range(3000):
        stream = _stream(rng)
        before = _pose(rng)
        after = before if rng.random() < 0.05 else _pose(rng)
        if rng.random() < 0.3:  # a small correction, as APCS makes them
            after = Pose(before.x + rng.normal(0.0, 0.05), before.y, before.theta + 1e-3)
        expected = copy.deepcopy(stream)
        stream.move_frame(before, after)
        move_frame_per_point(expected, before, after)
        assert _state(stream) == _state(expected)


@pytest.mark.parametrize("turn", [0.0, -0.0, math.pi / 2, math.pi, 1e-300])
def test_move_frame_on_axis_turns_is_the_per_point_form(turn: float) -> None:
    stream = WallStream("left")
    stream._group_points = [(1.0, -0.0), (0.0, 2.0), (-3.5, 1e-300), (1e308, -1e308)]
    stream._group_directions = [0.0, math.pi, -math.pi / 2, 1.0]
    stream._previous = ((-0.0, 0.5), math.pi / 2, 2.0)
    expected = copy.deepcopy(stream)
    before, after = Pose(0.5, -0.25, 0.0), Pose(0.25, 0.0, turn)
    with np.errstate(over="ignore", invalid="ignore"):
        stream.move_frame(before, after)
        move_frame_per_point(expected, before, after)
    assert _state(stream) == _state(expected)
