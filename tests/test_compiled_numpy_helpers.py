"""The compiled helpers that stand for numpy inside loops against numpy itself, bit for bit:
``np.remainder``, ``wrap_angles`` and ``ndarray.sum``'s pairwise summation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sonar_gym.compiled import floor_remainder, pairwise_sum, wrap_to_pi
from sonar_gym.pose import FloatArray, wrap_angles
from tests.fuzzing import fuzz_settings

_ANGLES = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)


def _bits(value: float) -> bytes:
    return np.float64(value).tobytes()


@fuzz_settings(2000)
@given(angle=_ANGLES, divisor=st.sampled_from([2.0 * math.pi, -2.0 * math.pi, 0.7, -0.7, 1.0]))
def test_floor_remainder_is_numpys(angle: float, divisor: float) -> None:
    assert _bits(floor_remainder(angle, divisor)) == _bits(np.remainder(angle, divisor))


@fuzz_settings(2000)
@given(angle=_ANGLES)
def test_wrap_to_pi_is_wrap_angles(angle: float) -> None:
    assert _bits(wrap_to_pi(angle)) == wrap_angles(np.array([angle])).tobytes()


@pytest.mark.parametrize("multiple", [-6, -5, -3, -2, -1, 0, 1, 2, 3, 5, 6])
def test_wrap_to_pi_of_multiples_of_pi_and_signed_zeros(multiple: int) -> None:
    for angle in (multiple * math.pi, math.nextafter(multiple * math.pi, math.inf), -0.0):
        assert _bits(wrap_to_pi(angle)) == wrap_angles(np.array([angle])).tobytes()
    for value, divisor in ((-0.0, 1.0), (0.0, -1.0), (-2.0, 1.0), (2.0, -1.0)):
        assert _bits(floor_remainder(value, divisor)) == _bits(np.remainder(value, divisor))


def test_wrap_to_pi_is_wrap_angles_of_extreme_and_non_finite_angles() -> None:
    rng = np.random.default_rng(0)
    angles = np.concatenate(
        [
            rng.uniform(-20.0, 20.0, 20_000),
            rng.normal(0.0, 1e3, 2_000),
            np.pi * np.arange(-12, 13),  # exact multiples of pi and their neighbours
            np.nextafter(np.pi * np.arange(-12, 13), np.inf),
            np.nextafter(np.pi * np.arange(-12, 13), -np.inf),
            [0.0, -0.0, 5e-324, -5e-324, 1e300, -1e300, np.nan, np.inf, -np.inf],
        ]
    )
    with np.errstate(invalid="ignore"):  # the remainder of inf
        expected = wrap_angles(angles)
    actual = np.array([wrap_to_pi(float(angle)) for angle in angles])
    assert actual.tobytes() == expected.tobytes()


def _sums_agree(values: FloatArray) -> bool:
    return _bits(pairwise_sum(values)) == _bits(values.sum())


@pytest.mark.parametrize(
    "size", [*range(0, 40), 63, 64, 127, 128, 129, 130, 135, 136, 255, 256, 257, 1000, 9000]
)
def test_pairwise_sum_is_numpys(size: int) -> None:
    rng = np.random.default_rng(size)
    # magnitudes over ten decades: any other order of the additions rounds differently
    values = rng.normal(size=size) * 10.0 ** rng.integers(-3, 8, size=size)
    assert _sums_agree(values)
    assert _sums_agree(values[::3])  # strided: the same order


def test_pairwise_sum_of_signed_zeros_and_cancellations() -> None:
    for values in ([], [-0.0], [-0.0] * 9, [0.0, -0.0], [1e16, 1.0, -1e16, 1.0] * 40):
        assert _sums_agree(np.array(values))
