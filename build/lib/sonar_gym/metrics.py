"""Pose-error metrics.

``E_xy`` and ``E_theta`` follow Beom & Cho eq. (16); the path errors sigma and sigma' of
Roh et al. live in :mod:`sonar_gym.localization.roh`, beside the method that defines them.
"""

from __future__ import annotations

import math

from sonar_gym.pose import Pose, angle_difference


def position_error_m(estimate: Pose, truth: Pose) -> float:
    """``E_xy`` of Beom & Cho eq. (16): Euclidean distance between the positions, metres."""
    return math.hypot(estimate.x - truth.x, estimate.y - truth.y)


def heading_error_rad(estimate: Pose, truth: Pose) -> float:
    """``E_theta`` of Beom & Cho eq. (16): ``|theta - theta_T|``, radians in [0, pi].

    The difference is wrapped first, so headings of +179 deg and -179 deg are 2 deg apart.
    """
    return abs(angle_difference(estimate.theta, truth.theta))
