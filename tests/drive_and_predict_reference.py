"""The drive of a command table with its EKF prediction as two compiled calls, the draws
taken in Python: the reference of
:meth:`~sonar_gym.robot.DifferentialDriveRobot.drive_to_and_predict` (which plans, draws,
drives and predicts in one compiled call) handed the plan of
:func:`sonar_gym.robot.move_commands`."""

from __future__ import annotations

import numpy as np

from sonar_gym import drive_kernels, odometry_kernels
from sonar_gym.pose import FloatArray, Pose
from sonar_gym.robot import DifferentialDriveRobot, _command_draws
from sonar_gym.world import World


def drive_and_predict_reference(
    robot: DifferentialDriveRobot,
    world: World,
    commands_m: FloatArray,
    rng: np.random.Generator,
    estimate: Pose,
    covariance: FloatArray,
    variance_per_m: float,
) -> tuple[FloatArray, Pose, FloatArray]:
    """``commands_m`` driven (the draws of ``robot.drive``, substeps picked per command), and
    the EKF prediction over their encoder increments from ``estimate`` and ``covariance``."""
    start = world.robot_pose
    arguments = robot._wheel_arguments(world, 0, start)
    motions, blocked = drive_kernels.drive_commands(
        commands_m, _command_draws(rng, len(commands_m)), *arguments
    )
    predicted, predicted_covariance = odometry_kernels.predict_commands(
        (estimate.x, estimate.y, estimate.theta),
        covariance,
        motions[:, drive_kernels.ENCODER : drive_kernels.ENCODER + 2],
        arguments[1],
        variance_per_m,
        0.0,
        False,
    )
    robot._finish_drive(world, motions, blocked, start)
    return motions, Pose.unchecked(*predicted[-1].tolist()), predicted_covariance
