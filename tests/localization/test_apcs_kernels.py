"""APCS's compiled loops against the array forms they replace, bit for bit.

The references are the array forms of commit 074d50b, kept here: ``newest_reflection_points``
as ``_newest_points`` on ranges with the invalid ones made NaN, and ``WallStream._pending``'s
scatter of its ERPs into one row per reading.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from sonar_gym.localization import apcs_kernels
from sonar_gym.localization.apcs_walls import (
    DEFAULT_PARAMETERS,
    _newest_points,
    newest_reflection_points,
    newest_reflection_rows,
)
from sonar_gym.pose import wrap_angles
from tests.fuzzing import fuzz_settings

SENSING_RANGE_M = DEFAULT_PARAMETERS.sensing_range_m


def reference_newest(
    positions: np.ndarray,
    directions: np.ndarray,
    ranges: np.ndarray,
    valid_range_m: tuple[float, float],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``newest_reflection_points`` of commit 074d50b."""
    if len(positions) < 2:
        return np.zeros((0, 2)), np.zeros(0), np.zeros(0, dtype=np.int64)
    low, high = valid_range_m
    ranges = np.where((ranges >= low) & (ranges <= high), ranges, np.nan)
    points, phi, pairs = _newest_points(positions, directions, ranges)
    return points, wrap_angles(phi), pairs + 1


def reference_rows(
    positions: np.ndarray,
    directions: np.ndarray,
    ranges: np.ndarray,
    valid_range_m: tuple[float, float],
    skipped: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``WallStream._pending``'s rows of commit 074d50b."""
    count = len(positions) - skipped
    points, phis, valid = np.zeros((count, 2)), np.zeros(count), np.zeros(count, dtype=bool)
    erp_points, erp_directions, readings = reference_newest(
        positions, directions, ranges, valid_range_m
    )
    rows = readings - skipped
    points[rows] = erp_points
    phis[rows] = erp_directions
    valid[rows] = True
    return points, phis, valid


def assert_same_bits(actual: tuple[np.ndarray, ...], expected: tuple[np.ndarray, ...]) -> None:
    assert len(actual) == len(expected)
    for got, want in zip(actual, expected, strict=True):
        assert got.dtype == want.dtype and got.shape == want.shape
        assert got.tobytes() == want.tobytes()


def assert_both_forms_agree(
    positions: np.ndarray,
    directions: np.ndarray,
    ranges: np.ndarray,
    valid_range_m: tuple[float, float] = SENSING_RANGE_M,
) -> None:
    if len(positions) >= 2:
        assert_same_bits(
            newest_reflection_points(positions, directions, ranges, valid_range_m),
            reference_newest(positions, directions, ranges, valid_range_m),
        )
    for skipped in (0, 1):
        if len(positions) >= skipped:
            assert_same_bits(
                newest_reflection_rows(positions, directions, ranges, valid_range_m, skipped),
                reference_rows(positions, directions, ranges, valid_range_m, skipped),
            )


def drive(seed: int, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A side sensor driving a wobbly line past walls, with dropouts, stops and jumps."""
    rng = np.random.default_rng(seed)
    steps = rng.choice([0.0, 0.03, 0.06], size=count, p=[0.1, 0.6, 0.3])
    headings = np.cumsum(rng.normal(0.0, 0.05, count)) + rng.uniform(-np.pi, np.pi)
    positions = np.column_stack(
        [np.cumsum(steps * np.cos(headings)), np.cumsum(steps * np.sin(headings))]
    )
    ranges = 1.0 + 0.01 * np.arange(count) * rng.normal() + rng.normal(0.0, 0.01, count)
    ranges[rng.random(count) < 0.1] = np.nan
    ranges[rng.random(count) < 0.05] = np.inf
    ranges[rng.random(count) < 0.05] = 6.0  # beyond the sensing range
    ranges[rng.random(count) < 0.05] = 0.1  # inside the minimum range
    ranges[rng.random(count) < 0.1] += 0.5  # a discontinuity
    side = rng.choice([-1.0, 1.0])
    return positions, headings + side * np.pi / 2.0 + 6.0 * np.pi * rng.integers(-2, 3), ranges


def test_reflection_points_of_driven_paths() -> None:
    for seed in range(40):
        for count in (0, 1, 2, 3, 7, 30):
            assert_both_forms_agree(*drive(seed, count))


def test_reflection_points_at_the_edges() -> None:
    # |P1P2| = 5 exactly (3-4-5) and |r2 - r1| = 5: the roots of eq. (4) meet (cosine -1 or 1).
    positions = np.array([[0.0, 0.0], [3.0, 4.0], [6.0, 8.0], [6.0, 8.0], [9.0, 12.0]])
    directions = np.array([0.3, 0.3, 0.3, 0.3, 0.3])
    for ranges in (
        np.array([0.5, 5.5, 0.5, 0.5, 5.5]),  # r2 - r1 = +5, -5; no motion; +5
        np.array([0.5, 5.5000000001, 0.5, 0.7, 0.7]),  # just past |P1P2|: no root
        np.array([np.nan, 1.0, np.inf, 1.0, -0.0]),  # dropouts, a zero range
        np.array([0.3, 5.0, 0.3, 0.29999999999999993, 5.000000000000001]),  # on the limits
    ):
        assert_both_forms_agree(positions, directions, ranges)
        assert_both_forms_agree(positions, -directions, ranges, (0.0, math.inf))
    # a stream that never moves, and positions a hair apart (the zero baseline's threshold)
    still = np.zeros((4, 2))
    assert_both_forms_agree(still, np.full(4, np.pi / 2.0), np.ones(4))
    hair = np.array([[0.0, 0.0], [1e-9, 0.0], [2.0000000001e-9, 0.0], [3e-9, 1e-12]])
    assert_both_forms_agree(hair, np.full(4, np.pi / 2.0), np.array([1.0, 1.0, 1.0, 1.0]))


_COORDINATES = st.sampled_from([0.0, -0.0, 0.03, -0.03, 0.06, 3.0, 4.0, 1e-10, 1e-9, 2.0])
_RANGES = st.one_of(
    st.sampled_from([0.3, 0.5, 1.0, 1.03, 5.0, 5.5, 0.1, 6.0, 0.0, math.nan, math.inf]),
    st.floats(min_value=0.0, max_value=7.0),
)
_DIRECTIONS = st.one_of(
    st.sampled_from([0.0, math.pi / 2.0, -math.pi / 2.0, math.pi, -math.pi, 7.0 * math.pi]),
    st.floats(min_value=-50.0, max_value=50.0),
)


@fuzz_settings(300)
@given(
    st.lists(st.tuples(_COORDINATES, _COORDINATES, _DIRECTIONS, _RANGES), max_size=12),
    st.sampled_from([SENSING_RANGE_M, (0.0, math.inf), (0.5, 1.03)]),
)
def test_reflection_points_of_any_readings(
    readings: list[tuple[float, float, float, float]], valid_range_m: tuple[float, float]
) -> None:
    steps = np.array([[x, y] for x, y, _, _ in readings]).reshape(-1, 2)
    positions = np.cumsum(steps, axis=0)
    directions = np.array([direction for _, _, direction, _ in readings])
    ranges = np.array([range_m for _, _, _, range_m in readings])
    assert_both_forms_agree(positions, directions, ranges, valid_range_m)


def test_the_erp_loop_takes_any_root() -> None:
    # The roots reach the last loop wrapped once already, where wrapping again rarely changes
    # a bit; any angle here, so that the loop's own wrap is tested too.
    rng = np.random.default_rng(5)
    positions = rng.uniform(-3.0, 3.0, (40, 2))
    ranges = rng.uniform(0.3, 5.0, 40)
    pairs = np.sort(rng.choice(39, 25, replace=False))
    phi = np.concatenate([rng.uniform(-4.0, 4.0, 20), [1e-20, -1e-17, np.pi, -np.pi, 3e-16]])
    unit = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    points = positions[1:][pairs] + ranges[1:][pairs, None] * unit  # R2, eqs (2)-(3)
    readings = np.vstack([positions.T, np.zeros(40), ranges])
    roots = np.vstack([phi, pairs.astype(np.float64)])
    for skipped in (0, 1):
        rows = np.zeros((40 - skipped, 6))
        rows[:, 0:2] = positions[skipped:]
        rows[pairs + 1 - skipped, 2:4] = points
        rows[pairs + 1 - skipped, 4] = wrap_angles(phi)
        rows[pairs + 1 - skipped, 5] = 1.0
        got = apcs_kernels.erp_table(readings, roots, unit[:, 0], unit[:, 1], skipped)
        assert_same_bits((got,), (rows,))


def test_wrapped_angles_of_turned_directions() -> None:
    rng = np.random.default_rng(20261203)
    edges = [0.0, -0.0, math.pi, -math.pi, 3 * math.pi, -3 * math.pi, 2 * math.pi, 1e-300]
    edges += [math.nextafter(math.pi, 0.0), math.nextafter(-math.pi, 0.0), 1e15, -1e15]
    angles = np.concatenate([edges, rng.uniform(-10.0, 10.0, 20000), rng.normal(0.0, 1e3, 2000)])
    assert np.array_equal(
        apcs_kernels.wrapped_angles(angles).view(np.int64), wrap_angles(angles).view(np.int64)
    )


@fuzz_settings(300)
@given(st.lists(st.floats(-1e12, 1e12), max_size=10))
def test_wrapped_angles_of_any_angles(angles: list[float]) -> None:
    values = np.array(angles, dtype=np.float64)
    assert np.array_equal(
        apcs_kernels.wrapped_angles(values).view(np.int64), wrap_angles(values).view(np.int64)
    )


def test_one_arctan2_of_two_rows_gives_each_rows_angles() -> None:
    """``newest_reflection_table`` takes ``alpha`` and the mean beam axis from one
    ``arctan2`` of a ``(2, K)`` block: each row has the bits of ``arctan2`` of that row alone."""
    rng = np.random.default_rng(20261207)
    for _ in range(20000):
        count = int(rng.integers(0, 40))
        rows = rng.normal(size=(4, count)) * 10.0 ** float(rng.integers(-5, 5))
        if count and rng.random() < 0.1:
            rows[rng.integers(4), rng.integers(count)] = rng.choice([0.0, -0.0, np.inf, np.nan])
        block = np.arctan2(rows[0:2], rows[2:4])
        assert_same_bits(
            (block[0], block[1]), (np.arctan2(rows[0], rows[2]), np.arctan2(rows[1], rows[3]))
        )
