"""A run of identical drive commands, as arrays where the robot touches nothing.

:meth:`sonar_gym.robot.DifferentialDriveRobot.drive` moves the true robot through pymunk one
command at a time. Where the robot's disc stays clear of every static shape, pymunk imposes
the planned displacements exactly (no contact, no impulse), so the true path is the planned
one: the circular arc of each command's ground increments (:func:`~sonar_gym.robot.unicycle_step`
with ``"arc"``). :func:`drive_straight_run` computes a run of commands that way, with the very
same random draws per command as ``drive`` (two standard normals, then four uniforms) and the
same wheel-error model (:meth:`~sonar_gym.odometry.OdometryConfig.ground_travel`), checks
the clearance of the whole planned path against the world's static geometry, and hands every
command from the first one that comes near a shape to ``drive`` itself (pymunk), so contacts
are resolved exactly as before. The odometry integrates the encoder increments per physics
substep, as ``drive`` does. The arithmetic over the commands runs in the compiled loops of
:mod:`sonar_gym.straight_drive_kernels`, between numpy's ``sin`` and ``cos`` of whole arrays.

:meth:`~sonar_gym.robot.DifferentialDriveRobot.drive_commands` is the compiled form of the
same drive that the other tasks use; the two agree to rounding (the odometry's substep sums
and the clearance test are written differently). The APCS route keeps this one because its
task's seeded rollouts pin these bits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from collections.abc import Mapping
from typing import Any

import numpy as np

from sonar_gym import drive_kernels, straight_drive_kernels
from sonar_gym.pose import FloatArray, Pose
from sonar_gym.robot import DifferentialDriveRobot
from sonar_gym.world import World

CLEARANCE_MARGIN_M = 0.002
"""Clearance (metres) beyond the robot's radius below which a command goes through pymunk."""


@dataclass(frozen=True)
class StraightRun:
    """The outcome of :func:`drive_straight_run` (arrays over the ``K`` commands).

    Attributes:
        encoder_left_m, encoder_right_m: ``(K,)`` encoder increments, metres.
        true_poses: ``(K, 3)`` true ``[x, y, theta]`` after each command ({W}).
        odometry_poses: ``(K, 3)`` the robot's dead-reckoning pose after each command.
        collided: ``(K,)`` whether the command touched a static shape.
    """

    encoder_left_m: FloatArray
    encoder_right_m: FloatArray
    true_poses: FloatArray
    odometry_poses: FloatArray
    collided: np.ndarray


def drive_straight_run(
    robot: DifferentialDriveRobot,
    world: World,
    step_m: float,
    count: int,
    rng: np.random.Generator,
) -> StraightRun:
    """Drive ``count`` straight commands of ``step_m`` metres, as ``count`` calls of
    :meth:`~sonar_gym.robot.DifferentialDriveRobot.drive_straight` would."""
    return drive_run(robot, world, step_m, step_m, count, rng)


def turn_run(
    robot: DifferentialDriveRobot, world: World, angle_rad: float, rng: np.random.Generator
) -> StraightRun:
    """One turn in place by ``angle_rad`` radians, as
    :meth:`~sonar_gym.robot.DifferentialDriveRobot.turn` would."""
    half = 0.5 * float(angle_rad) * robot.wheel_base_for(world)
    return drive_run(robot, world, -half, half, 1, rng)


def drive_run(
    robot: DifferentialDriveRobot,
    world: World,
    d_left_m: float,
    d_right_m: float,
    count: int,
    rng: np.random.Generator,
) -> StraightRun:
    """Command the wheel increments ``(d_left_m, d_right_m)`` ``count`` times, as ``count``
    calls of :meth:`~sonar_gym.robot.DifferentialDriveRobot.drive` would.

    Same random stream, same true motion (to rounding) and same odometry; the world's robot
    and ``robot.odometry_pose`` end where those calls leave them.
    """
    d_left_m, d_right_m = float(d_left_m), float(d_right_m)
    if not (math.isfinite(d_left_m) and math.isfinite(d_right_m)):
        raise ValueError(
            f"wheel increments must be finite (metres); got {d_left_m!r}, {d_right_m!r}"
        )
    if int(count) != count or count < 0:
        raise ValueError(f"argument 'count' must be an integer >= 0; got {count!r}")
    draws = CommandDraws.start(rng)
    draws.extend(*drive_kernels.draw_commands(rng, int(count)))
    commanded = np.tile([d_left_m, d_right_m], (int(count), 1))
    return drive_commands(robot, world, commanded, draws, rng)


@dataclass
class CommandDraws:
    """The random numbers of a run of :meth:`~sonar_gym.robot.DifferentialDriveRobot.drive`
    commands, drawn in its order (two standard normals, then four uniforms, per command).

    The numbers are kept in the blocks they were drawn in (one block per :meth:`extend` or
    :meth:`draw`); :attr:`normals` and :attr:`uniforms` join them.

    Attributes:
        start_state: the generator's state before the first command (to replay a command
            through ``drive``, or to stop the run early; :meth:`rewind` redraws from it).
        normal_blocks, uniform_blocks: ``(k, 2)`` normals and ``(k, 4)`` uniforms of each
            block of commands, in order.
        count: the number of commands drawn.
    """

    start_state: Mapping[str, Any]
    normal_blocks: list[FloatArray] = field(default_factory=list)
    uniform_blocks: list[FloatArray] = field(default_factory=list)
    count: int = 0

    @classmethod
    def start(cls, rng: np.random.Generator) -> CommandDraws:
        """Begin drawing from ``rng``."""
        return cls(rng.bit_generator.state)

    @property
    def normals(self) -> FloatArray:
        """``(K, 2)`` the standard normals of every command, in order."""
        return _joined(self.normal_blocks, 2)

    @property
    def uniforms(self) -> FloatArray:
        """``(K, 4)`` the uniforms of every command, in order."""
        return _joined(self.uniform_blocks, 4)

    def draw(self, rng: np.random.Generator) -> tuple[FloatArray, FloatArray]:
        """Draw one command's numbers; returns ``(normals, uniforms)``."""
        normals, uniforms = rng.standard_normal(2), rng.random(4)
        self.normal_blocks.append(normals[None, :])
        self.uniform_blocks.append(uniforms[None, :])
        self.count += 1
        return normals, uniforms

    def extend(self, normals: FloatArray, uniforms: FloatArray) -> None:
        """Add commands' numbers drawn in this order elsewhere: ``(k, 2)`` and ``(k, 4)``
        (:func:`sonar_gym.drive_kernels.draw_commands`)."""
        self.normal_blocks.append(normals)
        self.uniform_blocks.append(uniforms)
        self.count += len(normals)

    def rewind(self, rng: np.random.Generator, index: int) -> None:
        """Put ``rng`` in its state before command ``index`` (after the last for ``count``)."""
        rng.bit_generator.state = self.start_state
        drive_kernels.draw_commands(rng, index)


def _joined(blocks: list[FloatArray], width: int) -> FloatArray:
    """The rows of ``blocks`` (each ``(k, width)``) as one ``(K, width)`` array; the block
    itself when there is one."""
    if len(blocks) == 1:
        return blocks[0]
    if not blocks:
        return np.zeros((0, width))
    return np.concatenate(blocks)


def drive_commands(
    robot: DifferentialDriveRobot,
    world: World,
    commanded: FloatArray,
    draws: CommandDraws,
    rng: np.random.Generator,
) -> StraightRun:
    """Execute commands ``(K, 2)`` whose random numbers ``draws`` already holds.

    Each command is what :meth:`~sonar_gym.robot.DifferentialDriveRobot.drive` does with
    those numbers; commands whose planned path comes near a static shape go through ``drive``
    itself (the generator replayed from the command's state). ``rng`` comes in the state after
    the last command's draws (nothing drew from it since) and ends there.
    """
    commanded = np.asarray(commanded, dtype=np.float64).reshape(-1, 2)
    count = len(commanded)
    if count == 0:
        return StraightRun(
            np.zeros(0), np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, dtype=bool)
        )
    base = robot.wheel_base_for(world)
    noise = robot.noise
    normals = draws.normals
    uniforms = draws.uniforms
    encoder, ground = straight_drive_kernels.wheel_travel(
        commanded,
        normals,
        uniforms,
        noise.slip_probability(commanded),
        noise.encoder_std_m_per_sqrt_m,
        noise.scale_error_left,
        noise.scale_error_right,
        noise.slip_fraction_max,
    )
    odometry = robot.odometry_pose if robot.odometry_pose is not None else world.robot_pose
    ground_turn, substeps, substep_distance, substep_heading, odometry_theta_after = (
        straight_drive_kernels.command_substeps(
            encoder, ground, base, robot.max_substep_m, robot.max_substep_rad, odometry.theta
        )
    )
    true_poses = np.empty((count, 3))
    collided = np.zeros(count, dtype=bool)
    first = 0
    replayed = False
    while first < count:
        free = first + _free_commands(
            world, ground[first:], ground_turn[first:], true_poses[first:]
        )
        if free > first:  # the path to it was shown clear of every static shape
            world.place_robot_on_clear_path(Pose.unchecked(*true_poses[free - 1].tolist()))
        if free == count:
            break
        draws.rewind(rng, free)
        replayed = True
        result = robot.drive(world, commanded[free, 0], commanded[free, 1], rng)
        true_poses[free] = result.true_pose.as_array()
        collided[free] = result.collided
        first = free + 1
    if replayed:
        draws.rewind(rng, count)

    # The odometry: each command's encoder increments split over its substeps (midpoint).
    odometry_poses = straight_drive_kernels.odometry_poses(
        substep_distance,
        np.cos(substep_heading),
        np.sin(substep_heading),
        substeps,
        odometry_theta_after,
        (odometry.x, odometry.y),
    )
    robot.odometry_pose = Pose.unchecked(*odometry_poses[-1].tolist())
    return StraightRun(
        encoder[:, 0].copy(), encoder[:, 1].copy(), true_poses, odometry_poses, collided
    )


def _free_commands(
    world: World, ground: FloatArray, ground_turn: FloatArray, out: FloatArray
) -> int:
    """How many of the commands, from the robot's pose, keep clear of every static shape.

    Fills ``out[:k]`` with their planned end poses (``k`` the returned count).
    """
    start = world.robot_pose
    chord_heading, sinc_argument, theta_after = straight_drive_kernels.arc_headings(
        ground_turn, start.theta
    )
    geometry = world.geometry
    free: int = straight_drive_kernels.clear_commands(
        ground,
        ground_turn,
        np.sin(sinc_argument),
        np.cos(chord_heading),
        np.sin(chord_heading),
        theta_after,
        (start.x, start.y),
        world.robot_radius + CLEARANCE_MARGIN_M,
        geometry.segment_starts,
        geometry.segment_ends,
        geometry.circles,
        out,
    )
    return free


__all__ = [
    "CLEARANCE_MARGIN_M",
    "CommandDraws",
    "StraightRun",
    "drive_commands",
    "drive_run",
    "drive_straight_run",
    "turn_run",
]
