"""APCS: autonomous position correction from flat walls sensed by side sonars.

Yamamoto, Maeyama, Ohya & Yuta, *APCS: autonomous position correction system using ultrasonic
sensing for indoor mobile robot navigation*. The procedure of Fig. 2:

1. ERPs from consecutive side readings, eqs (1)-(6): :func:`estimated_reflection_points`
   (eq. (4) read with ``(y2 - y1)^2`` under the root, the length of ``P1P2``).
2. Flat walls from grouped ERPs, section 4.2.2-4.2.3: :func:`detect_walls`.
3. Matching to the map of oriented wall vectors, section 4.3: :func:`match_wall`; only a
   unique match is used.
4. Maximum-likelihood correction of pose and covariance, eqs (7)-(14): :func:`correct_pose`,
   with the measurement ``(r, xi)`` from :func:`observe_wall`.

:func:`correct_with_detected_wall` runs steps 3-4 for one detected wall. The thresholds of
section 6 are the defaults of :class:`APCSParameters`. The implementation lives in
:mod:`sonar_gym.localization.apcs_walls` (steps 1-3) and
:mod:`sonar_gym.localization.apcs_correction` (step 4).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import partial

import numpy.typing as npt

from sonar_gym.localization.apcs_correction import (
    HEADING_DEGENERATE,
    NUMERICAL_FAILURE,
    PRIOR_ON_WALL_LINE,
    CorrectionMethod,
    CorrectionResult,
    WallObservation,
    correct_pose,
    corrected_pose,
    information_matrix,
    information_vector,
    observe_wall,
    observed_wall,
    validated_covariance,
)
from sonar_gym.localization.apcs_walls import (
    AMBIGUOUS,
    DEFAULT_PARAMETERS,
    GROUP_OK,
    GROUP_TOO_FEW_POINTS,
    GROUP_TOO_MUCH_VARIANCE,
    GROUP_ZERO_LENGTH,
    MATCHED,
    NO_MATCH,
    REJECT_DISTANCE,
    REJECT_INCLUSION,
    REJECT_ORIENTATION,
    APCSParameters,
    DetectedWall,
    EstimatedReflectionPoints,
    MatchResult,
    WallCheck,
    WallChecks,
    WallFit,
    WallMap,
    WallVector,
    check_wall,
    detect_walls,
    detect_walls_from_readings,
    estimated_reflection_points,
    fit_wall_group,
    fit_wall_groups,
    group_erps,
    match_wall,
    reflection_direction_candidates,
)
from sonar_gym.pose import FloatArray, Pose

__all__ = [
    "AMBIGUOUS",
    "DEFAULT_PARAMETERS",
    "GROUP_OK",
    "GROUP_TOO_FEW_POINTS",
    "GROUP_TOO_MUCH_VARIANCE",
    "GROUP_ZERO_LENGTH",
    "HEADING_DEGENERATE",
    "MATCHED",
    "NO_MATCH",
    "NUMERICAL_FAILURE",
    "PRIOR_ON_WALL_LINE",
    "REJECT_DISTANCE",
    "REJECT_INCLUSION",
    "REJECT_ORIENTATION",
    "APCSParameters",
    "CorrectionMethod",
    "CorrectionResult",
    "DetectedWall",
    "EstimatedReflectionPoints",
    "MatchResult",
    "WallCheck",
    "WallChecks",
    "WallFit",
    "WallMap",
    "WallObservation",
    "WallVector",
    "check_wall",
    "correct_pose",
    "correct_with_checked_wall",
    "corrected_pose",
    "correct_with_detected_wall",
    "detect_walls",
    "detect_walls_from_readings",
    "estimated_reflection_points",
    "fit_wall_group",
    "fit_wall_groups",
    "group_erps",
    "information_matrix",
    "information_vector",
    "match_wall",
    "observe_wall",
    "reflection_direction_candidates",
    "validated_covariance",
]


def correct_with_detected_wall(
    pose: Pose,
    covariance: npt.ArrayLike,
    detected: DetectedWall,
    wall_map: Sequence[WallVector],
    sigma_r: float,
    sigma_xi: float,
    params: APCSParameters = DEFAULT_PARAMETERS,
    *,
    method: CorrectionMethod = "paper",
) -> tuple[MatchResult, CorrectionResult]:
    """Match one detected wall to the map and, on a unique match, correct the pose (Fig. 2).

    Args:
        pose: current pose estimate (odometry), {W}; the detected wall must be expressed in the
            same estimate of {W} (ERPs computed from the odometry positions).
        covariance: 3x3 covariance of ``pose``.
        detected: the wall found by :func:`detect_walls`.
        wall_map: the map's wall vectors.
        sigma_r: variance of the measured distance ``r``, m^2.
        sigma_xi: variance of the measured bearing ``xi``, rad^2.
        params: matching thresholds (section 6 by default).
        method: correction method of :func:`correct_pose`.

    Returns:
        The match and the correction. Without a unique match the correction's status is the
        match status (``"no_match"`` or ``"ambiguous"``), with no pose and the prior covariance.
    """
    if not isinstance(pose, Pose):
        raise ValueError(f"pose must be a Pose, got {type(pose).__name__}")
    prior = validated_covariance(covariance)
    prior.setflags(write=False)
    return _match_and_correct(
        pose,
        prior,
        detected,
        wall_map,
        params,
        method,
        lambda wall, r, xi: correct_pose(
            pose, covariance, wall, r, xi, sigma_r, sigma_xi, method=method
        ),
    )


def correct_with_checked_wall(
    pose: Pose,
    prior: FloatArray,
    detected: DetectedWall,
    wall_map: Sequence[WallVector],
    sigma_r: float,
    sigma_xi: float,
    params: APCSParameters = DEFAULT_PARAMETERS,
    *,
    method: CorrectionMethod = "paper",
) -> tuple[MatchResult, CorrectionResult]:
    """:func:`correct_with_detected_wall` on checked inputs, for a caller that keeps them so.

    ``prior`` is the covariance as :func:`validated_covariance` returns it (symmetric,
    positive definite, read-only); ``sigma_r``, ``sigma_xi`` are positive floats and
    ``method`` is ``"paper"`` or ``"linear"``. The same match and correction, without the
    checks.
    """
    return _match_and_correct(
        pose,
        prior,
        detected,
        wall_map,
        params,
        method,
        lambda wall, r, xi: corrected_pose(
            pose, prior, wall, r, xi, sigma_r, sigma_xi, method=method
        ),
    )


def _match_and_correct(
    pose: Pose,
    prior: FloatArray,
    detected: DetectedWall,
    wall_map: Sequence[WallVector],
    params: APCSParameters,
    method: CorrectionMethod,
    correct: Callable[[WallVector, float, float], CorrectionResult],
) -> tuple[MatchResult, CorrectionResult]:
    """Fig. 2 after the checks: match, observe the wall, ``correct(wall, r, xi)``."""
    match = match_wall(detected, wall_map, params)
    if not match.matched or match.wall is None:
        # The message lists every rejected map wall; it is written only when read.
        return match, CorrectionResult.explained_when_read(
            match.status, partial(_unmatched_message, match), prior, method
        )
    observation = observed_wall(detected.vector, pose)
    if observation.r_m <= 0.0:
        return match, CorrectionResult(
            PRIOR_ON_WALL_LINE,
            None,
            "the robot lies on the detected wall's line",
            covariance=prior,
            method=method,
        )
    return match, correct(match.wall, observation.r_m, observation.xi_rad)


def _unmatched_message(match: MatchResult) -> str:
    """Why a detected wall without a unique match corrects nothing (Fig. 2): more than one map
    wall matched, or none did, with each map wall's first failed condition."""
    if match.status == AMBIGUOUS:
        return "more than one map wall matches"
    return f"no map wall matches ({match.checks.rejection_summary()})"
