"""The WallCorrection observation on Python floats has exactly the bits of the numpy-array form
it replaced, along seeded episodes and for covariances with signed zeros, NaN and huge
variances."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.envs.wall_correction import WallCorrectionEnv
from tests.envs.wall_correction_observation_reference import observe_arrays


def _same_bits(env: WallCorrectionEnv) -> None:
    got, expected = env._observe(), observe_arrays(env)
    assert got.dtype == expected.dtype
    assert got.tobytes() == expected.tobytes(), (got, expected)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_observation_has_the_bits_of_the_array_form_along_episodes(seed: int) -> None:
    env = gym.make("SonarGym/WallCorrection-v0").unwrapped
    assert isinstance(env, WallCorrectionEnv)
    env.reset(seed=seed)
    env.action_space.seed(seed)
    for _ in range(30):
        _same_bits(env)
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            _same_bits(env)
            env.reset()


@pytest.mark.parametrize(
    "diagonal",
    [
        (0.0, 0.0, 0.0),
        (-0.0, -0.0, -0.0),
        (-1e-12, 2e-3, -0.0),
        (1e300, 4.0, 1e-300),
        (np.nan, 1e-4, np.inf),
        (0.01, np.nan, 1e-6),
    ],
)
def test_the_standard_deviations_round_as_numpy_for_any_diagonal(
    diagonal: tuple[float, float, float],
) -> None:
    env = gym.make("SonarGym/WallCorrection-v0").unwrapped
    assert isinstance(env, WallCorrectionEnv)
    env.reset(seed=4)
    env._require_episode().tracker.covariance = np.diag(diagonal)
    with np.errstate(invalid="ignore"):
        _same_bits(env)
