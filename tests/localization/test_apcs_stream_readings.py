"""A side stream's pending ERPs (Yamamoto et al. sec. 4.2.1, eqs (1)-(6)) with the compiled
:func:`~sonar_gym.localization.apcs_kernels.stream_readings` against the array form it replaced
(:mod:`tests.localization.apcs_stream_reference`), bit for bit."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from sonar_gym.localization.apcs_online import WallStream
from tests.fuzzing import fuzz_settings
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
    rng = np.random.default_rng(seed)
    stream = WallStream(side)
    low, high = stream.params.sensing_range_m
    steps = rng.normal(0.0, 0.05, (2 * count, 2))
    steps[rng.random(2 * count) < 0.1] = 0.0  # standstills: no baseline
    positions = np.cumsum(steps, axis=0) + rng.normal(0.0, 2.0, 2)
    headings = rng.normal(0.0, 0.02, 2 * count).cumsum()
    headings += math.pi if near_pi else rng.uniform(-math.pi, math.pi)
    # a wall seen along the way (ranges changing less than the sensor moves), some out of range
    ranges = rng.uniform(0.5 * low, 1.2 * high) + rng.normal(0.0, 0.03, 2 * count).cumsum()
    ranges[rng.random(2 * count) < 0.15] = np.nan  # dropouts
    if strided:  # every other reading: views, not contiguous
        positions, headings, ranges = positions[::2], headings[::2], ranges[::2]
    else:
        positions, headings, ranges = positions[:count], headings[:count], ranges[:count]
    if has_previous:
        previous_range = float(rng.uniform(low, high)) if rng.random() < 0.8 else math.nan
        stream._previous = (
            (float(rng.normal(0.0, 2.0)), float(rng.normal(0.0, 2.0))),
            float(rng.uniform(-4.0, 4.0)),
            previous_range,
        )
    got = stream._pending(positions, headings, ranges)
    expected = pending_erps_arrays(stream, positions, headings, ranges)
    for array, reference in zip(got, expected, strict=True):
        assert array.dtype == reference.dtype and array.shape == reference.shape
        assert array.tobytes() == reference.tobytes()
