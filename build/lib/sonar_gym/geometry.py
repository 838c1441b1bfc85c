"""A vectorised, read-only copy of a scenario's static geometry, for the sensors.

pymunk is the single source of truth for collisions (see :mod:`sonar_gym.world`); the sonar
works on these flat numpy arrays instead, so a whole pan is array arithmetic. Everything is in
metres in the world frame {W}.

Primitives:
    segments: every straight reflecting surface: the room's four walls, free walls and the four
        sides of every box. Plane reflectors.
    circles: cylinders, ``[x, y, radius]``.
    vertices: every segment end point, merged where segments meet. Each vertex keeps the two
        unit directions along its segments (``vertex_arms``); the vertex is a *concave corner*
        (a strong retro-reflector) when seen from inside the wedge between its arms with an
        opening below 180 deg, and a *convex edge* (a weak diffractor) otherwise. A free wall
        end has both arms equal, so it is always an edge.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonar_gym.pose import FloatArray
from sonar_gym.scenario import Scenario

_MERGE_TOLERANCE_M = 1e-6
_FLUSH_TOLERANCE_M = 1e-3


@dataclass(frozen=True, eq=False)
class StaticGeometry:
    """Flat arrays of the static reflectors of a scenario (metres, {W}).

    Attributes:
        segment_starts, segment_ends: ``(S, 2)`` end points of every plane reflector.
        segment_mapped: ``(S,)`` whether each segment is in the localizer's map.
        circles: ``(C, 3)`` cylinders as ``[x, y, radius]``.
        circle_mapped: ``(C,)`` whether each cylinder is in the localizer's map.
        vertices: ``(V, 2)`` merged segment end points.
        vertex_arms: ``(V, 2, 2)`` unit vectors from each vertex along its (up to) two segments.
    """

    segment_starts: FloatArray
    segment_ends: FloatArray
    segment_mapped: np.ndarray
    circles: FloatArray
    circle_mapped: np.ndarray
    vertices: FloatArray
    vertex_arms: FloatArray

    @property
    def segments(self) -> FloatArray:
        """``(S, 2, 2)`` segments as ``[[ax, ay], [bx, by]]``."""
        return np.stack([self.segment_starts, self.segment_ends], axis=1)

    @property
    def n_segments(self) -> int:
        return len(self.segment_starts)

    @property
    def n_circles(self) -> int:
        return len(self.circles)

    def is_concave_from(self, point: FloatArray) -> np.ndarray:
        """``(V,)`` whether each vertex acts as a concave corner seen from ``point`` (metres, {W}).

        True when the two arms open by less than 180 deg and ``point`` lies strictly inside the
        wedge between them: there the two faces form a retro-reflector.
        """
        arm_a, arm_b = self.vertex_arms[:, 0], self.vertex_arms[:, 1]
        to_point = np.asarray(point, dtype=np.float64)[None, :] - self.vertices
        cross_ab = arm_a[:, 0] * arm_b[:, 1] - arm_a[:, 1] * arm_b[:, 0]
        cross_ap = arm_a[:, 0] * to_point[:, 1] - arm_a[:, 1] * to_point[:, 0]
        cross_pb = to_point[:, 0] * arm_b[:, 1] - to_point[:, 1] * arm_b[:, 0]
        # For a convex wedge (opening < 180 deg) the point is inside when it is on the same
        # side of both arms as the other arm.
        sign = np.sign(cross_ab)
        return (np.abs(cross_ab) > 1e-9) & (sign * cross_ap > 0) & (sign * cross_pb > 0)


def build_static_geometry(scenario: Scenario) -> StaticGeometry:
    """Flatten a scenario's room, walls, boxes and cylinders into :class:`StaticGeometry`."""
    starts: list[tuple[float, float]] = []
    ends: list[tuple[float, float]] = []
    mapped: list[bool] = []

    def add_polygon(corners: tuple[tuple[float, float], ...], is_mapped: bool) -> None:
        for i, corner in enumerate(corners):
            starts.append(corner)
            ends.append(corners[(i + 1) % len(corners)])
            mapped.append(is_mapped)

    if scenario.room is not None:
        add_polygon(scenario.room.corners, True)
    for wall in scenario.walls:
        starts.append(wall.a)
        ends.append(wall.b)
        mapped.append(wall.mapped)

    n_room_and_walls = len(starts)
    for box in scenario.boxes:
        add_polygon(box.corners, box.mapped)

    segment_starts = np.array(starts, dtype=np.float64).reshape(-1, 2)
    segment_ends = np.array(ends, dtype=np.float64).reshape(-1, 2)
    vertices, arms = _merge_vertices(
        segment_starts[:n_room_and_walls], segment_ends[:n_room_and_walls]
    )
    box_corners, box_arms = _box_corner_arms(
        scenario, segment_starts[:n_room_and_walls], segment_ends[:n_room_and_walls]
    )
    vertices = np.concatenate([vertices, box_corners])
    arms = np.concatenate([arms, box_arms])
    circles = np.array(
        [[c.center[0], c.center[1], c.radius] for c in scenario.cylinders], dtype=np.float64
    ).reshape(-1, 3)
    return StaticGeometry(
        segment_starts=segment_starts,
        segment_ends=segment_ends,
        segment_mapped=np.array(mapped, dtype=bool),
        circles=circles,
        circle_mapped=np.array([c.mapped for c in scenario.cylinders], dtype=bool),
        vertices=vertices,
        vertex_arms=arms,
    )


def _box_corner_arms(
    scenario: Scenario, wall_starts: FloatArray, wall_ends: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Corners of every box with their arms.

    A free-standing box corner faces free space with an opening of 270 deg: always a convex
    edge, which equal arms encode. A corner standing on a wall (a table pushed against it)
    is hidden; instead the box's side leaving the wall and the wall form a concave 90 deg
    dihedral there, which the arms ``(side away from the wall, wall away from the box)``
    encode.
    """
    points: list[FloatArray] = []
    arms: list[list[FloatArray]] = []
    for box in scenario.boxes:
        corners = np.array(box.corners, dtype=np.float64)
        for i, corner in enumerate(corners):
            to_next = corners[(i + 1) % 4] - corner
            to_previous = corners[(i - 1) % 4] - corner
            to_next /= np.linalg.norm(to_next)
            to_previous /= np.linalg.norm(to_previous)
            wall = _segment_containing(corner, wall_starts, wall_ends, _FLUSH_TOLERANCE_M)
            points.append(corner)
            if wall is None:
                arms.append([to_next, to_next])
                continue
            along_wall_next = abs(float(wall @ to_next)) > 0.99
            leaving = to_previous if along_wall_next else to_next
            flush_side = to_next if along_wall_next else to_previous
            arms.append([leaving, -flush_side])
    return (
        np.array(points, dtype=np.float64).reshape(-1, 2),
        np.array(arms, dtype=np.float64).reshape(-1, 2, 2),
    )


def _segment_containing(
    point: FloatArray, starts: FloatArray, ends: FloatArray, tolerance_m: float
) -> FloatArray | None:
    """Unit direction of a segment passing within ``tolerance_m`` of ``point`` (ends included)."""
    for start, end in zip(starts, ends, strict=True):
        span = end - start
        length = float(np.linalg.norm(span))
        t = float((point - start) @ span) / length
        if -tolerance_m <= t <= length + tolerance_m:
            if np.linalg.norm(point - (start + span * t / length)) <= tolerance_m:
                return span / length
    return None


def _merge_vertices(starts: FloatArray, ends: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Merge coincident segment end points; keep up to two arms per vertex."""
    points: list[FloatArray] = []
    arm_lists: list[list[FloatArray]] = []
    for start, end in zip(starts, ends, strict=True):
        direction = (end - start) / np.linalg.norm(end - start)
        for point, arm in ((start, direction), (end, -direction)):
            for k, existing in enumerate(points):
                if np.linalg.norm(existing - point) < _MERGE_TOLERANCE_M:
                    arm_lists[k].append(arm)
                    break
            else:
                points.append(point.copy())
                arm_lists.append([arm])
    vertex_points: list[FloatArray] = []
    vertex_arms: list[list[FloatArray]] = []
    for point, arms in zip(points, arm_lists, strict=True):
        if len(arms) > 1:
            vertex_points.append(point)
            vertex_arms.append(arms[:2])
            continue
        host = _segment_through_interior(point, starts, ends)
        if host is None:  # a free end: an edge from every side
            vertex_points.append(point)
            vertex_arms.append([arms[0], arms[0]])
        else:  # a T-junction: two concave corners, one on each side of the free wall
            for along in (host, -host):
                vertex_points.append(point)
                vertex_arms.append([arms[0], along])
    return (
        np.array(vertex_points, dtype=np.float64).reshape(-1, 2),
        np.array(vertex_arms, dtype=np.float64).reshape(-1, 2, 2),
    )


def _segment_through_interior(
    point: FloatArray, starts: FloatArray, ends: FloatArray
) -> FloatArray | None:
    """Unit direction of a segment whose interior contains ``point``, if any."""
    for start, end in zip(starts, ends, strict=True):
        span = end - start
        length_sq = float(span @ span)
        t = float((point - start) @ span) / length_sq
        if _MERGE_TOLERANCE_M < t * np.sqrt(length_sq) < np.sqrt(length_sq) - _MERGE_TOLERANCE_M:
            foot = start + t * span
            if np.linalg.norm(point - foot) < _MERGE_TOLERANCE_M:
                return span / np.sqrt(length_sq)
    return None
