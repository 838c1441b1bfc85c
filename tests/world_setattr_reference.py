"""A world that moves its pymunk robot body through attribute assignment
(``body.position = ...``), as :class:`sonar_gym.world.World` did before it called the
properties' setters directly: the form kept as the tests' reference."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt
import pymunk

from sonar_gym.pose import Pose, wrap_angle
from sonar_gym.world import (
    _COLLISION_SLOP_M,
    _SETTLE_STEPS,
    MOTION_SUBSTEP_S,
    MotionOutcome,
    World,
    _has_contact_impulse,
)


class SetattrWorld(World):
    """:class:`~sonar_gym.world.World` whose teleports, motions and imposed velocities assign
    the body's attributes."""

    def _build_space(self) -> pymunk.Space:
        space = pymunk.Space()
        space.gravity = (0.0, 0.0)
        space.damping = 1.0
        space.collision_slop = _COLLISION_SLOP_M
        # Chipmunk has no speculative contacts: a substep may end inside a wall it was not yet
        # touching. Remove the whole overlap in the next substep (the default corrects ~6 %).
        space.collision_bias = 0.0
        self._space = space
        self._add_static_shapes(space)
        body, shape = self._new_robot()
        space.add(body, shape)
        self._robot_body, self._robot_shape = body, shape
        if self._placed_pose is not None:
            _move_fresh_body(space, body, self._placed_pose)
        return space

    def _teleport(self, pose: Pose) -> None:
        self._placed_pose = pose  # pose.theta is wrapped: the body reads back this very pose
        space = self._space
        if space is None:
            return
        if self._robot_is_fresh:
            _move_fresh_body(space, self._body(), pose)
            return
        old_shape = self._robot_shape
        assert old_shape is not None  # a body that has moved is in the built space
        space.remove(self._body(), old_shape)
        body, shape = self._new_robot()
        body.position = (pose.x, pose.y)
        body.angle = pose.theta
        space.add(body, shape)
        self._robot_body, self._robot_shape = body, shape
        self._robot_is_fresh = True

    def move_robot(self, substep_displacements: npt.ArrayLike) -> MotionOutcome:
        steps = np.asarray(substep_displacements, dtype=np.float64)
        if steps.ndim != 2 or steps.shape[1] != 3 or not np.all(np.isfinite(steps)):
            raise ValueError(
                "argument 'substep_displacements' must be a finite (N, 3) array of "
                "[dx, dy, dtheta]; "
                f"got shape {steps.shape}"
            )
        self._teleport(self.robot_pose)
        body = self._body()
        space = self.space
        collided = False
        path_length = 0.0
        previous = body.position
        velocities = steps / MOTION_SUBSTEP_S
        zero = np.zeros(3)
        # The velocity imposed in step k moves the body in step k + 1: one extra step applies the
        # last command, a settle step lets the contact bias remove any residual overlap.
        self._robot_is_fresh = False
        self._placed_pose = None
        for k in range(len(steps) + 1 + _SETTLE_STEPS):
            vx, vy, omega = velocities[k] if k < len(steps) else zero
            self._commanded_velocity = (float(vx), float(vy))
            self._commanded_angular_velocity = float(omega)
            space.step(MOTION_SUBSTEP_S)
            position = body.position
            path_length += math.dist(position, previous)
            previous = position
            if not collided:
                collided = _has_contact_impulse(body)
        self._commanded_velocity = (0.0, 0.0)
        self._commanded_angular_velocity = 0.0
        body.velocity = (0.0, 0.0)
        body.angular_velocity = 0.0
        body.angle = wrap_angle(body.angle)
        return MotionOutcome(self.robot_pose, collided, path_length)

    def _impose_velocity(self, body: pymunk.Body, gravity: Any, damping: float, dt: float) -> None:
        body.velocity = self._commanded_velocity
        body.angular_velocity = self._commanded_angular_velocity


def _move_fresh_body(space: pymunk.Space, body: pymunk.Body, pose: Pose) -> None:
    """Teleport ``body``, which ``space`` has not stepped since it was added, to ``pose``."""
    body.position = (pose.x, pose.y)
    body.angle = pose.theta
    space.reindex_shapes_for_body(body)
