"""The compiled principal axis of a ``2 x 2`` scatter has the bits of ``np.linalg.eigh``
(LAPACK's ``dsyevd``), and declines the matrices LAPACK would rescale."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.localization.scatter_axis import principal_axis


def _assert_eigh_bits(scatter: np.ndarray, count: int) -> None:
    answered, smallest, along_x, along_y = principal_axis(scatter, float(count))
    assert answered, scatter.tolist()
    values, vectors = np.linalg.eigh(scatter / count)
    got = np.array([smallest, along_x, along_y])
    expected = np.array([values[0], vectors[0, 1], vectors[1, 1]])
    assert got.tobytes() == expected.tobytes(), (scatter.tolist(), count, got, expected)


def _symmetric(a11: float, a21: float, a22: float) -> np.ndarray:
    return np.array([[a11, a21], [a21, a22]])


def test_principal_axis_of_line_groups_is_eighs() -> None:
    """Scatters of noisy ERP runs along walls of every orientation, length and noise level."""
    rng = np.random.default_rng(20261207)
    for _ in range(10000):
        count = int(rng.integers(2, 40))
        along = rng.uniform(0.0, rng.choice([0.01, 0.3, 3.0]), count)
        angle = rng.uniform(-np.pi, np.pi)
        noise = rng.choice([0.0, 1e-6, 1e-3, 0.02, 0.5])
        points = np.outer(along, [np.cos(angle), np.sin(angle)]) + rng.normal(0, noise, (count, 2))
        if rng.random() < 0.1:  # a wall along an axis of {W}
            points[:, rng.integers(2)] = rng.choice([0.0, -0.0, 1.5])
        centred = points - points.mean(axis=0)
        _assert_eigh_bits(centred.T @ centred, count)


def test_principal_axis_of_any_symmetric_matrix_is_eighs() -> None:
    """Random signs and scales, near-diagonal and equal-diagonal matrices: every branch of
    dsteqr's split and negligibility tests and of dlaev2."""
    rng = np.random.default_rng(7)
    for _ in range(10000):
        kind = int(rng.integers(5))
        scale = 10.0 ** rng.uniform(-100, 140)
        a11, a22 = rng.normal(size=2) * scale
        a21 = rng.normal() * scale
        if kind == 1:  # off-diagonal near each of the two tests' thresholds
            a21 = math.sqrt(abs(a11)) * math.sqrt(abs(a22)) * 2.0**-53 * rng.uniform(0.5, 1.5)
        elif kind == 2:
            a21 = abs(a11 * a22) ** 0.5 * 2.0**-53 * rng.uniform(0.5, 1.5)
        elif kind == 3:
            a22 = a11 if rng.random() < 0.5 else -a11
        elif kind == 4:
            a21 = rng.choice([0.0, -0.0])
        _assert_eigh_bits(_symmetric(a11, a21, a22), 1)


def test_principal_axis_just_past_the_split_test_is_eighs() -> None:
    """Off-diagonals a few ulps above dsteqr's split threshold, where its QL or QR test still
    finds them negligible for one of every ten or so matrices (no rotation: eigh's identity)."""
    rng = np.random.default_rng(11)
    for _ in range(3000):
        a11, a22 = (
            rng.uniform(0.1, 10.0, 2) * rng.choice([1.0, -1.0], 2) * 10.0 ** rng.integers(-8, 3)
        )
        a21 = math.sqrt(abs(a11)) * math.sqrt(abs(a22)) * 2.0**-53
        for _ in range(4):
            a21 = float(np.nextafter(a21, math.inf))
            _assert_eigh_bits(_symmetric(a11, a21 * rng.choice([1.0, -1.0]), a22), 1)


@pytest.mark.parametrize(
    "entries",
    [
        (0.0, 0.0, 0.0),
        (-0.0, -0.0, -0.0),
        (1.0, 0.0, 1.0),
        (1.0, 1.0, 1.0),
        (0.0, 1.0, 0.0),
        (-1.0, 1.0, 1.0),
        (2.0, -1.0, 2.0),
        (1e-3, 1e-20, 1e-6),
        (4e-4, 2e-4, 1e-4),
        (1e-120, 1e-121, 0.0),
        (1e145, -1e144, 1e140),
    ],
)
def test_principal_axis_of_edge_matrices_is_eighs(entries: tuple[float, float, float]) -> None:
    _assert_eigh_bits(_symmetric(*entries), 1)


@given(
    st.floats(-1e30, 1e30, allow_nan=False),
    st.floats(-1e30, 1e30, allow_nan=False),
    st.floats(-1e30, 1e30, allow_nan=False),
    st.integers(1, 1000),
)
@settings(max_examples=2000, deadline=None)
def test_principal_axis_is_eighs_or_declines(
    a11: float, a21: float, a22: float, count: int
) -> None:
    scatter = _symmetric(a11, a21, a22)
    if principal_axis(scatter, float(count))[0]:
        _assert_eigh_bits(scatter, count)
    else:  # only outside the range where LAPACK works unscaled
        largest = float(np.max(np.abs(scatter / count)))
        assert largest != 0.0 and not 1e-120 <= largest <= 1e145


@pytest.mark.parametrize(
    "entries",
    [
        (1e-130, 0.0, 1e-131),
        (1e150, 1.0, 0.0),
        (math.inf, 0.0, 1.0),
        (1.0, math.nan, 1.0),
    ],
)
def test_principal_axis_declines_what_lapack_rescales(entries: tuple[float, float, float]) -> None:
    answered, smallest, along_x, along_y = principal_axis(_symmetric(*entries), 1.0)
    assert not answered
    assert all(math.isnan(value) for value in (smallest, along_x, along_y))


def test_principal_axis_reads_the_lower_triangle_as_eigh_does() -> None:
    lower_only = np.array([[1.0, 5.0], [2.0, 1.0]])
    answered, smallest, along_x, along_y = principal_axis(lower_only, 1.0)
    values, vectors = np.linalg.eigh(lower_only)
    assert answered and smallest == values[0] == -1.0
    assert (along_x, along_y) == (vectors[0, 1], vectors[1, 1])
