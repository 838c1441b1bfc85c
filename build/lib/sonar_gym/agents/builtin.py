"""Registers the built-in agents with :mod:`sonar_gym.agents.base` on import.

Each task's module registers its own agents with ``register_agent`` when imported; the random
agent serves every environment.
"""

import importlib

from sonar_gym.agents.base import GENERIC, register_agent
from sonar_gym.agents.random_agent import RandomAgent

TASK_AGENT_MODULES = (
    "sonar_gym.agents.beacon_scan",
    "sonar_gym.agents.sweep_localization",
    "sonar_gym.agents.trilateration",
    "sonar_gym.agents.block_expansion",
    "sonar_gym.agents.wall_correction",
)

register_agent("random", RandomAgent, GENERIC)
for module_name in TASK_AGENT_MODULES:
    importlib.import_module(module_name)
