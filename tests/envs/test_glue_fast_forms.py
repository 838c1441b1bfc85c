"""The step glue's fast forms answer bit for bit as the forms they replaced
(``glue_reference.py``): the observation guard, the reward of a step's terms, the scaled
position and the range bins."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from sonar_gym.envs.base import EpisodeRecord, SonarEnv, StepOutcome
from sonar_gym.envs.features import RangeBins, ScaledPosition
from tests.envs import glue_reference

_any_float = st.floats(allow_nan=True, allow_infinity=True)
_edges = st.sampled_from([0.0, -0.0, 1.0, -1.0, 3e38, -3e38, 1e308, -1e308, math.inf, math.nan])


class _Stub:
    """The attributes the base's checks read, without a task."""

    def __init__(self, observation: np.ndarray | None = None) -> None:
        self._record = EpisodeRecord()
        self._observation = observation

    def _observe(self) -> np.ndarray:
        assert self._observation is not None
        return self._observation


def _passes_guard(observation: np.ndarray) -> bool:
    try:
        SonarEnv._checked_observation(_Stub(observation))  # type: ignore[arg-type]
    except RuntimeError as error:
        assert "non-finite observation" in str(error)
        return False
    return True


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # float32 casts and sums overflow
@settings(max_examples=400, deadline=None)
@given(
    arrays(
        st.sampled_from([np.float32, np.float64]),
        st.sampled_from([(1,), (5,), (24,), (2, 3), ()]),
        elements=st.one_of(_any_float, _edges),
    )
)
def test_the_observation_guard_passes_what_the_reduction_passed(observation: np.ndarray) -> None:
    assert _passes_guard(observation) == glue_reference.observation_is_finite(observation)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the reduction overflows
def test_the_observation_guard_clears_a_finite_vector_whose_sum_overflows() -> None:
    observation = np.full(4, 1e308)
    assert _passes_guard(observation)
    assert glue_reference.observation_is_finite(observation)
    observation[2] = math.nan
    assert not _passes_guard(observation)


def _reward_or_error(reward_of: Any, terms: dict[str, Any], reward: float) -> tuple[Any, ...]:
    stub = _Stub()
    stub._record.reward_terms = {"pose_error": -0.5}
    outcome = StepOutcome(reward=reward, reward_terms=terms)
    try:
        value = reward_of(stub, outcome)
    except RuntimeError as error:
        return ("error", str(error), dict(stub._record.reward_terms), dict(outcome.info))
    bits = np.float64(value).tobytes()
    return ("reward", bits, dict(stub._record.reward_terms), dict(outcome.info))


_term_values = st.one_of(_any_float, _edges, st.integers(-3, 3), st.just(np.float32(0.25)))


@settings(max_examples=400, deadline=None)
@given(
    st.dictionaries(
        st.sampled_from(["sensing_cost", "pose_error", "failure", "collision"]), _term_values
    ),
    st.sampled_from([0.0, 0.0, 0.0, 1.5]),
)
def test_the_reward_of_terms_is_the_old_reward_to_the_bit(
    terms: dict[str, Any], reward: float
) -> None:
    new = _reward_or_error(SonarEnv._reward_of, terms, reward)
    old = _reward_or_error(glue_reference.reward_of, terms, reward)
    assert repr(new) == repr(old)  # repr: NaN entries compare as text


_point_floats = st.one_of(st.floats(-5, 5), _edges, _any_float)
_points = st.tuples(_point_floats, _point_floats)


@settings(max_examples=400, deadline=None)
@given(_points, _points, _points, st.sampled_from(["tuple", "list", "array", "mixed"]))
def test_a_scaled_position_is_the_old_form_to_the_bit(
    position: tuple[float, float], low: tuple[float, float], high: tuple[float, float], form: str
) -> None:
    def shaped(point: tuple[float, float]) -> Any:
        if form == "list":
            return list(point)
        if form == "array":
            return np.array(point)
        if form == "mixed":
            return (np.float64(point[0]), point[1])
        return point

    with np.errstate(all="ignore"):
        try:
            new: Any = ScaledPosition.float_values(shaped(position), shaped(low), shaped(high))
        except ZeroDivisionError:
            new = "ZeroDivisionError"
        try:
            old: Any = glue_reference.scaled_position_float_values(
                shaped(position), shaped(low), shaped(high)
            )
        except ZeroDivisionError:
            old = "ZeroDivisionError"
    if isinstance(old, str):
        assert new == old
    else:
        assert np.array(new).tobytes() == np.array(old).tobytes()


@pytest.mark.parametrize(
    ("position", "low", "high"),
    [((1.0, 2.0, 3.0), (0.0, 0.0, 0.0), (4.0, 4.0, 4.0)), ((1.0,), (0.0,), (2.0,))],
)
def test_a_scaled_position_of_other_sizes_is_the_old_form(
    position: tuple[float, ...], low: tuple[float, ...], high: tuple[float, ...]
) -> None:
    new = ScaledPosition.float_values(position, low, high)
    assert new == glue_reference.scaled_position_float_values(position, low, high)


@settings(max_examples=300, deadline=None)
@given(
    st.integers(1, 40),
    arrays(
        np.float64,
        st.sampled_from([(0,), (1,), (19,), (73,), (4, 5), (3, 1)]),
        elements=st.one_of(st.floats(-0.5, 1.5), _edges),
    ),
    st.booleans(),
)
def test_range_bins_are_the_old_form_to_the_bit(
    n_bins: int, fractions: np.ndarray, as_list: bool
) -> None:
    given_fractions: Any = fractions.tolist() if as_list else fractions
    new = RangeBins("bins", n_bins).values(given_fractions)
    old = glue_reference.range_bins_values(n_bins, given_fractions)
    assert new.dtype == old.dtype and new.shape == old.shape
    assert new.tobytes() == old.tobytes()
