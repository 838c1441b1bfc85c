"""Kim, Lee & Jeong sec. 3.3 inside the EKF of sec. 3.2: a vote around the estimate, gated.

The voting localization (:func:`sonar_gym.localization.kim.vote_localize`) is restricted, as
sec. 3.3 says, "within a circle" around the dead-reckoning estimate; here the circle and the
heading window follow the EKF covariance ``P``:

- search radius ``3 sqrt(lambda_max(P_xy)) + cell``, clipped to [0.1, 0.6] m;
- heading window ``3 sqrt(P_thth) + 1 heading step``, clipped to [3, 30] deg.

A fix then corrects the EKF with the measurement covariance ``G = diag(s^2, s^2, h^2)``
(:func:`fix_covariance`), unless its squared Mahalanobis innovation ``nu^T (P + G)^-1 nu``
exceeds an optional gate (:func:`innovation_accepted`).

Units: metres, radians; poses and covariances in the world frame {W}.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from sonar_gym.localization.ekf import ekf_update_unchecked
from sonar_gym.localization.kim import Anchor, Sweep, VoteLocalization, vote_localize_unchecked
from sonar_gym.localization.kim_grid import OccupancyGrid
from sonar_gym.pose import FloatArray, Pose, angle_difference

MIN_SEARCH_RADIUS_M = 0.1
MAX_SEARCH_RADIUS_M = 0.6
MIN_HEADING_WINDOW_RAD = math.radians(3.0)
MAX_HEADING_WINDOW_RAD = math.radians(30.0)


def vote_around_estimate(
    grid: OccupancyGrid,
    sweeps: Sequence[Sweep],
    estimate: Pose,
    covariance: FloatArray,
    *,
    heading_step_rad: float,
    max_range_m: float,
    anchor: Anchor = "obstacle_point",
) -> VoteLocalization:
    """The vote of sec. 3.3 in the search circle and heading window that ``covariance`` sets.

    The arguments are the filter's own state, so the vote skips
    :func:`~sonar_gym.localization.kim.vote_localize`'s checks
    (:func:`~sonar_gym.localization.kim.vote_localize_unchecked`).

    Args:
        grid: the known map.
        sweeps: the sweeps, the first one's odometry the identity (see ``vote_localize``).
        estimate: the EKF estimate at the first sweep ({W}).
        covariance: its 3x3 covariance over ``[x, y, theta]``.
        heading_step_rad: spacing of the candidate headings, radians.
        max_range_m: readings at or beyond this range count as no echo, metres.
        anchor: where a range vector ends in an occupied cell (see ``vote_localize``).
    """
    position_spread = math.sqrt(max(float(np.linalg.eigvalsh(covariance[:2, :2])[-1]), 0.0))
    radius = _clipped(
        3.0 * position_spread + grid.cell_size_m, MIN_SEARCH_RADIUS_M, MAX_SEARCH_RADIUS_M
    )
    window = _clipped(
        3.0 * math.sqrt(max(float(covariance[2, 2]), 0.0)) + heading_step_rad,
        MIN_HEADING_WINDOW_RAD,
        MAX_HEADING_WINDOW_RAD,
    )
    return vote_localize_unchecked(
        grid,
        sweeps,
        estimate,
        radius,
        heading_step_rad=heading_step_rad,
        heading_window_rad=window,
        max_range_m=max_range_m,
        anchor=anchor,
    )


def _clipped(value: float, low: float, high: float) -> float:
    """``value`` clipped to [low, high] (as ``np.clip`` on one float)."""
    return min(max(value, low), high)


def fix_covariance(position_std_m: float, heading_std_rad: float) -> FloatArray:
    """``G = diag(s^2, s^2, h^2)``: the covariance of one vote fix (m^2, m^2, rad^2)."""
    position_var = position_std_m**2
    return np.diag([position_var, position_var, heading_std_rad**2])


def innovation_accepted(
    estimate: Pose,
    covariance: FloatArray,
    fix: Pose,
    measurement_covariance: FloatArray,
    gate: float | None,
) -> bool:
    """Whether ``nu^T (P + G)^-1 nu <= gate`` (always, with no gate), heading innovation wrapped."""
    if gate is None:
        return True
    innovation = np.array(
        [fix.x - estimate.x, fix.y - estimate.y, angle_difference(fix.theta, estimate.theta)]
    )
    spread = covariance + measurement_covariance
    return float(innovation @ np.linalg.solve(spread, innovation)) <= gate


def gated_ekf_update(
    estimate: Pose,
    covariance: FloatArray,
    fix: Pose,
    measurement_covariance: FloatArray,
    gate: float | None,
) -> tuple[Pose, FloatArray] | None:
    """The EKF correction of sec. 3.2 with ``fix``, or None if :func:`innovation_accepted`
    rejects it.

    ``estimate`` and ``covariance`` are the filter's own state and ``measurement_covariance``
    a checked fix covariance (:func:`fix_covariance`), so the update skips
    :func:`~sonar_gym.localization.ekf.ekf_update`'s argument checks.
    """
    if not innovation_accepted(estimate, covariance, fix, measurement_covariance, gate):
        return None
    return ekf_update_unchecked(estimate, covariance, fix, measurement_covariance)


__all__ = [
    "gated_ekf_update",
    "MAX_HEADING_WINDOW_RAD",
    "MAX_SEARCH_RADIUS_M",
    "MIN_HEADING_WINDOW_RAD",
    "MIN_SEARCH_RADIUS_M",
    "fix_covariance",
    "innovation_accepted",
    "vote_around_estimate",
]
