"""The largest eigenvalue of the EKF's position covariance that sizes Kim's search circle
(``kim_fix``), in Python floats, against ``np.linalg.eigvalsh`` bit for bit: covariances of
every scale, indefinite and negative matrices, equal diagonals, off-diagonals around LAPACK's
splitting threshold, signed zeros, subnormals, and the tiny, huge and non-finite matrices
that go to numpy itself."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.localization.kim_fix import largest_position_variance


def _assert_same_bits(matrix: np.ndarray) -> None:
    covariance = np.zeros((3, 3))
    covariance[:2, :2] = matrix
    covariance[2, 2] = 0.01
    expected = np.linalg.eigvalsh(covariance[:2, :2])[-1]
    result = largest_position_variance(covariance)
    assert np.float64(result).tobytes() == expected.tobytes(), (matrix.tolist(), result, expected)


def _symmetric(a: float, b: float, c: float) -> np.ndarray:
    return np.array([[a, b], [b, c]])


def _random_matrix(rng: np.random.Generator, kind: int) -> np.ndarray:
    if kind == 0:  # covariances of any scale
        root = rng.normal(size=(2, 2))
        return root @ root.T * 10 ** rng.uniform(-8.0, 2.0)
    if kind == 1:  # a valid correlation
        a, c = rng.uniform(1e-6, 1e-1, 2)
        return _symmetric(a, rng.uniform(-1.0, 1.0) * math.sqrt(a * c), c)
    if kind == 2:  # equal or nearly equal diagonals, off-diagonal from 1e-20 relative up
        a = rng.uniform(1e-6, 1e-1)
        b = a * rng.uniform(-1.0, 1.0) * 10 ** rng.uniform(-20.0, 0.0)
        return _symmetric(a, b, a * (1.0 + int(rng.integers(-3, 4)) * 2.0**-52))
    if kind == 3:  # any symmetric matrix, indefinite or negative, over 60 decades
        values = rng.normal(size=(2, 2)) * 10 ** rng.uniform(-30.0, 30.0)
        return values + values.T
    # off-diagonals around the splitting threshold eps sqrt(|a c|)
    a, c = rng.uniform(1e-6, 1e-1, 2)
    b = math.sqrt(a * c) * 10 ** rng.uniform(-18.0, -14.0) * rng.choice([-1.0, 1.0])
    return _symmetric(a, b, c)


@pytest.mark.parametrize("kind", range(5))
def test_random_matrices_give_eigvalsh_bits(kind: int) -> None:
    rng = np.random.default_rng(100 + kind)
    for _ in range(20_000):
        _assert_same_bits(_random_matrix(rng, kind))


def test_edge_matrices_give_eigvalsh_bits() -> None:
    values = [0.0, -0.0, 5e-324, 1e-200, 1e-101, 1e-100, 1e-3, -1e-3, 2.0, 1e100, 1e101, 1e200]
    for a in values:
        for b in values:
            for c in values:
                _assert_same_bits(_symmetric(a, b, c))
    for special in (math.inf, -math.inf, math.nan):
        for matrix in (_symmetric(special, 0.0, 1.0), _symmetric(1.0, special, 1.0)):
            covariance = np.eye(3)
            covariance[:2, :2] = matrix
            expected = np.linalg.eigvalsh(covariance[:2, :2])[-1]
            result = largest_position_variance(covariance)
            assert np.float64(result).tobytes() == expected.tobytes()


@settings(max_examples=2_000, deadline=None)
@given(
    st.floats(-1e3, 1e3, allow_nan=False),
    st.floats(-1e3, 1e3, allow_nan=False),
    st.floats(-1e3, 1e3, allow_nan=False),
)
def test_any_matrix_gives_eigvalsh_bits(a: float, b: float, c: float) -> None:
    _assert_same_bits(_symmetric(a, b, c))
