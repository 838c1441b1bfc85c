"""Stand-in worlds for the sonar tests: a scenario, its static geometry and an air temperature.

The sonar reads only ``geometry``, ``temperature_c`` and ``scenario`` from a world, so these
tests do not depend on :mod:`sonar_gym.world`. :func:`pymunk_space` builds the independent
pymunk copy of the same static shapes that the slow reference pan queries.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pymunk

from sonar_gym.geometry import StaticGeometry, build_static_geometry
from sonar_gym.scenario import Scenario, scenario_from_dict


@dataclass
class StandInWorld:
    """What a sonar needs from a world."""

    scenario: Scenario
    temperature_c: float = 20.0
    geometry: StaticGeometry = field(init=False)

    def __post_init__(self) -> None:
        self.geometry = build_static_geometry(self.scenario)


def world(temperature_c: float = 20.0, **tables: Any) -> StandInWorld:
    """A stand-in world from scenario tables (``room=..., boxes=[...]``...)."""
    return StandInWorld(scenario_from_dict(tables), temperature_c)


BEOM_CHO_BEACONS = [
    {"center": [2.85, -0.6], "radius": 0.0191, "role": "small_beacon"},
    {"center": [0.3, -1.5], "radius": 0.07, "role": "large_beacon"},
]
BEOM_CHO_ROOM = {"min": [-3.1, -2.5], "max": [3.1, 2.5]}


def beom_cho_room(temperature_c: float = 20.0) -> StandInWorld:
    """The 6.2 m x 5.0 m room of Beom & Cho with the two beacons only."""
    return world(temperature_c, room=BEOM_CHO_ROOM, cylinders=BEOM_CHO_BEACONS)


def cluttered_room(sensor_offset: tuple[float, float] = (0.0, 0.0)) -> StandInWorld:
    """A room with boxes (one turned), cylinders, a pillar on a wall and a free wall."""
    return world(
        room={"min": [-3.0, -2.5], "max": [3.0, 2.5]},
        walls=[
            {"a": [3.0, 1.5], "b": [2.6, 1.5]},
            {"a": [2.6, 1.5], "b": [2.6, 2.5]},
            {"a": [-1.0, 1.2], "b": [0.4, 1.9]},
        ],
        boxes=[
            {"center": [-2.0, -1.5], "size": [1.0, 0.6]},
            {"center": [1.5, -1.6], "size": [0.8, 0.5], "angle_deg": 30.0},
            {"center": [-0.5, -0.2], "size": [0.3, 0.3]},
            {"center": [2.2, 0.3], "size": [0.4, 1.0], "angle_deg": -15.0},
        ],
        cylinders=[
            {"center": [1.0, 0.9], "radius": 0.05},
            {"center": [-2.2, 1.0], "radius": 0.12},
            {"center": [0.4, -1.0], "radius": 0.02},
        ],
        robot={"radius": 0.3, "sensor_offset": list(sensor_offset)},
    )


def pymunk_space(geometry: StaticGeometry) -> pymunk.Space:
    """A pymunk space with the geometry's segments (radius 0) and circles as static shapes."""
    space = pymunk.Space()
    body = space.static_body
    shapes: list[pymunk.Shape] = [
        pymunk.Segment(body, tuple(a), tuple(b), 0.0)
        for a, b in zip(geometry.segment_starts, geometry.segment_ends, strict=True)
    ]
    shapes += [pymunk.Circle(body, float(r), (float(x), float(y))) for x, y, r in geometry.circles]
    space.add(*shapes)
    return space


def free_positions(
    test_world: StandInWorld, rng: np.random.Generator, n: int, clearance: float = 0.35
) -> list[tuple[float, float]]:
    """``n`` random points in the room, outside boxes, ``clearance`` metres from every shape."""
    space = pymunk_space(test_world.geometry)
    room = test_world.scenario.room
    assert room is not None
    boxes = [np.array(box.corners) for box in test_world.scenario.boxes]
    points: list[tuple[float, float]] = []
    while len(points) < n:
        point = (
            float(rng.uniform(room.min[0], room.max[0])),
            float(rng.uniform(room.min[1], room.max[1])),
        )
        if space.point_query_nearest(point, clearance, pymunk.ShapeFilter()) is not None:
            continue
        if any(_inside_convex(point, corners) for corners in boxes):
            continue
        points.append(point)
    return points


def _inside_convex(point: tuple[float, float], corners: np.ndarray) -> bool:
    edges = np.roll(corners, -1, axis=0) - corners
    offsets = np.asarray(point) - corners
    return bool(np.all(edges[:, 0] * offsets[:, 1] - edges[:, 1] * offsets[:, 0] > 0))


def degrees(angles: np.ndarray) -> np.ndarray:
    """Angles in whole degrees (rounded), for readable assertions."""
    return np.round(np.degrees(angles)).astype(int)
