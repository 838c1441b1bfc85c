"""The SweepLocalization observation built as one list of floats has exactly the bits of the
writer form it replaced, along seeded episodes and for covariances, distances and estimates
with signed zeros, NaN, infinities and values beyond the clip."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.envs.features import ScaledPosition, clipped
from sonar_gym.envs.sweep_localization import SweepLocalizationEnv
from sonar_gym.pose import Pose
from tests.envs.sweep_localization_observation_reference import (
    observe_with_writer,
    scaled_position_with_min_max,
)

_AWKWARD = (0.0, -0.0, 1.0, -1.0, 1.0 + 2.0**-30, -1.0 - 2.0**-30, 0.5, -0.7, 3.0, -3.0,
            1e-300, -1e300, math.inf, -math.inf, math.nan)  # fmt: skip


def _same_bits(env: SweepLocalizationEnv) -> None:
    got, expected = env._observe(), observe_with_writer(env)
    assert got.dtype == expected.dtype
    assert got.shape == expected.shape
    assert got.tobytes() == expected.tobytes(), (got, expected)


def _env(**kwargs: object) -> SweepLocalizationEnv:
    env = gym.make("SonarGym/SweepLocalization-v0", **kwargs).unwrapped
    assert isinstance(env, SweepLocalizationEnv)
    return env


@pytest.mark.parametrize(
    ("seed", "kwargs"),
    [(0, {}), (1, {"route": "random"}), (2, {"decision_points": "waypoints", "n_range_bins": 5})],
)
def test_the_observation_has_the_bits_of_the_writer_form_along_episodes(
    seed: int, kwargs: dict[str, object]
) -> None:
    env = _env(**kwargs)
    env.reset(seed=seed)
    env.action_space.seed(seed)
    for _ in range(40):
        _same_bits(env)
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            _same_bits(env)
            env.reset()


@pytest.mark.parametrize("value", _AWKWARD)
def test_the_features_clip_as_the_writer_form_for_any_state(value: float) -> None:
    env = _env()
    env.reset(seed=3)
    env.step(env.encode_action(2, "left"))
    episode = env._require_episode()
    with np.errstate(invalid="ignore", over="ignore"):  # the writer form casts 1e300
        episode.covariance = np.diag([value, 1e-4, value])
        episode.distance_since_fix_m = value
        _same_bits(env)
        episode.progress_m = value if math.isfinite(value) else 0.0
        _same_bits(env)
        if math.isfinite(value):
            episode.estimate = Pose(value, -value, value)
            _same_bits(env)
        episode.last_ranges = np.full(37, value)
        _same_bits(env)


@pytest.mark.parametrize("value", _AWKWARD)
@pytest.mark.parametrize("bound", [(-1.0, 1.0), (0.0, 1.0), (-0.0, 0.0), (2.0, 2.0)])
def test_clipped_is_min_of_max(value: float, bound: tuple[float, float]) -> None:
    low, high = bound
    expected = min(max(value, low), high)
    got = clipped(value, low, high)
    assert np.float64(got).tobytes() == np.float64(expected).tobytes()


@pytest.mark.parametrize("value", _AWKWARD)
def test_the_scaled_position_clips_as_min_of_max(value: float) -> None:
    low, high = (-0.1, -0.2), (2.1, 1.9)
    position = (value, 0.3 * value if math.isfinite(value) else 0.4)
    got = ScaledPosition.float_values(position, low, high)
    expected = scaled_position_with_min_max(position, low, high)
    assert np.array(got).tobytes() == np.array(expected).tobytes()
