"""Routes a robot drives, sampled as the positions where it takes its fixes.

Roh et al. (Sec. IV.A) drive a parabola across their beacon areas, localizing every 40 ms;
the paper does not print the curve. :class:`ParabolicRoute` is that curve as data,
:func:`random_parabolic_route` draws variations of it, :func:`route_suits_areas` checks
that a sampled route visits a chain of triangular beacon areas the way the block expansion
needs (Sec. II, Fig. 3), and :func:`range_along_route` ranges the beacons from every sample.
Metres and radians in the world frame {W}.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sonar_gym.localization.roh import parabolic_path
from sonar_gym.maps import (
    inside_triangle,
    jittered_beacons,
    side_of_line,
    to_map_frame,
    triangle_area,
)
from sonar_gym.pose import FloatArray
from sonar_gym.sonar.pulse_echo import WorldLike
from sonar_gym.sonar.ranging import BeaconRanger, RouteGeometry

LOCALIZATION_PERIOD_S = 0.04
"""Roh et al. Sec. III.C: "The localization occurs once every 40ms in our system"."""
ROBOT_SPEED_MPS = 0.1
"""Not in the paper (chosen): the robot's speed along the route, metres per second."""
PATH_STEP_M = ROBOT_SPEED_MPS * LOCALIZATION_PERIOD_S
"""Arc length between two fixes, metres (4 mm)."""
CURVATURE_SCALE_PER_M = 2.0
"""Largest |curvature| a route may have in observations that scale it to [-1, 1], 1/m."""


@dataclass(frozen=True)
class ParabolicRoute:
    """The parabola ``y = vertex_y + curvature (x - vertex_x)^2`` from ``x_start`` to ``x_end``.

    Metres and 1/m in {W}; sampled by :func:`~sonar_gym.localization.roh.parabolic_path`
    every :data:`PATH_STEP_M`.
    """

    x_start_m: float
    x_end_m: float
    vertex_m: tuple[float, float]
    curvature_per_m: float

    def sample(self, step_m: float = PATH_STEP_M) -> FloatArray:
        """``(n, 2)`` positions along the route every ``step_m`` of arc length, metres."""
        return parabolic_path(
            self.x_start_m, self.x_end_m, self.vertex_m, self.curvature_per_m, step_m
        )

    def y_at(self, x_m: float) -> float:
        """y of the parabola at ``x_m``, metres."""
        return self.vertex_m[1] + self.curvature_per_m * (x_m - self.vertex_m[0]) ** 2


def route_features(route: ParabolicRoute) -> FloatArray:
    """``(7,)`` a route as features: x, y of its start, end and vertex in the beacon map's
    frame (:func:`~sonar_gym.maps.to_map_frame`), then its curvature over
    :data:`CURVATURE_SCALE_PER_M` clipped to [-1, 1]."""
    points = np.array(
        [
            (route.x_start_m, route.y_at(route.x_start_m), 0.0),
            (route.x_end_m, route.y_at(route.x_end_m), 0.0),
            (*route.vertex_m, 0.0),
        ]
    )
    curvature = np.clip(route.curvature_per_m / CURVATURE_SCALE_PER_M, -1.0, 1.0)
    return np.append(to_map_frame(points)[:, :2].reshape(-1), curvature)


PAPER_ROUTE = ParabolicRoute(2.75, 0.55, (1.6, 1.45), -0.9)
"""The :func:`~sonar_gym.localization.roh.parabolic_path` defaults: across Areas 1-3 of
Table I from right to left."""


def random_parabolic_route(
    rng: np.random.Generator,
    x_end_m: float,
    curvature_range_per_m: tuple[float, float] = (-1.3, -0.5),
) -> ParabolicRoute:
    """A parabola of random curvature from near :data:`PAPER_ROUTE`'s start to near ``x_end_m``.

    Start x uniform in [2.65, 2.85] m, end x within +-0.1 m of ``x_end_m``, vertex x in
    [1.45, 1.75] m, start y in [0.15, 0.45] m, curvature uniform in
    ``curvature_range_per_m`` (1/m), drawn in that order from ``rng``.
    """
    x_start = float(rng.uniform(2.65, 2.85))
    x_end = float(x_end_m + rng.uniform(-0.1, 0.1))
    vertex_x = float(rng.uniform(1.45, 1.75))
    curvature = float(rng.uniform(*curvature_range_per_m))
    y_start = float(rng.uniform(0.15, 0.45))
    vertex_y = y_start - curvature * (x_start - vertex_x) ** 2
    return ParabolicRoute(x_start, x_end, (vertex_x, vertex_y), curvature)


def crosses_areas_in_order(
    path: FloatArray,
    beacons_xy: Mapping[str, Sequence[float]],
    areas: Sequence[Sequence[str]],
    end_margin_m: float,
    min_area_m2: float = 0.3,
) -> bool:
    """Whether a sampled route suits the block expansion over a chain of triangular areas.

    The route must start inside the first area and end inside the last; every area must
    span at least ``min_area_m2``; consecutive areas must lie on opposite sides of their
    shared boundary; and the route must cross each boundary line exactly once, in order, at
    least ``end_margin_m`` from the boundary's end beacons.

    Args:
        path: ``(n, 2)`` route samples, metres.
        beacons_xy: beacon name -> its ``(x, y, ...)`` position, metres (z ignored).
        areas: the chain of areas as beacon-name triples.
        end_margin_m: clearance of each crossing from the boundary's ends, metres.
        min_area_m2: smallest accepted triangle area, square metres.
    """
    xy = {name: np.asarray(position, dtype=np.float64)[:2] for name, position in beacons_xy.items()}
    triangles = [np.array([xy[n] for n in area]) for area in areas]
    if any(triangle_area(t) < min_area_m2 for t in triangles):
        return False
    if not (inside_triangle(path[0], triangles[0]) and inside_triangle(path[-1], triangles[-1])):
        return False
    last_crossing = -1
    for area, following in zip(areas[:-1], areas[1:], strict=True):
        a, b = (xy[n] for n in area if n in following)
        opposite = next(xy[n] for n in area if n not in following)
        new = next(xy[n] for n in following if n not in area)
        if side_of_line(opposite, a, b) * side_of_line(new, a, b) >= 0.0:
            return False
        sides = side_of_line(path, a, b)
        changes = np.flatnonzero(sides[1:] != sides[:-1])
        if len(changes) != 1 or changes[0] <= last_crossing:
            return False
        crossing = path[changes[0] + 1]
        length = float(np.linalg.norm(b - a))
        along = float((crossing - a) @ (b - a)) / length
        if not end_margin_m < along < length - end_margin_m:
            return False
        last_crossing = int(changes[0])
    return True


def route_suits_areas(
    path: FloatArray,
    beacons: Mapping[str, Sequence[float]],
    areas: Sequence[Sequence[str]],
    bounds: tuple[tuple[float, float], tuple[float, float]],
    min_beacon_height_m: float,
    end_margin_m: float,
) -> bool:
    """Whether every beacon stands at least ``min_beacon_height_m`` high, the route stays
    strictly inside ``bounds`` (``((x_min, y_min), (x_max, y_max))``, metres) and it
    :func:`crosses_areas_in_order`."""
    if min(float(position[2]) for position in beacons.values()) < min_beacon_height_m:
        return False
    (x_min, y_min), (x_max, y_max) = bounds
    inside = (
        (path[:, 0] > x_min) & (path[:, 0] < x_max) & (path[:, 1] > y_min) & (path[:, 1] < y_max)
    )
    return bool(np.all(inside)) and crosses_areas_in_order(path, beacons, areas, end_margin_m)


def range_along_route(
    ranger: BeaconRanger,
    world: WorldLike,
    path: npt.ArrayLike,
    beacon_names: Sequence[str],
    rng: np.random.Generator,
    geometry: RouteGeometry | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Range every beacon from every route sample, one ranging round per sample.

    Args:
        ranger: the one-way ranging sensor (its first receiver is the one used).
        world: the world whose emitters are the beacons.
        path: ``(n, 2)`` true receiver positions, metres.
        beacon_names: the beacons, in the column order wanted (e.g.
            :attr:`~sonar_gym.localization.roh.BlockExpansionConfig.beacon_names`).
        rng: the sensor's jitter.
        geometry: ``ranger.route_geometry(world, path, beacon_names)`` if already known
            (the same route among the same beacons again); computed when None.

    Returns:
        ``(ranges, durations)``: ``(n, beacons)`` measured ranges in metres (NaN for a
        dropout) and ``(n,)`` the duration of each sample's ranging round, seconds.
    """
    if geometry is None:
        geometry = ranger.route_geometry(world, path, tuple(beacon_names))
    elif geometry.emitter_names != tuple(beacon_names):
        raise ValueError(
            f"geometry is for the beacons {geometry.emitter_names}, not {tuple(beacon_names)}"
        )
    route = ranger.measure_geometry(geometry, world.temperature_c, rng)
    ranges = route.distances[:, 0, :]
    return np.where(ranges >= 0.0, ranges, np.nan), route.round_durations_s


def draw_beacons_and_route(
    rng: np.random.Generator,
    beacons_m: dict[str, tuple[float, float, float]],
    route: ParabolicRoute,
    areas: Sequence[Sequence[str]],
    bounds: tuple[tuple[float, float], tuple[float, float]],
    *,
    jitter_m: tuple[float, float] | None,
    route_x_end_m: float | None,
    curvature_range_per_m: tuple[float, float],
    min_beacon_height_m: float,
    end_margin_m: float,
    max_tries: int,
) -> tuple[dict[str, tuple[float, float, float]], ParabolicRoute, FloatArray | None]:
    """An episode's beacons and route, redrawn until the route suits the areas.

    Each try moves ``beacons_m`` with :func:`~sonar_gym.maps.jittered_beacons` by
    ``jitter_m = (xy, z)`` metres (None keeps them) and then draws a
    :func:`random_parabolic_route` ending near ``route_x_end_m`` (None keeps ``route``), and
    keeps them if :func:`route_suits_areas`. With neither drawn, or after ``max_tries``
    failed tries, ``beacons_m`` and ``route`` themselves are returned.

    Returns:
        ``(beacons, route, samples)``: ``samples`` is the drawn route's ``sample()``, or None
        when the given route is returned.
    """
    if jitter_m is None and route_x_end_m is None:
        return beacons_m, route, None
    for _ in range(max_tries):
        beacons = beacons_m if jitter_m is None else jittered_beacons(beacons_m, rng, *jitter_m)
        drawn = (
            route
            if route_x_end_m is None
            else random_parabolic_route(rng, route_x_end_m, curvature_range_per_m)
        )
        samples = drawn.sample()
        if route_suits_areas(samples, beacons, areas, bounds, min_beacon_height_m, end_margin_m):
            return beacons, drawn, samples
    return beacons_m, route, None
