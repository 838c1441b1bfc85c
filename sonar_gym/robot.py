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
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from sonar_gym import drive_kernels
from sonar_gym.odometry import (
    INTEGRATIONS,
    Integration,
    OdometryConfig,
    arc_displacements,
    sinc,
)
from sonar_gym.pose import FloatArray, Pose, angle_difference
from sonar_gym.world import World


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


@dataclass(frozen=True)
class CommandRun:
    """The outcome of :meth:`DifferentialDriveRobot.drive_commands` over its ``K`` commands.

    Attributes:
        motions: ``(K, MOTION_COLUMNS)`` the motion table of
            :func:`sonar_gym.drive_kernels.drive_commands`: per command the encoder
            increments the odometry integrated and the ground travel (metres), the substeps,
            the odometry pose and the true pose afterwards ({W}; metres, radians) and the path
            length of the true robot centre (metres).
        collided: ``(K,)`` whether the robot touched and pushed against a static shape.
        true_pose, odometry_pose: the true and the odometry pose after the last command
            (None if there is none).
    """

    motions: FloatArray
    collided: np.ndarray
    true_pose: Pose | None = None
    odometry_pose: Pose | None = None

    @property
    def encoder_m(self) -> FloatArray:
        """``(K, 2)`` the encoder increments ``(left, right)``, metres."""
        return self.motions[:, ENCODER_COLUMNS]

    def result(self, command: int) -> MotionResult:
        """Command ``command``'s :class:`MotionResult`."""
        row = self.motions[command].tolist()
        if (
            command in (-1, len(self.motions) - 1)
            and self.true_pose is not None
            and self.odometry_pose is not None
        ):
            true_pose, odometry_pose = self.true_pose, self.odometry_pose
        else:
            true_pose = Pose.unchecked(*row[_TRUE_POSE])
            odometry_pose = Pose.unchecked(*row[_ODOMETRY])
        return MotionResult(
            true_pose=true_pose,
            odometry_pose=odometry_pose,
            collided=bool(self.collided[command]),
            distance_m=row[drive_kernels.PATH_LENGTH],
            encoder_left_m=row[drive_kernels.ENCODER],
            encoder_right_m=row[drive_kernels.ENCODER + 1],
        )


_WheelArguments = tuple[
    FloatArray,  # noise
    float,  # wheel_base_m
    int,  # substeps
    int,  # integration
    tuple[float, float, float],  # odometry
    tuple[float, float, float],  # start
    float,  # robot_radius_m
    FloatArray,  # bounds
    np.ndarray,  # kinds
    FloatArray,  # shapes
]
"""The arguments of :func:`sonar_gym.drive_kernels.drive_commands` from ``noise`` on."""

ENCODER_COLUMNS = slice(drive_kernels.ENCODER, drive_kernels.ENCODER + 2)
"""The motion table's columns of the encoder increments ``(left, right)``, metres."""
# its columns of the other quantities
_GROUND = slice(drive_kernels.GROUND, drive_kernels.GROUND + 2)
_ODOMETRY = slice(drive_kernels.ODOMETRY, drive_kernels.ODOMETRY + 3)
_TRUE_POSE = slice(drive_kernels.TRUE_POSE, drive_kernels.TRUE_POSE + 3)


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
        # the last noise array of the kernels and what it was made from (_noise_arguments)
        self._kept_noise: tuple[OdometryNoise, float, float, FloatArray] | None = None

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
        run = self.drive_commands(world, ((d_left_m, d_right_m),), rng, substeps)
        return run.result(0)

    def drive_commands(
        self,
        world: World,
        commands_m: Sequence[tuple[float, float]] | FloatArray,
        rng: np.random.Generator,
        substeps: int | None = None,
    ) -> CommandRun:
        """:meth:`drive` each ``(d_left, d_right)`` of ``commands_m`` (metres) in turn.

        The wheels (draws, encoder noise, slip, substeps, odometry) run in one compiled loop
        (:func:`sonar_gym.drive_kernels.drive_commands`); so does the true motion while each
        command's arc is clear of the static shapes (:func:`sonar_gym.drive_kernels.clear_arcs`,
        where pymunk would impose the arc exactly). A command that may touch a shape goes
        through pymunk (:meth:`World.move_robot`). The body is placed at the end of a clear
        stretch only once, as the teleports in between leave no trace.
        """
        commands = np.asarray(commands_m, dtype=np.float64).reshape(-1, 2)
        if not all(map(math.isfinite, commands.ravel().tolist())):
            bad = commands[~np.isfinite(commands).all(axis=1)][0].tolist()
            raise ValueError(
                f"wheel increments must be finite (metres); got {bad[0]!r}, {bad[1]!r}"
            )
        if not isinstance(rng, np.random.Generator):
            raise ValueError(
                f"argument 'rng' must be a numpy.random.Generator; got {type(rng).__name__}"
            )
        fixed_substeps = 0 if substeps is None else _checked_substeps(substeps)
        if len(commands) == 0:
            return CommandRun(np.empty((0, drive_kernels.MOTION_COLUMNS)), np.zeros(0, dtype=bool))
        motions, collided, pose = self.drive_commands_unchecked(
            world, commands, rng, fixed_substeps
        )
        return CommandRun(motions, collided, pose, self.odometry_pose)

    def drive_commands_unchecked(
        self,
        world: World,
        commands_m: FloatArray,
        rng: np.random.Generator,
        substeps: int = 0,
    ) -> tuple[FloatArray, np.ndarray, Pose]:
        """:meth:`drive_commands` on checked arguments: ``(K, 2)`` finite float64 increments
        (metres, ``K >= 1``), a ``Generator`` and ``substeps`` (0: picked per command).

        Returns the motion table (:attr:`CommandRun.motions`), the ``(K,)`` collisions and the
        true pose after the last command.
        """
        start = world.robot_pose
        motions, blocked = drive_kernels.drive_commands(
            commands_m,
            _command_draws(rng, len(commands_m)),
            *self._wheel_arguments(world, substeps, start),
        )
        collided, pose = self._physics_after(world, motions, blocked, start)
        return motions, collided, pose

    def drive_to_and_predict(
        self,
        world: World,
        target_xy: tuple[float, float],
        rng: np.random.Generator,
        estimate: Pose,
        covariance: FloatArray,
        variance_per_m: float,
    ) -> tuple[FloatArray, Pose, FloatArray]:
        """:meth:`drive_commands_unchecked` (substeps picked per command) of the commands
        :func:`move_commands` plans from ``estimate`` to the point ``target_xy`` (Python floats,
        {W}, metres; no heading), with the wheel base used with ``world``, and the EKF
        prediction over their encoder increments from ``estimate`` and its float64 3x3
        ``covariance`` (:func:`sonar_gym.odometry.predict_over_motion`, paper Jacobians, ``V``
        of ``variance_per_m`` m^2 per metre rolled): planned, drawn, driven and predicted in
        one compiled call (:func:`sonar_gym.drive_kernels.drive_to_and_predict`).

        Returns the motion table, the predicted pose after the last command and its covariance.
        """
        start = world.robot_pose
        belief = (estimate.x, estimate.y, estimate.theta)
        distance = math.hypot(target_xy[0] - belief[0], target_xy[1] - belief[1])
        motions, blocked, predicted, predicted_covariance = drive_kernels.drive_to_and_predict(
            rng,
            target_xy,
            distance,
            *self._wheel_arguments(world, 0, start),
            belief,
            covariance,
            variance_per_m,
        )
        self._finish_drive(world, motions, blocked, start)
        return motions, Pose.unchecked(*predicted), predicted_covariance

    def _finish_drive(self, world: World, motions: FloatArray, blocked: int, start: Pose) -> None:
        """Move the body and set the odometry after the compiled drive of the motion table
        ``motions`` from the true pose ``start``, whose commands from ``blocked`` on need the
        physics."""
        if blocked == len(motions):  # every command clear of the shapes: no physics
            last = motions[-1].tolist()
            world.place_robot_on_clear_path(Pose.unchecked(*last[_TRUE_POSE]))
            self.odometry_pose = Pose.unchecked(*last[_ODOMETRY])
        else:
            self._physics_after(world, motions, blocked, start)

    def _wheel_arguments(self, world: World, substeps: int, start: Pose) -> _WheelArguments:
        """The arguments of :func:`sonar_gym.drive_kernels.drive_commands` after the commands
        and their draws, for a drive from the true pose ``start``: from ``noise`` on."""
        odometry = start if self.odometry_pose is None else self.odometry_pose
        table = world.static_shape_table
        return (
            self._noise_arguments(),
            float(self.wheel_base_for(world)),
            substeps,
            INTEGRATIONS.index(self.odometry_integration),
            (odometry.x, odometry.y, odometry.theta),
            (start.x, start.y, start.theta),
            float(world.robot_radius),
            table.bounds,
            table.kinds,
            table.shapes,
        )

    def _noise_arguments(self) -> FloatArray:
        """The ``noise`` array of :func:`sonar_gym.drive_kernels.drive_commands`: the odometry
        errors, then the substep limits (metres, radians). Kept (read-only) while ``noise``
        (frozen) is the same object and the limits keep their values."""
        noise, max_substep_m, max_substep_rad = self.noise, self.max_substep_m, self.max_substep_rad
        kept = self._kept_noise
        if (
            kept is not None
            and kept[0] is noise
            and kept[1] == max_substep_m
            and kept[2] == max_substep_rad
        ):
            return kept[3]
        array = np.array(
            (
                noise.encoder_std_m_per_sqrt_m,
                noise.scale_error_left,
                noise.scale_error_right,
                noise.slip_probability_per_m,
                noise.slip_fraction_max,
                max_substep_m,
                max_substep_rad,
            ),
            dtype=np.float64,
        )
        array.flags.writeable = False
        self._kept_noise = (noise, max_substep_m, max_substep_rad, array)
        return array

    def _physics_after(
        self, world: World, motions: FloatArray, blocked: int, start: Pose
    ) -> tuple[np.ndarray, Pose]:
        """Complete the motion table ``motions`` of a drive from ``start`` whose commands from
        ``blocked`` on need the physics: place the body, move it through pymunk where a command
        may touch a shape, set the odometry. Returns the collisions and the final true pose."""
        count = len(motions)
        collided = np.zeros(count, dtype=bool)
        pose, first = start, 0
        while True:
            if blocked > first:
                pose = Pose.unchecked(*motions[blocked - 1, _TRUE_POSE].tolist())
                world.place_robot_on_clear_path(pose)
            if blocked == count:
                break
            wheel_base = float(self.wheel_base_for(world))
            radius = float(world.robot_radius)
            table = world.static_shape_table
            left, right = motions[blocked, _GROUND].tolist()
            substeps_here = int(motions[blocked, drive_kernels.SUBSTEPS])
            outcome = world.move_robot(
                arc_displacements(pose, left, right, wheel_base, substeps_here)
            )
            pose = outcome.pose
            motions[blocked, _TRUE_POSE] = (pose.x, pose.y, pose.theta)
            motions[blocked, drive_kernels.PATH_LENGTH] = outcome.path_length_m
            collided[blocked] = outcome.collided
            first = blocked + 1
            blocked = drive_kernels.clear_arcs(
                motions, first, (pose.x, pose.y, pose.theta), wheel_base, radius, *table.arrays
            )
        self.odometry_pose = Pose.unchecked(*motions[-1, _ODOMETRY].tolist())
        return collided, pose

    # --- convenience commands -----------------------------------------------------------

    def drive_straight(
        self, world: World, distance_m: float, rng: np.random.Generator
    ) -> MotionResult:
        """Roll both wheels by ``distance_m`` metres (negative: backwards)."""
        return self.drive(world, distance_m, distance_m, rng)

    def turn(self, world: World, angle_rad: float, rng: np.random.Generator) -> MotionResult:
        """Turn in place by ``angle_rad`` radians (counter-clockwise positive)."""
        return self.drive(world, *_turn_in_place(angle_rad, self.wheel_base_for(world)), rng)

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
        true end pose differ. Each part is one :meth:`drive` command (:meth:`plan_move`).
        """
        run = self.drive_commands(world, self.plan_move(world, target, from_pose), rng)
        parts = [run.result(command) for command in range(len(run.collided))]
        return MotionResult(
            true_pose=parts[-1].true_pose,
            odometry_pose=parts[-1].odometry_pose,
            collided=any(p.collided for p in parts),
            distance_m=sum(p.distance_m for p in parts),
            encoder_left_m=sum(p.encoder_left_m for p in parts),
            encoder_right_m=sum(p.encoder_right_m for p in parts),
            parts=tuple(parts),
        )

    def plan_move(
        self, world: World, target: Pose | tuple[float, float], from_pose: Pose | None = None
    ) -> list[tuple[float, float]]:
        """The ``(d_left, d_right)`` commands (metres) of :meth:`move_to`: the turn towards
        ``target`` and the straight to it (none if it is within 1 nm), then the turn to its
        heading if it is a Pose; one command of no travel if that leaves none. Planned from
        ``from_pose`` (default: the odometry estimate, or the true pose if odometry was never
        set)."""
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
        return move_commands(belief, target_xy, self.wheel_base_for(world), target_heading)


def move_commands(
    belief: Pose,
    target_xy: tuple[float, float],
    wheel_base_m: float,
    target_heading: float | None = None,
) -> list[tuple[float, float]]:
    """:meth:`DifferentialDriveRobot.plan_move` from ``belief`` ({W}) to the point
    ``target_xy`` (Python floats, metres), then to ``target_heading`` (radians) if not None,
    for a wheel base of ``wheel_base_m`` metres."""
    dx, dy = target_xy[0] - belief.x, target_xy[1] - belief.y
    distance = math.hypot(dx, dy)
    commands: list[tuple[float, float]] = []
    heading = belief.theta
    if distance > 1e-9:
        bearing = math.atan2(dy, dx)
        commands.append(_turn_in_place(angle_difference(bearing, heading), wheel_base_m))
        commands.append((distance, distance))
        heading = bearing
    if target_heading is not None:
        commands.append(_turn_in_place(angle_difference(target_heading, heading), wheel_base_m))
    return commands or [(0.0, 0.0)]


def _command_draws(rng: np.random.Generator, count: int) -> FloatArray:
    """The ``6 count`` numbers of ``count`` :meth:`DifferentialDriveRobot.drive` commands:
    per command two standard normals, then four uniforms, drawn from ``rng`` in that order."""
    draws = np.empty(6 * count)
    normal, uniform = rng.standard_normal, rng.random
    for start in range(0, 6 * count, 6):  # one slice each: no row views of a 2-d table
        normal(out=draws[start : start + 2])
        uniform(out=draws[start + 2 : start + 6])
    return draws


def _turn_in_place(angle_rad: float, wheel_base_m: float) -> tuple[float, float]:
    """The ``(d_left, d_right)`` wheel travel (metres) turning by ``angle_rad`` in place."""
    half = 0.5 * float(angle_rad) * wheel_base_m
    return -half, half


def _checked_substeps(substeps: int) -> int:
    if int(substeps) != substeps or substeps < 1:
        raise ValueError(
            f"argument 'substeps' must be a positive integer or None; got {substeps!r}"
        )
    return int(substeps)


__all__ = [
    "CommandRun",
    "DifferentialDriveRobot",
    "ENCODER_COLUMNS",
    "INTEGRATIONS",
    "MotionResult",
    "OdometryConfig",
    "OdometryNoise",
    "move_commands",
    "unicycle_step",
]
