"""The single maximum-likelihood step of Yamamoto et al. eqs (11)-(14) as
:mod:`sonar_gym.localization.apcs_correction` wrote it with ``np.diag``, ``np.eye`` and the
cosine and sine of ``theta + xi`` taken per use, and ``corrected_pose`` copying the step's
covariance, and ``observe_wall`` through the wall's array normal: the forms the module's
``_paper_step``, ``corrected_pose`` and ``observed_wall`` replaced, kept as the tests'
reference."""

from __future__ import annotations

import math

import numpy as np

from sonar_gym.localization.apcs_correction import (
    _MIN_NORMAL_ALIGNMENT,
    HEADING_DEGENERATE,
    NUMERICAL_FAILURE,
    PRIOR_ON_WALL_LINE,
    CorrectionMethod,
    CorrectionResult,
    WallObservation,
    _linear_step,
    _paper_step,
    _readonly,
)
from sonar_gym.localization.apcs_walls import ZERO_LENGTH_M, WallVector
from sonar_gym.localization.result import OK
from sonar_gym.pose import FloatArray, Pose, wrap_angle


def paper_step_arrays(
    prior: FloatArray,
    covariance: FloatArray,
    wall: WallVector,
    r: float,
    xi: float,
    sigma_r: float,
    sigma_xi: float,
) -> tuple[str, FloatArray, FloatArray, str]:
    """The corrected pose and covariance of one matched wall, eqs (11)-(12) in gain form."""
    a, b, c = wall.line_coefficients
    x, y, theta = prior
    if abs(a * x + b * y + c) / math.hypot(a, b) <= ZERO_LENGTH_M:
        return (
            PRIOR_ON_WALL_LINE,
            prior,
            covariance,
            ("the prior position lies on the wall line: eq. (10) has no slope there"),
        )
    u = theta + xi
    if abs(a * math.cos(u) + b * math.sin(u)) / math.hypot(a, b) < _MIN_NORMAL_ALIGNMENT:
        return (
            HEADING_DEGENERATE,
            prior,
            covariance,
            ("theta_A + xi is parallel to the wall: eq. (9) has no slope there"),
        )
    # Eqs (11)-(12) in gain form: with J = J_PA and W = Sigma_su^-1, the matrix inversion lemma
    # gives Sigma_f J^T W = Sigma_PA J^T (J Sigma_PA J^T + Sigma_su)^-1 = K and
    # Sigma_f = (I - K J) Sigma_PA, identical in exact arithmetic to eqs (11)-(14) (see
    # information_vector / information_matrix) and accurate when the wall's information
    # dwarfs the prior's.
    distance_term = a * x + b * y + c
    norm2 = a * a + b * b
    normal_alignment = a * math.cos(u) + b * math.sin(u)
    constraint_jacobian = np.array(  # d(eq. 10, eq. 9) / d(x_A, y_A, theta_A)
        [[2.0 * a * distance_term, 2.0 * b * distance_term, 0.0], [0.0, 0.0, -normal_alignment]]
    )
    constraint_covariance = np.diag(  # Sigma_su = J_z diag(sigma_r, sigma_xi) J_z^T
        [4.0 * r * r * norm2**2 * sigma_r, normal_alignment**2 * sigma_xi]
    )
    constraint_residual = -np.array(  # P_su = -(eq. 10, eq. 9) at the prior
        [
            distance_term**2 - r * r * norm2,
            b * math.cos(u) - a * math.sin(u),
        ]
    )
    gain = np.linalg.solve(
        constraint_jacobian @ covariance @ constraint_jacobian.T + constraint_covariance,
        constraint_jacobian @ covariance,
    ).T
    corrected = prior + gain @ constraint_residual  # eq. (11)
    reduction = np.eye(3) - gain @ constraint_jacobian
    corrected_covariance = (  # eq. (12), Joseph form: symmetric and PSD by construction
        reduction @ covariance @ reduction.T + gain @ constraint_covariance @ gain.T
    )
    corrected_covariance = 0.5 * (corrected_covariance + corrected_covariance.T)
    return OK, corrected, corrected_covariance, ""


def corrected_pose_copied(
    pose: Pose,
    prior_covariance: FloatArray,
    wall: WallVector,
    r: float,
    xi: float,
    sigma_r: float,
    sigma_xi: float,
    *,
    method: CorrectionMethod = "paper",
) -> CorrectionResult:
    """:func:`~sonar_gym.localization.apcs_correction.corrected_pose` with the corrected
    covariance copied into a read-only array."""
    step = _paper_step if method == "paper" else _linear_step
    status, corrected, corrected_covariance, message = step(
        pose.as_array(), prior_covariance, wall, r, xi, sigma_r, sigma_xi
    )
    if status == OK and not (
        np.all(np.isfinite(corrected)) and np.all(np.isfinite(corrected_covariance))
    ):
        status, corrected_covariance = NUMERICAL_FAILURE, prior_covariance
        message = "the correction overflowed"
    if status != OK:
        return CorrectionResult(
            status, None, message, covariance=_readonly(prior_covariance), method=method
        )
    return CorrectionResult(
        OK,
        Pose.from_array(corrected),
        covariance=_readonly(corrected_covariance),
        method=method,
    )


def observe_wall_arrays(wall: WallVector, pose: Pose) -> WallObservation:
    """``(r, xi)`` of ``wall`` seen from ``pose`` (Fig. 8) through the wall's array normal."""
    signed_distance = wall.signed_distance(pose.position)
    outward = wall.normal
    towards_line = -outward if signed_distance >= 0.0 else outward
    bearing_world = math.atan2(towards_line[1], towards_line[0])
    return WallObservation(abs(signed_distance), wrap_angle(bearing_world - pose.theta))
