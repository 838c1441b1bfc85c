"""The run prediction of :func:`sonar_gym.odometry.predict_run` as numpy arrays: the form the
compiled loops :func:`sonar_gym.odometry_kernels.run_headings` and
:func:`sonar_gym.odometry_kernels.run_poses` replaced, kept as the tests' reference.

Kim et al. sec. 3.1, eqs (5)-(6), midpoint integration: the distances, turns, cumulative
headings and chords as whole-array expressions (``np.cumsum``, :func:`wrap_angles`), the
covariances from :func:`sonar_gym.odometry_kernels.run_covariances` on them.
"""

from __future__ import annotations

import numpy as np

from sonar_gym import odometry_kernels
from sonar_gym.pose import FloatArray, Pose, wrap_angles


def predict_run_arrays(
    pose: Pose,
    covariance: FloatArray,
    encoder_left_m: FloatArray,
    encoder_right_m: FloatArray,
    wheel_base_m: float,
    variance_per_m: float,
) -> tuple[FloatArray, FloatArray]:
    """``(poses, covariances)`` of :func:`sonar_gym.odometry.predict_run` on checked arguments:
    ``(K + 1, 3)`` rows ``[x, y, theta]`` ({W}; metres, radians) and ``(K + 1, 3, 3)``."""
    left, right = encoder_left_m, encoder_right_m
    distance = 0.5 * (right + left)
    turn = (right - left) / wheel_base_m
    thetas = pose.theta + np.concatenate([[0.0], np.cumsum(turn)])
    heading = thetas[:-1] + 0.5 * turn
    cos_h, sin_h = np.cos(heading), np.sin(heading)
    poses = np.empty((len(left) + 1, 3))
    poses[0] = pose.x, pose.y, pose.theta
    poses[1:, 0] = pose.x + np.cumsum(distance * cos_h)
    poses[1:, 1] = pose.y + np.cumsum(distance * sin_h)
    poses[1:, 2] = wrap_angles(thetas[1:])
    covariances = odometry_kernels.run_covariances(
        covariance, distance, cos_h, sin_h, right, left, wheel_base_m, variance_per_m
    )
    return poses, covariances
