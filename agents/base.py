"""The one protocol every agent follows, the base of the scripted agents, and the registry
that builds agents by name.

An agent maps an observation to an action (``act``). Scripted agents may read the
environment they are built for through its agent API (:mod:`sonar_gym.envs.base`: its
configuration, observation layout, action encoding and episode counter) when they are made
and to tell a new episode, never the hidden state during an episode: everything they decide
on comes through ``act``'s observation, exactly as for a learned policy.

Agents are registered as entry points, ``"module:attribute"`` strings (the built-in ones in
:mod:`sonar_gym.agents.builtin`), imported only when that agent is made.
"""

from __future__ import annotations

import importlib
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Generic, Protocol, TypeVar, cast, runtime_checkable

import gymnasium as gym

from sonar_gym.agents.builtin import BUILTIN_AGENTS, CONDITIONAL_AGENTS, GENERIC
from sonar_gym.envs.base import SonarEnv, unwrap_sonar_env


@runtime_checkable
class Agent(Protocol):
    """Chooses actions from observations."""

    name: str

    def reset(self, seed: int | None = None) -> None:
        """Start a new episode; ``seed`` seeds any randomness the agent has."""

    def act(self, observation: Any) -> Any:
        """The action for this observation (an element of the env's action space)."""


EnvT = TypeVar("EnvT", bound=SonarEnv)


class AgentEnvMismatchError(ValueError):
    """An agent cannot act in an env: the env's arguments leave out a choice the agent's
    procedure needs (the message names the agent, the env argument and what the env offers)."""


class ScriptedAgent(ABC, Generic[EnvT]):
    """Base of the scripted agents: a fixed procedure over one sonar_gym environment.

    Subclasses implement :meth:`decide` and, if they keep anything from one decision to the
    next, :meth:`start_episode`. The agent notices a new episode itself: the env's
    ``episode_count`` changes at every ``reset``, so a caller that only ever calls
    ``act(observation)`` gets the same actions as one that also calls ``reset()`` before each
    episode.

    Args:
        env: the environment (any wrappers around a :class:`SonarEnv`) the agent acts in.

    Raises:
        ValueError: ``env`` is not a sonar_gym environment.
        AgentEnvMismatchError: the env's arguments leave out a choice the procedure needs.
    """

    name: str = "scripted"

    def __init__(self, env: gym.Env[Any, Any]) -> None:
        self._env: EnvT = cast(EnvT, unwrap_sonar_env(env))
        self._episode_seen: int | None = None

    def reset(self, seed: int | None = None) -> None:
        """Start a new episode (scripted agents draw nothing, so ``seed`` is unused)."""
        self._episode_seen = None  # adopt the next episode without starting it twice
        self.start_episode()

    def act(self, observation: Any) -> Any:
        """The action for ``observation``, after starting afresh if the env began a new episode."""
        current = self._env.episode_count
        if self._episode_seen is None:
            self._episode_seen = current
        elif current != self._episode_seen:
            self._episode_seen = current
            self.start_episode()
        return self.decide(observation)

    def start_episode(self) -> None:
        """Forget the previous episode (nothing to forget by default)."""

    @abstractmethod
    def decide(self, observation: Any) -> Any:
        """The procedure's action for ``observation`` within the current episode."""


def env_mismatch(agent: str, env: SonarEnv, reason: str) -> AgentEnvMismatchError:
    """The error refusing ``env`` to agent ``agent``, ``reason`` naming the argument that
    falls short and what the env has."""
    env_name = env.spec.id if env.spec is not None else type(env).__name__
    return AgentEnvMismatchError(f"agent {agent!r} cannot act in {env_name}: {reason}")


def require_offered(
    agent: str, env: SonarEnv, purpose: str, argument: str, needed: int, offered: Sequence[int]
) -> None:
    """Refuse ``env`` to agent ``agent`` unless its argument ``argument`` (with the value
    ``offered``) offers ``needed``, which the agent's ``purpose`` needs.

    Raises:
        AgentEnvMismatchError: ``needed`` is not in ``offered``.
    """
    if needed not in offered:
        raise env_mismatch(
            agent,
            env,
            f"{purpose} needs the env argument {argument!r} to include {needed}; "
            f"the env has {argument}={list(offered)}",
        )


AgentFactory = Callable[..., Agent]
"""Builds an agent from the env (and keyword options): an agent class or a function."""
_REGISTRY: dict[str, dict[str, AgentFactory | str]] = {
    env_id: dict(agents) for env_id, agents in BUILTIN_AGENTS.items()
}
_REGISTRY.setdefault(GENERIC, {}).update(
    {name: factory for name, (factory, _) in CONDITIONAL_AGENTS.items()}
)


def register_agent(name: str, factory: AgentFactory | str, env_id: str = GENERIC) -> None:
    """Register agent ``name`` for ``env_id`` (every env with ``"*"``).

    Args:
        name: the agent's name (``sonar-gym evaluate --agent NAME``).
        factory: a callable ``factory(env, **options) -> Agent``, or its entry point
            ``"module:attribute"``, imported only when the agent is made.
        env_id: the environment id the agent is for.

    Raises:
        ValueError: an entry point not of the form ``"module:attribute"``.
    """
    if isinstance(factory, str):
        _split_entry_point(factory)
    _REGISTRY.setdefault(env_id, {})[name] = factory


def agent_names(env_id: str) -> list[str]:
    """Names of the agents available for ``env_id`` (imports no agent module); an agent of
    :data:`~sonar_gym.agents.builtin.CONDITIONAL_AGENTS` only where its predicate holds."""
    names = set(_REGISTRY.get(env_id, {})) | set(_REGISTRY.get(GENERIC, {}))
    return sorted(name for name in names if not is_conditional(name) or _available(name, env_id))


def is_conditional(name: str) -> bool:
    """True for an agent offered only where a file it loads exists (e.g. ``learned``): it can
    be made for any env, and then fails with a ``ValueError`` when it does not fit."""
    return name in CONDITIONAL_AGENTS


def _available(name: str, env_id: str) -> bool:
    module_name, attribute = _split_entry_point(CONDITIONAL_AGENTS[name][1])
    predicate: Callable[[str], bool] = getattr(importlib.import_module(module_name), attribute)
    return bool(predicate(env_id))


def make_agent(name: str, env: gym.Env[Any, Any], **options: Any) -> Agent:
    """Build agent ``name`` for ``env``; a path to a saved model loads a learned policy, and
    ``"learned"`` the policy shipped for the env's id (:mod:`sonar_gym.pretrained`).

    Args:
        name: a registered agent name, or the path of a saved model (``.zip`` or run dir).
        env: the environment the agent will act in.
        options: keyword arguments of the agent's constructor.

    Raises:
        ValueError: the name is neither a registered agent for this env nor an existing
            model file; the message lists what is allowed.
        AgentEnvMismatchError: (a ``ValueError``) a built-in agent whose procedure the env's
            arguments do not allow (e.g. the paper's 1 deg pan where the env offers only 5 deg).
    """
    env_id = env.spec.id if env.spec is not None else ""
    factory = _REGISTRY.get(env_id, {}).get(name) or _REGISTRY.get(GENERIC, {}).get(name)
    if factory is not None:
        return _resolve(factory)(env, **options)
    from sonar_gym.agents.rllib_policy import RLlibPolicyAgent, is_rllib_run

    if is_rllib_run(name):
        return RLlibPolicyAgent(name, env)
    if name.endswith(".zip") or Path(name).exists():
        from sonar_gym.agents.learned import load_policy_agent

        return load_policy_agent(name, env)
    raise ValueError(
        f"unknown agent {name!r} for {env_id or 'this env'}; choose one of "
        f"{agent_names(env_id)} or give the path of a saved model (.zip) or RLlib run directory"
    )


def _resolve(factory: AgentFactory | str) -> AgentFactory:
    if not isinstance(factory, str):
        return factory
    module_name, attribute = _split_entry_point(factory)
    resolved: AgentFactory = getattr(importlib.import_module(module_name), attribute)
    return resolved


def _split_entry_point(entry_point: str) -> tuple[str, str]:
    module_name, _, attribute = entry_point.partition(":")
    if not module_name or not attribute:
        raise ValueError(
            f"argument 'factory' must be a callable or an entry point 'module:attribute'; "
            f"got {entry_point!r}"
        )
    return module_name, attribute
