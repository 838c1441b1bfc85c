"""The WallCorrection observation as it was written with numpy arrays (the estimate's scaled
position, the standard deviations and the wall counts): the form its float glue replaced, kept
as the tests' reference."""

from __future__ import annotations

import math

import numpy as np

from sonar_gym.envs.features import Heading, ScaledPosition
from sonar_gym.envs.wall_correction import (
    COUNT_SCALE,
    HEADING_STD_SCALE_RAD,
    OBSERVATION,
    POSITION_STD_SCALE_M,
    SIDE_NAMES,
    WallCorrectionEnv,
)


def observe_arrays(env: WallCorrectionEnv) -> np.ndarray:
    """``env``'s observation of its current episode, every step on numpy arrays."""
    route = env._require_episode()
    config = env.config
    observation = OBSERVATION.writer()
    room = env.scenario.room
    assert room is not None
    estimate = route.tracker.estimate
    observation["progress"] = route.leg / config.n_legs
    observation["estimate_xy"] = ScaledPosition.values(estimate.position, room.min, room.max)
    observation["estimate_heading"] = Heading.values(estimate.theta)
    variances = np.maximum(np.diag(route.tracker.covariance), 0.0)
    position_std, heading_std = np.sqrt(variances[:2]), math.sqrt(variances[2])
    observation["position_std"] = np.minimum(position_std / POSITION_STD_SCALE_M, 1.0)
    observation["heading_std"] = min(heading_std / HEADING_STD_SCALE_RAD, 1.0)
    if route.leg < config.n_legs:
        observation["map_ahead"] = env._map_ahead[route.leg]
    last = route.last_leg
    tallies = (last.detected, last.matched, last.rejected)
    counts = [tally[side] for side in SIDE_NAMES for tally in tallies]
    observation["last_leg_walls"] = np.minimum(np.asarray(counts) / COUNT_SCALE, 1.0)
    observation["last_leg_dropped"] = min(last.dropped_groups / COUNT_SCALE, 1.0)
    observation["collided"] = float(last.collided)
    sensing_fraction = route.sensing_time_s / env._max_sensing_time_s
    observation["sensing_time"] = min(sensing_fraction, 1.0)
    observation["samples"] = min(last.samples / env._max_samples_per_leg, 1.0)
    return observation.vector
