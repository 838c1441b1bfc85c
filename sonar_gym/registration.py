"""Registers the ``SonarGym/...`` environment ids with Gymnasium.

Entry points are strings, so no environment module (nor anything it imports) loads until an
environment is made.

Episode limits (``gym.spec(id).max_episode_steps``, enforced by Gymnasium's ``TimeLimit``):
every env ends its episodes itself, after a number of decisions fixed by its arguments. The
registered limit is one step past the longest episode any valid arguments allow (``TimeLimit``
marks the step that reaches its limit truncated even when the env terminates on it), so the
wrapper never cuts or relabels an episode and behaviour is the same with it as without it, at
default arguments and at any others. :data:`DEFAULT_EPISODE_STEPS` gives the
length at default arguments (the horizon a learner sees out of the box).
"""

from __future__ import annotations

from dataclasses import dataclass

import gymnasium as gym


@dataclass(frozen=True)
class Registration:
    """One env id: where it lives and how long its episodes can be.

    Attributes:
        entry_point: ``"module:Class"``.
        max_episode_steps: the registered step limit, one past the longest episode (see the
            module docstring).
        limit_reason: which argument and validation bound the longest episode follows from.
        default_episode_steps: the episode length at default arguments (most steps, for envs
            whose agent may end early).
        vector_entry_point: ``"module:Class"`` of a native vector env, which ``gym.make_vec``
            builds with ``vectorization_mode="vector_entry_point"`` (and by default); None
            when the id has none (``make_vec`` then steps ``gym.make``'d envs in a
            ``SyncVectorEnv``).
    """

    entry_point: str
    max_episode_steps: int
    limit_reason: str
    default_episode_steps: int
    vector_entry_point: str | None = None


REGISTRATIONS: dict[str, Registration] = {
    "SonarGym/BeaconScan-v0": Registration(
        "sonar_gym.envs.beacon_scan:BeaconScanEnv",
        max_episode_steps=1001,
        limit_reason="the env truncates itself after max_steps decisions (default 12, at most "
        "1000); the agent may localize earlier",
        default_episode_steps=12,
        vector_entry_point="sonar_gym.envs.beacon_scan_vector:BeaconScanVectorEnv",
    ),
    "SonarGym/ActiveBeaconScan-v0": Registration(
        "sonar_gym.envs.active_beacon_scan:ActiveBeaconScanEnv",
        max_episode_steps=1001,
        limit_reason="the env truncates itself after max_steps decisions (default 24, at most "
        "1000); the agent may commit earlier",
        default_episode_steps=24,
    ),
    "SonarGym/SweepLocalization-v0": Registration(
        "sonar_gym.envs.sweep_localization:SweepLocalizationEnv",
        max_episode_steps=1001,
        limit_reason="one decision every decision_spacing_m along the route: ceil(route length "
        "/ spacing), at most ceil(50 m / 0.05 m) = 1000 (default 3.2 m / 0.4 m -> 8 stations "
        "plus the route's end)",
        default_episode_steps=9,
    ),
    "SonarGym/Trilateration-v0": Registration(
        "sonar_gym.envs.trilateration:TrilaterationEnv",
        max_episode_steps=201,
        limit_reason="one decision per decision point: n_decision_points (default 16, at most 200)",
        default_episode_steps=16,
    ),
    "SonarGym/BlockExpansion-v0": Registration(
        "sonar_gym.envs.block_expansion:BlockExpansionEnv",
        max_episode_steps=3,
        limit_reason="one decision per area boundary with decisions='per_boundary': n_areas - 1 "
        "(default 2 areas -> 1 step, at most 3 areas -> 2 steps); one step with 'all_at_once'",
        default_episode_steps=1,
    ),
    "SonarGym/WallCorrection-v0": Registration(
        "sonar_gym.envs.wall_correction:WallCorrectionEnv",
        max_episode_steps=101,
        limit_reason="one decision per route leg: n_legs (default 6, at most 100)",
        default_episode_steps=6,
    ),
}

ENVIRONMENTS: dict[str, str] = {
    env_id: registration.entry_point for env_id, registration in REGISTRATIONS.items()
}
"""Entry point per env id."""

DEFAULT_EPISODE_STEPS: dict[str, int] = {
    env_id: registration.default_episode_steps for env_id, registration in REGISTRATIONS.items()
}
"""Episode length (at most) per env id at default arguments."""


def register_environments() -> None:
    """Register every id once; calling it again is harmless."""
    for env_id, registration in REGISTRATIONS.items():
        if env_id not in gym.registry:
            gym.register(
                id=env_id,
                entry_point=registration.entry_point,
                vector_entry_point=registration.vector_entry_point,
                max_episode_steps=registration.max_episode_steps,
            )
