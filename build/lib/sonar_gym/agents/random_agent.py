"""The random baseline: uniform samples from the action space, seeded per episode."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np


class RandomAgent:
    """Samples actions uniformly; ``reset(seed)`` makes the sequence reproducible."""

    name = "random"

    def __init__(self, env: gym.Env) -> None:
        self._space = env.action_space
        self._space.seed(0)

    def reset(self, seed: int | None = None) -> None:
        self._space.seed(seed)

    def act(self, observation: np.ndarray) -> Any:
        return self._space.sample()
