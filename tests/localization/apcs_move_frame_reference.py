"""The move of a side stream's stored points after a correction, one point at a time through
``rotation @ (point - origin)``: the form
:meth:`sonar_gym.localization.apcs_online.WallStream.move_frame` replaced with one
``np.matvec`` over all the points, kept as the tests' reference."""

from __future__ import annotations

import math

import numpy as np

from sonar_gym.localization.apcs_online import WallStream
from sonar_gym.pose import Pose


def move_frame_per_point(stream: WallStream, before: Pose, after: Pose) -> None:
    """Re-express ``stream``'s stored positions after a pose correction from ``before`` to
    ``after`` (Yamamoto et al., Fig. 2): the frame of the estimate moves rigidly."""
    turn = after.theta - before.theta
    cos_turn, sin_turn = math.cos(turn), math.sin(turn)
    rotation = np.array([[cos_turn, -sin_turn], [sin_turn, cos_turn]])
    origin_before, origin_after = before.position, after.position

    def moved(point: tuple[float, float]) -> tuple[float, float]:
        x, y = origin_after + rotation @ (np.asarray(point) - origin_before)
        return float(x), float(y)

    if stream._previous is not None:
        position, direction, range_m = stream._previous
        stream._previous = (moved(position), direction + turn, range_m)
    stream._group_points = [moved(point) for point in stream._group_points]
    stream._group_directions = [direction + turn for direction in stream._group_directions]
