"""Roh et al.'s public helpers answer every finite input: a status on bad geometry, never NaN
or an OverflowError, at any scale; a ValueError naming the argument for non-finite or
wrongly shaped arrays; and a bounded path sampler."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.localization.roh import (
    auto_calibrate,
    circle_intersections,
    linearised_least_squares,
    paper_centroid,
    parabolic_path,
    radical_axis,
    radical_centre,
    trilaterate,
)
from sonar_gym.localization.roh_block_expansion import MAX_PATH_SAMPLES

BEACONS = np.array([[0.0, 0.0, 2.0], [1.0, 0.0, 2.2], [0.0, 1.0, 1.9]])
SENSOR = np.array([0.3, 0.2, 0.3])
POSITIONS = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
NEW_BEACON = np.array([0.3, 0.3, 2.0])

SCALES = [1e-300, 1e-200, 1e-120, 1.0, 1e120, 1e200, 1e250, 1e300]


@pytest.mark.parametrize("scale", SCALES)
def test_circle_intersections_scale_with_the_circles(scale: float) -> None:
    points = circle_intersections([0.0, 0.0], scale, [scale, 0.0], scale)
    expected = np.array([[0.5, math.sqrt(3) / 2], [0.5, -math.sqrt(3) / 2]])
    np.testing.assert_allclose(points / scale, expected, rtol=1e-12)
    apart = circle_intersections([0.0, 0.0], scale, [3 * scale, 0.0], scale)
    assert apart.shape == (0, 2)


@settings(max_examples=150, deadline=None)
@given(
    st.lists(st.floats(-1e300, 1e300), min_size=4, max_size=4),
    st.floats(0.0, 1e300),
    st.floats(0.0, 1e300),
)
def test_circle_intersections_never_give_nan_for_finite_circles(coords, ra, rb) -> None:
    points = circle_intersections(coords[:2], ra, coords[2:], rb)
    assert points.shape in ((0, 2), (1, 2), (2, 2))
    assert not np.isnan(points).any()
    normal, offset = radical_axis(coords[:2], ra, coords[2:], rb)
    assert np.all(np.isfinite(normal)) and math.isfinite(offset)


@pytest.mark.parametrize("scale", SCALES)
def test_trilateration_and_calibration_scale_with_the_layout(scale: float) -> None:
    distances = np.linalg.norm(BEACONS - SENSOR, axis=1)
    for method in ("paper", "least_squares"):
        fix = trilaterate(BEACONS * scale, distances * scale, SENSOR[2] * scale, method)
        assert fix.ok, fix.message
        np.testing.assert_allclose(np.asarray(fix.position) / scale, SENSOR[:2], atol=1e-9)
    sensors = np.column_stack([POSITIONS, np.full(3, SENSOR[2])])
    ranges = np.linalg.norm(sensors - NEW_BEACON, axis=1)
    calibration = auto_calibrate(POSITIONS * scale, ranges * scale, SENSOR[2] * scale)
    assert calibration.ok, calibration.message
    np.testing.assert_allclose(np.asarray(calibration.position) / scale, NEW_BEACON, atol=1e-9)
    # The area in square metres itself leaves float64 beyond 1e+-154 m; it is never NaN.
    area = calibration.triangle_area_m2
    assert not math.isnan(area)
    if 1e-150 < scale < 1e150:
        assert area / scale / scale == pytest.approx(0.5)
    centre = radical_centre(BEACONS[:, :2] * scale, distances * scale)
    assert centre is not None and np.all(np.isfinite(centre))
    position, _ = paper_centroid(BEACONS[:, :2] * scale, np.ones(3) * scale)
    assert position is not None and np.all(np.isfinite(position))


def test_calibration_on_positions_collinear_to_float_precision_is_a_status() -> None:
    result = auto_calibrate([[0, 0], [1, 0], [2, 1e-300]], [1, 1, 1], max_condition=1e308)
    assert result.status == "collinear_positions"


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: circle_intersections([0.0, 0.0, 1.0], 1.0, [1.0, 0.0], 1.0), "centre_a"),
        (lambda: circle_intersections([0.0, 0.0], 1.0, [np.nan, 0.0], 1.0), "centre_b"),
        (lambda: circle_intersections([0.0, 0.0], math.inf, [1.0, 0.0], 1.0), "radius_a"),
        (lambda: circle_intersections([0.0, 0.0], 1.0, [1.0, 0.0], -1.0), "radius_b"),
        (lambda: radical_axis([0.0, 0.0], 1.0, [1.0], 1.0), "centre_b"),
        (lambda: paper_centroid(np.zeros((2, 2)), [1.0, 1.0]), "centres"),
        (lambda: paper_centroid(POSITIONS, [1.0, np.inf, 1.0]), "radii"),
        (lambda: paper_centroid(POSITIONS, [1.0, 1.0]), "radii"),
        (lambda: radical_centre(np.zeros((4, 2)), [1.0, 1.0, 1.0]), "centres"),
        (lambda: linearised_least_squares(np.zeros((3, 3)), [1.0, 1.0, 1.0]), "centres"),
        (lambda: linearised_least_squares(POSITIONS, [1.0, 1.0]), "radii"),
        (lambda: linearised_least_squares(POSITIONS, [1.0, np.nan, 1.0]), "radii"),
    ],
)
def test_bad_arrays_raise_a_value_error_naming_the_argument(call, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        call()


def test_parabolic_path_bounds_what_it_allocates() -> None:
    with pytest.raises(ValueError, match="MAX_PATH_SAMPLES"):
        parabolic_path(step_m=1e-9)
    with pytest.raises(ValueError, match="arc length"):
        parabolic_path(x_start_m=1e200, x_end_m=-1e200)
    with pytest.raises(ValueError, match="arc length|MAX_PATH_SAMPLES"):
        parabolic_path(quadratic_coefficient_per_m=1e306)
    longest = parabolic_path(
        x_start_m=0.0,
        x_end_m=MAX_PATH_SAMPLES * 0.004 * 0.99,
        step_m=0.004,
        quadratic_coefficient_per_m=0.0,
        vertex_m=(0.0, 0.0),
    )
    assert len(longest) <= MAX_PATH_SAMPLES + 1
