"""Agents: the papers' scripted procedures, random and heuristic baselines, learned policies.

``make_agent(name, env)`` builds one by name (``agent_names(env_id)`` lists them) or loads a
saved stable-baselines3 model from a path. Scripted agents derive from :class:`ScriptedAgent`.
"""

from sonar_gym.agents.base import (
    Agent,
    AgentEnvMismatchError,
    ScriptedAgent,
    agent_names,
    make_agent,
    register_agent,
)

__all__ = [
    "Agent",
    "AgentEnvMismatchError",
    "ScriptedAgent",
    "agent_names",
    "make_agent",
    "register_agent",
]
