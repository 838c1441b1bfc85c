"""The step path's action check answers exactly as ``space.contains`` does."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.envs.base import ActionCheck

MULTI = gym.spaces.MultiDiscrete([3, 36, 5, 3])
MULTI_WITH_START = gym.spaces.MultiDiscrete([3, 4], start=[-2, 5])
DISCRETE = gym.spaces.Discrete(542)
DISCRETE_WITH_START = gym.spaces.Discrete(7, start=-3)
SPACES = [MULTI, MULTI_WITH_START, DISCRETE, DISCRETE_WITH_START]

_DTYPES = [np.int64, np.int32, np.int8, np.uint8, np.float64, np.float32, np.bool_]
_values = st.integers(min_value=-(2**63), max_value=2**63 - 1)


@st.composite
def _candidate_actions(draw: st.DrawFn) -> Any:
    """Arrays of several dtypes and shapes, Python and NumPy scalars, lists, odd objects."""
    kind = draw(st.sampled_from(["array", "int", "np_scalar", "list", "float", "other"]))
    small = st.integers(min_value=-5, max_value=40)
    if kind == "array":
        shape = draw(st.sampled_from([(4,), (2,), (), (1, 4), (5,)]))
        dtype = draw(st.sampled_from(_DTYPES))
        size = int(np.prod(shape))
        values = draw(st.lists(st.one_of(small, _values), min_size=size, max_size=size))
        return np.array(values, dtype=np.int64).astype(dtype).reshape(shape)  # wraps to fit
    if kind == "int":
        return draw(st.one_of(small, _values, st.integers(min_value=2**63, max_value=2**70)))
    if kind == "np_scalar":
        dtype = draw(st.sampled_from(_DTYPES))
        return np.array(draw(small), dtype=np.int64).astype(dtype)[()]
    if kind == "list":
        return draw(st.lists(small, min_size=0, max_size=5))
    if kind == "float":
        return draw(st.floats(allow_nan=True, allow_infinity=True))
    return draw(st.sampled_from([None, "0", True, False, (0, 1, 2, 0), b"\x00"]))


@settings(max_examples=400, deadline=None)
@given(space_index=st.integers(0, len(SPACES) - 1), action=_candidate_actions())
def test_action_check_agrees_with_space_contains(space_index: int, action: Any) -> None:
    space = SPACES[space_index]
    assert ActionCheck(space)(action) == bool(space.contains(action))


@pytest.mark.parametrize(
    ("action", "expected"),
    [
        (np.array([2, 35, 4, 2]), True),
        (np.array([3, 0, 0, 0]), False),
        (np.array([0, 0, 0, -1]), False),
        (np.array([0, 36, 0, 0]), False),
        (np.array([0, 0, 0]), False),
        (np.array([0, 0, 0, 0], dtype=np.int32), True),  # casts safely to int64
        (np.array([0.0, 0.0, 0.0, 0.0]), False),  # floats do not cast safely
        ([1, 2, 3, 1], True),
    ],
)
def test_multi_discrete_edges(action: Any, expected: bool) -> None:
    assert ActionCheck(MULTI)(action) is expected


@pytest.mark.parametrize(
    ("action", "expected"),
    [(0, True), (541, True), (542, False), (-1, False), (np.int64(5), True), (True, True)],
)
def test_discrete_edges(action: Any, expected: bool) -> None:
    assert ActionCheck(DISCRETE)(action) is expected


def test_check_notices_replaced_bounds() -> None:
    space = gym.spaces.MultiDiscrete([3, 4])
    check = ActionCheck(space)
    assert check.is_current_for(space)
    space.nvec = np.array([3, 9])
    assert not check.is_current_for(space)
    assert not check.is_current_for(gym.spaces.MultiDiscrete([3, 4]))
