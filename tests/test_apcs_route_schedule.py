"""The route's sampling schedule (which straight steps read the sonars, and the count carried
to the next plan) equals the per-command loop it replaced, for every consumed prefix."""

from __future__ import annotations

import bisect

import numpy as np
import pytest

from sonar_gym.apcs_route import counter_after, first_sample_step
from tests.apcs_route_schedule_reference import sampling_schedule


@pytest.mark.parametrize("seed", range(40))
def test_schedule_matches_the_per_command_loop(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(50):
        count = int(rng.integers(1, 60))
        flags = (rng.random(count) < rng.random()).tolist()
        counter = int(rng.integers(-3, 12))
        steps_per_sample = int(rng.integers(-1, 9))
        sampling = bool(rng.random() < 0.8)
        expected_samples, expected_counters = sampling_schedule(
            flags, counter, steps_per_sample, sampling
        )
        straight = [index for index, flag in enumerate(flags) if flag]
        first = first_sample_step(counter, steps_per_sample) if sampling else len(straight)
        assert straight[first :: max(steps_per_sample, 1)] == expected_samples
        for consumed in range(1, count + 1):
            steps = bisect.bisect_left(straight, consumed)
            after = counter_after(counter, steps_per_sample, first, steps)
            assert after == expected_counters[consumed - 1]
