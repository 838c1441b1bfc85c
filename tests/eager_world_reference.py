"""A world whose pymunk space is built with the world, as :meth:`sonar_gym.world.World._build`
built it before the space was built on first use: the form kept as the tests' reference."""

from __future__ import annotations

import pymunk

from sonar_gym.pose import Pose
from sonar_gym.scenario import Scenario
from sonar_gym.world import _COLLISION_SLOP_M, _STATIC_FILTER, World


class EagerWorld(World):
    """:class:`~sonar_gym.world.World` with the space, its static shapes and the robot body at
    the origin made in the constructor, before any teleport."""

    def _build(self, scenario: Scenario) -> None:
        self.scenario = scenario
        space = pymunk.Space()
        space.gravity = (0.0, 0.0)
        space.damping = 1.0
        space.collision_slop = _COLLISION_SLOP_M
        space.collision_bias = 0.0
        self._space = space
        self._static_shapes: list[pymunk.Shape] = []
        self.rebuild_geometry()
        self._add_eager_static_shapes(scenario)

        self._commanded_velocity: tuple[float, float] = (0.0, 0.0)
        self._commanded_angular_velocity = 0.0
        self._robot_body, self._robot_shape = self._new_robot()
        self._robot_is_fresh = True
        self._placed_pose: Pose | None = None
        space.add(self._robot_body, self._robot_shape)

    def _add_eager_static_shapes(self, scenario: Scenario) -> None:
        assert self._space is not None
        static_body = self._space.static_body
        geometry = self.geometry
        shapes: list[pymunk.Shape] = [
            pymunk.Segment(static_body, a, b, 0.0)
            for a, b in zip(
                geometry.segment_starts.tolist(), geometry.segment_ends.tolist(), strict=True
            )
        ]
        shapes += [
            pymunk.Circle(static_body, radius, (x, y)) for x, y, radius in geometry.circles.tolist()
        ]
        for shape in shapes:
            shape.filter = _STATIC_FILTER
        if shapes:
            self._space.add(*shapes)
        self._static_shapes = shapes
        self._index_static_content(scenario)
