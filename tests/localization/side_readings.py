"""Side-sonar readings to test the APCS stream on: a sensor driving a wobbly line past a wall."""

from __future__ import annotations

import numpy as np


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
