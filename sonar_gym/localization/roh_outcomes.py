"""What the boundaries of a block expansion run (Roh et al., Sec. II-III) tell, in short.

A :class:`~sonar_gym.localization.roh_block_expansion.BlockExpansionResult` holds one
:class:`~sonar_gym.localization.roh_block_expansion.BoundaryCalibration` per boundary. These
helpers condense the boundaries decided so far into what an agent or a log needs: the
calibrated beacon positions (metres), per-beacon errors, statuses and condition numbers, a
run's overall status, and the last calibration as three numbers in [-1, 1].
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from sonar_gym.localization.result import OK
from sonar_gym.localization.roh_block_expansion import (
    STATUS_LOCALIZATION_FAILED,
    BlockExpansionResult,
    BoundaryCalibration,
)
from sonar_gym.pose import FloatArray

CONDITION_LOG_SCALE = 4.0
"""log10 of the condition number that maps to 1 in :func:`calibration_features`."""
TRIANGLE_AREA_SCALE_M2 = 0.1
"""Triangle area of the three saved positions that maps to 1 in :func:`calibration_features`,
square metres."""


def calibrated_positions(calibrations: Sequence[BoundaryCalibration]) -> dict[str, FloatArray]:
    """New beacon name -> its calibrated ``(x, y, z)``, metres, for the calibrated ones."""
    return {
        c.new_beacon: np.asarray(c.calibration.position)
        for c in calibrations
        if c.calibration is not None and c.calibration.position is not None
    }


def calibration_summaries(calibrations: Sequence[BoundaryCalibration]) -> dict[str, dict]:
    """``calibration_errors_m`` (metres, calibrated beacons), ``calibration_statuses`` and
    ``calibration_conditions`` (finite condition numbers only), each by new beacon name."""
    return {
        "calibration_errors_m": {
            c.new_beacon: float(c.error_m) for c in calibrations if c.error_m is not None
        },
        "calibration_statuses": {c.new_beacon: c.status for c in calibrations},
        "calibration_conditions": {
            c.new_beacon: float(c.calibration.condition)
            for c in calibrations
            if c.calibration is not None and math.isfinite(c.calibration.condition)
        },
    }


def calibration_features(calibration: BoundaryCalibration) -> list[float]:
    """A boundary's calibration as three numbers: outcome (1 ok, -1 failed),
    log10(condition) / :data:`CONDITION_LOG_SCALE` and triangle area /
    :data:`TRIANGLE_AREA_SCALE_M2`, both capped at 1 (a missing calibration counts as an
    infinite condition and no area)."""
    outcome = 1.0 if calibration.status == OK else -1.0
    solved = calibration.calibration
    condition = solved.condition if solved is not None else math.inf
    area = solved.triangle_area_m2 if solved is not None else 0.0
    return [
        outcome,
        min(math.log10(max(condition, 1.0)) / CONDITION_LOG_SCALE, 1.0),
        min(area / TRIANGLE_AREA_SCALE_M2, 1.0),
    ]


def final_status(result: BlockExpansionResult) -> str:
    """``"ok"``, the first failed boundary's status, or ``"localization_failed"``."""
    for calibration in result.calibrations:
        if calibration.status != OK:
            return calibration.status
    return OK if result.ok else STATUS_LOCALIZATION_FAILED
