"""Differential-drive kinematics, odometry noise and wheel slip.

The motion model is that of Kim, Lee & Jeong, section 3.1 (after Komoriya et al.): with the
wheel increments ``d_r = T u_r`` and ``d_l = T u_l`` over one sampling period ``T``,

    x(k+1)     = x(k) + (d_r + d_l)/2 cos(theta(k))
    y(k+1)     = y(k) + (d_r + d_l)/2 sin(theta(k))
    theta(k+1) = theta(k) + (d_r - d_l)/l

where ``l`` is the wheel base. The paper's ``F(k)`` prints ``T/1`` in its last row; it is
``T/l``, the derivative of the heading equation above, and the heading change here divides by
the wheel base.

:func:`unicycle_step` offers three integrations of the same model: ``"euler"`` (the equations
exactly as printed), ``"midpoint"`` (the second-order form ``x += d cos(theta + dtheta/2)``,
the default) and ``"arc"`` (exact for constant wheel speeds: the centre moves along a circular
arc, ``x += d sinc(dtheta/2) cos(theta + dtheta/2)``). All three agree exactly for a straight
move and for a turn in place, and converge as the increments shrink.

:class:`DifferentialDriveRobot` executes commanded wheel increments: the *true* motion (with
wheel scale errors and slip) runs through the pymunk world, so walls stop it; the *odometry*
integrates the encoder increments (commanded plus encoder noise), which see neither slip nor a
blocked robot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pymunk

from sonar_gym.odometry import (
    INTEGRATIONS,
    Integration,
    OdometryConfig,
    arc_displacements,
    integrate_substeps,
    sinc,
)
from sonar_gym.pose import Pose, angle_difference
from sonar_gym.world import STATIC_ONLY, World


def unicycle_step(
    pose: Pose,
    d_left_m: float,
    d_right_m: float,
    wheel_base_m: float,
    integration: Integration = "midpoint",
) -> Pose:
    """Advance ``pose`` by wheel increments of a differential-drive robot (Kim et al. sec. 3.1).

    Args:
        pose: the pose before the step ({W}; metres, radians).
        d_left_m, d_right_m: distance rolled by the left and right wheel, metres (``T u_l`` and
            ``T u_r`` of the paper); positive is forward.
        wheel_base_m: distance between the wheels ``l``, metres (> 0).
        integration: ``"euler"``: the printed equations, ``x += d cos(theta)``; ``"midpoint"``:
            ``x += d cos(theta + dtheta/2)``; ``"arc"``: the exact circular arc.
            ``d = (d_r + d_l)/2`` and ``dtheta = (d_r - d_l)/l`` in all three.

    Returns:
        the pose after the step, heading wrapped to (-pi, pi].
    """
    if integration not in INTEGRATIONS:
        raise ValueError(
            f"argument 'integration' must be one of {list(INTEGRATIONS)}; got {integration!r}"
        )
    wheel_base_m = float(wheel_base_m)
    if not math.isfinite(wheel_base_m) or wheel_base_m <= 0.0:
        raise ValueError(
            f"argument 'wheel_base_m' must be a finite positive number (metres); "
            f"got {wheel_base_m!r}"
        )
    d_left_m, d_right_m = float(d_left_m), float(d_right_m)
    if not (math.isfinite(d_left_m) and math.isfinite(d_right_m)):
        raise ValueError(
            f"wheel increments must be finite (metres); got {d_left_m!r}, {d_right_m!r}"
        )
    distance = 0.5 * (d_right_m + d_left_m)
    dtheta = (d_right_m - d_left_m) / wheel_base_m
    if integration == "euler":
        direction, length = pose.theta, distance
    else:
        direction = pose.theta + 0.5 * dtheta
        length = distance * (sinc(0.5 * dtheta) if integration == "arc" else 1.0)
    return Pose(
        pose.x + length * math.cos(direction),
        pose.y + length * math.sin(direction),
        pose.theta + dtheta,
    )


OdometryNoise = OdometryConfig
"""The robot's odometry errors: :class:`sonar_gym.odometry.OdometryConfig` (one vocabulary)."""

PATH_CLEARANCE_M = 1e-3
"""A command whose swept disc stays this far (metres) beyond the robot radius from every static
shape meets no contact, so it is integrated without stepping the physics."""


@dataclass(frozen=True)
class MotionResult:
    """Outcome of one command of :class:`DifferentialDriveRobot`.

    Attributes:
        true_pose: the robot's true pose afterwards ({W}; metres, radians).
        odometry_pose: the dead-reckoning estimate afterwards, from the encoder increments.
        collided: whether the robot touched and pushed against a static shape.
        distance_m: path length of the true robot centre, metres.
        encoder_left_m, encoder_right_m: the encoder increments the odometry integrated,
            metres (the ``T u_l``, ``T u_r`` of Kim et al.; summed over the parts of a
            compound move).
        parts: for compound moves (:meth:`DifferentialDriveRobot.move_to`), the result of each
            elementary command; empty otherwise.
    """

    true_pose: Pose
    odometry_pose: Pose
    collided: bool
    distance_m: float
    encoder_left_m: float = 0.0
    encoder_right_m: float = 0.0
    parts: tuple[MotionResult, ...] = field(default=())


class DifferentialDriveRobot:
    """A differential-drive robot that moves a :class:`~sonar_gym.world.World`'s body.

    Args:
        noise: the odometry, scale and slip errors (:class:`OdometryNoise`).
        wheel_base_m: wheel base in metres; ``None`` takes the scenario's
            ``robot.wheel_base`` at each command.
        odometry_integration: how the odometry integrates encoder increments (see
            :func:`unicycle_step`), applied per substep.
        max_substep_m: largest wheel travel per physics substep, metres; together with
            ``max_substep_rad`` sets the number of substeps of a command.
        max_substep_rad: largest heading change per physics substep, radians.
        odometry_pose: the initial dead-reckoning estimate; ``None`` starts it at the true pose
            at the first command (a robot put down at a known pose).
    """

    def __init__(
        self,
        noise: OdometryNoise | None = None,
        *,
        wheel_base_m: float | None = None,
        odometry_integration: Integration = "midpoint",
        max_substep_m: float = 0.02,
        max_substep_rad: float = math.radians(3.0),
        odometry_pose: Pose | None = None,
    ) -> None:
        self.noise = OdometryNoise() if noise is None else noise
        if not isinstance(self.noise, OdometryNoise):
            raise ValueError(
                f"argument 'noise' must be an OdometryNoise; got {type(noise).__name__}"
            )
        if wheel_base_m is not None and (not math.isfinite(wheel_base_m) or wheel_base_m <= 0.0):
            raise ValueError(
                "argument 'wheel_base_m' must be a positive number (metres) or None; "
                f"got {wheel_base_m!r}"
            )
        if odometry_integration not in INTEGRATIONS:
            raise ValueError(
                f"argument 'odometry_integration' must be one of {list(INTEGRATIONS)}; "
                f"got {odometry_integration!r}"
            )
        for name, value in (("max_substep_m", max_substep_m), ("max_substep_rad", max_substep_rad)):
            if not math.isfinite(value) or value <= 0.0:
                raise ValueError(
                    f"argument '{name}' must be a finite positive number; got {value!r}"
                )
        self.wheel_base_m = wheel_base_m
        self.odometry_integration: Integration = odometry_integration
        self.max_substep_m = float(max_substep_m)
        self.max_substep_rad = float(max_substep_rad)
        self.odometry_pose: Pose | None = odometry_pose

    def reset_odometry(self, pose: Pose | None) -> None:
        """Set the dead-reckoning estimate (``None``: the true pose at the next command)."""
        if pose is not None and not isinstance(pose, Pose):
            raise ValueError(f"argument 'pose' must be a Pose or None; got {type(pose).__name__}")
        self.odometry_pose = pose

    def wheel_base_for(self, world: World) -> float:
        """The wheel base used with ``world``, metres."""
        return (
            self.wheel_base_m if self.wheel_base_m is not None else world.scenario.robot.wheel_base
        )

    # --- elementary command ----------------------------------------------------------------

    def drive(
        self,
        world: World,
        d_left_m: float,
        d_right_m: float,
        rng: np.random.Generator,
        substeps: int | None = None,
    ) -> MotionResult:
        """Command wheel increments; move the true robot through pymunk and update odometry.

        Each call draws exactly two standard normals (encoder noise, left then right) and four
        uniforms (slip occurrence left/right, slip size left/right) from ``rng``, whatever the
        noise settings, so the random stream stays aligned across settings.

        Args:
            world: the world whose robot body moves.
            d_left_m, d_right_m: commanded wheel increments, metres.
            rng: the only source of randomness.
            substeps: physics substeps; ``None`` picks enough that no wheel travels more than
                ``max_substep_m`` and the heading changes by at most ``max_substep_rad`` per
                substep.
        """
        d_left_m, d_right_m = float(d_left_m), float(d_right_m)
        if not (math.isfinite(d_left_m) and math.isfinite(d_right_m)):
            raise ValueError(
                f"wheel increments must be finite (metres); got {d_left_m!r}, {d_right_m!r}"
            )
        if not isinstance(rng, np.random.Generator):
            raise ValueError(
                f"argument 'rng' must be a numpy.random.Generator; got {type(rng).__name__}"
            )
        wheel_base = self.wheel_base_for(world)
        noise = self.noise
        normal_left, normal_right = rng.standard_normal(2).tolist()
        slip_left, slip_right, size_left, size_right = rng.random(4).tolist()

        # Per wheel in plain floats (two-element arrays cost more than the arithmetic).
        encoder = (
            float(noise.encoder_increments(d_left_m, normal_left)),
            float(noise.encoder_increments(d_right_m, normal_right)),
        )
        ground = (
            float(noise.ground_travel(d_left_m, noise.scale_error_left, slip_left, size_left)),
            float(noise.ground_travel(d_right_m, noise.scale_error_right, slip_right, size_right)),
        )

        n = self._substep_count(ground, encoder, wheel_base, substeps)
        start = world.robot_pose
        odometry_start = start if self.odometry_pose is None else self.odometry_pose

        arc_end = integrate_substeps(start, ground[0], ground[1], wheel_base, 1, "arc")
        if _path_is_clear(world, start, ground, wheel_base, arc_end):
            true_pose, collided, path_length = _free_motion(world, arc_end, ground, wheel_base, n)
        else:
            outcome = world.move_robot(
                arc_displacements(start, ground[0], ground[1], wheel_base, n)
            )
            true_pose, collided, path_length = outcome.pose, outcome.collided, outcome.path_length_m

        odometry = integrate_substeps(
            odometry_start, encoder[0], encoder[1], wheel_base, n, self.odometry_integration
        )
        self.odometry_pose = odometry
        return MotionResult(
            true_pose=true_pose,
            odometry_pose=odometry,
            collided=collided,
            distance_m=path_length,
            encoder_left_m=float(encoder[0]),
            encoder_right_m=float(encoder[1]),
        )

    def _substep_count(
        self,
        ground: tuple[float, float],
        encoder: tuple[float, float],
        wheel_base: float,
        substeps: int | None,
    ) -> int:
        if substeps is not None:
            if int(substeps) != substeps or substeps < 1:
                raise ValueError(
                    f"argument 'substeps' must be a positive integer or None; got {substeps!r}"
                )
            return int(substeps)
        travel = max(abs(ground[0]), abs(ground[1]), abs(encoder[0]), abs(encoder[1]))
        turn = abs(float(ground[1] - ground[0])) / wheel_base
        return max(
            1, math.ceil(travel / self.max_substep_m), math.ceil(turn / self.max_substep_rad)
        )

    # --- convenience commands -----------------------------------------------------------

    def drive_straight(
        self, world: World, distance_m: float, rng: np.random.Generator
    ) -> MotionResult:
        """Roll both wheels by ``distance_m`` metres (negative: backwards)."""
        return self.drive(world, distance_m, distance_m, rng)

    def turn(self, world: World, angle_rad: float, rng: np.random.Generator) -> MotionResult:
        """Turn in place by ``angle_rad`` radians (counter-clockwise positive)."""
        half = 0.5 * float(angle_rad) * self.wheel_base_for(world)
        return self.drive(world, -half, half, rng)

    def move_to(
        self,
        world: World,
        target: Pose | tuple[float, float],
        rng: np.random.Generator,
        *,
        from_pose: Pose | None = None,
    ) -> MotionResult:
        """Turn towards ``target``, drive straight to it, then turn to its heading (if a Pose).

        The plan is made from ``from_pose`` (default: the odometry estimate, or the true pose
        if odometry was never set), as a robot plans from its belief; noise and walls make the
        true end pose differ. Each part is one :meth:`drive` command.
        """
        if from_pose is not None:
            belief = from_pose
        elif self.odometry_pose is not None:
            belief = self.odometry_pose
        else:
            belief = world.robot_pose
        if isinstance(target, Pose):
            target_xy, target_heading = (target.x, target.y), target.theta
        else:
            tx, ty = np.asarray(target, dtype=np.float64).reshape(2)
            target_xy, target_heading = (float(tx), float(ty)), None
        dx, dy = target_xy[0] - belief.x, target_xy[1] - belief.y
        distance = math.hypot(dx, dy)
        parts: list[MotionResult] = []
        heading = belief.theta
        if distance > 1e-9:
            bearing = math.atan2(dy, dx)
            parts.append(self.turn(world, angle_difference(bearing, heading), rng))
            parts.append(self.drive_straight(world, distance, rng))
            heading = bearing
        if target_heading is not None:
            parts.append(self.turn(world, angle_difference(target_heading, heading), rng))
        if not parts:
            parts.append(self.drive(world, 0.0, 0.0, rng))
        return MotionResult(
            true_pose=parts[-1].true_pose,
            odometry_pose=parts[-1].odometry_pose,
            collided=any(p.collided for p in parts),
            distance_m=sum(p.distance_m for p in parts),
            encoder_left_m=sum(p.encoder_left_m for p in parts),
            encoder_right_m=sum(p.encoder_right_m for p in parts),
            parts=tuple(parts),
        )


def _path_is_clear(
    world: World,
    start: Pose,
    ground: tuple[float, float],
    wheel_base_m: float,
    end: Pose | None = None,
) -> bool:
    """Whether the robot disc can follow the planned arc without touching a static shape.

    The arc of length ``L`` turning by ``phi`` lies within its sagitta ``<= L |phi| / 8`` of
    its chord, so the disc of the robot radius plus that sagitta plus :data:`PATH_CLEARANCE_M`
    swept along the chord (``start`` to ``end``, the arc's end, integrated here if not given)
    covers every position the body takes. pymunk's bounding-box index
    picks the shapes near the chord; their exact distance to it decides.
    """
    turned = abs(float(ground[1] - ground[0])) / wheel_base_m
    if turned > math.pi:
        return False
    arc_length = 0.5 * abs(float(ground[0] + ground[1]))
    if end is None:
        end = integrate_substeps(start, float(ground[0]), float(ground[1]), wheel_base_m, 1, "arc")
    radius = world.robot_radius + arc_length * turned / 8.0 + PATH_CLEARANCE_M
    a = (start.x, start.y)
    b = (end.x, end.y)
    box = pymunk.BB(
        min(a[0], b[0]) - radius,
        min(a[1], b[1]) - radius,
        max(a[0], b[0]) + radius,
        max(a[1], b[1]) + radius,
    )
    for shape in world.space.bb_query(box, STATIC_ONLY):
        if isinstance(shape, pymunk.Segment):
            p, q = (shape.a.x, shape.a.y), (shape.b.x, shape.b.y)
            gap = _segment_distance(a, b, p, q) - shape.radius
        elif isinstance(shape, pymunk.Circle) and shape.body is not None:
            centre = shape.body.local_to_world(shape.offset)
            gap = _point_segment_distance((centre.x, centre.y), a, b) - shape.radius
        else:  # a shape this check does not know: let the physics decide
            return False
        if gap <= radius:
            return False
    return True


def _point_segment_distance(
    point: tuple[float, float], a: tuple[float, float], b: tuple[float, float]
) -> float:
    ex, ey = b[0] - a[0], b[1] - a[1]
    length2 = ex * ex + ey * ey
    t = 0.0 if length2 == 0.0 else ((point[0] - a[0]) * ex + (point[1] - a[1]) * ey) / length2
    t = min(max(t, 0.0), 1.0)
    return math.hypot(point[0] - a[0] - t * ex, point[1] - a[1] - t * ey)


def _segment_distance(
    a: tuple[float, float], b: tuple[float, float], p: tuple[float, float], q: tuple[float, float]
) -> float:
    """Shortest distance between the segments ``ab`` and ``pq`` (0 if they cross), metres."""

    def side(o: tuple[float, float], u: tuple[float, float], v: tuple[float, float]) -> float:
        return (u[0] - o[0]) * (v[1] - o[1]) - (u[1] - o[1]) * (v[0] - o[0])

    if side(a, b, p) * side(a, b, q) < 0.0 and side(p, q, a) * side(p, q, b) < 0.0:
        return 0.0
    return min(
        _point_segment_distance(a, p, q),
        _point_segment_distance(b, p, q),
        _point_segment_distance(p, a, b),
        _point_segment_distance(q, a, b),
    )


def _free_motion(
    world: World, end: Pose, ground: tuple[float, float], wheel_base_m: float, substeps: int
) -> tuple[Pose, bool, float]:
    """The outcome of :meth:`World.move_robot` along the arc when no contact can occur.

    With no contact the body integrates the imposed velocities exactly: it ends where the arc
    ends (``end``), and its centre travels the ``n`` chords of the substeps, each ``|d / n|
    sinc(delta / 2)`` long (``d`` the centre's arc length, ``delta`` the substep's turn).
    """
    left, right = float(ground[0]), float(ground[1])
    pose = end
    world.place_robot_on_clear_path(pose)  # _path_is_clear has shown the end free
    half_turn = 0.5 * (right - left) / (wheel_base_m * substeps)
    path_length = abs(0.5 * (left + right)) * abs(sinc(half_turn))
    return pose, False, path_length


__all__ = [
    "DifferentialDriveRobot",
    "INTEGRATIONS",
    "MotionResult",
    "OdometryConfig",
    "OdometryNoise",
    "unicycle_step",
]
