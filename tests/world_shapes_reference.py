"""A world's static pymunk shapes made straight from a scenario: the form
:meth:`sonar_gym.world.World._add_static_shapes` replaced (it now makes them from the
scenario's :class:`~sonar_gym.geometry.StaticGeometry`), kept as the tests' reference."""

from __future__ import annotations

import pymunk

from sonar_gym.scenario import Scenario
from sonar_gym.world import STATIC_CATEGORY


def reference_static_shapes(space: pymunk.Space, scenario: Scenario) -> list[pymunk.Shape]:
    """Room sides, free walls, box sides (segments of radius 0), then cylinders (circles), on
    ``space``'s static body, each set frictionless, inelastic and in :data:`STATIC_CATEGORY`,
    and added to ``space`` in that order."""
    static_body = space.static_body
    shapes: list[pymunk.Shape] = []

    def segment(a: tuple[float, float], b: tuple[float, float]) -> None:
        shapes.append(pymunk.Segment(static_body, a, b, 0.0))

    if scenario.room is not None:
        corners = scenario.room.corners
        for i, corner in enumerate(corners):
            segment(corner, corners[(i + 1) % 4])
    for wall in scenario.walls:
        segment(wall.a, wall.b)
    for box in scenario.boxes:
        corners = box.corners
        for i, corner in enumerate(corners):
            segment(corner, corners[(i + 1) % 4])
    for cylinder in scenario.cylinders:
        shapes.append(pymunk.Circle(static_body, cylinder.radius, cylinder.center))
    for shape in shapes:
        shape.friction = 0.0
        shape.elasticity = 0.0
        shape.filter = pymunk.ShapeFilter(categories=STATIC_CATEGORY)
    if shapes:
        space.add(*shapes)
    return shapes
