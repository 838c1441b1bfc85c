"""Running one scripted episode, shared by the environment tests."""

from __future__ import annotations

from typing import Any

import gymnasium as gym

from sonar_gym.agents import make_agent


def run_episode(env: gym.Env, agent_name: str, seed: int) -> tuple[float, dict[str, Any]]:
    """Play agent ``agent_name`` for one episode from ``reset(seed=seed)``.

    Returns the summed reward and the final ``info``.
    """
    agent = make_agent(agent_name, env)
    agent.reset(seed=seed)
    observation, info = env.reset(seed=seed)
    total = 0.0
    while True:
        observation, reward, terminated, truncated, info = env.step(agent.act(observation))
        total += reward
        if terminated or truncated:
            return total, info
