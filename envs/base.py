"""The small base every sonar_gym environment builds on.

A task subclasses :class:`SonarEnv` and fills four hooks: ``_reset_task`` (build the episode
from ``self.np_random``), ``_apply_action`` (one decision: sense, move or localize), ``_observe``
(the float32 observation) and ``_render_frame``. The base owns what must be the same
everywhere: seeding, action validation, the finite-value guard on observations and rewards,
the ``info`` keys, and the wall-clock profile that ``sonar-gym benchmark`` reads.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

INFO_KEYS = ("position_error_m", "heading_error_rad", "sensing_time_s", "status")


@dataclass
class StepOutcome:
    """What a task's ``_apply_action`` returns; the base adds the observation and checks."""

    reward: float
    terminated: bool = False
    truncated: bool = False
    info: dict[str, Any] = field(default_factory=dict)


class SonarEnv(gym.Env[np.ndarray, Any], ABC):
    """Shared machinery of the sonar_gym tasks (not registered itself)."""

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(self, render_mode: str | None = None) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"argument 'render_mode' must be one of {self.metadata['render_modes']} or None; "
                f"got {render_mode!r}"
            )
        self.render_mode = render_mode
        self.timing: dict[str, float] = {"sensing": 0.0, "localization": 0.0}
        self._episode_started = False

    # --- hooks -------------------------------------------------------------------------
    @abstractmethod
    def _reset_task(self, options: dict[str, Any] | None) -> dict[str, Any]:
        """Build a new episode from ``self.np_random``; return the task's reset info."""

    @abstractmethod
    def _apply_action(self, action: Any) -> StepOutcome:
        """Carry out one validated action."""

    @abstractmethod
    def _observe(self) -> np.ndarray:
        """The current observation, an element of ``observation_space``."""

    @abstractmethod
    def _render_frame(self) -> np.ndarray:
        """An RGB image ``(H, W, 3)`` uint8 of the current state."""

    # --- Gymnasium API ---------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        info = self._reset_task(options)
        self._episode_started = True
        return self._checked_observation(), info

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if not self._episode_started:
            raise RuntimeError(f"{type(self).__name__}: call reset() before step()")
        if not self.action_space.contains(action):
            raise ValueError(
                f"{type(self).__name__}: action {action!r} is not in the action space "
                f"{self.action_space}"
            )
        outcome = self._apply_action(action)
        reward = float(outcome.reward)
        if not np.isfinite(reward):
            raise RuntimeError(f"{type(self).__name__}: non-finite reward {reward!r}")
        if outcome.terminated or outcome.truncated:
            self._episode_started = False
        return (
            self._checked_observation(),
            reward,
            outcome.terminated,
            outcome.truncated,
            outcome.info,
        )

    def render(self) -> np.ndarray | None:  # type: ignore[override]
        if self.render_mode == "rgb_array":
            return self._render_frame()
        return None

    # --- helpers ---------------------------------------------------------------------
    def _checked_observation(self) -> np.ndarray:
        observation = self._observe()
        if not np.all(np.isfinite(observation)):
            raise RuntimeError(f"{type(self).__name__}: non-finite observation")
        return observation

    @contextmanager
    def _timed(self, phase: str) -> Iterator[None]:
        """Add the wall-clock time of the block to ``self.timing[phase]`` (seconds)."""
        start = time.perf_counter()
        try:
            yield
        finally:
            self.timing[phase] = self.timing.get(phase, 0.0) + time.perf_counter() - start
