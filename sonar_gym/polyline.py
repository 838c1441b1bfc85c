"""A route as a polyline in the world frame {W}, and free routes drawn at random.

:class:`Route` is the path a robot follows (metres, {W}); :func:`draw_free_route` joins free
waypoints by legs the robot disc can drive straight along, as the Kim et al. task uses for its
``route="random"`` episodes.
"""

from __future__ import annotations

import bisect
import functools
import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from sonar_gym.odometry import propagate_covariance
from sonar_gym.pose import FloatArray, Pose, vector_norm
from sonar_gym.robot import ENCODER_COLUMNS, DifferentialDriveRobot, MotionResult
from sonar_gym.world import World

ROUTE_CLEARANCE_M = 0.03
"""Margin beyond the robot radius a drawn route keeps from every obstacle, metres."""
ROUTE_MIN_LEG_M = 0.3
"""Shortest leg of a drawn route, metres."""


@dataclass(frozen=True)
class Route:
    """A polyline in {W} the robot follows (metres).

    Attributes:
        vertices: ``(K, 2)`` corner points, the first one the start.
        cumulative_m: ``(K,)`` route length at each vertex (0 at the start).
    """

    vertices: np.ndarray
    cumulative_m: np.ndarray

    @classmethod
    def through(cls, points: np.ndarray) -> Route:
        vertices = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        lengths = np.linalg.norm(np.diff(vertices, axis=0), axis=1)
        return cls(vertices, np.concatenate([[0.0], np.cumsum(lengths)]))

    @property
    def length_m(self) -> float:
        return float(self.cumulative_m[-1])

    @functools.cached_property
    def _as_floats(self) -> tuple[list[float], list[list[float]]]:
        """``cumulative_m`` and ``vertices`` as Python floats (for :meth:`point_at`)."""
        return self.cumulative_m.tolist(), self.vertices.tolist()

    def point_at(self, s_m: float) -> np.ndarray:
        """The point at route length ``s_m`` (clipped to the route)."""
        return np.array(self.xy_at(s_m))

    def xy_at(self, s_m: float) -> tuple[float, float]:
        """:meth:`point_at` as Python floats ``(x, y)``."""
        cumulative, vertices = self._as_floats
        # min(max(value, low), high) as its two comparisons: the same object, no builtin calls
        end, last = cumulative[-1], len(vertices) - 2
        s = 0.0 if s_m < 0.0 else s_m
        s = end if end < s else s
        index = bisect.bisect_right(cumulative, s) - 1  # np.searchsorted(..., side="right")
        index = 0 if index < 0 else index
        index = last if last < index else index
        span = cumulative[index + 1] - cumulative[index]
        fraction = 0.0 if span <= 0.0 else (s - cumulative[index]) / span
        (x0, y0), (x1, y1) = vertices[index], vertices[index + 1]
        return x0 + fraction * (x1 - x0), y0 + fraction * (y1 - y0)

    def targets_between(self, start_m: float, stop_m: float) -> list[tuple[float, float]]:
        """The vertices strictly between ``start_m`` and ``stop_m`` metres along the route,
        then the point at ``stop_m`` ({W}, metres)."""
        cumulative, vertices = self._as_floats
        # cumulative ascends: the vertices with start < s < stop are one run
        first = bisect.bisect_right(cumulative, start_m)
        stop = bisect.bisect_left(cumulative, stop_m)
        between = [(x, y) for x, y in vertices[first:stop]]
        return [*between, self.xy_at(stop_m)]

    def heading_at_start(self) -> float:
        delta = self.vertices[1] - self.vertices[0]
        return math.atan2(delta[1], delta[0])

    def truncated(self, length_m: float) -> Route:
        """The first ``length_m`` metres of the route."""
        keep = [v for v, s in zip(self.vertices, self.cumulative_m, strict=True) if s < length_m]
        return Route.through(np.array([*keep, self.point_at(length_m)]))


def draw_free_route(world: World, rng: np.random.Generator, length_m: float) -> Route:
    """Free waypoints joined by collision-free legs (at least 0.3 m), up to ``length_m`` metres.

    Every draw comes from ``rng``. Raises ``RuntimeError`` if the scenario has no room for it.
    """
    for _ in range(50):
        points = [world.sample_free_pose(rng, clearance=ROUTE_CLEARANCE_M).position]
        length = 0.0
        for _ in range(200):
            if length >= length_m:
                return Route.through(np.array(points)).truncated(length_m)
            candidate = world.sample_free_pose(rng, clearance=ROUTE_CLEARANCE_M).position
            leg = float(np.linalg.norm(candidate - points[-1]))
            if leg >= ROUTE_MIN_LEG_M and leg_is_free(world, points[-1], candidate):
                points.append(candidate)
                length += leg
    raise RuntimeError(
        f"scenario {world.scenario.name!r}: could not draw a free route of "
        f"{length_m} m; use route='table1' or a roomier scenario"
    )


def leg_is_free(
    world: World,
    start: FloatArray,
    stop: FloatArray,
    margin_m: float | None = None,
    step_m: float = 0.02,
) -> bool:
    """Whether the robot can drive straight from ``start`` to ``stop`` ({W}, metres) keeping
    ``margin_m`` from every obstacle (default: its radius plus :data:`ROUTE_CLEARANCE_M`).

    Checks points every ``step_m`` metres or closer along the leg, both ends included.
    """
    if margin_m is None:
        margin_m = world.robot_radius + ROUTE_CLEARANCE_M
    delta = stop - start
    length = vector_norm(delta)
    count = max(2, math.ceil(length / step_m) + 1)
    start_x, start_y = np.asarray(start, dtype=np.float64).tolist()
    delta_x, delta_y = delta.tolist()
    for fraction in _unit_fractions(count):  # start + fraction * delta, as numpy rounds it
        if not world.is_free(
            (start_x + fraction * delta_x, start_y + fraction * delta_y), margin_m
        ):
            return False
    return True


@functools.lru_cache(maxsize=256)
def _unit_fractions(count: int) -> tuple[float, ...]:
    """``np.linspace(0.0, 1.0, count)`` as floats, shared (legs repeat a few counts)."""
    return tuple(np.linspace(0.0, 1.0, count).tolist())


def draw_polyline(
    image: np.ndarray, points: np.ndarray, to_pixel: Any, colour: tuple[int, int, int]
) -> None:
    """Paint a 2-pixel polyline through world ``points`` onto ``image`` in place."""
    if len(points) < 2:
        return
    height, width = image.shape[:2]
    for start, stop in itertools.pairwise(points):
        (r0, c0), (r1, c1) = to_pixel(start), to_pixel(stop)
        count = max(abs(r1 - r0), abs(c1 - c0), 1) + 1
        rows = np.rint(np.linspace(r0, r1, count)).astype(int)
        cols = np.rint(np.linspace(c0, c1, count)).astype(int)
        for dr in (0, 1):
            for dc in (0, 1):
                keep = (
                    (rows + dr >= 0) & (rows + dr < height) & (cols + dc >= 0) & (cols + dc < width)
                )
                image[rows[keep] + dr, cols[keep] + dc] = colour


def draw_equal_legs(
    world: World,
    rng: np.random.Generator,
    n_legs: int,
    leg_length_m: float,
    clearance_m: float,
    fallback_towards: FloatArray,
    tries: int = 200,
) -> FloatArray:
    """``n_legs + 1`` points in {W}: a free start, then legs of ``leg_length_m`` in random
    directions that keep the robot ``clearance_m`` beyond its radius from every obstacle.

    A leg that finds no free direction in ``tries`` draws heads for ``fallback_towards`` (the
    middle of the free space). Every draw comes from ``rng``.
    """
    margin = world.robot_radius + clearance_m
    points = [world.sample_free_pose(rng, clearance=clearance_m).position]
    for _ in range(n_legs):
        here = points[-1]
        here_x, here_y = here.tolist()
        for _ in range(tries):
            direction = float(rng.uniform(-math.pi, math.pi))
            candidate = np.array(
                [
                    here_x + leg_length_m * math.cos(direction),
                    here_y + leg_length_m * math.sin(direction),
                ]
            )
            if leg_is_free(world, here, candidate, margin, step_m=0.1):
                break
        else:
            towards = fallback_towards - here
            towards = towards / max(float(np.linalg.norm(towards)), 1e-9)
            candidate = here + leg_length_m * towards
        points.append(candidate)
    return np.array(points)


def densify(points: FloatArray, spacing_m: float) -> list[tuple[float, float]]:
    """Points every ``spacing_m`` metres along the polyline ``points`` (to draw it as dots)."""
    dense: list[tuple[float, float]] = []
    for start, end in itertools.pairwise(points):
        steps = max(1, math.ceil(float(np.linalg.norm(end - start)) / spacing_m))
        for t in np.arange(steps) / steps:
            x, y = start + t * (end - start)
            dense.append((float(x), float(y)))
    dense.append((float(points[-1][0]), float(points[-1][1])))
    return dense


@dataclass(frozen=True)
class FollowedLeg:
    """The belief after :func:`follow_route`.

    Attributes:
        estimate: the EKF prediction at the end ({W}; metres, radians).
        covariance: its 3x3 covariance over ``[x, y, theta]``.
        rolled_m: the mean wheel travel ``(|d_l| + |d_r|) / 2`` of each elementary command,
            metres, in order.
    """

    estimate: Pose
    covariance: FloatArray
    rolled_m: tuple[float, ...]


def follow_route(
    robot: DifferentialDriveRobot,
    world: World,
    route: Route,
    span_m: tuple[float, float],
    estimate: Pose,
    covariance: FloatArray,
    variance_per_m: float,
    rng: np.random.Generator,
) -> FollowedLeg:
    """Drive along ``route`` from ``span_m[0]`` to ``span_m[1]`` metres, steering from the belief.

    Each vertex in between, then the point at ``span_m[1]``, is reached by
    :meth:`DifferentialDriveRobot.move_to` planned from the current estimate; the EKF predicts
    over every motion's encoder increments (Kim et al. sec. 3.1 eqs. (5)-(6),
    :func:`sonar_gym.odometry.predict_over_motion` with ``V`` of ``variance_per_m`` m^2 per
    metre rolled).
    """
    variance = float(variance_per_m)
    covariance = np.asarray(covariance, dtype=np.float64)
    rolled: list[float] = []
    for target in route.targets_between(*span_m):
        motions, estimate, covariance = robot.drive_to_and_predict(
            world, target, rng, estimate, covariance, variance
        )
        increments = motions[:, ENCODER_COLUMNS].tolist()
        rolled += [0.5 * (abs(left) + abs(right)) for left, right in increments]
    return FollowedLeg(estimate, covariance, tuple(rolled))


@dataclass(frozen=True)
class DeadReckonedLeg:
    """One leg driven by :func:`drive_leg_dead_reckoned`.

    Attributes:
        motion: the robot's motion (its parts: the turn, then the straight).
        covariance: the dead-reckoning covariance at its end (3x3, ``[x, y, theta]``).
        drive_time_s: forward travel over the speed plus turning over the turn rate, seconds.
        travelled_m: the forward encoder travel ``|d_l + d_r| / 2`` summed over the parts, m.
    """

    motion: MotionResult
    covariance: FloatArray
    drive_time_s: float
    travelled_m: float


def drive_leg_dead_reckoned(
    robot: DifferentialDriveRobot,
    world: World,
    target_xy: FloatArray,
    covariance: FloatArray,
    encoder_variance_per_m: float,
    scale_error_variance: float,
    speed_mps: float,
    turn_rate_rad_s: float,
    rng: np.random.Generator,
) -> DeadReckonedLeg:
    """Turn toward ``target_xy`` ({W}) and drive to it, planned from the odometry estimate.

    The covariance follows every part through the odometry model of Kim et al. sec. 3.1
    (:func:`sonar_gym.odometry.propagate_covariance`, midpoint integration): encoder variance
    ``encoder_variance_per_m |d|`` plus ``scale_error_variance d^2`` per wheel and command.
    """
    wheel_base = robot.wheel_base_for(world)
    estimate_before = robot.odometry_pose or world.robot_pose  # the belief move_to plans from
    motion = robot.move_to(world, (float(target_xy[0]), float(target_xy[1])), rng)
    parts = motion.parts or (motion,)
    covariance = propagate_covariance(
        [estimate_before, *(part.odometry_pose for part in parts[:-1])],
        [(part.encoder_left_m, part.encoder_right_m) for part in parts],
        covariance,
        wheel_base,
        encoder_variance_per_m,
        scale_error_variance,
        integration="midpoint",
    )
    drive_time = 0.0
    travelled = 0.0
    for part in parts:
        forward = 0.5 * abs(part.encoder_left_m + part.encoder_right_m)
        turn = abs(part.encoder_right_m - part.encoder_left_m) / wheel_base
        drive_time += forward / speed_mps + turn / turn_rate_rad_s
        travelled += forward
    return DeadReckonedLeg(motion, covariance, drive_time, travelled)


__all__ = [
    "DeadReckonedLeg",
    "ROUTE_CLEARANCE_M",
    "ROUTE_MIN_LEG_M",
    "Route",
    "draw_free_route",
    "draw_polyline",
    "drive_leg_dead_reckoned",
    "leg_is_free",
]
