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
    position_spread = math.sqrt(max(largest_position_variance(covariance), 0.0))
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


_EPS = 2.0**-53
"""LAPACK's ``dlamch('E')``: the relative machine precision of float64."""
_UNSCALED_RANGE = (1e-100, 1e100)
"""Magnitudes of the largest entry for which LAPACK's ``dsyevd`` and ``dsterf`` scale nothing
(they scale below about 1e-122 and above about 1e146)."""


def largest_position_variance(covariance: FloatArray) -> float:
    """``np.linalg.eigvalsh(covariance[:2, :2])[-1]``: the largest eigenvalue of the position
    block (m^2), the same bits in Python floats.

    numpy's ``eigvalsh`` is LAPACK's ``dsyevd`` on the lower triangle, eigenvalues only. On a
    2x2 ``[[a, b], [b, c]]`` whose largest entry's magnitude lies in :data:`_UNSCALED_RANGE`
    nothing is scaled, the tridiagonal form is ``d = (a, c)``, ``e = b``, and ``dsterf`` either
    splits the matrix (eigenvalues ``a``, ``c``) or solves it with ``dlae2``
    (:func:`_dlae2`), then sorts ascending; this follows those steps. Any other matrix (tiny,
    huge or not finite) goes to ``np.linalg.eigvalsh`` itself.
    """
    a, b, c = float(covariance[0, 0]), float(covariance[1, 0]), float(covariance[1, 1])
    low, high = _UNSCALED_RANGE
    if not low <= max(abs(a), abs(b), abs(c)) <= high:
        return float(np.linalg.eigvalsh(covariance[:2, :2])[-1])
    # dsterf: a negligible off-diagonal splits the matrix into two 1x1 blocks
    if abs(b) <= (math.sqrt(abs(a)) * math.sqrt(abs(c))) * _EPS:
        return _last_sorted(a, c)
    squared_b = b * b
    if squared_b <= _EPS * _EPS * abs(a * c):
        return _last_sorted(a, c)
    # dsterf iterates from the end with the smaller diagonal entry (QL from a, QR from c)
    # (QR from c: d becomes (rt2, rt1); QL from a: (rt1, rt2))
    if abs(c) < abs(a):
        rt1, rt2 = _dlae2(c, math.sqrt(squared_b), a)
        return _last_sorted(rt2, rt1)
    rt1, rt2 = _dlae2(a, math.sqrt(squared_b), c)
    return _last_sorted(rt1, rt2)


def _last_sorted(first: float, second: float) -> float:
    """The last of ``(first, second)`` sorted ascending by LAPACK's ``dlasrt`` (an insertion
    sort: swapped only when ``second < first``)."""
    return first if second < first else second


def _dlae2(a: float, b: float, c: float) -> tuple[float, float]:
    """LAPACK's ``dlae2``: the eigenvalues ``(rt1, rt2)`` of ``[[a, b], [b, c]]``, ``rt1`` the
    larger in magnitude, in its steps and order."""
    total, difference = a + c, a - c
    abs_difference, abs_twice_b = abs(difference), abs(b + b)
    larger, smaller = (a, c) if abs(a) > abs(c) else (c, a)
    if abs_difference > abs_twice_b:
        ratio = abs_twice_b / abs_difference
        root = abs_difference * math.sqrt(1.0 + ratio * ratio)
    elif abs_difference < abs_twice_b:
        ratio = abs_difference / abs_twice_b
        root = abs_twice_b * math.sqrt(1.0 + ratio * ratio)
    else:
        root = abs_twice_b * math.sqrt(2.0)
    if total == 0.0:
        return 0.5 * root, -0.5 * root
    rt1 = 0.5 * (total - root) if total < 0.0 else 0.5 * (total + root)
    return rt1, (larger / rt1) * smaller - (b / rt1) * b


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
    "largest_position_variance",
    "vote_around_estimate",
]
