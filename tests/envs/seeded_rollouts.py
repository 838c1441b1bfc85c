"""Seeded rollouts of every registered id, reduced to digests that pin them bit for bit.

With default arguments the environments' observations, actions, rewards, statuses and info
values must not move (trained policies ship against them). The fixture
``seeded_rollouts.<family>.json`` beside this file (one per numerics family,
:mod:`tests.envs.numerics`) was written by running this module as a script on the tree before
the config, reward-term and info-key unification (fdfde8b), with ``tests`` from this tree and
``sonar_gym`` from the old one (as in ``make_rollout_fixture.py``)::

    here=$PWD; cd /tmp; PYTHONPATH=/tmp/t:<old tree> python "$here/tests/envs/seeded_rollouts.py"

and ``test_seeded_rollouts.py`` replays the same episodes on the current tree. Only the public
API is used (``gym.make``, ``make_agent``), so the script runs on either tree.

Each step is recorded as the info keys it carried and a digest of the observation, action,
reward, termination flags and those info values; rewards and statuses are also kept in the
clear so that a mismatch reads as numbers. Info keys added later are left out of the
comparison (the old tree cannot know them); a key the old tree reported must keep its value.
"""

from __future__ import annotations

import hashlib
import json
import math
import sys
from dataclasses import asdict, is_dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.agents import make_agent
from sonar_gym.registration import ENVIRONMENTS
from tests.envs.numerics import family_fixture

ENV_IDS = tuple(sorted(ENVIRONMENTS))
AGENTS = ("random", "paper", "lowest")
"""``lowest`` (defined here) always plays the action of all-lowest indices or zeros: in
BeaconScan and ActiveBeaconScan a pan that never localizes, so episodes end by truncation."""
SEEDS = (0, 1, 2)
MAX_STEPS = 60
"""Steps recorded per episode at most (enough to cross every decision kind of every task)."""
EPISODES = 2
"""Episodes per rollout: the first from ``reset(seed=seed)``, the next from ``reset()``."""
FIXTURE = family_fixture(Path(__file__).with_name("seeded_rollouts.json"))
"""This machine's family's fixture (:mod:`tests.envs.numerics`)."""


def canonical(value: Any) -> Any:
    """A JSON-able, exact rendering of ``value`` (floats as hex, arrays as dtype+shape+bytes)."""
    if isinstance(value, (bool, np.bool_)):
        return ["bool", bool(value)]
    if isinstance(value, (int, np.integer)):
        return ["int", int(value)]
    if isinstance(value, (float, np.floating)):
        return ["float", float(value).hex()]
    if isinstance(value, str):
        return ["str", value]
    if value is None:
        return ["none"]
    if isinstance(value, np.ndarray):
        data = np.ascontiguousarray(value)
        return ["array", str(data.dtype), list(data.shape), hashlib.sha256(data).hexdigest()]
    if isinstance(value, dict):
        return ["dict", [[str(key), canonical(value[key])] for key in sorted(value, key=str)]]
    if isinstance(value, (list, tuple)):
        return ["seq", [canonical(item) for item in value]]
    if is_dataclass(value) and not isinstance(value, type):
        return ["dataclass", type(value).__name__, canonical(asdict(value))]
    return ["repr", repr(value)]


def step_digest(
    observation: np.ndarray,
    action: Any,
    reward: float,
    terminated: bool,
    truncated: bool,
    info: dict[str, Any],
    keys: list[str],
) -> str:
    """The digest of one step, over the info values of ``keys`` only."""
    record = [
        canonical(observation),
        canonical(action),
        canonical(reward),
        canonical(terminated),
        canonical(truncated),
        [[key, canonical(info[key])] for key in keys],
    ]
    return hashlib.sha256(json.dumps(record).encode()).hexdigest()[:20]


class LowestActionAgent:
    """Always the action with every index at its lowest value (zeros for a Box)."""

    def __init__(self, env: gym.Env) -> None:
        space = env.action_space
        if isinstance(space, gym.spaces.Discrete):
            self._action: Any = int(space.start)
        else:  # MultiDiscrete (starting at 0 here) or Box (0 lies inside every env's box)
            self._action = np.zeros(space.shape, dtype=space.dtype)

    def reset(self, seed: int | None = None) -> None:
        """Nothing to reseed."""

    def act(self, observation: np.ndarray) -> Any:
        return self._action


def agent_for(agent_name: str, env: gym.Env) -> Any:
    """A built-in agent by name, or :class:`LowestActionAgent` for ``"lowest"``."""
    return LowestActionAgent(env) if agent_name == "lowest" else make_agent(agent_name, env)


def rollout(env_id: str, agent_name: str, seed: int) -> dict[str, Any]:
    """:data:`EPISODES` episodes (each at most :data:`MAX_STEPS` steps) as the fixture records
    them."""
    env = gym.make(env_id)
    agent = agent_for(agent_name, env)
    agent.reset(seed=seed)
    episodes = [_recorded_episode(env, agent, seed)]
    episodes += [_recorded_episode(env, agent, None) for _ in range(EPISODES - 1)]
    env.close()
    return {"episodes": episodes}


def _recorded_episode(env: gym.Env, agent: Any, seed: int | None) -> dict[str, Any]:
    observation, info = env.reset(seed=seed)
    reset_keys = sorted(info)
    steps = []
    for _ in range(MAX_STEPS):
        action = agent.act(observation)
        observation, reward, terminated, truncated, info = env.step(action)
        keys = sorted(info)
        steps.append(
            {
                "keys": keys,
                "reward": float(reward).hex(),
                "status": str(info.get("status")),
                "digest": step_digest(
                    observation, action, reward, terminated, truncated, info, keys
                ),
            }
        )
        if terminated or truncated:
            break
    return {"reset_keys": reset_keys, "steps": steps}


def replay_digests(env_id: str, agent_name: str, seed: int, old: dict[str, Any]) -> list[str]:
    """Replay an episode of the fixture on this tree; one problem description per mismatch.

    Compares, step by step, only the info keys the old step carried (a key it carried must
    still be there).
    """
    env = gym.make(env_id)
    agent = agent_for(agent_name, env)
    agent.reset(seed=seed)
    problems: list[str] = []
    for number, episode in enumerate(old["episodes"]):
        where = f"{env_id} {agent_name} seed {seed} episode {number}"
        problems += _replayed_episode(env, agent, seed if number == 0 else None, episode, where)
        if problems:
            break
    env.close()
    return problems


def _replayed_episode(
    env: gym.Env, agent: Any, seed: int | None, old: dict[str, Any], episode_name: str
) -> list[str]:
    observation, info = env.reset(seed=seed)
    problems = [
        f"{episode_name}: reset info lacks {key!r}" for key in old["reset_keys"] if key not in info
    ]
    for index, expected in enumerate(old["steps"]):
        action = agent.act(observation)
        observation, reward, terminated, truncated, info = env.step(action)
        where = f"{episode_name} step {index}"
        missing = [key for key in expected["keys"] if key not in info]
        if missing:
            problems.append(f"{where}: info lacks {missing}")
            break
        if float(reward).hex() != expected["reward"]:
            problems.append(f"{where}: reward {reward!r} != {float.fromhex(expected['reward'])!r}")
        if str(info.get("status")) != expected["status"]:
            problems.append(f"{where}: status {info.get('status')!r} != {expected['status']!r}")
        digest = step_digest(
            observation, action, reward, terminated, truncated, info, expected["keys"]
        )
        if digest != expected["digest"]:
            problems.append(f"{where}: observation, action, flags or info values moved")
        if problems or terminated or truncated:
            break
    return problems


def record_all() -> dict[str, Any]:
    """Every (id, agent, seed) rollout of the fixture."""
    return {
        f"{env_id}|{agent_name}|{seed}": rollout(env_id, agent_name, seed)
        for env_id in ENV_IDS
        for agent_name in AGENTS
        for seed in SEEDS
    }


def packed(rollouts: dict[str, Any]) -> dict[str, Any]:
    """``rollouts`` with each step's info keys replaced by an index into one table."""
    key_sets: list[list[str]] = []
    for rollout_record in rollouts.values():
        for episode in rollout_record["episodes"]:
            for step in episode["steps"]:
                if step["keys"] not in key_sets:
                    key_sets.append(step["keys"])
                step["keys"] = key_sets.index(step["keys"])
    return {"key_sets": key_sets, "rollouts": rollouts}


def unpacked(fixture: dict[str, Any]) -> dict[str, Any]:
    """The rollouts of a fixture written by :func:`packed`."""
    key_sets = fixture["key_sets"]
    for rollout_record in fixture["rollouts"].values():
        for episode in rollout_record["episodes"]:
            for step in episode["steps"]:
                step["keys"] = key_sets[step["keys"]]
    return dict(fixture["rollouts"])


def load_fixture(path: Path = FIXTURE) -> dict[str, Any]:
    """The recorded rollouts, keyed ``"<env id>|<agent>|<seed>"``."""
    return unpacked(json.loads(path.read_text()))


if __name__ == "__main__":
    target = Path(sys.argv[1]) if len(sys.argv) > 1 else FIXTURE
    recorded = record_all()
    rewards = [
        float.fromhex(step["reward"])
        for rollout_record in recorded.values()
        for episode in rollout_record["episodes"]
        for step in episode["steps"]
    ]
    if not all(map(math.isfinite, rewards)):
        raise SystemExit("a recorded reward is not finite")
    target.write_text(json.dumps(packed(recorded), separators=(",", ":"), sort_keys=True) + "\n")
    print(f"wrote {len(recorded)} episodes to {target}")
