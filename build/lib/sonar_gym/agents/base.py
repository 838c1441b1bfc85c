"""The one protocol every agent follows, and the registry that builds agents by name.

An agent maps an observation to an action (``act``). Scripted agents may read the
environment they are built for (its scenario, its action layout) when they are made, never
the hidden state during an episode: everything they decide on comes through ``act``'s
observation, exactly as for a learned policy.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import gymnasium as gym


@runtime_checkable
class Agent(Protocol):
    """Chooses actions from observations."""

    name: str

    def reset(self, seed: int | None = None) -> None:
        """Start a new episode; ``seed`` seeds any randomness the agent has."""

    def act(self, observation: Any) -> Any:
        """The action for this observation (an element of the env's action space)."""


AgentFactory = Callable[[gym.Env], Agent]
_REGISTRY: dict[str, dict[str, AgentFactory]] = {}
GENERIC = "*"


def register_agent(name: str, factory: AgentFactory, env_id: str = GENERIC) -> None:
    """Register ``factory`` as agent ``name`` for ``env_id`` (or every env with ``"*"``)."""
    _REGISTRY.setdefault(env_id, {})[name] = factory


def agent_names(env_id: str) -> list[str]:
    """Names of the agents available for ``env_id``."""
    _load_builtin_agents()
    return sorted(set(_REGISTRY.get(env_id, {})) | set(_REGISTRY.get(GENERIC, {})))


def make_agent(name: str, env: gym.Env) -> Agent:
    """Build agent ``name`` for ``env``; a path to a saved model loads a learned policy.

    Raises:
        ValueError: the name is neither a registered agent for this env nor an existing
            model file; the message lists what is allowed.
    """
    _load_builtin_agents()
    env_id = env.spec.id if env.spec is not None else ""
    factory = _REGISTRY.get(env_id, {}).get(name) or _REGISTRY.get(GENERIC, {}).get(name)
    if factory is not None:
        return factory(env)
    if name.endswith(".zip") or Path(name).exists():
        from sonar_gym.agents.learned import load_policy_agent

        return load_policy_agent(name, env)
    raise ValueError(
        f"unknown agent {name!r} for {env_id or 'this env'}; choose one of "
        f"{agent_names(env_id)} or give the path of a saved model (.zip)"
    )


def _load_builtin_agents() -> None:
    """Import the modules that register the built-in agents (once)."""
    import sonar_gym.agents.builtin  # noqa: F401  (registers on import)
