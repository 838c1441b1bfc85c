"""The input contract of the public localization functions, fuzzed.

Every finite input gives a result (a status, a finite array, or ``None`` where documented)
or a clean ``ValueError``: never NaN, inf or another exception. Non-finite or wrong-shape
arrays give a ``ValueError``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from hypothesis import event, example, given
from hypothesis import strategies as st

from sonar_gym.localization.beom_cho import solve_two_circles
from sonar_gym.localization.roh_block_expansion import parabolic_path
from sonar_gym.localization.roh_trilateration import (
    circle_intersections,
    linearised_least_squares,
    paper_centroid,
    radical_axis,
    radical_centre,
    trilaterate,
)
from sonar_gym.localization.wu_tsai import receiver_position
from tests.fuzzing import fuzz_settings

finite = st.one_of(
    st.floats(-10.0, 10.0),
    st.sampled_from([0.0, -0.0, 5e-324, 1e-300, 1e-9, 1.0, 1e9, 1e150, 1e300, -1e300]),
    st.floats(allow_nan=False, allow_infinity=False),
)
positive = st.one_of(st.floats(1e-3, 10.0), finite.map(abs))
non_finite = st.sampled_from([math.nan, math.inf, -math.inf])


def point(size: int = 2) -> st.SearchStrategy[list[float]]:
    return st.lists(finite, min_size=size, max_size=size)


def assert_finite(value: Any) -> None:
    """No NaN or inf anywhere inside ``value`` (arrays, tuples, dataclasses, numbers)."""
    if value is None or isinstance(value, (str, bool)):
        return
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        for item in dataclasses.fields(value):
            assert_finite(getattr(value, item.name))
        return
    if isinstance(value, (tuple, list)):
        for item in value:
            assert_finite(item)
        return
    array = np.asarray(value)
    if array.dtype.kind in "fc":
        assert np.all(np.isfinite(array)), value


def outcome(function: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """Call ``function``; a ``ValueError`` is a clean outcome, anything else must be finite."""
    try:
        result = function(*args, **kwargs)
    except ValueError:
        event("clean ValueError")
        return None
    status = getattr(result, "status", None)
    event(f"status {status}" if status is not None else "finite result")
    if status is not None:
        assert isinstance(status, str) and status
    assert_finite(result)
    return result


# -- Beom & Cho --------------------------------------------------------------------------------


@fuzz_settings(300, shrink=False)
@given(point(), positive, point(), positive, finite)
def test_solve_two_circles_gives_a_status_or_a_value_error(
    small: list[float], d_small: float, large: list[float], d_large: float, bearing: float
) -> None:
    outcome(solve_two_circles, small, d_small, large, d_large, bearing)


@fuzz_settings(300)
@given(st.sampled_from(["small_center", "small_distance", "large_center", "bearing"]), non_finite)
def test_solve_two_circles_refuses_non_finite_input(argument: str, bad: float) -> None:
    args: dict[str, Any] = {
        "small_center": (2.85, -0.6),
        "small_distance": 2.9,
        "large_center": (0.3, -1.5),
        "large_distance": 1.5,
        "bearing_difference": 0.5,
    }
    key = "bearing_difference" if argument == "bearing" else argument
    args[key] = (bad, 0.0) if key.endswith("center") else bad
    with pytest.raises(ValueError):
        solve_two_circles(**args)


# -- Wu & Tsai ---------------------------------------------------------------------------------


@fuzz_settings(300, shrink=False)
@given(st.lists(positive, min_size=3, max_size=3), positive, st.sampled_from([-1, 1]))
def test_receiver_position_is_finite_or_a_value_error(
    d: list[float], a: float, z_sign: int
) -> None:
    outcome(receiver_position, d, a, z_sign)


@fuzz_settings(300)
@given(
    st.one_of(
        st.lists(finite, min_size=0, max_size=2),
        st.lists(finite, min_size=4, max_size=5),
        st.lists(non_finite, min_size=3, max_size=3),
    )
)
def test_receiver_position_refuses_non_finite_or_wrong_shape(d: list[float]) -> None:
    with pytest.raises(ValueError):
        receiver_position(d, 0.2)


# -- Roh ---------------------------------------------------------------------------------------


@fuzz_settings(300, shrink=False)
@given(point(), positive, point(), positive)
def test_circle_intersections_are_finite_or_a_value_error(
    a: list[float], r_a: float, b: list[float], r_b: float
) -> None:
    result = outcome(circle_intersections, a, r_a, b, r_b)
    if result is not None:
        assert result.ndim == 2 and result.shape[1] == 2 and result.shape[0] in (0, 1, 2)


@fuzz_settings(300, shrink=False)
@given(
    st.sampled_from([circle_intersections, radical_axis]),
    st.sampled_from(["centre", "radius", "shape"]),
    non_finite,
)
def test_circle_helpers_refuse_non_finite_or_wrong_shape(
    function: Callable[..., Any], kind: str, bad: float
) -> None:
    centre: Any = [bad, 0.0] if kind == "centre" else [0.0, 0.0, 0.0] if kind == "shape" else [0, 0]
    radius = bad if kind == "radius" else 1.0
    with pytest.raises(ValueError):
        function(centre, radius, [1.0, 0.0], 1.0)


@fuzz_settings(300, shrink=False)
@given(
    st.sampled_from([linearised_least_squares, radical_centre, paper_centroid]),
    st.lists(point(), min_size=3, max_size=3),
    st.lists(positive, min_size=3, max_size=3),
)
def test_three_circle_solvers_are_finite_or_a_value_error(
    function: Callable[..., Any], centres: list[list[float]], radii: list[float]
) -> None:
    outcome(function, centres, radii)


@fuzz_settings(300, shrink=False)
@example(  # found by a 3,000-example run: OverflowError squaring the range
    [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]], [1.0, 1.0, 1e150], 0.0, "paper"
)
@given(
    st.lists(point(3), min_size=3, max_size=3),
    st.lists(positive, min_size=3, max_size=3),
    finite,
    st.sampled_from(["paper", "least_squares"]),
)
def test_trilaterate_gives_a_status_or_a_value_error(
    beacons: list[list[float]], distances: list[float], height: float, method: str
) -> None:
    outcome(trilaterate, beacons, distances, height, method)


@fuzz_settings(300)
@given(st.floats(0.0, 3.0), st.floats(0.0, 0.3), st.floats(-2.0, 2.0), st.floats(1e-3, 0.05))
def test_trilaterate_on_a_paper_like_layout_is_ok(
    x: float, y: float, curvature: float, noise: float
) -> None:
    beacons = np.array([[3.467, 0.101, 0.825], [1.551, 0.139, 1.441], [2.459, 1.870, 1.457]])
    sensor = np.array([x, y + 0.5 + 0.1 * curvature, 0.3])
    distances = np.linalg.norm(beacons - sensor, axis=1) + noise
    result = outcome(trilaterate, beacons, distances, 0.3)
    assert result is not None and result.status == "ok"


@fuzz_settings(300)
@given(
    st.floats(-10.0, 10.0),
    st.floats(-10.0, 10.0),
    st.lists(st.floats(-10.0, 10.0), min_size=2, max_size=2),
    st.floats(-10.0, 10.0),
    st.one_of(st.floats(1e-3, 0.5), st.sampled_from([0.0, -0.0, -0.1, 5e-324, 1e300])),
)
def test_parabolic_path_is_finite_or_a_value_error(  # bounded: a huge path exhausts memory
    x_start: float, x_end: float, vertex: list[float], a: float, step: float
) -> None:
    result = outcome(parabolic_path, x_start, x_end, tuple(vertex), a, step)
    if result is not None:
        assert result.ndim == 2 and result.shape[1] == 2
