"""Maps made from scenarios: the beacon map of the one-way ranging tasks.

Roh et al. place ultrasonic beacons so that triples of them form triangular areas (Table I,
Fig. 3); the robot knows some beacons exactly and the others only roughly until it
calibrates them. This module holds that map's plane geometry (which side of a boundary,
triangle areas, inside a triangle), the random variation of a layout, and the frame in which
positions are scaled to [-1, 1] for observations. Metres in the world frame {W}.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from sonar_gym.pose import FloatArray

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
