"""The EKF correction as :func:`sonar_gym.localization.ekf.ekf_update_unchecked` first wrote it
(array state, a fresh identity per call), kept as the tests' reference."""

from __future__ import annotations

import numpy as np

from sonar_gym.pose import FloatArray, Pose, wrap_angle


def ekf_update_reference(
    pose: Pose,
    covariance: FloatArray,
    measured_pose: Pose,
    measurement_covariance: FloatArray,
    joseph_form: bool = False,
) -> tuple[Pose, FloatArray]:
    """Sec. 3.2 eqs. (3)-(5), ``K = P H^T (H P H^T + G)^-1``, in the original array form."""
    prior, noise = covariance, measurement_covariance
    rows = noise.shape[0]
    observation = np.eye(3)[:rows]
    innovation = np.array(
        [
            measured_pose.x - pose.x,
            measured_pose.y - pose.y,
            wrap_angle(measured_pose.theta - pose.theta),
        ]
    )[:rows]
    innovation_covariance = observation @ prior @ observation.T + noise
    try:
        inverse = np.linalg.inv(innovation_covariance)
        if not np.all(np.isfinite(inverse)):
            raise np.linalg.LinAlgError
    except np.linalg.LinAlgError:
        inverse = np.linalg.pinv(innovation_covariance)
    gain = prior @ observation.T @ inverse
    state = pose.as_array() + gain @ innovation
    correction = np.eye(3) - gain @ observation
    if joseph_form:
        posterior = correction @ prior @ correction.T + gain @ noise @ gain.T
    else:
        posterior = correction @ prior
    return Pose.from_array(state), 0.5 * (posterior + posterior.T)


def symmetrised_reference(matrix: FloatArray) -> FloatArray:
    """``sonar_gym.localization.ekf._symmetrised`` as it was written before it halved the sum
    in place."""
    return 0.5 * (matrix + matrix.T)
