"""A world whose teleports move the pymunk body at once, as :meth:`sonar_gym.world.World._teleport`
did before the body followed only when next read: the form kept as the tests' reference."""

from __future__ import annotations

from sonar_gym.pose import Pose
from sonar_gym.world import _SET_ANGLE, _SET_POSITION, World, _move_fresh_body


class EagerTeleportWorld(World):
    """:class:`~sonar_gym.world.World` whose every teleport places the body in the space."""

    def _teleport(self, pose: Pose) -> None:
        # A new body and shape carry no cached contacts and no solver bias velocity, so what
        # happens next depends only on the pose, never on the history of the space. A body
        # the space has not stepped since it was made is still in that state: it only moves.
        # Before the space is built, the pose is all there is to keep (see _build_space).
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
        _SET_POSITION(body, (pose.x, pose.y))
        _SET_ANGLE(body, pose.theta)
        space.add(body, shape)
        self._robot_body, self._robot_shape = body, shape
        self._robot_is_fresh = True
