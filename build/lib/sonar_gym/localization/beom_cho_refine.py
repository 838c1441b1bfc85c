"""A least-squares refinement of the Beom & Cho (1995) two-beacon pose.

The paper's closed form (eqs (8)-(15)) takes the position from the two ranges alone and the
heading from the large beacon's bearing alone (eq. (15)); the small beacon's bearing only picks
the root of eq. (10). This module uses all four measurements at once: the sensor pose
``(x, y, theta)`` minimises

    sum_b ((|p - c_b| - d_b) / sigma_d_b)^2
      + sum_b (wrap(atan2(c_b - p) - theta - beta_b) / sigma_beta)^2

over both beacons ``b``, by Gauss-Newton started from the paper's solution. ``d_b`` is the
distance to the beacon centre (RCD range plus beacon radius). Since every sample of a
cylinder's RCD ranges the same point of the cylinder (the one on the line of centres), the
range of an RCD is estimated from its central samples rather than its single centre sample
(:func:`central_range_estimate`), which divides the range noise by the square root of their
number.

Plain floats and tuples only, so that the module depends on nothing but numpy and the pose.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from sonar_gym.pose import Pose, wrap_angle

__all__ = ["central_range_estimate", "refine_two_beacon_pose"]

_MAX_ITERATIONS = 20
_STEP_TOLERANCE = 1e-12
_MIN_CENTER_DISTANCE_M = 1e-6


def central_range_estimate(
    delta_m: float, sample_ranges_m: Sequence[float], range_sigma_m: float
) -> tuple[float, float]:
    """Range of an RCD and its standard deviation, metres.

    The mean of the samples in the central half of the RCD (those within a quarter of the
    angular extent of ``beta``); the outer samples are left out because the threshold delay
    lengthens ranges where the echo is weak. Without samples, ``delta_m`` with
    ``range_sigma_m``.

    Args:
        delta_m: the RCD's range ``delta`` (the paper's value at ``beta``), metres.
        sample_ranges_m: ranges of all samples of the RCD in angular order, metres; may be
            empty.
        range_sigma_m: standard deviation of one range sample, metres, > 0.
    """
    if not math.isfinite(range_sigma_m) or range_sigma_m <= 0.0:
        raise ValueError(f"range_sigma_m must be > 0, got {range_sigma_m!r}")
    count = len(sample_ranges_m)
    if count == 0:
        return float(delta_m), float(range_sigma_m)
    centre = 0.5 * (count - 1)
    positions = np.arange(count)
    central = np.asarray(sample_ranges_m, dtype=np.float64)[
        np.abs(positions - centre) <= 0.25 * (count - 1) + 1e-9
    ]
    return float(np.mean(central)), float(range_sigma_m / math.sqrt(len(central)))


def refine_two_beacon_pose(
    initial: Pose,
    centers: tuple[tuple[float, float], tuple[float, float]],
    center_distances_m: tuple[float, float],
    range_sigmas_m: tuple[float, float],
    bearings_rad: tuple[float, float],
    bearing_sigma_rad: float,
) -> Pose:
    """Weighted least-squares sensor pose from two beacons' ranges and bearings.

    Args:
        initial: starting pose in {W} (the paper's solution), metres and radians.
        centers: the two beacon centres ``(x, y)`` in {W}, metres.
        center_distances_m: measured distance from the sensor to each centre (RCD range plus
            beacon radius), metres.
        range_sigmas_m: standard deviation of each of those distances, metres, > 0.
        bearings_rad: each beacon's bearing ``beta`` in the robot frame, radians.
        bearing_sigma_rad: standard deviation of a bearing, radians, > 0.

    Returns:
        The refined pose; ``initial`` itself if the fit does not lower the cost.
    """
    if bearing_sigma_rad <= 0.0 or min(range_sigmas_m) <= 0.0:
        raise ValueError("range_sigmas_m and bearing_sigma_rad must be > 0")
    center_array = np.asarray(centers, dtype=np.float64)
    distances = np.asarray(center_distances_m, dtype=np.float64)
    range_weights = 1.0 / np.asarray(range_sigmas_m, dtype=np.float64)
    bearings = np.asarray(bearings_rad, dtype=np.float64)
    bearing_weight = 1.0 / bearing_sigma_rad

    def residuals_and_jacobian(state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        to_centers = center_array - state[:2]
        center_ranges = np.maximum(
            np.hypot(to_centers[:, 0], to_centers[:, 1]), _MIN_CENTER_DISTANCE_M
        )
        world_bearings = np.arctan2(to_centers[:, 1], to_centers[:, 0])
        range_residuals = (center_ranges - distances) * range_weights
        bearing_residuals = (
            np.remainder(world_bearings - state[2] - bearings + np.pi, 2.0 * np.pi) - np.pi
        ) * bearing_weight
        jacobian = np.zeros((4, 3))
        jacobian[:2, 0] = -to_centers[:, 0] / center_ranges * range_weights
        jacobian[:2, 1] = -to_centers[:, 1] / center_ranges * range_weights
        squared = center_ranges**2
        jacobian[2:, 0] = to_centers[:, 1] / squared * bearing_weight
        jacobian[2:, 1] = -to_centers[:, 0] / squared * bearing_weight
        jacobian[2:, 2] = -bearing_weight
        return np.concatenate((range_residuals, bearing_residuals)), jacobian

    state = initial.as_array()
    residuals, jacobian = residuals_and_jacobian(state)
    cost = float(residuals @ residuals)
    initial_cost = cost
    for _ in range(_MAX_ITERATIONS):
        step = np.linalg.lstsq(jacobian, -residuals, rcond=None)[0]
        scale = 1.0
        while scale > 1e-4:
            trial = state + scale * step
            trial_residuals, trial_jacobian = residuals_and_jacobian(trial)
            trial_cost = float(trial_residuals @ trial_residuals)
            if trial_cost <= cost:
                break
            scale *= 0.5
        else:
            break
        state, residuals, jacobian, cost = trial, trial_residuals, trial_jacobian, trial_cost
        if float(np.max(np.abs(scale * step))) < _STEP_TOLERANCE:
            break
    if not np.all(np.isfinite(state)) or cost > initial_cost:
        return initial
    return Pose(float(state[0]), float(state[1]), wrap_angle(float(state[2])))
