"""A side stream's pending ERPs as the one table the tracker reads
(:meth:`~sonar_gym.localization.apcs_online.WallStream._pending_rows`, the compiled loops of
:func:`~sonar_gym.localization.apcs_kernels.reading_table` on) against the loops that returned
separate arrays (:mod:`tests.localization.apcs_row_kernels_reference`) and the array form
(:mod:`tests.localization.apcs_stream_reference`) with the sensor positions, bit for bit
(Yamamoto et al. sec. 4.2.1, eqs (1)-(6))."""

from __future__ import annotations


import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from sonar_gym.localization import apcs_kernels
from sonar_gym.localization.apcs_walls import newest_reflection_table
from tests.fuzzing import fuzz_settings
from tests.localization.side_readings import PENDING_STREAM_CASES, PendingStreamCase
from tests.localization.apcs_row_kernels_reference import newest_reflection_rows, pending_rows
from tests.localization.apcs_stream_reference import pending_erps_arrays


def _expected_rows(
    positions: np.ndarray, points: np.ndarray, directions: np.ndarray, valid: np.ndarray
) -> np.ndarray:
    """The rows of :data:`~sonar_gym.localization.apcs_kernels.ERP_COLUMNS` of separate arrays."""
    table = np.zeros((len(positions), len(apcs_kernels.ERP_COLUMNS)))
    table[:, 0:2] = positions
    table[:, 2:4] = points
    table[:, 4] = directions
    table[:, 5] = valid
    return table


@fuzz_settings(300)
@given(case=PENDING_STREAM_CASES)
def test_pending_rows_are_the_pending_arrays_bit_for_bit(case: PendingStreamCase) -> None:
    stream, positions, headings, ranges = case
    got = np.array(stream._pending_rows(positions, headings, ranges)).reshape(-1, 6)
    compiled = _expected_rows(positions, *pending_rows(stream, positions, headings, ranges))
    arrays = _expected_rows(positions, *pending_erps_arrays(stream, positions, headings, ranges))
    assert got.shape == (len(positions), 6)
    assert got.tobytes() == compiled.tobytes()
    assert got.tobytes() == arrays.tobytes()


@fuzz_settings(200)
@given(seed=st.integers(0, 2**32 - 1), count=st.sampled_from([1, 2, 3, 9, 33]))
def test_reflection_table_is_the_row_loops_bit_for_bit(seed: int, count: int) -> None:
    rng = np.random.default_rng(seed)
    positions = np.cumsum(rng.normal(0.0, 0.05, (count, 2)), axis=0)
    directions = rng.uniform(-4.0, 4.0) + rng.normal(0.0, 0.02, count).cumsum()
    ranges = rng.uniform(0.2, 3.0) + rng.normal(0.0, 0.03, count).cumsum()
    ranges[rng.random(count) < 0.15] = np.nan
    readings = np.ascontiguousarray(np.vstack([positions.T, directions, ranges]))
    for skipped in (0, 1):
        if count - skipped < 0:
            continue
        got = newest_reflection_table(readings, (0.3, 2.5), skipped)
        expected = newest_reflection_rows(positions, directions, ranges, (0.3, 2.5), skipped)
        assert got.tobytes() == _expected_rows(positions[skipped:], *expected).tobytes()
