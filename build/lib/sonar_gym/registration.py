"""Registers the ``SonarGym/...`` environment ids with Gymnasium.

Entry points are strings, so no environment module (nor anything it imports) loads until an
environment is made.
"""

from __future__ import annotations

import gymnasium as gym

ENVIRONMENTS: dict[str, str] = {
    "SonarGym/BeaconScan-v0": "sonar_gym.envs.beacon_scan:BeaconScanEnv",
    "SonarGym/SweepLocalization-v0": "sonar_gym.envs.sweep_localization:SweepLocalizationEnv",
    "SonarGym/Trilateration-v0": "sonar_gym.envs.trilateration:TrilaterationEnv",
    "SonarGym/BlockExpansion-v0": "sonar_gym.envs.block_expansion:BlockExpansionEnv",
    "SonarGym/WallCorrection-v0": "sonar_gym.envs.wall_correction:WallCorrectionEnv",
}


def register_environments() -> None:
    """Register every id once; calling it again is harmless."""
    for env_id, entry_point in ENVIRONMENTS.items():
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point=entry_point)
