"""Writes ``fixtures/rollouts.<family>.json``: digests of seeded rollouts of every env.

Run it once per numerics family (:mod:`tests.envs.numerics`) on a tree whose behaviour is the
reference (never on the code under test; the reference is fdfde8b). ``tests`` must come from
this tree and ``sonar_gym`` from the reference, so put a directory holding only a link to this
tree's ``tests/`` first, and run from outside both trees::

    mkdir -p /tmp/t && ln -sfn "$PWD/tests" /tmp/t/tests
    here=$PWD; cd /tmp
    PYTHONPATH=/tmp/t:/path/to/reference/tree python "$here/tests/envs/make_rollout_fixture.py"

``test_rollout_fixture.py`` replays the same rollouts and compares. Each step is digested
(observation bytes, reward, terminated, truncated, info) so the file stays small while any
changed bit shows; spaces are kept as their ``repr``.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from tests.envs.numerics import family_fixture

FIXTURE = family_fixture(Path(__file__).with_name("fixtures") / "rollouts.json")
"""This machine's family's fixture (:mod:`tests.envs.numerics`)."""

CASES: list[tuple[str, dict[str, Any], str]] = [
    ("SonarGym/BeaconScan-v0", {}, "random"),
    ("SonarGym/BeaconScan-v0", {}, "paper"),
    ("SonarGym/BeaconScan-v0", {"action_type": "discrete"}, "random"),
    ("SonarGym/ActiveBeaconScan-v0", {}, "random"),
    ("SonarGym/ActiveBeaconScan-v0", {}, "retry"),
    ("SonarGym/SweepLocalization-v0", {}, "random"),
    ("SonarGym/SweepLocalization-v0", {}, "covariance"),
    ("SonarGym/Trilateration-v0", {}, "random"),
    ("SonarGym/Trilateration-v0", {}, "adaptive"),
    ("SonarGym/BlockExpansion-v0", {}, "random"),
    ("SonarGym/BlockExpansion-v0", {"n_areas": 3}, "random"),
    ("SonarGym/BlockExpansion-v0", {}, "paper"),
    ("SonarGym/WallCorrection-v0", {}, "random"),
    ("SonarGym/WallCorrection-v0", {"action_type": "discrete"}, "random"),
    ("SonarGym/WallCorrection-v0", {}, "both_walls"),
]
SEEDS = (0, 1, 2, 3)


def canonical(value: Any) -> Any:
    """A JSON-able form of ``value`` that keeps every bit (floats as hex)."""
    if isinstance(value, np.ndarray):
        return ["ndarray", str(value.dtype), list(value.shape), value.tobytes().hex()]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value).hex()
    if isinstance(value, dict):
        return {str(key): canonical(item) for key, item in sorted(value.items())}
    if isinstance(value, (list, tuple)):
        return [canonical(item) for item in value]
    return repr(value)


def digest(*parts: Any) -> str:
    text = json.dumps(canonical(list(parts)), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


ADDED_SINCE_REFERENCE: dict[str, tuple[str, ...]] = {
    "*": ("rewards",),
    "SonarGym/BlockExpansion-v0": ("heading_error_rad",),
}
"""Info keys the reference tree did not have (the reward terms; BlockExpansion's heading
error): left out of the digests, so the replay compares every key the reference had."""


def reference_info(env_id: str, info: dict[str, Any]) -> dict[str, Any]:
    """``info`` without the keys added since the reference tree."""
    added = (*ADDED_SINCE_REFERENCE["*"], *ADDED_SINCE_REFERENCE.get(env_id, ()))
    return {key: value for key, value in info.items() if key not in added}


REFERENCE_TIME_LIMITS: dict[str, int] = {"SonarGym/BlockExpansion-v0": 2}
"""Episode limits the reference tree registered at its longest episodes: Gymnasium's
``TimeLimit`` then marked the last step of such an episode (three areas) truncated as well as
terminated. The limits are now one past the longest episode, so the step is terminated alone
(``test_registered_envs.py`` pins that); the digests keep the flag as the reference recorded
it, and every other bit of the step is compared."""


def recorded_truncated(env_id: str, truncated: bool, steps_taken: int) -> bool:
    """``truncated`` as the reference's ``TimeLimit`` reported it after ``steps_taken`` steps."""
    return truncated or steps_taken >= REFERENCE_TIME_LIMITS.get(env_id, steps_taken + 1)


def rollout(env_id: str, kwargs: dict[str, Any], agent_name: str, seed: int) -> dict[str, Any]:
    """One episode's digests: the reset, then every step."""
    from sonar_gym.agents import make_agent

    env = gym.make(env_id, **kwargs)
    agent = make_agent(agent_name, env)
    agent.reset(seed=seed)
    env.action_space.seed(seed)
    observation, info = env.reset(seed=seed)
    steps = [digest(observation, reference_info(env_id, info))]
    actions = []
    while True:
        action = agent.act(observation)
        actions.append(canonical(np.asarray(action)))
        observation, reward, terminated, truncated, info = env.step(action)
        flag = recorded_truncated(env_id, truncated, len(actions))
        steps.append(digest(observation, reward, terminated, flag, reference_info(env_id, info)))
        if terminated or truncated:
            break
    return {
        "observation_space": repr(env.observation_space),
        "action_space": repr(env.action_space),
        "actions": digest(actions),
        "steps": steps,
        "final_status": str(info.get("status")),
    }


def case_key(env_id: str, kwargs: dict[str, Any], agent_name: str, seed: int) -> str:
    return f"{env_id} {json.dumps(kwargs, sort_keys=True)} {agent_name} seed={seed}"


def main() -> None:
    import sonar_gym  # noqa: F401  (registers the ids)

    result = {
        case_key(env_id, kwargs, agent, seed): rollout(env_id, kwargs, agent, seed)
        for env_id, kwargs, agent in CASES
        for seed in SEEDS
    }
    FIXTURE.parent.mkdir(exist_ok=True)
    FIXTURE.write_text(json.dumps(result, indent=1, sort_keys=True) + "\n")
    print(f"wrote {len(result)} rollouts from {sonar_gym.__file__} to {FIXTURE}", file=sys.stderr)


if __name__ == "__main__":
    main()
