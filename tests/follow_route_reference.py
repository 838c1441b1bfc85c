""":func:`sonar_gym.polyline.follow_route` as it was before the drive and the EKF prediction of
each target ran in one compiled call: the public robot and odometry calls, kept as the tests'
reference."""

from __future__ import annotations

import numpy as np

from sonar_gym.odometry import predict_over_motion
from sonar_gym.polyline import FollowedLeg, Route
from sonar_gym.pose import FloatArray, Pose
from sonar_gym.robot import DifferentialDriveRobot
from sonar_gym.world import World


def follow_route_reference(
    robot: DifferentialDriveRobot,
    world: World,
    route: Route,
    span_m: tuple[float, float],
    estimate: Pose,
    covariance: FloatArray,
    variance_per_m: float,
    rng: np.random.Generator,
) -> FollowedLeg:
    """Each target planned by :meth:`DifferentialDriveRobot.plan_move`, driven by
    :meth:`DifferentialDriveRobot.drive_commands` and predicted by
    :func:`sonar_gym.odometry.predict_over_motion`."""
    wheel_base = robot.wheel_base_for(world)
    rolled: list[float] = []
    for target in route.targets_between(*span_m):
        plan = robot.plan_move(world, target, from_pose=estimate)
        increments = robot.drive_commands(world, plan, rng).encoder_m
        estimate, covariance, _ = predict_over_motion(
            estimate, covariance, increments, wheel_base, variance_per_m
        )
        rolled += [0.5 * (abs(left) + abs(right)) for left, right in increments.tolist()]
    return FollowedLeg(estimate, covariance, tuple(rolled))
