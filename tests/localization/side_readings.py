"""Side-sonar readings to test the APCS stream on: a sensor driving a wobbly line past a wall,
or creeping along one."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st

from sonar_gym.localization.apcs_online import WallStream


def wobbly_side_readings(
    rng: np.random.Generator, count: int, heading_std_rad: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(positions (count, 2) metres, beam directions (count,) radians, ranges (count,)
    metres)`` of a side sensor stepping 0, 3 or 6 cm at a time along a heading that wanders
    by ``heading_std_rad`` per step, its beam at the heading + pi/2; the ranges hold dropouts
    (NaN), readings beyond the sensing range and inside the minimum range, and jumps."""
    steps = rng.choice([0.0, 0.03, 0.06], size=count, p=[0.1, 0.6, 0.3])
    headings = np.cumsum(rng.normal(0.0, heading_std_rad, count))
    positions = np.column_stack(
        [np.cumsum(steps * np.cos(headings)), np.cumsum(steps * np.sin(headings))]
    )
    ranges = 1.0 + 0.002 * np.arange(count) + rng.normal(0.0, 0.003, count)
    ranges[rng.random(count) < 0.1] = np.nan
    ranges[rng.random(count) < 0.05] = 6.0  # beyond the sensing range
    ranges[rng.random(count) < 0.05] = 0.1  # inside the minimum range
    ranges[rng.random(count) < 0.1] += 0.5  # a discontinuity
    return positions, headings + np.pi / 2.0, ranges


PendingStreamCase = tuple[WallStream, np.ndarray, np.ndarray, np.ndarray]
"""A stream and the readings to pend on it: ``(stream, positions, headings, ranges)``."""


def pending_stream_case(
    seed: int, count: int, side: str, has_previous: bool, near_pi: bool, strided: bool
) -> PendingStreamCase:
    """A ``side`` stream (with a remembered previous reading when ``has_previous``) and
    ``count`` readings to pend on it: ``(positions (count, 2) metres, headings (count,)
    radians, ranges (count,) metres)`` of a sensor creeping along a wall with standstills,
    dropouts and readings out of range; headings near pi when ``near_pi``; every other
    reading of twice as many (strided views) when ``strided``."""
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
    return stream, positions, headings, ranges


PENDING_STREAM_CASES = st.builds(
    pending_stream_case,
    seed=st.integers(0, 2**32 - 1),
    count=st.sampled_from([0, 1, 2, 3, 12, 40]),
    side=st.sampled_from(["left", "right"]),
    has_previous=st.booleans(),
    near_pi=st.booleans(),
    strided=st.booleans(),
)
"""Hypothesis strategy of :func:`pending_stream_case`'s cases."""
