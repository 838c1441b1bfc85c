"""The sampling schedule of :meth:`sonar_gym.apcs_route.APCSRoute._execute` as it was written:
one pass over the planned commands counting the straight steps since the last reading, with
the count after every command kept; the form the module replaced, kept as the tests'
reference."""

from __future__ import annotations

from collections.abc import Sequence


def sampling_schedule(
    straight_flags: Sequence[bool], counter: int, steps_per_sample: int, sampling: bool
) -> tuple[list[int], list[int]]:
    """``(samples, counters)``: the commands that take a reading, and the count of straight
    steps since the last reading after each command."""
    samples: list[int] = []
    counters: list[int] = []
    for index, straight in enumerate(straight_flags):
        if straight:
            counter += 1
            if sampling and counter >= steps_per_sample:
                counter = 0
                samples.append(index)
        counters.append(counter)
    return samples, counters
