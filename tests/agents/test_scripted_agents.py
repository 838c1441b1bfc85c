"""Scripted agents notice a new episode without ``reset()`` and refuse, when made, an env they
cannot act in."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

from sonar_gym.agents import AgentEnvMismatchError, ScriptedAgent, make_agent
from sonar_gym.agents.base import Agent
from sonar_gym.agents.beacon_scan import PaperAgent as BeaconScanPaperAgent

BEACON_SCAN = "SonarGym/BeaconScan-v0"

# Every env's paper agent, and the heuristics that carry state from one decision to the next.
SCRIPTED_CASES = [
    (BEACON_SCAN, "paper", {}),
    (BEACON_SCAN, "sector", {}),
    ("SonarGym/SweepLocalization-v0", "paper", {}),
    ("SonarGym/Trilateration-v0", "paper", {}),
    ("SonarGym/Trilateration-v0", "adaptive", {}),
    ("SonarGym/BlockExpansion-v0", "paper", {}),
    ("SonarGym/WallCorrection-v0", "paper", {}),
    ("SonarGym/WallCorrection-v0", "both_walls", {"pause_when_confident": True}),
]


def _play(
    env: gym.Env[Any, Any], agent: Agent, seeds: range, reset_agent: bool
) -> list[tuple[float, str]]:
    """Episode returns and final statuses of ``agent`` over ``seeds``, one after another."""
    outcomes = []
    for seed in seeds:
        if reset_agent:
            agent.reset(seed=seed)
        observation, info = env.reset(seed=seed)
        total, done = 0.0, False
        while not done:
            observation, reward, terminated, truncated, info = env.step(agent.act(observation))
            total += float(reward)
            done = terminated or truncated
        outcomes.append((total, str(info["status"])))
    return outcomes


@pytest.mark.parametrize(("env_id", "agent_name", "options"), SCRIPTED_CASES)
def test_scripted_agent_driven_without_reset_plays_as_with_reset(
    env_id: str, agent_name: str, options: dict[str, Any]
) -> None:
    env = gym.make(env_id)
    with_reset = _play(env, make_agent(agent_name, env, **options), range(2), reset_agent=True)
    without_reset = _play(env, make_agent(agent_name, env, **options), range(2), False)
    assert without_reset == with_reset


def test_beacon_scan_paper_agent_localizes_as_often_without_reset() -> None:
    env = gym.make(BEACON_SCAN)
    seeds = range(20)
    with_reset = _play(env, make_agent("paper", env), seeds, reset_agent=True)
    without_reset = _play(env, make_agent("paper", env), seeds, reset_agent=False)
    localized = [status == "ok" for _, status in with_reset]
    assert [status == "ok" for _, status in without_reset] == localized
    assert sum(localized) > len(seeds) // 2  # the paper's procedure localizes in most rooms


class _CountingAgent(ScriptedAgent[Any]):
    """Localizes at once and counts the episodes it started."""

    def __init__(self, env: gym.Env[Any, Any]) -> None:
        super().__init__(env)
        self.episodes_started = 0

    def start_episode(self) -> None:
        self.episodes_started += 1

    def decide(self, observation: np.ndarray) -> Any:
        return self._env.encode_action("localize")


def test_reset_before_the_env_reset_starts_the_episode_once() -> None:
    env = gym.make(BEACON_SCAN)
    agent = _CountingAgent(env)
    agent.reset(seed=0)
    observation, _ = env.reset(seed=0)
    agent.act(observation)
    assert agent.episodes_started == 1
    observation, _ = env.reset(seed=1)
    agent.act(observation)
    agent.act(observation)
    assert agent.episodes_started == 2


def test_scripted_agent_refuses_an_env_that_is_not_a_sonar_env() -> None:
    with pytest.raises(ValueError, match="sonar_gym environment.*CartPoleEnv"):
        BeaconScanPaperAgent(gym.make("CartPole-v1"))


ACTIVE_BEACON_SCAN = "SonarGym/ActiveBeaconScan-v0"


@pytest.mark.parametrize(
    ("env_id", "agent_name", "env_kwargs", "argument", "needed", "offered"),
    [
        (BEACON_SCAN, "paper", {"increments_deg": [5]}, "increments_deg", "1", "[5]"),
        (
            BEACON_SCAN,
            "paper",
            {"sector_widths_deg": [90, 180]},
            "sector_widths_deg",
            "360",
            "[90, 180]",
        ),
        (BEACON_SCAN, "sector", {"sector_widths_deg": [60]}, "sector_widths_deg", "360", "[60]"),
        (ACTIVE_BEACON_SCAN, "paper", {"increments_deg": [2, 5]}, "increments_deg", "1", "[2, 5]"),
        (ACTIVE_BEACON_SCAN, "retry", {"increments_deg": [5]}, "increments_deg", "1", "[5]"),
        (
            ACTIVE_BEACON_SCAN,
            "retry",
            {"turn_angles_deg": [30, -30]},
            "turn_angles_deg",
            "90",
            "[30, -30]",
        ),
    ],
)
def test_scripted_agent_refuses_up_front_an_env_without_the_choices_it_needs(
    env_id: str,
    agent_name: str,
    env_kwargs: dict[str, Any],
    argument: str,
    needed: str,
    offered: str,
) -> None:
    env = gym.make(env_id, **env_kwargs)
    with pytest.raises(AgentEnvMismatchError) as caught:
        make_agent(agent_name, env)
    message = str(caught.value)
    assert f"agent {agent_name!r} cannot act in {env_id}" in message
    assert f"env argument {argument!r} to include {needed}" in message
    assert f"the env has {argument}={offered}" in message


@pytest.mark.parametrize(
    ("env_id", "agent_name", "env_kwargs"),
    [
        # no 360 deg sector, but one wide enough wherever the 90 deg centre grid snaps to
        (BEACON_SCAN, "sector", {"sector_widths_deg": [90, 180], "n_sector_centres": 4}),
        # the paper agent never turns, so it needs none of the turns
        (ACTIVE_BEACON_SCAN, "paper", {"turn_angles_deg": [30, -30]}),
    ],
)
def test_scripted_agent_plays_an_env_that_offers_what_its_procedure_uses(
    env_id: str, agent_name: str, env_kwargs: dict[str, Any]
) -> None:
    env = gym.make(env_id, **env_kwargs)
    outcomes = _play(env, make_agent(agent_name, env), range(5), reset_agent=False)
    assert len(outcomes) == 5
