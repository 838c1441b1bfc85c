"""Pose construction: the unchecked constructor of inner loops is the checked one without checks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sonar_gym.pose import Pose

_FINITE = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_infinity=False)


@given(_FINITE, _FINITE, _FINITE)
def test_unchecked_pose_equals_the_checked_one(x: float, y: float, theta: float) -> None:
    checked = Pose(x, y, theta)
    fast = Pose.unchecked(x, y, theta)
    assert fast == checked
    assert (fast.x, fast.y, fast.theta) == (checked.x, checked.y, checked.theta)
    assert hash(fast) == hash(checked)
    assert -math.pi < fast.theta <= math.pi


@pytest.mark.parametrize("theta", [-math.pi, math.pi, 3.0 * math.pi, -3.0 * math.pi, 7.5])
def test_unchecked_pose_wraps_the_heading_like_the_checked_one(theta: float) -> None:
    assert Pose.unchecked(0.0, 0.0, theta).theta == Pose(0.0, 0.0, theta).theta


def test_unchecked_pose_is_frozen() -> None:
    pose = Pose.unchecked(1.0, 2.0, 0.5)
    with pytest.raises(AttributeError):
        pose.x = 3.0  # type: ignore[misc]


@given(_FINITE, _FINITE, _FINITE, _FINITE, _FINITE, _FINITE)
def test_compose_is_transform_point_plus_the_headings(
    x: float, y: float, theta: float, rx: float, ry: float, rtheta: float
) -> None:
    base, relative = Pose(x, y, theta), Pose(rx, ry, rtheta)
    composed = base.compose(relative)
    expected_xy = base.transform_point(np.array([relative.x, relative.y]))
    assert (composed.x, composed.y) == (float(expected_xy[0]), float(expected_xy[1]))
    assert composed.theta == Pose(0.0, 0.0, base.theta + relative.theta).theta
