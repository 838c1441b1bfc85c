"""The step glue's checks and feature values as they were written before their fast forms (the
observation guard's NumPy reduction, the reward terms' order of checks and copies, the scaled
position through ``_floats``, the range bins' unconditional reshape), kept verbatim as the tests'
reference."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from sonar_gym.envs.base import REWARDS_INFO_KEY, StepOutcome, _sum_in_order
from sonar_gym.envs.features import _nearest_per_bin, clipped


def observation_is_finite(observation: np.ndarray) -> bool:
    """Whether the guard of ``SonarEnv._checked_observation`` lets ``observation`` pass."""
    # A sum is finite unless an entry is not (or the sum overflows, which the full
    # check then clears): one reduction for the common case.
    if not math.isfinite(observation.sum()) and not np.isfinite(observation).all():  # noqa: SIM103
        return False
    return True


def reward_of(self, outcome: StepOutcome) -> float:  # type: ignore[no-untyped-def]
    """``SonarEnv._reward_of``: the step's reward, or the sum of its terms (copied into info)."""
    name = type(self).__name__
    if outcome.reward_terms is None:
        reward = float(outcome.reward)
        if not np.isfinite(reward):
            raise RuntimeError(f"{name}: non-finite reward {reward!r}")
        return reward
    if outcome.reward != 0.0:
        raise RuntimeError(
            f"{name}: a StepOutcome gives either reward or reward_terms; got reward "
            f"{outcome.reward!r} and terms {dict(outcome.reward_terms)}"
        )
    terms = {key: float(value) for key, value in outcome.reward_terms.items()}
    bad = {key: value for key, value in terms.items() if not math.isfinite(value)}
    if bad:
        raise RuntimeError(f"{name}: non-finite reward term(s) {bad}")
    for key, value in terms.items():
        self._record.reward_terms[key] = self._record.reward_terms.get(key, 0.0) + value
    outcome.info[REWARDS_INFO_KEY] = dict(terms)
    reward = _sum_in_order(list(terms.values()))
    if not math.isfinite(reward):
        raise RuntimeError(f"{name}: reward terms {terms} overflow to {reward!r}")
    return reward


def scaled_position_float_values(
    position: npt.ArrayLike, low: npt.ArrayLike, high: npt.ArrayLike
) -> list[float]:
    """``ScaledPosition.float_values``."""
    # On Python floats: numpy's six calls on two coordinates cost more than the arithmetic,
    # which rounds the same, step by step; clipped as np.clip does (NaN stays).
    return [
        clipped(2.0 * (p - lo) / (hi - lo) - 1.0, -1.0, 1.0)
        for p, lo, hi in zip(_floats(position), _floats(low), _floats(high), strict=True)
    ]


def _floats(values: npt.ArrayLike) -> Sequence[float]:
    """``values`` as a flat sequence of Python floats (a tuple of floats as it is)."""
    if type(values) is tuple and all(type(value) is float for value in values):
        return values
    return np.asarray(values, dtype=np.float64).reshape(-1).tolist()  # type: ignore[no-any-return]


def range_bins_values(size: int, range_fractions: npt.ArrayLike | None) -> np.ndarray:
    """``RangeBins(name, size).values(range_fractions)``."""
    if range_fractions is None:
        return np.ones(size)
    fractions = np.asarray(range_fractions, dtype=np.float64)
    if fractions.size == 0:
        return np.ones(size)
    return _nearest_per_bin(fractions.reshape(-1), size)  # type: ignore[no-any-return]
