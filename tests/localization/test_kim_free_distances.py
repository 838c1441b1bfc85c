"""Kim's unobstructed-ray table (sec. 3.3) traced in one compiled loop against the numpy form
it replaced (``kim_free_distance_reference``), bit for bit: the arena of the Kim tests, random
occupancy grids with off-origin corners and odd cell sizes, clearances from zero to several
cells, and direction counts that put rays exactly along the axes and diagonals."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.localization import kim
from sonar_gym.localization.kim import OccupancyGrid
from tests.localization.kim_free_distance_reference import reference_trace
from tests.localization.test_kim import ARENA_BOUNDS, ARENA_CIRCLES, ARENA_SEGMENTS


def _assert_table_is_reference(
    grid: OccupancyGrid, direction_bins: int, clearance_m: float
) -> None:
    table = kim._FreeDistanceTable(grid, direction_bins, clearance_m)
    directions = np.arange(direction_bins)
    expected = reference_trace(table, directions)
    distance = table.columns(directions)
    assert table.complete
    assert distance.shape == expected.shape
    assert distance.tobytes() == np.asfortranarray(expected).tobytes()


@pytest.mark.parametrize("direction_bins", [8, 90, 360, 361])
@pytest.mark.parametrize("clearance_cells", [0.0, 1.0, 2.5])
def test_arena_table_is_the_array_form(direction_bins: int, clearance_cells: float) -> None:
    grid = OccupancyGrid.from_segments(ARENA_SEGMENTS, ARENA_CIRCLES, ARENA_BOUNDS, 0.05)
    _assert_table_is_reference(grid, direction_bins, clearance_cells * grid.cell_size_m)


@pytest.mark.parametrize("seed", range(12))
def test_random_grid_tables_are_the_array_form(seed: int) -> None:
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(1, 30)), int(rng.integers(1, 30)))
    occupied = rng.random(shape) < rng.uniform(0.02, 0.4)
    occupied[rng.integers(shape[0]), rng.integers(shape[1])] = True
    grid = OccupancyGrid(
        origin_m=(float(rng.uniform(-3.0, 3.0)), float(rng.uniform(-3.0, 3.0))),
        cell_size_m=float(rng.choice([0.05, 0.1, 0.037, 0.3])),
        occupied=occupied,
    )
    bins = int(rng.choice([8, 16, 360, 1000]))
    _assert_table_is_reference(grid, bins, float(rng.uniform(0.0, 3.0)) * grid.cell_size_m)


def test_rows_filled_on_demand_are_the_array_form() -> None:
    grid = OccupancyGrid.from_segments(ARENA_SEGMENTS, ARENA_CIRCLES, ARENA_BOUNDS, 0.05)
    table = kim._FreeDistanceTable(grid, 360, grid.cell_size_m)
    first, second = np.array([5, 5, 90, 359]), np.array([90, 4, 180])
    table.columns(first)
    distance = table.columns(second)
    rows = np.unique(np.concatenate([first, second]))
    assert not table.complete
    assert np.array_equal(table.filled, np.isin(np.arange(360), rows))
    expected = reference_trace(table, rows)
    assert distance[rows].tobytes() == expected.tobytes()
