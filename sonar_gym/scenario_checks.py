"""Geometry checks of a scenario at load time, so a bad world fails there and not at reset.

:func:`geometry_problem` answers with the first problem found, as ``(field, allowed, got)``
for :class:`~sonar_gym.scenario.ScenarioError` messages, or ``None``. What is checked
(metres, {W}):

- emitters (beacons, transmitters) are distinct: their floor positions at least
  :data:`MIN_EMITTER_SEPARATION_M` apart (coincident ones make trilateration singular), and
  inside the room's floor plan when there is a room;
- each beacon cylinder (roles ``small_beacon``, ``large_beacon``) lies inside the room and
  clears every wall, box and other cylinder by :data:`BEACON_CLEARANCE_M` (the sonar must see
  its convex face), and is not walled in: some free robot position on a grid over the scenario
  (spacing at most :data:`FREE_GRID_STEP_M`) sees it in a straight line.

Pure numpy over segments and discs; the pymunk world is not built.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    from sonar_gym.scenario import Cylinder, Scenario

FloatArray = npt.NDArray[np.float64]
Problem = tuple[str, str, object]

MIN_EMITTER_SEPARATION_M = 0.01
"""Least floor-plan distance between two emitters, metres."""
BEACON_CLEARANCE_M = 1e-3
"""Least gap between a beacon cylinder and any other shape, metres."""
FREE_GRID_STEP_M = 0.1
"""Largest spacing of the grid of robot positions searched for a view of each beacon, metres."""
MAX_GRID_POINTS = 40_000
"""The grid is coarsened beyond this many points (a large room is searched more sparsely)."""
_GRID_STRIDE = 97
_CHUNK = 128


def geometry_problem(scenario: Scenario) -> Problem | None:
    """The first geometric problem of ``scenario`` as ``(field, allowed, got)``, or ``None``."""
    return _emitter_problem(scenario) or _beacon_problem(scenario)


def _emitter_problem(scenario: Scenario) -> Problem | None:
    emitters = scenario.emitters
    for i, first in enumerate(emitters):
        for second in emitters[i + 1 :]:
            gap = math.dist(first.position[:2], second.position[:2])
            if gap < MIN_EMITTER_SEPARATION_M:
                return (
                    "emitters",
                    f"emitters at least {MIN_EMITTER_SEPARATION_M:g} m apart on the floor plan",
                    f"{first.name!r} and {second.name!r} {gap:.3g} m apart",
                )
    room = scenario.room
    if room is None:
        return None
    for i, emitter in enumerate(emitters):
        x, y = emitter.position[:2]
        if not (room.min[0] <= x <= room.max[0] and room.min[1] <= y <= room.max[1]):
            return (
                f"emitters[{i}].position",
                f"a point above the room's floor (x, y within {room.min} .. {room.max})",
                emitter.position,
            )
    return None


def _segments(scenario: Scenario) -> FloatArray:
    """``(n, 4)``: every wall, room wall and box side as ``ax, ay, bx, by``."""
    rows: list[tuple[float, float, float, float]] = []
    if scenario.room is not None:
        corners = scenario.room.corners
        rows += [(*corners[k], *corners[(k + 1) % 4]) for k in range(4)]
    rows += [(*wall.a, *wall.b) for wall in scenario.walls]
    for box in scenario.boxes:
        corners = box.corners
        rows += [(*corners[k], *corners[(k + 1) % 4]) for k in range(4)]
    return np.asarray(rows, dtype=float).reshape(-1, 4)


def _point_segment_distances(points: FloatArray, segments: FloatArray) -> FloatArray:
    """``(n_points, n_segments)`` Euclidean distances, metres."""
    a, b = segments[None, :, :2], segments[None, :, 2:]
    p = points[:, None, :]
    ab = b - a
    length2 = np.maximum(np.sum(ab * ab, axis=-1), 1e-300)
    t = np.clip(np.sum((p - a) * ab, axis=-1) / length2, 0.0, 1.0)
    foot = a + t[..., None] * ab
    return np.asarray(np.linalg.norm(p - foot, axis=-1), dtype=float)


def _inside_boxes(points: FloatArray, scenario: Scenario) -> npt.NDArray[np.bool_]:
    """Whether each point lies strictly inside any box."""
    inside = np.zeros(len(points), dtype=bool)
    for box in scenario.boxes:
        c, s = math.cos(math.radians(box.angle_deg)), math.sin(math.radians(box.angle_deg))
        local = points - np.asarray(box.center)
        u = local[:, 0] * c + local[:, 1] * s
        v = -local[:, 0] * s + local[:, 1] * c
        inside |= (np.abs(u) < box.size[0] / 2.0) & (np.abs(v) < box.size[1] / 2.0)
    return inside


def _beacon_problem(scenario: Scenario) -> Problem | None:
    segments = _segments(scenario)
    for i, beacon in enumerate(scenario.cylinders):
        if beacon.role == "clutter":
            continue
        where = f"cylinders[{i}]"
        centre = np.asarray([beacon.center], dtype=float)
        room = scenario.room
        if room is not None and not (
            room.min[0] + beacon.radius < beacon.center[0] < room.max[0] - beacon.radius
            and room.min[1] + beacon.radius < beacon.center[1] < room.max[1] - beacon.radius
        ):
            return (
                f"{where}.center",
                f"a beacon wholly inside the room {room.min} .. {room.max}",
                beacon.center,
            )
        if _inside_boxes(centre, scenario)[0]:
            return (f"{where}.center", "a beacon outside every box", beacon.center)
        if len(segments):
            gap = float(np.min(_point_segment_distances(centre, segments))) - beacon.radius
            if gap < BEACON_CLEARANCE_M:
                return (
                    where,
                    f"a beacon clear of every wall and box by {BEACON_CLEARANCE_M:g} m",
                    f"center={beacon.center}, radius={beacon.radius} ({gap:.3g} m clear)",
                )
        for j, other in enumerate(scenario.cylinders):
            if j == i:
                continue
            gap = math.dist(beacon.center, other.center) - beacon.radius - other.radius
            if gap < BEACON_CLEARANCE_M:
                return (
                    where,
                    f"a beacon clear of every other cylinder by {BEACON_CLEARANCE_M:g} m",
                    f"it overlaps cylinders[{j}] ({gap:.3g} m clear)",
                )
        if not _seen_from_free_space(beacon, scenario, segments):
            return (
                where,
                "a beacon that some free robot position sees (not walled in)",
                beacon.center,
            )
    return None


def _grid(scenario: Scenario) -> FloatArray:
    """Candidate robot positions over the scenario's bounds, in an order that spreads out.

    The order visits the grid with a stride, so the first few hundred points already cover
    the whole room and the search below usually stops after its first chunk.
    """
    (x0, y0), (x1, y1) = scenario.bounds
    step = max(FREE_GRID_STEP_M, math.sqrt(max((x1 - x0) * (y1 - y0), 1e-12) / MAX_GRID_POINTS))
    xs = np.arange(x0 + step / 2.0, x1, step)
    ys = np.arange(y0 + step / 2.0, y1, step)
    grid = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    stride = _GRID_STRIDE
    while math.gcd(stride, max(len(grid), 1)) != 1:  # coprime, so every point is visited once
        stride += 1
    order = (np.arange(len(grid)) * stride) % max(len(grid), 1)
    return np.asarray(grid[order], dtype=float)


def _free(points: FloatArray, scenario: Scenario, segments: FloatArray) -> FloatArray:
    """The points where the robot's disc clears every shape and lies outside every box."""
    radius = scenario.robot.radius
    free = ~_inside_boxes(points, scenario)
    if scenario.room is not None:
        room = scenario.room
        free &= (points[:, 0] > room.min[0]) & (points[:, 0] < room.max[0])
        free &= (points[:, 1] > room.min[1]) & (points[:, 1] < room.max[1])
    points = points[free]
    if len(segments) and len(points):
        points = points[np.min(_point_segment_distances(points, segments), axis=1) >= radius]
    for cylinder in scenario.cylinders:
        if len(points):
            away = np.linalg.norm(points - np.asarray(cylinder.center), axis=1)
            points = points[away >= cylinder.radius + radius]
    return points


def _seen_from_free_space(beacon: Cylinder, scenario: Scenario, segments: FloatArray) -> bool:
    """Whether a free grid position has a straight, unblocked view of the beacon's centre.

    The sight line ends at the beacon's surface; walls, box sides and other cylinders block.
    The grid is searched in chunks, stopping at the first position that sees the beacon.
    """
    grid = _grid(scenario)
    centre = np.asarray(beacon.center, dtype=float)
    for start in range(0, len(grid), _CHUNK):
        points = _free(grid[start : start + _CHUNK], scenario, segments)
        if not len(points):
            continue
        towards = centre - points
        distance = np.maximum(np.linalg.norm(towards, axis=1, keepdims=True), 1e-12)
        ends = centre - towards / distance * beacon.radius
        clear = np.ones(len(points), dtype=bool)
        if len(segments):
            clear &= ~_crosses_any(points, ends, segments)
        rays = np.concatenate([points, ends], axis=1)
        for other in scenario.cylinders:
            if other is not beacon:
                near = _point_segment_distances(np.asarray([other.center]), rays)[0]
                clear &= near > other.radius
        if np.any(clear):
            return True
    return False


def _crosses_any(
    starts: FloatArray, ends: FloatArray, segments: FloatArray
) -> npt.NDArray[np.bool_]:
    """Whether each sight line ``starts[k] -> ends[k]`` properly crosses any segment."""
    p, r = starts[:, None, :], (ends - starts)[:, None, :]
    q, s = segments[None, :, :2], (segments[None, :, 2:] - segments[None, :, :2])

    def cross(u: FloatArray, v: FloatArray) -> FloatArray:
        return np.asarray(u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0], dtype=float)

    denominator = cross(r, s)
    parallel = np.abs(denominator) < 1e-15
    safe = np.where(parallel, 1.0, denominator)
    t = cross(q - p, s) / safe
    u = cross(q - p, r) / safe
    hits = ~parallel & (t > 1e-9) & (t < 1.0 - 1e-9) & (u >= 0.0) & (u <= 1.0)
    return np.asarray(np.any(hits, axis=1), dtype=bool)
