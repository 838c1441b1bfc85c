"""The built-in agents: name -> entry point (``"module:attribute"``), per environment id.

Plain data: nothing here imports an agent module. :mod:`sonar_gym.agents.base` resolves an
entry point only when that agent is made, so listing the agents loads no task code.
"""

from __future__ import annotations

GENERIC = "*"
"""The key of the agents that serve every environment."""

BUILTIN_AGENTS: dict[str, dict[str, str]] = {
    GENERIC: {"random": "sonar_gym.agents.random_agent:RandomAgent"},
    "SonarGym/BeaconScan-v0": {
        "paper": "sonar_gym.agents.beacon_scan:PaperAgent",
        "sector": "sonar_gym.agents.beacon_scan:SectorAgent",
    },
    "SonarGym/ActiveBeaconScan-v0": {
        "paper": "sonar_gym.agents.active_beacon_scan:PaperAgent",
        "retry": "sonar_gym.agents.active_beacon_scan:RetryAgent",
    },
    "SonarGym/SweepLocalization-v0": {
        "paper": "sonar_gym.agents.sweep_localization:PaperAgent",
        "covariance": "sonar_gym.agents.sweep_localization:CovarianceAgent",
    },
    "SonarGym/Trilateration-v0": {
        "paper": "sonar_gym.agents.trilateration:PaperAgent",
        "adaptive": "sonar_gym.agents.trilateration:AdaptiveAgent",
    },
    "SonarGym/BlockExpansion-v0": {
        "paper": "sonar_gym.agents.block_expansion:PaperAgent",
        "spread": "sonar_gym.agents.block_expansion:SpreadAgent",
    },
    "SonarGym/WallCorrection-v0": {
        "paper": "sonar_gym.agents.wall_correction:PaperAgent",
        "both_walls": "sonar_gym.agents.wall_correction:BothWallsAgent",
    },
}

CONDITIONAL_AGENTS: dict[str, tuple[str, str]] = {
    "learned": ("sonar_gym.agents.learned:shipped_policy_agent", "sonar_gym.pretrained:has_policy"),
}
"""Agents of every environment that are offered only where a predicate holds: name ->
(factory entry point, predicate ``(env_id) -> bool`` entry point). The ``learned`` agent lists
for an env only when a policy ships for its id. Such agents load files when made, so they may
not fit an env; making one where the predicate fails raises a ``ValueError`` saying why."""
