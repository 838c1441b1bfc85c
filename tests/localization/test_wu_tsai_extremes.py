"""Theorem 2 at the edges of the float range: a status or a finite point, never NaN."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.localization.wu_tsai import (
    PAPER_RECEIVER_OFFSETS_M,
    InconsistentDistances,
    localize,
    localize_repeated,
    receiver_position,
)

finite_distances = st.floats(min_value=0.0, max_value=1.7e308, allow_nan=False)
spacings = st.floats(min_value=1e-6, max_value=1e300, allow_nan=False)


@pytest.mark.parametrize("scale", [1e160, 1e200, 1e300])
def test_equal_huge_distances_put_the_receiver_straight_below_the_centre(scale: float) -> None:
    point = receiver_position([scale, scale, scale], 0.2)
    assert np.all(np.isfinite(point))
    assert point[:2] == pytest.approx([0.1, 0.1])
    assert point[2] == pytest.approx(-scale)


def test_a_point_beyond_the_float_range_is_reported_not_returned_as_nan() -> None:
    with pytest.raises(InconsistentDistances, match="floating-point range"):
        receiver_position([1e308, 1.0, 1.0], 0.2)
    result = localize([[1e308, 1.0, 1.0], [1.0, 1.0, 1.0]], 0.2, PAPER_RECEIVER_OFFSETS_M)
    assert result.status == "inconsistent_distances"


@settings(max_examples=300, deadline=None)
@given(st.lists(finite_distances, min_size=3, max_size=3), spacings)
def test_receiver_position_is_finite_or_inconsistent_for_every_finite_input(
    distances: list[float], a: float
) -> None:
    try:
        point = receiver_position(distances, a)
    except InconsistentDistances:
        return
    assert np.all(np.isfinite(point))


@settings(max_examples=200, deadline=None)
@given(st.lists(finite_distances, min_size=6, max_size=6), spacings)
def test_localize_gives_a_status_and_finite_numbers_for_every_finite_input(
    distances: list[float], a: float
) -> None:
    table = np.array(distances).reshape(2, 3)
    result = localize(table, a, PAPER_RECEIVER_OFFSETS_M)
    repeated = localize_repeated(table[None], a, PAPER_RECEIVER_OFFSETS_M)
    assert repeated.statuses[0] == result.status
    if result.ok:
        assert result.fix is not None
        assert all(math.isfinite(v) for v in (result.fix.x, result.fix.y, result.fix.z))
        assert np.all(np.isfinite(repeated.poses[0]))


@pytest.mark.parametrize(
    ("distances", "name"),
    [
        (np.zeros((2, 3)), "distances"),
        (-np.ones((1, 2, 3)), "distances"),
        (np.ones((1, 3, 3)), "receiver_offsets"),
    ],
)
def test_repeated_fixes_reject_bad_arrays_by_name(distances: np.ndarray, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        localize_repeated(distances, 0.2, PAPER_RECEIVER_OFFSETS_M)


def test_receivers_near_the_float_limit_still_average_to_a_finite_fix() -> None:
    below = receiver_position([1.7e308, 1.7e308, 1.7e308], 0.2)
    assert np.isfinite(below).all()
    offsets = ((0.0, 0.0), (0.0, 1e-3))
    table = [[1.7e308, 1.7e308, 1.7e308], [1.7e308, 1.7e308, 1.6e308]]
    result = localize(table, 0.2, offsets)
    repeated = localize_repeated(np.array([table]), 0.2, offsets)
    assert repeated.statuses[0] == result.status
    if result.ok:
        assert result.fix is not None and math.isfinite(result.fix.z)
