"""The agent registry: entry points resolved lazily, no import cycle, clear errors."""

from __future__ import annotations

import importlib
import subprocess
import sys
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import EnvSpec

from sonar_gym.agents import ScriptedAgent, agent_names, make_agent, register_agent
from sonar_gym.agents.builtin import BUILTIN_AGENTS, GENERIC
from sonar_gym.agents.random_agent import RandomAgent
from sonar_gym.registration import ENVIRONMENTS

BEACON_SCAN = "SonarGym/BeaconScan-v0"


class _UserEnv(gym.Env[np.ndarray, int]):
    """A user's own env, known to the agent registry only by its id."""

    observation_space = gym.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
    action_space = gym.spaces.Discrete(2)


def _run_python(code: str) -> str:
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=False, timeout=120
    )
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()


def test_listing_agents_imports_no_agent_or_env_module() -> None:
    loaded = _run_python(
        "import sys\n"
        "from sonar_gym.agents import agent_names\n"
        f"names = agent_names({BEACON_SCAN!r})\n"
        "assert 'paper' in names, names\n"
        "print(sorted(m for m in sys.modules if m.startswith(('sonar_gym.agents.', "
        "'sonar_gym.envs.')) and not m.endswith(('.base', '.builtin'))))"
    )
    assert loaded == "[]"


@pytest.mark.parametrize("module", ["sonar_gym.agents.builtin", "sonar_gym.agents.base"])
def test_each_registry_module_imports_first_on_its_own(module: str) -> None:
    assert _run_python(f"import {module}; print('ok')") == "ok"


def test_every_registered_env_has_a_paper_agent_and_the_random_one() -> None:
    for env_id in ENVIRONMENTS:
        assert {"paper", "random"} <= set(agent_names(env_id)), env_id


@pytest.mark.parametrize(
    ("env_id", "name", "entry_point"),
    [(e, n, p) for e, agents in BUILTIN_AGENTS.items() for n, p in agents.items()],
)
def test_every_builtin_entry_point_names_an_agent_class(
    env_id: str, name: str, entry_point: str
) -> None:
    module_name, attribute = entry_point.split(":")
    agent_class = getattr(importlib.import_module(module_name), attribute)
    expected_base = RandomAgent if env_id == GENERIC else ScriptedAgent
    assert issubclass(agent_class, expected_base)
    assert agent_class.name == name


def test_make_agent_builds_the_registered_class_with_options() -> None:
    env = gym.make("SonarGym/WallCorrection-v0")
    agent: Any = make_agent("both_walls", env, pause_when_confident=True)
    assert type(agent).__name__ == "BothWallsAgent"
    assert agent.pause_when_confident is True


def test_an_entry_point_registered_by_a_user_resolves_when_made() -> None:
    register_agent("user_random", "sonar_gym.agents.random_agent:RandomAgent", "User/Env-v0")
    assert "user_random" in agent_names("User/Env-v0")
    env = _UserEnv()
    env.spec = EnvSpec("User/Env-v0")
    assert isinstance(make_agent("user_random", env), RandomAgent)


def test_a_malformed_entry_point_is_refused_with_its_form() -> None:
    with pytest.raises(ValueError, match="'module:attribute'.*'no_colon'"):
        register_agent("broken", "no_colon", "User/Env-v0")


def test_an_unknown_agent_name_lists_the_known_ones() -> None:
    with pytest.raises(ValueError, match=r"unknown agent 'wizard'.*'paper'"):
        make_agent("wizard", gym.make(BEACON_SCAN))
