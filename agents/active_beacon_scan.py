"""Scripted agents for ``SonarGym/ActiveBeaconScan-v0``.

``paper``: Beom & Cho's procedure at the start pose, never moving: one full 360 deg pan at
1 deg (Table I), a speed-of-sound calibration when allowed (section II.A), try the fix, commit.

``retry``: the same; when the fix gives no pose (no RCD pair, D < 0), turn and move a short
way to a new pose and pan and try again, up to ``max_retries`` times, then commit.
"""

from __future__ import annotations

from collections import deque
from typing import Any

import gymnasium as gym
import numpy as np

from sonar_gym.agents.base import ScriptedAgent, require_offered
from sonar_gym.agents.beacon_scan import require_full_pan
from sonar_gym.envs.active_beacon_scan import ActiveBeaconScanEnv


class RetryAgent(ScriptedAgent[ActiveBeaconScanEnv]):
    """Full pan, calibrate, try_fix; on failure turn + move and rescan, then commit.

    Args:
        max_retries: new poses to try after a failed fix (0: Beom & Cho's procedure).
        turn_deg: the turn before each move, degrees CCW (one of the env's ``turn_angles_deg``).

    Raises:
        AgentEnvMismatchError: the env offers no 360 deg sector or no 1 deg increment, or
            (with retries) not the turn ``turn_deg``.
    """

    name = "retry"

    def __init__(self, env: gym.Env[Any, Any], max_retries: int = 3, turn_deg: int = 90) -> None:
        super().__init__(env)
        self.max_retries = max_retries
        self.turn_deg = turn_deg
        require_full_pan(self.name, self._env)
        if max_retries > 0:
            require_offered(
                self.name,
                self._env,
                f"its turn of {turn_deg} deg before each new pose",
                "turn_angles_deg",
                turn_deg,
                self._env.config.turn_angles_deg,
            )
        self._retries = 0
        self._queue: deque[Any] = deque()

    def start_episode(self) -> None:
        self._retries = 0
        self._queue.clear()

    def _flag(self, observation: np.ndarray, name: str) -> bool:
        return bool(observation[self._env.observation_layout[name]][0] > 0.5)

    def decide(self, observation: np.ndarray) -> Any:
        env = self._env
        if self._queue:
            return self._queue.popleft()
        if self._flag(observation, "fix_ok"):
            return env.encode_action("commit")
        if self._flag(observation, "fix_tried"):
            if self._retries >= self.max_retries:
                return env.encode_action("commit")
            self._retries += 1
            self._queue.append(env.encode_action("move"))
            return env.encode_action("turn", turn_deg=self.turn_deg)
        if observation[env.observation_layout["coverage"]][0] < 1.0:
            return env.encode_action("pan", centre_deg=0, width_deg=360, increment_deg=1)
        if self._flag(observation, "calibration_allowed") and not self._flag(
            observation, "calibrated"
        ):
            return env.encode_action("calibrate")
        return env.encode_action("try_fix")


class PaperAgent(RetryAgent):
    """Beom & Cho at the start pose: full pan at 1 deg, calibrate (if allowed), fix, commit."""

    name = "paper"

    def __init__(self, env: gym.Env[Any, Any]) -> None:
        super().__init__(env, max_retries=0)
