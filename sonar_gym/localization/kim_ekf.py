"""Kim, Lee & Jeong secs. 3.1-3.2: the odometry prediction and EKF correction they use.

The filter itself lives in :mod:`sonar_gym.localization.ekf`, shared by every task that fuses
dead reckoning with fixes; this module keeps the paper's name for it.
"""

from sonar_gym.localization.ekf import (
    INTEGRATIONS,
    Integration,
    ekf_update,
    jacobian_state,
    jacobian_wheels,
    motion_model,
    predict,
    proportional_encoder_noise,
)

__all__ = [
    "INTEGRATIONS",
    "Integration",
    "ekf_update",
    "jacobian_state",
    "jacobian_wheels",
    "motion_model",
    "predict",
    "proportional_encoder_noise",
]
