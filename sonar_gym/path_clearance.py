"""Whether a robot's planned arcs keep clear of a world's static shapes, as a compiled loop.

A command of wheel travel ``(d_l, d_r)`` moves the centre along a circular arc of length
``L = |d_l + d_r| / 2`` turning by ``phi = |d_r - d_l| / l``. The arc lies within its sagitta
``<= L phi / 8`` of its chord, so the disc of radius ``robot radius + L phi / 8 + clearance``
swept along the chord covers every position the body takes; a command whose swept disc keeps
that far from every static shape meets no contact. A turn of more than pi is never clear.

The shapes near the chord are those whose bounding box meets the chord's box grown by that
radius: the test pymunk's ``Space.bb_query`` makes, on the boxes pymunk cached for the shapes
(:class:`StaticShapeTable`), so the same shapes are measured. Their exact distance to the chord
decides: a segment's (0 where the two cross) less its radius, a circle centre's less its
radius.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pymunk
from numba import types

from sonar_gym.compiled import INDICES, TABLE, compiled, nan_max, nan_min
from sonar_gym.pose import FloatArray

PATH_CLEARANCE_M = 1e-3
"""A command whose swept disc stays this far (metres) beyond the robot radius from every static
shape meets no contact, so it is integrated without stepping the physics."""

SEGMENT, CIRCLE = 0, 1
"""Kinds of :attr:`StaticShapeTable.kinds`."""


@dataclass(frozen=True)
class StaticShapeTable:
    """A world's static shapes as arrays ({W}, metres).

    Attributes:
        bounds: ``(S, 4)`` each shape's bounding box ``(left, bottom, right, top)`` as pymunk
            caches it.
        kinds: ``(S,)`` :data:`SEGMENT` or :data:`CIRCLE`.
        shapes: ``(S, 5)`` a segment's ``(a_x, a_y, b_x, b_y, radius)`` or a circle's
            ``(centre_x, centre_y, radius, 0, 0)``.
    """

    bounds: FloatArray
    kinds: np.ndarray
    shapes: FloatArray

    @property
    def arrays(self) -> tuple[FloatArray, np.ndarray, FloatArray]:
        """``(bounds, kinds, shapes)``, the arguments of the compiled loops."""
        return self.bounds, self.kinds, self.shapes

    @classmethod
    def of(cls, shapes: Sequence[pymunk.Shape]) -> StaticShapeTable:
        """The table of ``shapes`` (segments and circles, already added to their space, whose
        bodies do not move)."""
        bounds = np.zeros((len(shapes), 4))
        kinds = np.zeros(len(shapes), dtype=np.int64)
        rows = np.zeros((len(shapes), 5))
        for index, shape in enumerate(shapes):
            box = shape.bb
            bounds[index] = (box.left, box.bottom, box.right, box.top)
            if isinstance(shape, pymunk.Segment):
                kinds[index] = SEGMENT
                rows[index] = (shape.a.x, shape.a.y, shape.b.x, shape.b.y, shape.radius)
            elif isinstance(shape, pymunk.Circle) and shape.body is not None:
                kinds[index] = CIRCLE
                centre = shape.body.local_to_world(shape.offset)
                rows[index, :3] = (centre.x, centre.y, shape.radius)
            else:
                raise ValueError(
                    f"a static shape must be a pymunk Segment or Circle; got {type(shape).__name__}"
                )
        for array in (bounds, kinds, rows):
            array.setflags(write=False)
        return cls(bounds, kinds, rows)

    @classmethod
    def of_outlines(
        cls, segment_starts: FloatArray, segment_ends: FloatArray, circles: FloatArray
    ) -> StaticShapeTable:
        """The table :meth:`of` gives for segments of radius 0 from ``segment_starts`` to
        ``segment_ends`` (``(S, 2)`` each) followed by circles ``(C, 3)`` ``[x, y, radius]``,
        made on a space's static body (at the origin, angle 0) and added to its space; built
        from the numbers pymunk was given instead of read back from its shapes.

        pymunk maps a point to {W} as ``1 x + 0 y + 0``: the same number, but for ``-0.0``,
        which becomes ``0.0``. The bounding boxes and circle centres are of mapped points; a
        segment's end points are kept as given. One compiled loop
        (:func:`_outline_table`) fills the three arrays.
        """
        bounds, kinds, rows = _outline_table(segment_starts, segment_ends, circles)
        for array in (bounds, kinds, rows):
            array.setflags(write=False)
        return cls(bounds, kinds, rows)


def _outline_table_loop(
    segment_starts: FloatArray, segment_ends: FloatArray, circles: FloatArray
) -> tuple[FloatArray, np.ndarray, FloatArray]:
    """``(bounds, kinds, rows)`` of :meth:`StaticShapeTable.of_outlines`, element by element:
    the mapped points (``x + 0.0``, never ``-0.0``, so the minimum and maximum meet no signed
    zeros), numpy's NaN-keeping minimum and maximum, a circle's box as its mapped centre minus
    and plus its radius."""
    n_segments, n_circles = segment_starts.shape[0], circles.shape[0]
    bounds = np.empty((n_segments + n_circles, 4))
    kinds = np.empty(n_segments + n_circles, dtype=np.int64)
    rows = np.zeros((n_segments + n_circles, 5))
    for i in range(n_segments):
        for axis in range(2):
            a = segment_starts[i, axis] + 0.0
            b = segment_ends[i, axis] + 0.0
            bounds[i, axis] = nan_min(a, b)
            bounds[i, 2 + axis] = nan_max(a, b)
            rows[i, axis] = segment_starts[i, axis]
            rows[i, 2 + axis] = segment_ends[i, axis]
        kinds[i] = SEGMENT
    for k in range(n_circles):
        i = n_segments + k
        radius = circles[k, 2]
        for axis in range(2):
            centre = circles[k, axis] + 0.0
            bounds[i, axis] = centre - radius
            bounds[i, 2 + axis] = centre + radius
            rows[i, axis] = centre
        rows[i, 2] = radius
        kinds[i] = CIRCLE
    return bounds, kinds, rows


_outline_table = compiled(
    types.Tuple(
        (
            types.Array(types.float64, 2, "C"),
            types.Array(types.int64, 1, "C"),
            types.Array(types.float64, 2, "C"),
        )
    ),
    TABLE,
    TABLE,
    TABLE,
)(_outline_table_loop)


def _point_segment_distance(
    px: float, py: float, ax: float, ay: float, bx: float, by: float
) -> float:
    ex, ey = bx - ax, by - ay
    length2 = ex * ex + ey * ey
    t = 0.0 if length2 == 0.0 else ((px - ax) * ex + (py - ay) * ey) / length2
    t = min(max(t, 0.0), 1.0)
    return math.hypot(px - ax - t * ex, py - ay - t * ey)


_point_segment_distance_compiled = compiled(types.float64, *[types.float64] * 6, inline=True)(
    _point_segment_distance
)


def _side(ox: float, oy: float, ux: float, uy: float, vx: float, vy: float) -> float:
    return (ux - ox) * (vy - oy) - (uy - oy) * (vx - ox)


_side_compiled = compiled(types.float64, *[types.float64] * 6, inline=True)(_side)


def _segment_distance(
    ax: float, ay: float, bx: float, by: float, px: float, py: float, qx: float, qy: float
) -> float:
    """Shortest distance between the segments ``ab`` and ``pq`` (0 if they cross), metres."""
    if (
        _side_compiled(ax, ay, bx, by, px, py) * _side_compiled(ax, ay, bx, by, qx, qy) < 0.0
        and _side_compiled(px, py, qx, qy, ax, ay) * _side_compiled(px, py, qx, qy, bx, by) < 0.0
    ):
        return 0.0
    return min(
        _point_segment_distance_compiled(ax, ay, px, py, qx, qy),
        _point_segment_distance_compiled(bx, by, px, py, qx, qy),
        _point_segment_distance_compiled(px, py, ax, ay, bx, by),
        _point_segment_distance_compiled(qx, qy, ax, ay, bx, by),
    )


_segment_distance_compiled = compiled(types.float64, *[types.float64] * 8, inline=True)(
    _segment_distance
)


def _arc_is_clear(
    start_x: float,
    start_y: float,
    end_x: float,
    end_y: float,
    left_m: float,
    right_m: float,
    wheel_base_m: float,
    robot_radius_m: float,
    bounds: FloatArray,
    kinds: np.ndarray,
    shapes: FloatArray,
) -> bool:
    turned = abs(right_m - left_m) / wheel_base_m
    if turned > math.pi:
        return False
    arc_length = 0.5 * abs(left_m + right_m)
    radius = robot_radius_m + arc_length * turned / 8.0 + PATH_CLEARANCE_M
    left, bottom = min(start_x, end_x) - radius, min(start_y, end_y) - radius
    right, top = max(start_x, end_x) + radius, max(start_y, end_y) + radius
    for index in range(kinds.shape[0]):
        if not (
            left <= bounds[index, 2]
            and bounds[index, 0] <= right
            and bottom <= bounds[index, 3]
            and bounds[index, 1] <= top
        ):
            continue
        row = shapes[index]
        if kinds[index] == SEGMENT:
            distance = _segment_distance_compiled(
                start_x, start_y, end_x, end_y, row[0], row[1], row[2], row[3]
            )
            gap = distance - row[4]
        else:
            gap = (
                _point_segment_distance_compiled(row[0], row[1], start_x, start_y, end_x, end_y)
                - row[2]
            )
        if gap <= radius:
            return False
    return True


arc_is_clear = compiled(types.boolean, *[types.float64] * 8, TABLE, INDICES, TABLE, inline=True)(
    _arc_is_clear
)
"""Whether the robot (radius ``robot_radius_m``) can follow the arc of
wheel travel ``(left_m, right_m)`` over wheel base ``wheel_base_m`` from ``(start_x, start_y)``
to ``(end_x, end_y)`` ({W}, metres) without touching a shape of a :class:`StaticShapeTable`
``(bounds, kinds, shapes)`` (see the module docstring)."""


__all__ = [
    "CIRCLE",
    "PATH_CLEARANCE_M",
    "SEGMENT",
    "StaticShapeTable",
    "arc_is_clear",
]
