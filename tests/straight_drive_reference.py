"""The straight drive of :mod:`sonar_gym.straight_drive` as numpy arrays: the form the compiled
loops of :mod:`sonar_gym.straight_drive_kernels` replaced, kept as the tests' reference.

:func:`drive_commands_arrays` is :func:`sonar_gym.straight_drive.drive_commands` with the wheel
travel, the substep counts, the odometry's substep sums, the planned arcs and their clearance
test written as whole-array numpy expressions (:func:`free_commands_arrays`,
:func:`clearance_arrays`).
"""

from __future__ import annotations

import math

import numpy as np

from sonar_gym.geometry import StaticGeometry
from sonar_gym.odometry import sinc_of_array
from sonar_gym.pose import FloatArray, Pose, wrap_angles
from sonar_gym.robot import DifferentialDriveRobot
from sonar_gym.straight_drive import CLEARANCE_MARGIN_M, CommandDraws, StraightRun
from sonar_gym.world import World

_ROUNDING_M = 1e-6


def clearance_arrays(
    geometry: StaticGeometry, points: FloatArray, within_m: float | None = None
) -> FloatArray:
    """``(P,)`` distance (metres) from each point to the nearest static segment or circle.

    With ``within_m``, only the distances up to ``within_m`` are exact; a point whose nearest
    shape is farther gets some value above ``within_m``. Shapes whose bounding box lies
    farther than ``within_m`` from the points' bounding box are then left out.
    """
    nearest = np.full(len(points), math.inf)
    starts, ends = geometry.segment_starts, geometry.segment_ends
    circles = geometry.circles
    if within_m is not None:
        low, high = points.min(axis=0), points.max(axis=0)
        reach = within_m + _ROUNDING_M
        if geometry.n_segments:
            box_low, box_high = np.minimum(starts, ends), np.maximum(starts, ends)
            near = np.all((box_low - high <= reach) & (low - box_high <= reach), axis=1)
            starts, ends = starts[near], ends[near]
        if geometry.n_circles:
            radii = circles[:, 2:3]
            near = np.all(
                (circles[:, :2] - radii - high <= reach) & (low - circles[:, :2] - radii <= reach),
                axis=1,
            )
            circles = circles[near]
    if len(starts):
        edges = ends - starts
        lengths_sq = np.maximum(np.einsum("sk,sk->s", edges, edges), 1e-24)
        rel = points[:, None, :] - starts[None, :, :]
        t = np.clip(np.einsum("psk,sk->ps", rel, edges) / lengths_sq, 0.0, 1.0)
        gap = rel - t[:, :, None] * edges[None, :, :]
        nearest = np.minimum(nearest, np.sqrt(np.einsum("psk,psk->ps", gap, gap)).min(axis=1))
    if len(circles):
        centres, radii = circles[:, :2], circles[:, 2]
        gaps = np.hypot(*(points[:, None, :] - centres[None, :, :]).transpose(2, 0, 1)) - radii
        nearest = np.minimum(nearest, np.abs(gaps).min(axis=1))
    return nearest


def drive_commands_arrays(
    robot: DifferentialDriveRobot,
    world: World,
    commanded: FloatArray,
    draws: CommandDraws,
    rng: np.random.Generator,
) -> StraightRun:
    """:func:`sonar_gym.straight_drive.drive_commands` in numpy arrays."""
    commanded = np.asarray(commanded, dtype=np.float64).reshape(-1, 2)
    count = len(commanded)
    if count == 0:
        return StraightRun(
            np.zeros(0), np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, dtype=bool)
        )
    base = robot.wheel_base_for(world)
    noise = robot.noise
    normals = np.array(draws.normals)
    uniforms = np.array(draws.uniforms)
    encoder = noise.encoder_increments(commanded, normals)  # (K, 2)
    scale_errors = np.array([noise.scale_error_left, noise.scale_error_right])
    ground = noise.ground_travel(commanded, scale_errors, uniforms[:, :2], uniforms[:, 2:])
    travel = np.maximum(np.abs(ground).max(axis=1), np.abs(encoder).max(axis=1))
    ground_turn = (ground[:, 1] - ground[:, 0]) / base
    substeps = np.maximum.reduce(
        [
            np.ones(count, dtype=np.int64),
            np.ceil(travel / robot.max_substep_m).astype(np.int64),
            np.ceil(np.abs(ground_turn) / robot.max_substep_rad).astype(np.int64),
        ]
    )
    true_poses = np.empty((count, 3))
    collided = np.zeros(count, dtype=bool)
    odometry = robot.odometry_pose if robot.odometry_pose is not None else world.robot_pose
    first = 0
    while first < count:
        free = first + free_commands_arrays(
            world, ground[first:], ground_turn[first:], true_poses[first:]
        )
        if free > first:  # the path to it was shown clear of every static shape
            world.place_robot_on_clear_path(Pose(*true_poses[free - 1]))
        if free == count:
            break
        draws.rewind(rng, free)
        result = robot.drive(world, commanded[free, 0], commanded[free, 1], rng)
        true_poses[free] = result.true_pose.as_array()
        collided[free] = result.collided
        first = free + 1
    draws.rewind(rng, count)

    # The odometry: each command's encoder increments split over its substeps (midpoint).
    sub_distance = np.repeat(0.5 * (encoder[:, 0] + encoder[:, 1]) / substeps, substeps)
    sub_turn = np.repeat((encoder[:, 1] - encoder[:, 0]) / base / substeps, substeps)
    thetas = odometry.theta + np.concatenate([[0.0], np.cumsum(sub_turn)])
    heading = thetas[:-1] + 0.5 * sub_turn
    xs = np.cumsum(np.concatenate([[odometry.x], sub_distance * np.cos(heading)]))
    ys = np.cumsum(np.concatenate([[odometry.y], sub_distance * np.sin(heading)]))
    ends = np.cumsum(substeps)
    odometry_poses = np.column_stack([xs[ends], ys[ends], wrap_angles(thetas[ends])])
    robot.odometry_pose = Pose(*odometry_poses[-1])
    return StraightRun(
        encoder[:, 0].copy(), encoder[:, 1].copy(), true_poses, odometry_poses, collided
    )


def free_commands_arrays(
    world: World, ground: FloatArray, ground_turn: FloatArray, out: FloatArray
) -> int:
    """How many of the commands, from the robot's pose, keep clear of every static shape.

    Fills ``out[:k]`` with their planned end poses (``k`` the returned count).
    """
    count = len(ground)
    start = world.robot_pose
    distance = 0.5 * (ground[:, 0] + ground[:, 1])
    thetas = start.theta + np.concatenate([[0.0], np.cumsum(ground_turn)])
    half_turn = 0.5 * ground_turn
    step = distance * sinc_of_array(half_turn)
    ends_x = np.cumsum(np.concatenate([[start.x], step * np.cos(thetas[:-1] + half_turn)]))
    ends_y = np.cumsum(np.concatenate([[start.y], step * np.sin(thetas[:-1] + half_turn)]))
    reach = 0.5 * np.abs(distance) + np.abs(distance * ground_turn) / 8.0 + _ROUNDING_M
    margin = world.robot_radius + CLEARANCE_MARGIN_M
    gaps = clearance_arrays(
        world.geometry, np.column_stack([ends_x, ends_y]), float(reach.max()) + margin
    )
    clear = np.minimum(gaps[:-1], gaps[1:]) - reach > margin
    free = count if clear.all() else int(np.argmin(clear))
    out[:free, 0] = ends_x[1 : free + 1]
    out[:free, 1] = ends_y[1 : free + 1]
    out[:free, 2] = wrap_angles(thetas[1 : free + 1])
    return free
