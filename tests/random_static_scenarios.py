"""Random scenarios for bit-for-bit checks of what is built from a scenario's static content:
any room (or none), free walls, boxes at any angle and cylinders, with coordinates that are
often signed zeros or repeat (so end points meet and walls cross)."""

from __future__ import annotations

import numpy as np

from sonar_gym.apcs_route import with_wall_obstacles
from sonar_gym.scenario import Box, Cylinder, Room, Scenario, Wall, load_scenario


def _coordinate(rng: np.random.Generator) -> float:
    """A coordinate in metres, often a signed zero or a value that repeats."""
    choice = rng.integers(6)
    if choice == 0:
        return -0.0
    if choice == 1:
        return 0.0
    if choice == 2:
        return float(rng.choice([-1.5, 1.25, -0.5]))
    return float(rng.uniform(-3.0, 3.0))


def random_scenario(rng: np.random.Generator) -> Scenario:
    """A room (or none) with free walls, boxes at any angle (one sometimes against the room's
    top wall) and cylinders, anywhere in it."""
    room = None
    if rng.random() < 0.8:
        low_y, high_y = [(-0.0, 4.0), (-3.0, 0.0), (-3.0, 4.0)][rng.integers(3)]
        room = Room((-float(rng.uniform(2.0, 4.0)), low_y), (float(rng.uniform(3.0, 5.0)), high_y))

    def point() -> tuple[float, float]:
        return (_coordinate(rng), _coordinate(rng))

    walls: list[Wall] = []
    n_walls = int(rng.integers(4))
    while len(walls) < n_walls:
        a, b = point(), point()
        if a != b:  # a scenario's walls have a length
            walls.append(Wall(a, b, bool(rng.random() < 0.5)))
    boxes = tuple(
        Box(
            point(),
            (float(rng.uniform(0.05, 1.0)), float(rng.uniform(0.05, 1.0))),
            float(rng.choice([0.0, 90.0, -30.0, rng.uniform(-180.0, 180.0)])),
            bool(rng.random() < 0.5),
        )
        for _ in range(rng.integers(5))
    )
    if room is not None and rng.random() < 0.5:  # a box against the room's top wall
        depth = float(rng.uniform(0.05, 0.5))
        centre = (float(rng.uniform(room.min[0] + 1.0, room.max[0] - 1.0)), room.max[1] - depth / 2)
        boxes += (Box(centre, (float(rng.uniform(0.1, 1.0)), depth), 0.0, False),)
    cylinders = tuple(
        Cylinder(point(), float(rng.uniform(0.01, 0.5))) for _ in range(rng.integers(4))
    )
    return Scenario("random", room, tuple(walls), boxes, cylinders)


def builtin_with_obstacles(name: str, seed: int, count: int = 5) -> list[Scenario]:
    """The built-in scenario ``name`` and, if it has a room, ``count`` copies with four unmapped
    boxes against its long walls (as WallCorrection draws them per episode), from ``seed``."""
    scenario = load_scenario(name)
    if scenario.room is None:
        return [scenario]
    rng = np.random.default_rng(seed)
    (x0, _), (x1, _) = scenario.room.min, scenario.room.max
    return [scenario] + [
        with_wall_obstacles(scenario, rng, 4, (0.3, 1.2), (0.1, 0.4), (x0 + 0.5, x1 - 0.5))
        for _ in range(count)
    ]
