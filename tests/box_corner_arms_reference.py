"""The box corners' arms as :func:`sonar_gym.geometry._box_corner_arms` found them one corner at
a time, before the corners' wall tests ran as arrays: the form kept as the tests' reference."""

from __future__ import annotations

import numpy as np

from sonar_gym.geometry import _FLUSH_TOLERANCE_M, _norms, _SegmentIndex, ring_shift
from sonar_gym.pose import FloatArray


def reference_box_corner_arms(
    box_corners: FloatArray, walls: _SegmentIndex
) -> tuple[FloatArray, FloatArray]:
    """Corners of every box with their arms; ``box_corners`` is ``(B, 4, 2)``, counter-clockwise.

    A free-standing box corner faces free space with an opening of 270 deg: always a convex
    edge, which equal arms encode. A corner standing on a wall (a table pushed against it)
    is hidden; instead the box's side leaving the wall and the wall form a concave 90 deg
    dihedral there, which the arms ``(side away from the wall, wall away from the box)``
    encode.
    """
    points = box_corners.reshape(-1, 2)
    to_next = (ring_shift(box_corners, 1, axis=1) - box_corners).reshape(-1, 2)
    to_previous = (ring_shift(box_corners, -1, axis=1) - box_corners).reshape(-1, 2)
    to_next /= _norms(to_next)[:, None]
    to_previous /= _norms(to_previous)[:, None]
    arms = np.stack([to_next, to_next], axis=1)
    candidates = walls.near(points, _FLUSH_TOLERANCE_M)
    for k, point in enumerate(points):
        wall = reference_segment_containing(point, walls, candidates[k], _FLUSH_TOLERANCE_M)
        if wall is None:
            continue
        along_wall_next = abs(float(wall @ to_next[k])) > 0.99
        leaving = to_previous[k] if along_wall_next else to_next[k]
        flush_side = to_next[k] if along_wall_next else to_previous[k]
        arms[k] = [leaving, -flush_side]
    return points.copy(), arms


def reference_segment_containing(
    point: FloatArray, walls: _SegmentIndex, candidates: list[int], tolerance_m: float
) -> FloatArray | None:
    """Unit direction of the first segment passing within ``tolerance_m`` of ``point`` (ends
    included), among the ascending ``candidates``."""
    for i in candidates:
        span, length = walls.spans[i], walls.lengths[i]
        t = float((point - walls.starts[i]) @ span) / length
        if -tolerance_m <= t <= length + tolerance_m:
            offset = point - (walls.starts[i] + span * t / length)
            if np.sqrt(offset.dot(offset)) <= tolerance_m:  # np.linalg.norm's arithmetic
                return span / length
    return None
