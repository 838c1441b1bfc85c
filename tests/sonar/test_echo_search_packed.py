"""The echo search handing back fewer arrays (:func:`~sonar_gym.sonar.kernels.echo_ranges`,
:func:`~sonar_gym.sonar.kernels.audible_paths`,
:func:`~sonar_gym.sonar.kernels.clear_paths_nearest_first`) against the loops they wrap and the
search as it called them (:mod:`tests.sonar.echo_candidates_unpacked_reference`): the same
candidates, bit for bit, over every built-in scenario and a cluttered room, with and without
air absorption, receiver gain and footprint, both edge laws."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from sonar_gym.scenario import load_scenario
from sonar_gym.sonar import kernels
from sonar_gym.sonar.echo_tables import EchoTables, echo_tables
from sonar_gym.sonar.echoes import (
    _CYLINDER,
    _EDGE,
    _LN10,
    _PATH_CENTRE,
    _PLANE,
    EchoCandidates,
    edge_law_constants,
)
from sonar_gym.sonar.presets import preset
from sonar_gym.world import World
from tests.sonar.echo_candidates_unpacked_reference import echo_candidates_unpacked_reference
from tests.sonar.test_echo_search import SCENARIOS, assert_search_finds_what
from tests.sonar.worlds import cluttered_room


def _bits_equal(got: np.ndarray, want: np.ndarray) -> bool:
    return got.dtype == want.dtype and got.shape == want.shape and got.tobytes() == want.tobytes()


def _world(name: str) -> Any:
    return cluttered_room() if name == "cluttered_room" else World(load_scenario(name))


def _assert_same(got: EchoCandidates, want: EchoCandidates) -> None:
    for name in ("position", "directions", "path_lengths", "amplitudes", "kinds"):
        assert _bits_equal(getattr(got, name), getattr(want, name)), name
    assert _bits_equal(got._primitive_indices, want._primitive_indices)
    assert _bits_equal(got._concave, want._concave)
    assert got.threshold == want.threshold
    assert got._tables is want._tables
    for array in (got.directions, got.path_lengths, got.amplitudes):
        assert array.flags.c_contiguous and not array.flags.writeable


@pytest.mark.parametrize("world_name", [*SCENARIOS, "cluttered_room"])
def test_packed_echo_search_finds_what_the_unpacked_search_finds(world_name: str) -> None:
    assert_search_finds_what(echo_candidates_unpacked_reference, world_name, 29, _assert_same)


def _search_inputs(
    tables: EchoTables, rng: np.random.Generator, low: np.ndarray, high: np.ndarray
) -> tuple[np.ndarray, tuple[Any, ...], float, np.ndarray, np.ndarray]:
    """A sensor's map product, the on-axis arguments, an absorption exponent per metre, a
    footprint and the inclusive bounds, drawn at random."""
    px, py = rng.uniform(low, high).tolist()
    transducer = preset(str(rng.choice(["srf04", "polaroid-6500", "ma40b8"])))
    law = edge_law_constants(str(rng.choice(["weak", "gtd"])), float(rng.uniform(300, 1000)))
    exponent_per_m = -float(rng.choice([0.0, 1.3, 2.5])) * _LN10 / 10.0
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
    layout = (tables.search_layout, tables.radius_padded, tables.radius, law)
    return mapped, layout, exponent_per_m, footprint, bounds


@pytest.mark.parametrize("world_name", [*SCENARIOS, "cluttered_room"])
def test_packed_loops_give_the_bits_of_the_loops_they_wrap(world_name: str) -> None:
    geometry = _world(world_name).geometry
    tables = echo_tables(geometry, _PLANE, _CYLINDER, _EDGE)
    n_circles, n_candidates = tables.n_circles, tables.n_candidates
    low = geometry.segment_starts.min(axis=0) - 0.5
    high = geometry.segment_starts.max(axis=0) + 0.5
    rng = np.random.default_rng(43)
    kept_any = False
    for _ in range(120):
        mapped, layout, exponent_per_m, footprint, bounds = _search_inputs(tables, rng, low, high)
        mapped_reference = mapped.copy()
        concave = np.empty(tables.n_wedges, dtype=np.bool_)
        distances = kernels.echo_ranges(mapped, *layout, exponent_per_m, concave)
        concave_want, distances_want = kernels.on_axis_echoes(mapped_reference, *layout)
        assert _bits_equal(concave, concave_want)
        assert _bits_equal(distances[: n_circles + n_candidates], distances_want)
        exponents_want = exponent_per_m * distances_want[n_circles:]
        assert _bits_equal(distances[n_circles + n_candidates :], exponents_want)
        assert _bits_equal(mapped, mapped_reference)

        absorption = np.exp(exponents_want) if rng.random() < 0.7 else np.empty(0)
        gain_law = preset("polaroid-6500").time_varying_gain
        gain = gain_law.gain(distances_want[n_circles:]) if rng.random() < 0.5 else np.empty(0)
        tests = (
            tables.strict_bounds,
            bounds,
            concave,
            tables.twin,
            tables.twin_comes_last,
            tables.has_t_junctions,
        )
        picks = np.full(tables.n_picks, -7, dtype=np.int64)
        footprint_floats = footprint.tolist() if len(footprint) else [0.0, 0.0, 0.0]
        kept = kernels.audible_paths(
            mapped, tables.search_layout, absorption, gain, *tests, *footprint_floats, picks
        )
        keep_want, kept_want, occluders_want = kernels.audible_candidates(
            mapped_reference, tables.search_layout, absorption, gain, *tests, footprint
        )
        assert _bits_equal(kept, kept_want)
        assert _bits_equal(picks[: len(keep_want)], keep_want)
        assert _bits_equal(picks[-len(occluders_want) :].astype(np.bool_), occluders_want)
        assert set(picks[-len(occluders_want) :].tolist()) <= {0, 1}
        assert _bits_equal(mapped, mapped_reference)

        products = np.dot(mapped[tables.occlusion_rows].reshape(-1, 3), kept.T)
        indices, floats = kernels.clear_paths_nearest_first(
            products,
            picks,
            kept,
            mapped,
            distances,
            tables.search_layout,
            tables.radius_sq,
            _PATH_CENTRE,
        )
        want = kernels.clear_nearest_first(
            products,
            keep_want,
            kept_want,
            mapped_reference[tables.ranges_rows],
            mapped_reference[tables.amplitudes_rows],
            distances_want[:n_circles],
            tables.radius_sq,
            occluders_want,
            _PATH_CENTRE,
        )
        n_kept = len(want[0])
        assert _bits_equal(indices, want[0])
        assert _bits_equal(floats[: 2 * n_kept].reshape(n_kept, 2), want[1])
        assert _bits_equal(floats[2 * n_kept : 3 * n_kept], want[2])
        assert _bits_equal(floats[3 * n_kept :], want[3])
        assert floats.shape == (4 * n_kept,)
        kept_any = kept_any or n_kept > 0
    assert kept_any
