"""Maps made from scenarios: what a localizer's map holds of a world.

Two kinds, each conversion a function named after the map it builds (metres, world frame {W}):

- wall maps (APCS, Yamamoto et al. sec. 4.1): the mapped flat surfaces as wall vectors, and
  what of them faces a row of points;
- beacon maps (Roh et al.): ultrasonic beacons whose triples form triangular areas (Table I,
  Fig. 3), known exactly or only roughly until calibrated: the map's plane geometry (which side
  of a boundary, triangle areas, inside a triangle), the random variation of a layout, and the
  frame in which positions are scaled to [-1, 1] for observations.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from sonar_gym.localization.apcs import WallVector
from sonar_gym.localization.apcs_online import nearest_facing_walls
from sonar_gym.pose import FloatArray
from sonar_gym.scenario import Scenario

# --- wall maps (APCS) ------------------------------------------------------------------------


def map_wall_vectors(scenario: Scenario) -> tuple[WallVector, ...]:
    """The mapped flat surfaces of ``scenario`` as APCS wall vectors (sec. 4.1, Fig. 3).

    Each vector has the occupied side on its left:

    - the room's walls: the room is free inside, so its counter-clockwise edges are reversed;
    - free walls with ``mapped = true``: ``a -> b`` as listed, the convention of the scenario
      files (the occupied side of ``a -> b`` on the left, see ``apcs_corridor.toml``);
    - mapped boxes: their counter-clockwise edges as they are (the inside is occupied).

    Cylinders are not flat and unmapped objects are not in the map; neither appears.
    """
    vectors: list[WallVector] = []
    if scenario.room is not None:
        corners = scenario.room.corners
        for index in range(4):
            start, end = corners[(index + 1) % 4], corners[index]
            vectors.append(WallVector(start, end, name=f"room_{index}"))
    for index, wall in enumerate(scenario.walls):
        if wall.mapped:
            vectors.append(WallVector(wall.a, wall.b, name=f"wall_{index}"))
    for index, box in enumerate(scenario.boxes):
        if box.mapped:
            corners = box.corners
            for side in range(4):
                vectors.append(
                    WallVector(corners[side], corners[(side + 1) % 4], name=f"box_{index}_{side}")
                )
    return tuple(vectors)


def facing_wall_stretch(
    wall_map: Sequence[WallVector],
    origins: npt.ArrayLike,
    direction: npt.ArrayLike,
    spacing_m: float,
) -> tuple[float, float]:
    """How long and how far one mapped wall faces a row of points, looking along ``direction``.

    For each of ``origins`` (``(n, 2)``, metres in {W}, ``spacing_m`` apart along a line) the
    nearest wall vector the ray along ``direction`` meets face on is looked up
    (:func:`~sonar_gym.localization.apcs_online.nearest_facing_walls`).

    Returns:
        ``(longest_m, median_m)``: the longest run of consecutive points facing one wall, times
        ``spacing_m`` (metres), and the median distance to the walls met (metres; inf when no
        ray meets a wall).
    """
    wall_ids, distances = nearest_facing_walls(
        wall_map, origins, np.asarray(direction, dtype=np.float64)
    )
    seen = distances[wall_ids >= 0]
    median = float(np.median(seen)) if seen.size else math.inf
    return longest_run(wall_ids.tolist()) * spacing_m, median


def map_ahead_features(
    wall_map: Sequence[WallVector],
    leg_starts_x: Sequence[float] | npt.NDArray[np.floating[Any]],
    leg_length_m: float,
    centre_line_y: float,
    spacing_m: float,
    max_range_m: float,
) -> npt.NDArray[np.float64]:
    """``(n_legs, 4)``: per leg of a route along ``+x``, per side, how well a mapped wall faces it.

    Along leg ``i``'s centre line (``x`` from ``leg_starts_x[i]`` to ``leg_starts_x[i + 1]``,
    ``leg_length_m`` long, at ``y = centre_line_y``; metres in {W}), every ``spacing_m`` the
    nearest map vector facing the route on each side (left: ``+y``, right: ``-y``) is looked
    up (:func:`facing_wall_stretch`). Columns: left continuity, left distance, right
    continuity, right distance; continuity is the longest run of one vector over the leg's
    length, the distance its median over ``max_range_m``, each clipped to 1.
    """
    n_legs = len(leg_starts_x) - 1
    features = np.zeros((n_legs, 4))
    for leg in range(n_legs):
        xs = np.arange(leg_starts_x[leg], leg_starts_x[leg + 1], spacing_m)
        origins = np.column_stack([xs, np.full_like(xs, centre_line_y)])
        for side_index, sign in enumerate((1.0, -1.0)):
            longest_m, median_m = facing_wall_stretch(wall_map, origins, (0.0, sign), spacing_m)
            features[leg, 2 * side_index] = min(longest_m / leg_length_m, 1.0)
            features[leg, 2 * side_index + 1] = min(median_m / max_range_m, 1.0)
    return features


def longest_run(ids: Sequence[int]) -> int:
    """Length of the longest run of one non-negative id (negative ids break runs)."""
    longest = current = 0
    previous = -1
    for wall_id in ids:
        current = (
            current + 1 if wall_id == previous and wall_id >= 0 else (1 if wall_id >= 0 else 0)
        )
        previous = wall_id
        longest = max(longest, current)
    return longest


# --- beacon maps (Roh et al.) ---------------------------------------------------------------
MAP_FRAME_CENTRE_M = np.array([2.0, 1.0, 1.25])
"""Centre of the beacon map's scaling frame: ``scaled = (position - centre) / half span``."""
MAP_FRAME_HALF_SPAN_M = np.array([2.5, 2.0, 1.25])
"""Half spans of the beacon map's scaling frame, metres (x, y, z)."""

SURVEYED, CALIBRATED, PRIOR_ONLY, UNUSED = 1.0, 0.5, 0.0, -1.0
"""What the robot knows of a beacon: its surveyed position, a position it calibrated, only a
rough prior, or nothing (an unused slot)."""


def to_map_frame(position: npt.ArrayLike) -> FloatArray:
    """A position in {W} (metres) scaled to the map frame and clipped to [-1, 1]."""
    scaled = (np.asarray(position, dtype=np.float64) - MAP_FRAME_CENTRE_M) / MAP_FRAME_HALF_SPAN_M
    return np.clip(scaled, -1.0, 1.0)


def beacon_slot_features(
    positions_m: Sequence[npt.ArrayLike], statuses: Sequence[float], max_slots: int
) -> FloatArray:
    """``(4 max_slots,)`` the beacon map as features: per slot x, y, z in the map frame
    (:func:`to_map_frame`) and what the robot knows of the beacon (:data:`SURVEYED`, ...);
    the slots after the given beacons are zeros with status :data:`UNUSED`."""
    slots = np.zeros((max_slots, 4))
    slots[:, 3] = UNUSED
    count = len(positions_m)
    if count:
        slots[:count, :3] = to_map_frame(np.array(positions_m, dtype=np.float64))
        slots[:count, 3] = statuses
    return slots.reshape(-1)


def from_map_frame(scaled: npt.ArrayLike) -> FloatArray:
    """The {W} position (metres) of a map-frame value (the inverse of :func:`to_map_frame`
    inside the frame)."""
    return np.asarray(scaled, dtype=np.float64) * MAP_FRAME_HALF_SPAN_M + MAP_FRAME_CENTRE_M


def side_of_line(points: npt.ArrayLike, a: FloatArray, b: FloatArray) -> FloatArray:
    """Sign of the cross product: which side of the line a-b each point lies on (0 on it)."""
    p = np.asarray(points, dtype=np.float64)
    direction = b - a
    offset = p - a
    return np.sign(direction[0] * offset[..., 1] - direction[1] * offset[..., 0])


def triangle_area(corners: FloatArray) -> float:
    """Area of the triangle of three ``(x, y)`` corners, square metres."""
    a, b, c = corners
    return 0.5 * abs(float((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])))


def inside_triangle(point: FloatArray, corners: FloatArray) -> bool:
    """Whether a point lies strictly inside a triangle of three ``(x, y)`` corners."""
    signs = [side_of_line(point, corners[i], corners[(i + 1) % 3]) for i in range(3)]
    return bool(all(s > 0 for s in signs) or all(s < 0 for s in signs))


def jittered_beacons(
    beacons: Mapping[str, tuple[float, float, float]],
    rng: np.random.Generator,
    jitter_xy_m: float,
    jitter_z_m: float,
) -> dict[str, tuple[float, float, float]]:
    """Each beacon moved uniformly within +-``jitter_xy_m`` in x and y and +-``jitter_z_m``
    in height, metres (draws: dx, dy, then dz per beacon, in the mapping's order)."""
    moved = {}
    for name, (x, y, z) in beacons.items():
        dx, dy = rng.uniform(-jitter_xy_m, jitter_xy_m, 2)
        dz = rng.uniform(-jitter_z_m, jitter_z_m)
        moved[name] = (float(x + dx), float(y + dy), float(z + dz))
    return moved


def new_beacons_of_areas(areas: tuple[tuple[str, str, str], ...]) -> tuple[str, ...]:
    """The beacon each later area of a chain adds to the one before it."""
    return tuple(
        next(name for name in following if name not in area)
        for area, following in zip(areas[:-1], areas[1:], strict=True)
    )
