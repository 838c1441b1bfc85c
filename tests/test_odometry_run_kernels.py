"""The compiled headings and poses of the run prediction (Kim et al. sec. 3.1 eqs. (5)-(6))
against the array form they replaced (:mod:`tests.odometry_run_reference`), bit for bit."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from sonar_gym.odometry import predict_run, predict_run_unchecked
from sonar_gym.pose import FloatArray, Pose
from tests.fuzzing import fuzz_settings
from tests.odometry_run_reference import predict_run_arrays


def _covariance(rng: np.random.Generator) -> FloatArray:
    root = rng.normal(0.0, 0.05, (3, 3))
    return root @ root.T + 1e-6 * np.eye(3)


def _increments(rng: np.random.Generator, count: int, turns: bool) -> tuple[FloatArray, FloatArray]:
    left = 0.03 + rng.normal(0.0, 0.002, count)
    right = 0.03 + rng.normal(0.0, 0.002, count)
    if turns:  # turns in place (both ways), standstills and reversing among the steps
        spins = rng.random(count) < 0.25
        sign = np.where(rng.random(count) < 0.5, 1.0, -1.0)
        left[spins], right[spins] = -0.05 * sign[spins], 0.05 * sign[spins]
        left[rng.random(count) < 0.1] = 0.0
        back = rng.random(count) < 0.1
        left[back], right[back] = -left[back], -right[back]
    return left, right


def _assert_same_bits(
    got: tuple[FloatArray, FloatArray], expected: tuple[FloatArray, FloatArray]
) -> None:
    for array, reference in zip(got, expected, strict=True):
        assert array.shape == reference.shape
        assert array.tobytes() == reference.tobytes()


@fuzz_settings(300)
@given(
    seed=st.integers(0, 2**32 - 1),
    count=st.sampled_from([0, 1, 2, 3, 7, 40, 130]),
    theta=st.one_of(
        st.floats(-math.pi, math.pi),
        st.sampled_from([math.pi, -math.pi, math.nextafter(-math.pi, 0.0), -0.0, 0.0]),
    ),
    turns=st.booleans(),
    variance_per_m=st.sampled_from([0.0, 3e-7, 1e-3]),
)
def test_compiled_run_prediction_is_the_array_form_bit_for_bit(
    seed: int, count: int, theta: float, turns: bool, variance_per_m: float
) -> None:
    rng = np.random.default_rng(seed)
    left, right = _increments(rng, count, turns)
    pose = Pose(rng.normal(0.0, 3.0), rng.normal(0.0, 3.0), theta)
    covariance = _covariance(rng)
    expected = predict_run_arrays(pose, covariance, left, right, 0.3, variance_per_m)
    _assert_same_bits(
        predict_run_unchecked(pose, covariance, left, right, 0.3, variance_per_m), expected
    )
    _assert_same_bits(predict_run(pose, covariance, left, right, 0.3, variance_per_m), expected)


def test_headings_crossing_pi_wrap_as_wrap_angles_does() -> None:
    """Turns in place through +-pi, both ways, from headings on either side of it."""
    covariance = np.eye(3) * 1e-4
    for theta in (math.pi - 1e-12, -math.pi + 1e-12, math.pi, math.pi / 2.0):
        for sign in (1.0, -1.0):
            count = 64
            left = np.full(count, -sign * math.pi * 0.3 / 32.0)
            right = -left
            pose = Pose(1.0, -2.0, theta)
            got = predict_run_unchecked(pose, covariance, left, right, 0.3, 1e-4)
            _assert_same_bits(got, predict_run_arrays(pose, covariance, left, right, 0.3, 1e-4))
            assert np.all(got[0][:, 2] > -math.pi) and np.all(got[0][:, 2] <= math.pi)


def test_unchecked_form_of_a_strided_run() -> None:
    """Every other command of a run (a view, not contiguous) as the contiguous copy gives."""
    rng = np.random.default_rng(5)
    left, right = _increments(rng, 41, True)
    pose, covariance = Pose(0.5, 0.25, 3.0), _covariance(rng)
    _assert_same_bits(
        predict_run_unchecked(pose, covariance, left[::2], right[::2], 0.25, 2e-6),
        predict_run_arrays(pose, covariance, left[::2].copy(), right[::2].copy(), 0.25, 2e-6),
    )
