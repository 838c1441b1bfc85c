"""The unmapped wall boxes drawn as :func:`sonar_gym.apcs_route.with_wall_obstacles` drew them
before the free walls' spans were kept per room: the form kept as the tests' reference."""

from __future__ import annotations

import dataclasses

import numpy as np

from sonar_gym.localization.apcs_online import SIDE_NAMES
from sonar_gym.scenario import Box, Scenario


def reference_with_wall_obstacles(
    scenario: Scenario,
    rng: np.random.Generator,
    count: int,
    length_range_m: tuple[float, float],
    depth_range_m: tuple[float, float],
    x_range_m: tuple[float, float],
) -> Scenario:
    """``scenario`` plus ``count`` unmapped boxes standing against its room's long walls.

    Each box is drawn on a random long wall (left ``y = max``, right ``y = min``) with a length
    and a depth (metres) uniform in their ranges and a start uniform in ``x_range_m``; a box
    keeps 0.1 m from the other boxes and from the scenario's free walls near that wall, with
    50 attempts per box (a box that finds no place is left out).
    """
    room = scenario.room
    if room is None:
        raise ValueError(f"argument 'scenario': {scenario.name!r} has no room")
    boxes: list[Box] = []
    taken: dict[str, list[tuple[float, float]]] = {"left": [], "right": []}
    for wall in scenario.walls:  # keep clear of the scenario's own free walls
        for side, y_wall in (("left", room.max[1]), ("right", room.min[1])):
            if min(abs(wall.a[1] - y_wall), abs(wall.b[1] - y_wall)) < 0.5:
                taken[side].append((min(wall.a[0], wall.b[0]), max(wall.a[0], wall.b[0])))
    low_x, high_x = x_range_m
    for _ in range(count):
        for _attempt in range(50):
            side = SIDE_NAMES[int(rng.integers(2))]
            length = float(rng.uniform(*length_range_m))
            depth = float(rng.uniform(*depth_range_m))
            start_x = float(rng.uniform(low_x, max(low_x, high_x - length)))
            span = (start_x, start_x + length)
            if all(span[1] + 0.1 < a or span[0] - 0.1 > b for a, b in taken[side]):
                break
        else:
            continue
        taken[side].append(span)
        y_centre = room.max[1] - depth / 2.0 if side == "left" else room.min[1] + depth / 2.0
        boxes.append(Box((start_x + length / 2.0, y_centre), (length, depth), 0.0, mapped=False))
    return dataclasses.replace(scenario, boxes=scenario.boxes + tuple(boxes))
