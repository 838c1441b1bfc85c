"""Registers the built-in agents with :mod:`agents.base` on import.

Each task's module registers its own agents with ``register_agent`` when imported; the random
agent serves every environment.
"""

import importlib

from agents.base import GENERIC, register_agent
from agents.random_agent import RandomAgent

TASK_AGENT_MODULES = (
    "agents.beacon_scan",
    "agents.sweep_localization",
    "agents.trilateration",
    "agents.block_expansion",
    "agents.wall_correction",
)

register_agent("random", RandomAgent, GENERIC)
for module_name in TASK_AGENT_MODULES:
    importlib.import_module(module_name)
