"""The side sonars' products of the echo tables' maps at many points, taken in the order that
costs BLAS less, against the products as written before: the same bits."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sonar_gym.scenario import load_scenario
from sonar_gym.sonar.echo_tables import EchoTables, echo_tables
from sonar_gym.sonar.echoes import EchoKind
from sonar_gym.sonar.swept import map_at_points
from sonar_gym.world import World
from tests.fuzzing import fuzz_settings
from tests.sonar.side_products_reference import (
    occlusion_map_reference,
    search_map_reference,
)
from tests.sonar.worlds import cluttered_room

WORLDS = {
    "cluttered_room": cluttered_room(),
    "apcs_corridor": World(load_scenario("apcs_corridor")),
    "kim_arena": World(load_scenario("kim_arena")),
}


def _tables(world_name: str) -> EchoTables:
    geometry = WORLDS[world_name].geometry
    return echo_tables(geometry, EchoKind.PLANE, EchoKind.CYLINDER, EchoKind.EDGE)


def _points(rng: np.random.Generator, count: int, scale: float) -> np.ndarray:
    return np.column_stack([rng.uniform(-scale, scale, (count, 2)), np.ones(count)])


@fuzz_settings(200)
@given(
    seed=st.integers(0, 2**32 - 1),
    world_name=st.sampled_from(sorted(WORLDS)),
    count=st.integers(0, 200),
    scale=st.sampled_from([0.01, 1.0, 4.0, 1e3]),
)
def test_maps_at_points_are_the_products_as_written(
    seed: int, world_name: str, count: int, scale: float
) -> None:
    tables = _tables(world_name)
    rng = np.random.default_rng(seed)
    points = _points(rng, count, scale)
    mapped = map_at_points(tables.position_map, points)
    want = search_map_reference(tables, points)
    assert mapped.shape == want.shape and mapped.tobytes() == want.tobytes()
    sensor_rows = rng.integers(0, max(count, 1), count)
    matrix = map_at_points(tables.occlusion_map, points).reshape(
        count, 3 * tables.n_segments + tables.n_circles, 3
    )
    want_matrix = occlusion_map_reference(tables, sensor_rows, points)
    assert matrix.shape == want_matrix.shape and matrix.tobytes() == want_matrix.tobytes()


@pytest.mark.parametrize("rows", [1, 2, 3, 7, 64, 300])
@pytest.mark.parametrize("count", [1, 2, 5, 33, 129])
def test_maps_of_any_size_at_points_are_the_products(rows: int, count: int) -> None:
    """Random maps of every small shape (BLAS picks its kernels by shape)."""
    rng = np.random.default_rng(rows * 1000 + count)
    linear_map = rng.normal(size=(rows, 3)) * np.exp(3.0 * rng.normal(size=(rows, 3)))
    points = _points(rng, count, 5.0)
    got = map_at_points(linear_map, points)
    assert np.ascontiguousarray(got).tobytes() == (points @ linear_map.T).tobytes()
