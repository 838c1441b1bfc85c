"""A side stream's pending ERPs (Yamamoto et al. sec. 4.2.1, eqs (1)-(6)) with the compiled
:func:`~sonar_gym.localization.apcs_kernels.reading_table` against the array form it replaced
(:mod:`tests.localization.apcs_stream_reference`), bit for bit."""

from __future__ import annotations


from hypothesis import given

from tests.fuzzing import fuzz_settings
from tests.localization.side_readings import PENDING_STREAM_CASES, PendingStreamCase
from tests.localization.apcs_stream_reference import pending_erps_arrays


@fuzz_settings(300)
@given(case=PENDING_STREAM_CASES)
def test_pending_erps_are_the_array_form_bit_for_bit(case: PendingStreamCase) -> None:
    stream, positions, headings, ranges = case
    got = stream._pending(positions, headings, ranges)
    expected = pending_erps_arrays(stream, positions, headings, ranges)
    for array, reference in zip(got, expected, strict=True):
        assert array.dtype == reference.dtype and array.shape == reference.shape
        assert array.tobytes() == reference.tobytes()
