"""Scripted agents for ``SonarGym/WallCorrection-v0`` (registered on import).

``paper``: APCS as Yamamoto et al. ran it (sec. 6): the side sonar on the wall side sampling
every 3 cm of travel, on every leg, with the robot on the corridor's centre line. The wall side
is the side whose mapped wall is nearer ahead (read from the observation's map-ahead
features); on a tie, the left side, the side the paper's experiment used ("In this experiment
only left side is used").

``both_walls``: a heuristic beyond the paper. It runs the flat-wall detection on both side
sonars at once, which the paper describes but did not use ("If there are some ultrasonic
sensors equipped to the different directions, the flat wall detection process for each
direction could be run in parallel", sec. 4.2.2), at the paper's 3 cm on the centre line.
The two sonars look in opposite directions and listen at the same time, so this costs no
more sensing time than one side, and it roughly doubles the matched walls. That matters
because the +-0.5 deg orientation test (sec. 6) rejects every wall once the heading error
exceeds about half a degree: corrections must come often enough that the drift never gets
there, and with one wall a pillar, a doorway or an unmapped board can leave a gap long enough
to lose the heading for good. Optionally (``pause_when_confident``) it skips a leg, never two
in a row, when the filter's heading and across-corridor deviations are both small.

Everything the agents decide on comes from the observation.
"""

from __future__ import annotations

from abc import abstractmethod
import math
from typing import Any

import gymnasium as gym
import numpy as np

from sonar_gym.agents.base import ScriptedAgent
from sonar_gym.envs.wall_correction import (
    HEADING_STD_SCALE_RAD,
    POSITION_STD_SCALE_M,
    WallCorrectionEnv,
)

ENV_ID = "SonarGym/WallCorrection-v0"
PAPER_SPACING_CM = 3
"""APCS sec. 6: "The data of ultrasonic sensors were taken every 3cm"."""
_TIE_TOLERANCE = 1e-3


class _WallCorrectionAgent(ScriptedAgent[WallCorrectionEnv]):
    """Shared reading of the observation and encoding of the actions."""

    def __init__(self, env: gym.Env[Any, Any]) -> None:
        super().__init__(env)
        self._layout = self._env.observation_layout
        config = self._env.config
        self._spacing_cm = (
            PAPER_SPACING_CM
            if PAPER_SPACING_CM in config.sample_spacings_cm
            else min(config.sample_spacings_cm)
        )

    def _map_ahead(self, observation: np.ndarray) -> tuple[float, float, float, float]:
        """``(left continuity, left distance, right continuity, right distance)``, normalised."""
        left_run, left_distance, right_run, right_distance = (
            float(v) for v in observation[self._layout["map_ahead"]]
        )
        return left_run, left_distance, right_run, right_distance

    def _action(self, side: str) -> Any:
        return self._env.encode_action(side, spacing_cm=self._spacing_cm, standoff_m=0.0)

    @abstractmethod
    def decide(self, observation: np.ndarray) -> Any:
        """The action for this observation."""


class PaperAgent(_WallCorrectionAgent):
    """Yamamoto et al.: the wall-side sonar every 3 cm on every leg, on the centre line."""

    name = "paper"

    def decide(self, observation: np.ndarray) -> Any:
        _, left_distance, _, right_distance = self._map_ahead(observation)
        side = "right" if right_distance < left_distance - _TIE_TOLERANCE else "left"
        return self._action(side)


class BothWallsAgent(_WallCorrectionAgent):
    """APCS on both side sonars every 3 cm, on the centre line (see the module docstring).

    Args:
        pause_when_confident: skip a leg (never two in a row) when the heading deviation is
            below ``heading_std_threshold_deg`` and the across-corridor deviation below
            ``position_std_threshold_m``.
        heading_std_threshold_deg: heading standard deviation of a confident estimate, degrees.
        position_std_threshold_m: across-corridor standard deviation of a confident estimate,
            metres.
    """

    name = "both_walls"

    def __init__(
        self,
        env: gym.Env[Any, Any],
        pause_when_confident: bool = False,
        heading_std_threshold_deg: float = 0.3,
        position_std_threshold_m: float = 0.01,
    ) -> None:
        super().__init__(env)
        self.pause_when_confident = pause_when_confident
        self.heading_std_threshold_rad = math.radians(heading_std_threshold_deg)
        self.position_std_threshold_m = position_std_threshold_m
        self._paused_last_leg = False

    def start_episode(self) -> None:
        self._paused_last_leg = False

    def decide(self, observation: np.ndarray) -> Any:
        if self.pause_when_confident and not self._paused_last_leg and self._confident(observation):
            self._paused_last_leg = True
            return self._action("none")
        self._paused_last_leg = False
        return self._action("both")

    def _confident(self, observation: np.ndarray) -> bool:
        across_std_m = float(observation[self._layout["position_std"]][1]) * POSITION_STD_SCALE_M
        heading_std_rad = float(observation[self._layout["heading_std"]][0]) * HEADING_STD_SCALE_RAD
        return (
            heading_std_rad < self.heading_std_threshold_rad
            and across_std_m < self.position_std_threshold_m
        )
