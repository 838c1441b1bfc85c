"""``sonar_gym.robot.DifferentialDriveRobot._noise_arguments`` as it was written before it kept
its array between calls (a new array each call), kept as the tests' reference."""

from __future__ import annotations

import numpy as np

from sonar_gym.pose import FloatArray
from sonar_gym.robot import DifferentialDriveRobot


def noise_arguments_reference(self: DifferentialDriveRobot) -> FloatArray:
    """The ``noise`` array of :func:`sonar_gym.drive_kernels.drive_commands`: the odometry
    errors, then the substep limits (metres, radians)."""
    noise = self.noise
    return np.array(
        (
            noise.encoder_std_m_per_sqrt_m,
            noise.scale_error_left,
            noise.scale_error_right,
            noise.slip_probability_per_m,
            noise.slip_fraction_max,
            self.max_substep_m,
            self.max_substep_rad,
        ),
        dtype=np.float64,
    )
