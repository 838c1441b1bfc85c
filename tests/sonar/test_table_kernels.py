""":func:`~sonar_gym.sonar.table_kernels.linear_maps` fills the echo tables' maps with the bits of
the array form it replaced (:mod:`tests.sonar.echo_tables_maps_reference`): on random and
built-in scenarios (with the unmapped boxes WallCorrection draws), and on geometries of random
floats whose vertex arms include parallel, opposite, one-armed and near-threshold pairs."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.geometry import StaticGeometry, build_static_geometry
from sonar_gym.scenario import builtin_names
from sonar_gym.sonar.echo_tables import _build
from sonar_gym.sonar.echoes import _CYLINDER, _EDGE, _PLANE
from sonar_gym.sonar.table_kernels import WEDGE_CROSS_TOLERANCE
from tests.random_static_scenarios import builtin_with_obstacles, random_scenario
from tests.sonar.echo_tables_maps_reference import reference_linear_maps


def _assert_same_maps(geometry: StaticGeometry) -> None:
    tables = _build(geometry, _PLANE, _CYLINDER, _EDGE)
    position_map, occlusion_map, order, n_wedges = reference_linear_maps(geometry)
    for got, want in ((tables.position_map, position_map), (tables.occlusion_map, occlusion_map)):
        assert got.dtype == want.dtype and got.shape == want.shape
        assert got.tobytes() == want.tobytes()
    assert tables.n_wedges == n_wedges
    assert tables.n_vertices == len(order)
    # the wedge vertices' order shows in the twins' rows and the candidates' points
    rel_points = tables.position_map[tables.rel_rows].reshape(-1, 3, 3)[:, :2, 2]
    np.testing.assert_array_equal(
        rel_points[geometry.n_segments + geometry.n_circles :], geometry.vertices[order]
    )


@pytest.mark.parametrize("seed", range(3))
def test_the_maps_equal_the_array_form_on_random_scenarios(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(60):
        _assert_same_maps(build_static_geometry(random_scenario(rng)))


@pytest.mark.parametrize("name", builtin_names())
def test_the_maps_equal_the_array_form_on_the_builtin_scenarios(name: str) -> None:
    for each in builtin_with_obstacles(name, seed=1):
        _assert_same_maps(build_static_geometry(each))


def _random_arms(rng: np.random.Generator, count: int) -> np.ndarray:
    """``(count, 2, 2)`` unit arms: random pairs, and pairs parallel, opposite, one-armed
    (a zero second arm) or at a cross product a hair from the wedge threshold."""
    first = rng.uniform(-np.pi, np.pi, count)
    kind = rng.integers(5, size=count)
    turn = rng.uniform(-np.pi, np.pi, count)
    turn[kind == 1] = 0.0
    turn[kind == 2] = np.pi
    turn[kind == 3] = WEDGE_CROSS_TOLERANCE * rng.choice([0.5, 1.0, 1.5, -1.0], (kind == 3).sum())
    arms = np.stack(
        [
            np.column_stack([np.cos(first), np.sin(first)]),
            np.column_stack([np.cos(first + turn), np.sin(first + turn)]),
        ],
        axis=1,
    )
    arms[kind == 4, 1] = 0.0
    return arms


@pytest.mark.parametrize("seed", range(4))
def test_the_maps_equal_the_array_form_on_random_floats(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(40):
        n_segments, n_circles, n_vertices = rng.integers(0, 12, size=3)
        scale = 10.0 ** rng.uniform(-3, 3)
        starts = rng.normal(0.0, scale, (n_segments, 2))
        ends = starts + rng.normal(0.0, scale, (n_segments, 2))
        circles = np.column_stack(
            [rng.normal(0.0, scale, (n_circles, 2)), rng.uniform(0.01, 1.0, n_circles)]
        )
        geometry = StaticGeometry(
            segment_starts=starts,
            segment_ends=ends,
            segment_mapped=np.ones(n_segments, dtype=bool),
            circles=circles.reshape(-1, 3),
            circle_mapped=np.ones(n_circles, dtype=bool),
            vertices=rng.normal(0.0, scale, (n_vertices, 2)),
            vertex_arms=_random_arms(rng, n_vertices).reshape(-1, 2, 2),
        )
        _assert_same_maps(geometry)
