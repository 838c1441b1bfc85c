"""The SweepLocalization observation as it was written through the observation writer (two runs
of features and the range bins, then a clip of the float32 vector): the form its one-list
build replaced, kept as the tests' reference."""

from __future__ import annotations

import math

import numpy as np

from sonar_gym.envs.features import Heading, ScaledPosition
from sonar_gym.envs.sweep_localization import (
    _STD_SCALES,
    DISTANCE_SCALE_M,
    SECTOR_CENTRES_RAD,
    SweepLocalizationEnv,
)
from sonar_gym.pose import wrap_angle


def observe_with_writer(env: SweepLocalizationEnv) -> np.ndarray:
    """``env``'s observation of its current episode, written feature run by feature run."""
    self = env
    spec = env.observation_spec
    belief_run = spec.run(
        (
            "estimate_xy",
            "estimate_heading",
            "estimate_std",
            "distance_since_fix",
            "route_progress",
        )
    )
    status_run = spec.run(("last_sweep_sector", "last_fix_ok", "route_heading", "steps_remaining"))
    episode = self._require_episode()
    observation = self.observation_spec.writer()
    estimate = episode.estimate
    low, high = self._bounds
    variances = episode.covariance.diagonal().tolist()
    observation.write_run(
        belief_run,
        [
            *ScaledPosition.float_values((estimate.x, estimate.y), low, high),
            *Heading.values(estimate.theta),
            *[
                min(max(math.sqrt(max(variance, 0.0)) / scale, 0.0), 1.0)
                for variance, scale in zip(variances, _STD_SCALES, strict=True)
            ],
            min(episode.distance_since_fix_m / DISTANCE_SCALE_M, 1.0),
            min(episode.progress_m / max(episode.route.length_m, 1e-9), 1.0),
        ],
    )
    observation["last_sweep_ranges"] = self._sweep_bins.values(episode.last_ranges)
    station_x, station_y = self._next_station_point(episode)
    ahead_x, ahead_y = station_x - estimate.x, station_y - estimate.y
    bearing = (
        wrap_angle(math.atan2(ahead_y, ahead_x) - estimate.theta)
        if ahead_x != 0.0 or ahead_y != 0.0
        else 0.0
    )
    remaining = len(episode.decision_stations_m) - episode.decisions
    observation.write_run(
        status_run,
        [
            *Heading.values(SECTOR_CENTRES_RAD[episode.last_sector]),
            float(episode.last_fix_ok),
            *Heading.values(bearing),
            remaining / len(episode.decision_stations_m),
        ],
    )
    return observation.vector.clip(-1.0, 1.0)


def scaled_position_with_min_max(
    position: tuple[float, float], low: tuple[float, float], high: tuple[float, float]
) -> list[float]:
    """``ScaledPosition.float_values`` as it was written, clipped with ``min`` and ``max``."""
    return [
        min(max(2.0 * (p - lo) / (hi - lo) - 1.0, -1.0), 1.0)
        for p, lo, hi in zip(position, low, high, strict=True)
    ]
