"""The first two loops of the echo search, :func:`~sonar_gym.sonar.kernels.on_axis_echoes` and
:func:`~sonar_gym.sonar.kernels.audible_candidates`, against their forms that returned the
on-axis amplitudes, ranges and centre distances as arrays of their own
(:mod:`tests.sonar.echo_search_kernels_reference`): the same map, ranges, distances, amplitudes
and candidates, bit for bit, with and without air absorption, receiver gain and footprint."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from sonar_gym.scenario import load_scenario
from sonar_gym.sonar import kernels
from sonar_gym.sonar.echo_tables import echo_tables
from sonar_gym.sonar.echoes import _CYLINDER, _EDGE, _LN10, _PLANE, edge_law_constants
from sonar_gym.sonar.presets import preset
from sonar_gym.world import World
from tests.sonar.echo_search_kernels_reference import (
    audible_candidates_reference,
    on_axis_echoes_reference,
)
from tests.sonar.test_echo_search import SCENARIOS
from tests.sonar.worlds import cluttered_room


def _bits_equal(got: np.ndarray, want: np.ndarray) -> bool:
    return got.dtype == want.dtype and got.shape == want.shape and got.tobytes() == want.tobytes()


@pytest.mark.parametrize("world_name", [*SCENARIOS, "cluttered_room"])
def test_one_distances_array_and_amplitudes_in_the_map_give_the_same_search(
    world_name: str,
) -> None:
    world: Any = (
        cluttered_room() if world_name == "cluttered_room" else World(load_scenario(world_name))
    )
    tables = echo_tables(world.geometry, _PLANE, _CYLINDER, _EDGE)
    low = world.geometry.segment_starts.min(axis=0) - 0.5
    high = world.geometry.segment_starts.max(axis=0) + 0.5
    rng = np.random.default_rng(41)
    kept_any = False
    for _ in range(120):
        px, py = rng.uniform(low, high).tolist()
        transducer = preset(str(rng.choice(["srf04", "polaroid-6500", "ma40b8"])))
        law = edge_law_constants(str(rng.choice(["weak", "gtd"])), float(rng.uniform(300, 1000)))
        absorbs = rng.random() < 0.7
        gain_law = transducer.time_varying_gain if rng.random() < 0.5 else None
        footprint = (
            np.array((*rng.uniform(-0.1, 0.1, 2).tolist(), float(rng.choice([0.1, 0.25]))))
            if rng.random() < 0.7
            else np.empty(0)
        )
        bounds = tables.inclusive_bounds(
            float(rng.choice([1e-9, transducer.min_range_m])),
            float(rng.choice([0.0, transducer.detection_threshold])),
        )
        mapped = np.dot(tables.search_map, np.array((px, py, 1.0)))
        mapped_reference = mapped.copy()
        layout = (tables.search_layout, tables.radius_padded, tables.radius, law)
        concave, distances = kernels.on_axis_echoes(mapped, *layout)
        concave_want, centre_want, safe_want, on_axis = on_axis_echoes_reference(
            mapped_reference, *layout
        )
        centre_distance, safe = distances[: tables.n_circles], distances[tables.n_circles :]
        assert _bits_equal(concave, concave_want)
        assert _bits_equal(centre_distance, centre_want)
        assert _bits_equal(safe, safe_want)
        assert _bits_equal(mapped[tables.amplitudes_rows], on_axis)
        absorption = np.exp((-1.3 * _LN10 / 10.0) * safe) if absorbs else np.empty(0)
        gain = gain_law.gain(safe) if gain_law is not None else np.empty(0)
        tests = (
            tables.strict_bounds,
            bounds,
            concave,
            tables.twin,
            tables.twin_comes_last,
            tables.has_t_junctions,
            footprint,
        )
        got = kernels.audible_candidates(mapped, tables.search_layout, absorption, gain, *tests)
        want = audible_candidates_reference(
            mapped_reference, tables.search_layout, on_axis, absorption, gain, *tests
        )
        for got_array, want_array in zip(got, want, strict=True):
            assert _bits_equal(got_array, want_array)
        # the whole map alike: ranges, offsets, amplitudes and every row read by the tests
        assert _bits_equal(mapped, mapped_reference)
        kept_any = kept_any or got[0].size > 0
    assert kept_any
