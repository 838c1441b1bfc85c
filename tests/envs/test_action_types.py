"""The action types: each space round-trips through its codec; the registry checks names."""

from __future__ import annotations

import itertools
import math
import re

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.envs.action_types import (
    ACTION_TYPES,
    ActionType,
    BoxActions,
    ContinuousRange,
    DiscreteChoices,
    FlatDiscreteActions,
    MultiDiscreteActions,
    make_action_type,
)

choices_strategy = st.builds(
    lambda sizes, flags: DiscreteChoices(
        tuple(sizes),
        tuple(kind for kind, flag in zip(range(sizes[0]), flags, strict=False) if flag),
    ),
    st.lists(st.integers(1, 5), min_size=1, max_size=4),
    st.lists(st.booleans(), max_size=5),
)


def all_index_tuples(choices: DiscreteChoices) -> list[tuple[int, ...]]:
    """Every distinct choice: parameterless kinds once (parameters 0), others per combination."""
    tuples = []
    for kind in range(choices.sizes[0]):
        if kind in choices.parameterless_kinds:
            tuples.append((kind, *(0 for _ in choices.parameter_sizes)))
        else:
            ranges = [range(size) for size in choices.parameter_sizes]
            tuples.extend((kind, *rest) for rest in itertools.product(*ranges))
    return tuples


@settings(max_examples=60, deadline=None)
@given(choices_strategy)
def test_flat_codes_cover_the_discrete_space_once_and_round_trip(
    choices: DiscreteChoices,
) -> None:
    codec = FlatDiscreteActions(choices)
    tuples = all_index_tuples(choices)
    assert isinstance(codec.space, gym.spaces.Discrete)
    assert int(codec.space.n) == len(tuples)
    codes = [codec.encode(choice) for choice in tuples]
    assert sorted(codes) == list(range(len(tuples)))
    for code in range(int(codec.space.n)):
        assert codec.encode(codec.decode(code)) == code
        assert codec.space.contains(code)


@settings(max_examples=60, deadline=None)
@given(choices_strategy)
def test_multi_discrete_round_trips_over_the_whole_space(choices: DiscreteChoices) -> None:
    codec = MultiDiscreteActions(choices)
    assert codec.space == gym.spaces.MultiDiscrete(list(choices.sizes))
    for choice in itertools.product(*(range(size) for size in choices.sizes)):
        action = codec.encode(choice)
        assert codec.space.contains(action)
        assert codec.decode(action) == choice
        assert codec.decode(list(action)) == choice


def test_flat_order_puts_parameterless_kinds_first_then_row_major_blocks() -> None:
    # Beacon scan's flattening: 0 calibrate, 1 localize, then pans by (centre, width, step).
    codec = FlatDiscreteActions(DiscreteChoices((3, 4, 2, 3), parameterless_kinds=(1, 2)))
    assert codec.space.n == 2 + 4 * 2 * 3
    assert codec.decode(0) == (1, 0, 0, 0)
    assert codec.decode(1) == (2, 0, 0, 0)
    assert codec.decode(2) == (0, 0, 0, 0)
    assert codec.decode(3) == (0, 0, 0, 1)
    assert codec.decode(2 + 3) == (0, 0, 1, 0)
    assert codec.decode(2 + 6) == (0, 1, 0, 0)
    # Without parameterless kinds the flat code is numpy's row-major index.
    plain = FlatDiscreteActions(DiscreteChoices((4, 3, 5)))
    for choice in itertools.product(range(4), range(3), range(5)):
        assert plain.encode(choice) == int(np.ravel_multi_index(choice, (4, 3, 5)))


finite = st.floats(-1e3, 1e3, allow_nan=False)


@settings(max_examples=100, deadline=None)
@given(
    st.lists(st.tuples(finite, st.floats(1e-2, 1e3)), min_size=1, max_size=4),
    st.data(),
)
def test_box_round_trips_values_inside_the_range(bounds: list, data: st.DataObject) -> None:
    low = tuple(lo for lo, _ in bounds)
    high = tuple(lo + span for lo, span in bounds)
    codec = BoxActions(ContinuousRange(low, high))
    fractions = np.array(data.draw(st.lists(st.floats(0, 1), min_size=len(low), max_size=len(low))))
    values = np.asarray(low) + fractions * (np.asarray(high) - np.asarray(low))
    action = codec.encode(values)
    assert action.dtype == np.float32
    assert codec.space.contains(np.clip(action, -1.0, 1.0))
    np.testing.assert_allclose(
        codec.decode(action),
        values,
        rtol=1e-5,
        atol=1e-5 * max(1.0, *(abs(v) for v in (*low, *high))),
    )
    # the ends of the space are the ends of the range, and decoding clips
    np.testing.assert_array_equal(codec.decode(-np.ones(len(low))), np.asarray(low))
    np.testing.assert_allclose(codec.decode(np.full(len(low), 7.0)), np.asarray(high))


def test_box_rejects_an_action_of_the_wrong_shape() -> None:
    codec = BoxActions(ContinuousRange.unit(3))
    with pytest.raises(ValueError, match=r"shape \(3,\)"):
        codec.decode([0.0, 0.0])


def test_an_unknown_name_lists_the_registered_names() -> None:
    with pytest.raises(ValueError, match="action_type") as error:
        make_action_type("continuous", DiscreteChoices((2,)))
    for name in ACTION_TYPES:
        assert repr(name) in str(error.value)
    assert set(ACTION_TYPES) == {"multi_discrete", "discrete", "box"}


@pytest.mark.parametrize(
    ("name", "choices"),
    [("box", DiscreteChoices((2,))), ("discrete", ContinuousRange.unit(2))],
)
def test_a_type_given_the_other_family_of_choices_says_what_it_needs(name, choices) -> None:
    with pytest.raises(ValueError, match=name):
        make_action_type(name, choices)


@pytest.mark.parametrize(
    ("sizes", "parameterless", "field"),
    [
        ((), (), "sizes"),
        ((3, 0), (), "sizes"),
        ((3, 2), (3,), "parameterless_kinds"),
        ((3, 2), (1, 1), "parameterless_kinds"),
    ],
)
def test_bad_choices_name_the_field(sizes, parameterless, field) -> None:
    with pytest.raises(ValueError, match=field):
        DiscreteChoices(sizes, parameterless)


@pytest.mark.parametrize(
    ("low", "high"), [((0.0,), (0.0,)), ((0.0, 1.0), (1.0,)), ((0.0,), (math.inf,))]
)
def test_bad_ranges_are_refused(low, high) -> None:
    with pytest.raises(ValueError, match="'low' and 'high'"):
        ContinuousRange(low, high)


@pytest.mark.parametrize(
    ("codec", "action", "allowed"),
    [
        (
            MultiDiscreteActions(DiscreteChoices((3, 4))),
            [0, 4],
            r"2 integers, in \[0, 2\], \[0, 3\]",
        ),
        (MultiDiscreteActions(DiscreteChoices((3, 4))), [-1, 0], r"in \[0, 2\], \[0, 3\]"),
        (MultiDiscreteActions(DiscreteChoices((3, 4))), [0.5, 1.0], r"in \[0, 2\], \[0, 3\]"),
        (MultiDiscreteActions(DiscreteChoices((3, 4))), [[0], [0, 1]], r"in \[0, 2\], \[0, 3\]"),
        (FlatDiscreteActions(DiscreteChoices((2, 3), (0,))), 4, r"an integer in \[0, 3\]"),
        (FlatDiscreteActions(DiscreteChoices((2, 3), (0,))), -1, r"an integer in \[0, 3\]"),
        (FlatDiscreteActions(DiscreteChoices((2, 3), (0,))), "1", r"an integer in \[0, 3\]"),
        (BoxActions(ContinuousRange.unit(3)), [5.0, 5.0, 5.0], r"3 finite numbers in \[-1, 1\]"),
        (BoxActions(ContinuousRange.unit(3)), [math.nan, 0.0, 0.0], r"finite numbers"),
        (BoxActions(ContinuousRange.unit(3)), [0.0, -math.inf, 0.0], r"finite numbers"),
        (BoxActions(ContinuousRange.unit(3)), [1e300, 0.0, 0.0], r"finite numbers"),
        (BoxActions(ContinuousRange.unit(3)), [0.0, 0.0], r"3 finite numbers"),
        (BoxActions(ContinuousRange.unit(3)), None, r"3 finite numbers"),
        (BoxActions(ContinuousRange.unit(3)), "abc", r"3 finite numbers"),
    ],
)
def test_check_refuses_an_action_outside_the_space_naming_it_and_what_is_allowed(
    codec: ActionType, action: object, allowed: str
) -> None:
    with pytest.raises(ValueError, match=r"argument 'action' must be an element of") as error:
        codec.check(action)
    assert re.search(allowed, str(error.value)), error.value
    assert str(error.value).endswith(f"got {action!r}")


@pytest.mark.filterwarnings("ignore:.*Casting input x to numpy array")
@pytest.mark.filterwarnings("ignore:overflow encountered in cast")
@settings(max_examples=300, deadline=None)
@given(
    st.lists(
        st.one_of(
            st.floats(-1.0, 1.0),
            st.floats(1.0, 1.0 + 1e-7),  # rounds to 1 in float32 or past it
            st.floats(-1.0 - 1e-7, -1.0),
            st.floats(),  # anything, NaN and inf included
        ),
        min_size=3,
        max_size=3,
    )
)
def test_box_check_accepts_exactly_what_the_space_contains(action: list[float]) -> None:
    codec = BoxActions(ContinuousRange.unit(3))
    contained = codec.space.contains(action)  # what step accepts
    try:
        codec.check(action)
    except ValueError:
        assert not contained
    else:
        assert contained
        decoded = codec.decode(action)
        assert np.all((decoded >= 0.0) & (decoded <= 1.0))  # inside the range
