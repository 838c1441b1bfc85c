"""A world's static shapes and their table, made from the scenario's geometry, equal the shapes
made straight from the scenario (:mod:`tests.world_shapes_reference`) and the table read back
from pymunk (:meth:`StaticShapeTable.of`), bit for bit."""

from __future__ import annotations

import numpy as np
import pymunk
import pytest

from sonar_gym.geometry import build_static_geometry
from sonar_gym.path_clearance import StaticShapeTable
from sonar_gym.world import World, _ConvexPolygons
from tests.outline_table_reference import reference_of_outlines
from tests.random_static_scenarios import random_scenario
from tests.world_shapes_reference import reference_static_shapes


def _same_bits(left: np.ndarray, right: np.ndarray) -> bool:
    """Equal shape, dtype and bytes (so ``-0.0`` and ``0.0`` differ)."""
    return (
        left.shape == right.shape
        and left.dtype == right.dtype
        and (left.tobytes() == right.tobytes())
    )


def _shape_state(shape: pymunk.Shape) -> tuple[object, ...]:
    """Everything of a static shape that collisions and queries read, as exact floats."""
    box = shape.bb
    common = (
        type(shape).__name__,
        shape.friction,
        shape.elasticity,
        shape.filter,
        shape.sensor,
        shape.collision_type,
        tuple(shape.surface_velocity),
        shape.body is not None and shape.body.body_type,
        (box.left, box.bottom, box.right, box.top),
    )
    if isinstance(shape, pymunk.Segment):
        detail: tuple[float, ...] = (*shape.a, *shape.b, shape.radius, *shape.normal)
    else:
        assert isinstance(shape, pymunk.Circle)
        detail = (*shape.offset, shape.radius)
    return (*common, np.array(detail, dtype=np.float64).tobytes())


@pytest.mark.parametrize("seed", range(4))
def test_the_table_of_the_outlines_equals_the_table_read_from_pymunk(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(100):
        scenario = random_scenario(rng)
        space = pymunk.Space()
        expected = StaticShapeTable.of(reference_static_shapes(space, scenario))
        geometry = build_static_geometry(scenario)
        table = StaticShapeTable.of_outlines(
            geometry.segment_starts, geometry.segment_ends, geometry.circles
        )
        for name in ("bounds", "kinds", "shapes"):
            assert _same_bits(getattr(table, name), getattr(expected, name)), (name, scenario)
            assert not getattr(table, name).flags.writeable


def test_the_table_of_no_outlines_is_empty() -> None:
    table = StaticShapeTable.of_outlines(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 3)))
    expected = StaticShapeTable.of([])
    for name in ("bounds", "kinds", "shapes"):
        assert _same_bits(getattr(table, name), getattr(expected, name))


@pytest.mark.parametrize("seed", range(3))
def test_a_worlds_shapes_and_box_polygons_equal_those_made_from_its_scenario(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    for _ in range(40):
        scenario = random_scenario(rng)
        world = World(scenario)
        space = pymunk.Space()
        expected = reference_static_shapes(space, scenario)
        assert [_shape_state(s) for s in world.static_shapes] == [
            _shape_state(s) for s in expected
        ], scenario
        # The same insertion order: the spatial index and the contact order depend on it.
        assert list(world.space.shapes)[: len(expected)] == list(world.static_shapes)
        corners = np.array([box.corners for box in scenario.boxes], dtype=np.float64)
        polygons = _ConvexPolygons(corners.reshape(-1, 4, 2))
        assert repr(world._box_polygons._polygons) == repr(polygons._polygons)
        table = StaticShapeTable.of(world.static_shapes)
        for name in ("bounds", "kinds", "shapes"):
            assert _same_bits(getattr(world.static_shape_table, name), getattr(table, name))


def test_the_table_of_the_outlines_equals_the_array_form_bit_for_bit() -> None:
    """Against the numpy form it replaced: scenarios' outlines, and raw outlines with signed
    zeros, infinities and NaNs."""
    rng = np.random.default_rng(12)
    cases = []
    for _ in range(200):
        geometry = build_static_geometry(random_scenario(rng))
        cases.append((geometry.segment_starts, geometry.segment_ends, geometry.circles))
    specials = np.array([0.0, -0.0, np.inf, -np.inf, np.nan, 1.5, -2.25, 1e-300])
    for _ in range(200):
        n_segments, n_circles = rng.integers(0, 6, size=2)
        values = rng.choice(specials, size=4 * n_segments + 3 * n_circles)
        values = np.where(rng.random(values.shape) < 0.5, values, rng.normal(size=values.shape))
        starts = values[: 2 * n_segments].reshape(-1, 2)
        ends = values[2 * n_segments : 4 * n_segments].reshape(-1, 2)
        cases.append((starts, ends, values[4 * n_segments :].reshape(-1, 3)))
    for starts, ends, circles in cases:
        table = StaticShapeTable.of_outlines(starts, ends, circles)
        with np.errstate(invalid="ignore"):  # inf - inf in the numpy form
            expected = reference_of_outlines(starts, ends, circles)
        for name in ("bounds", "kinds", "shapes"):
            assert _same_bits(getattr(table, name), getattr(expected, name)), name
            assert not getattr(table, name).flags.writeable
