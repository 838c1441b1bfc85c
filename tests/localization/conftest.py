"""Fixtures shared by the localization tests."""

from __future__ import annotations

import pytest

from sonar_gym.localization.kim import OccupancyGrid
from tests.localization.test_kim import ARENA_BOUNDS, ARENA_CIRCLES, ARENA_SEGMENTS, CELL


@pytest.fixture(scope="module")
def arena_grid() -> OccupancyGrid:
    """Kim's test arena (a 2 m box with a block and two posts) as an occupancy grid of
    ``CELL`` (5 cm) cells, built once per test module."""
    return OccupancyGrid.from_segments(ARENA_SEGMENTS, ARENA_CIRCLES, ARENA_BOUNDS, CELL)
