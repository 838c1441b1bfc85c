"""A side stream's pending ERPs (Yamamoto et al. sec. 4.2.1, eqs (1)-(6)) with the compiled
:func:`~sonar_gym.localization.apcs_kernels.reading_table` against the array form it replaced
(:mod:`tests.localization.apcs_stream_reference`), bit for bit."""

from __future__ import annotations


from hypothesis import given
from hypothesis import strategies as st

from tests.fuzzing import fuzz_settings
from tests.localization.side_readings import pending_stream_case
from tests.localization.apcs_stream_reference import pending_erps_arrays


@fuzz_settings(300)
@given(
    seed=st.integers(0, 2**32 - 1),
    count=st.sampled_from([0, 1, 2, 3, 12, 40]),
    side=st.sampled_from(["left", "right"]),
    has_previous=st.booleans(),
    near_pi=st.booleans(),
    strided=st.booleans(),
)
def test_pending_erps_are_the_array_form_bit_for_bit(
    seed: int, count: int, side: str, has_previous: bool, near_pi: bool, strided: bool
) -> None:
    stream, positions, headings, ranges = pending_stream_case(
        seed, count, side, has_previous, near_pi, strided
    )
    got = stream._pending(positions, headings, ranges)
    expected = pending_erps_arrays(stream, positions, headings, ranges)
    for array, reference in zip(got, expected, strict=True):
        assert array.dtype == reference.dtype and array.shape == reference.shape
        assert array.tobytes() == reference.tobytes()
