"""Scripted agents for ``SonarGym/SweepLocalization-v0`` (registered on import).

``paper``: Kim, Lee & Jeong's procedure: at every decision point, sweeps toward the front
sector ("the rotating angle is determined to 90 degree to get the forward environment
information", sec. 3), combined through dead reckoning. Sec. 3.3: "best results are observed
when between two and four sweeps are used to build the local map. If more are used, the map
will be distorted"; within that range "if more sweeps are added, the localization process will
be more accurate". The paper names no single number; the agent takes the middle of the range,
3 sweeps (``n_sweeps`` changes it; ``sonar-gym reproduce kim`` measures 1-4).

``covariance``: a heuristic beyond the paper. It sweeps only when the EKF is uncertain (a
position or heading standard deviation in the observation above a threshold), and then toward
the sector with the most usable map structure in view. With ``sector_rule="vote"`` (default)
it predicts each sector's sweep from the estimated pose on the known map (an ideal sweep of
the env's sonar on the scenario's geometry: the agent reads the map, never the hidden state),
runs the voting localization on it from a few priors offset from the estimate, and picks the
sector whose votes come back closest to the estimate (lowest ``E_xy / 0.1 m + E_theta / 5 deg``,
the env's error units): a sector that sees only one wall at normal incidence fixes neither the
position along the wall nor the heading, one that sees corners and edges fixes both.
``sector_rule="range_sum"`` is a cheaper proxy: the sector whose predicted echoes reach
farthest in total (a heading error ``d`` moves the end of a reading of range ``r`` by ``r d``).
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

from sonar_gym.agents.base import ScriptedAgent
from sonar_gym.envs.sweep_localization import (
    HEADING_STD_SCALE_RAD,
    HEADING_UNIT_RAD,
    POSITION_STD_SCALE_M,
    POSITION_UNIT_M,
    SECTOR_CENTRES_RAD,
    SweepLocalizationEnv,
)
from sonar_gym.localization.kim import Sweep, vote_localize
from sonar_gym.pose import Pose, angle_difference
from sonar_gym.sonar.swept import SweptSonar
from sonar_gym.world import World

ENV_ID = "SonarGym/SweepLocalization-v0"
SECTOR_RULES = ("vote", "range_sum")
PRIOR_OFFSETS = ((0.04, 0.0, 3.0), (-0.04, 0.0, -3.0), (0.0, 0.04, -3.0), (0.0, -0.04, 3.0))
"""Priors ``(dx m, dy m, dtheta deg)`` around the estimate from which a predicted sweep is voted:
about one to two standard deviations of the EKF between fixes."""
PREDICTION_SEARCH_RADIUS_M = 0.15
PREDICTION_HEADING_WINDOW_DEG = 6.0
FAILED_PREDICTION_LOSS = 5.0
"""Loss charged to a predicted vote that returns no pose (in the env's error units)."""


def _decode_estimate(env: SweepLocalizationEnv, observation: np.ndarray) -> Pose:
    """The EKF estimate in {W} from the observation's normalised features."""
    layout = env.observation_layout
    (x_min, y_min), (x_max, y_max) = env.scenario.bounds
    x_n, y_n = (float(v) for v in observation[layout["estimate_xy"]])
    cos_h, sin_h = (float(v) for v in observation[layout["estimate_heading"]])
    return Pose(
        x_min + 0.5 * (x_n + 1.0) * (x_max - x_min),
        y_min + 0.5 * (y_n + 1.0) * (y_max - y_min),
        math.atan2(sin_h, cos_h),
    )


def _check_sweep_count(env: SweepLocalizationEnv, n_sweeps: object) -> int:
    max_sweeps = env.config.max_sweeps
    if (
        isinstance(n_sweeps, bool)
        or not isinstance(n_sweeps, int)
        or not 1 <= n_sweeps <= max_sweeps
    ):
        raise ValueError(
            f"argument 'n_sweeps' must be an integer in [1, {max_sweeps}]; got {n_sweeps!r}"
        )
    return n_sweeps


class PaperAgent(ScriptedAgent[SweepLocalizationEnv]):
    """Kim et al.: ``n_sweeps`` forward sweeps at every decision point.

    Args:
        env: the environment (its action encoding is read).
        n_sweeps: sweeps per decision, 3 by default (the middle of the paper's 2-4).
    """

    name = "paper"

    def __init__(self, env: gym.Env[Any, Any], n_sweeps: int = 3) -> None:
        super().__init__(env)
        self.n_sweeps = _check_sweep_count(self._env, n_sweeps)

    def decide(self, observation: np.ndarray) -> np.ndarray:
        return self._env.encode_action(self.n_sweeps, "front")


class CovarianceAgent(ScriptedAgent[SweepLocalizationEnv]):
    """Sweeps only when the EKF is uncertain, toward the sector with the most structure.

    Args:
        env: the environment (its scenario, map, sonar and observation layout are read).
        position_std_threshold_m: sweep when ``sqrt(P_xx)`` or ``sqrt(P_yy)`` exceeds this (m).
        heading_std_threshold_deg: ... or when ``sqrt(P_thth)`` exceeds this (deg).
        n_sweeps: sweeps taken when sensing.
        sector_rule: ``"vote"`` or ``"range_sum"`` (see the module docstring).
    """

    name = "covariance"

    def __init__(
        self,
        env: gym.Env[Any, Any],
        position_std_threshold_m: float = 0.02,
        heading_std_threshold_deg: float = 3.5,
        n_sweeps: int = 2,
        sector_rule: str = "vote",
    ) -> None:
        super().__init__(env)
        self.n_sweeps = _check_sweep_count(self._env, n_sweeps)
        for name, value in (
            ("position_std_threshold_m", position_std_threshold_m),
            ("heading_std_threshold_deg", heading_std_threshold_deg),
        ):
            if (
                isinstance(value, bool)
                or not isinstance(value, (int, float))
                or not (math.isfinite(value) and value >= 0.0)
            ):
                raise ValueError(f"argument {name!r} must be a finite number >= 0; got {value!r}")
        if sector_rule not in SECTOR_RULES:
            raise ValueError(
                f"argument 'sector_rule' must be one of {list(SECTOR_RULES)}; got {sector_rule!r}"
            )
        self.position_std_threshold_m = float(position_std_threshold_m)
        self.heading_std_threshold_rad = math.radians(heading_std_threshold_deg)
        self.sector_rule = sector_rule
        self._map_world = World(self._env.scenario, temperature_c=20.0)
        sonar: SweptSonar = self._env.sonar
        self._predictor = sonar.with_readout(
            range_noise=False, crossing_delay=False, quantisation=False
        )
        self._rng = np.random.default_rng(0)  # an ideal readout draws nothing; the API wants one

    def decide(self, observation: np.ndarray) -> np.ndarray:
        layout = self._env.observation_layout
        std_x, std_y, std_heading = (float(v) for v in observation[layout["estimate_std"]])
        position_std = max(std_x, std_y) * POSITION_STD_SCALE_M
        heading_std = std_heading * HEADING_STD_SCALE_RAD
        if (
            position_std <= self.position_std_threshold_m
            and heading_std <= self.heading_std_threshold_rad
        ):
            return self._env.encode_action(0, "front")
        estimate = _decode_estimate(self._env, observation)
        losses = [self.predicted_loss(estimate, centre) for centre in SECTOR_CENTRES_RAD]
        return self._env.encode_action(self.n_sweeps, int(np.argmin(losses)))

    def predicted_loss(self, estimate: Pose, sector_centre_rad: float) -> float:
        """How badly a sweep toward ``sector_centre_rad`` ({R}, rad) is expected to localize.

        ``"vote"``: the mean over :data:`PRIOR_OFFSETS` of the vote's error against the
        estimate, in units of 0.1 m and 5 deg. ``"range_sum"``: minus the sum of the predicted
        ranges (m).
        """
        scan = self._predictor.sweep(self._map_world, estimate, self._rng, sector_centre_rad)
        if self.sector_rule == "range_sum":
            return -float(np.nansum(scan.ranges))
        sweep = Sweep(scan.angles, scan.ranges, self._map_world.scenario.robot.sensor_offset)
        total = 0.0
        for dx, dy, dtheta_deg in PRIOR_OFFSETS:
            prior = Pose(
                estimate.x + dx, estimate.y + dy, estimate.theta + math.radians(dtheta_deg)
            )
            result = vote_localize(
                self._env.grid,
                [sweep],
                search_center=prior,
                search_radius=PREDICTION_SEARCH_RADIUS_M,
                heading_window_rad=math.radians(PREDICTION_HEADING_WINDOW_DEG),
                max_range_m=self._predictor.transducer.max_range_m,
                anchor=self._env.config.anchor,
                return_vote_map=False,
            )
            if not result.ok or result.pose is None:
                total += FAILED_PREDICTION_LOSS
                continue
            total += (
                math.hypot(result.pose.x - estimate.x, result.pose.y - estimate.y) / POSITION_UNIT_M
                + abs(angle_difference(result.pose.theta, estimate.theta)) / HEADING_UNIT_RAD
            )
        return total / len(PRIOR_OFFSETS)
