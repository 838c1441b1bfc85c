"""``DetectedWall.unchecked`` and ``WallVector.unchecked`` build the objects the checked
constructors build from the same floats, field for field and bit for bit, and raise their
errors for end points that coincide or are not finite."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization.apcs_walls import ZERO_LENGTH_M, DetectedWall, WallVector
from tests.localization.float_bits import canonical


def _bits(wall: DetectedWall | WallVector) -> list[object]:
    """Every attribute of the wall (and of a detected wall's segment), in order, floats by
    their bits."""
    owners = (wall, wall.vector) if isinstance(wall, DetectedWall) else (wall,)
    return [
        (type(owner).__name__, name, canonical(value))
        for owner in owners
        for name, value in owner.__dict__.items()
        if name != "_vector"
    ]


def _end_points(rng: np.random.Generator) -> tuple[tuple[float, float], tuple[float, float]]:
    start = tuple(rng.uniform(-50.0, 50.0, 2).tolist())
    kind = rng.integers(6)
    if kind == 0:
        end = start  # coincide
    elif kind == 1:
        end = (start[0] + ZERO_LENGTH_M * rng.uniform(0.5, 1.5), start[1])  # near the length
    elif kind == 2:
        end = (rng.choice([math.inf, -math.inf, math.nan]), start[1])
    elif kind == 3:
        end = (-0.0, 0.0) if rng.random() < 0.5 else (1e308, 1e308)
    else:
        end = tuple(rng.uniform(-50.0, 50.0, 2).tolist())
    return start, end  # type: ignore[return-value]


def _outcome(build: object, *arguments: object) -> list[object] | str:
    try:
        return _bits(build(*arguments))  # type: ignore[operator]
    except ValueError as error:
        return f"ValueError: {error}"


@pytest.mark.parametrize("seed", range(5))
def test_unchecked_detected_wall_equals_the_checked_one(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(2000):
        start, end = _end_points(rng)
        indices = tuple(range(int(rng.integers(0, 12))))
        variance = float(rng.choice([0.0, -0.0, 1e-9, math.nan, rng.random()]))
        arguments = (start, end, indices, variance)
        expected = _outcome(DetectedWall, *arguments)
        assert _outcome(DetectedWall.unchecked, *arguments) == expected, arguments
        name_arguments = (start, end, "detected")
        assert _outcome(WallVector.unchecked, *name_arguments) == _outcome(
            WallVector, *name_arguments
        )
