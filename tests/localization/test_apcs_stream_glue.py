"""The APCS stream's glue gives exactly the bits of the forms it replaced: the ERPs with each
reading's sine and cosine taken once (through the tables of
:func:`~sonar_gym.localization.apcs_walls.newest_reflection_table`), and the sensor positions
without ``np.column_stack``."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.localization.apcs import DEFAULT_PARAMETERS
from sonar_gym.localization.apcs_online import _sensor_positions
from sonar_gym.localization.apcs_walls import newest_reflection_rows
from tests.localization.apcs_glue_reference import chosen_roots_sliced, sensor_positions_stacked
from tests.localization.apcs_row_kernels_reference import newest_rows
from tests.localization.side_readings import wobbly_side_readings


def _readings(rng: np.random.Generator, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wobbly side readings whose directions are turned by whole turns, many of them."""
    positions, directions, ranges = wobbly_side_readings(rng, count, heading_std_rad=0.05)
    turns = 2.0 * np.pi * rng.integers(-3, 4, count)
    return positions, directions + turns, ranges


def test_reflection_rows_match_the_sliced_form() -> None:
    rng = np.random.default_rng(20261207)
    pairs_seen = 0
    for _ in range(400):
        positions, directions, ranges = _readings(rng, int(rng.integers(2, 70)))
        got = newest_reflection_rows(
            positions, directions, ranges, DEFAULT_PARAMETERS.sensing_range_m, 0
        )
        phi, pairs = chosen_roots_sliced(
            positions, directions, ranges, DEFAULT_PARAMETERS.sensing_range_m
        )
        expected = newest_rows(positions, ranges, phi, pairs, np.cos(phi), np.sin(phi), 0)
        for array, reference in zip(got, expected, strict=True):
            assert array.dtype == reference.dtype and array.shape == reference.shape
            assert array.tobytes() == reference.tobytes()
        pairs_seen += len(pairs)
    assert pairs_seen > 1000


@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("offset_m", [0.0, 0.12, -0.05])
def test_sensor_positions_match_the_stacked_form(side: str, offset_m: float) -> None:
    rng = np.random.default_rng(7)
    for count in (0, 1, 2, 5, 33):
        poses = np.column_stack(
            [rng.uniform(-20.0, 20.0, (count, 2)), rng.uniform(-10.0, 10.0, count)]
        )
        got = _sensor_positions(poses, side, offset_m)
        expected = sensor_positions_stacked(poses, side, offset_m)
        assert got.shape == expected.shape == (count, 2)
        assert got.tobytes() == expected.tobytes()


def test_numpy_sine_and_cosine_of_a_slice_are_the_slice_of_theirs() -> None:
    """What the pair geometry relies on: numpy's sine and cosine of each reading do not
    depend on the readings around it (on SIMD builds too: a vector's tail rounds as its body)."""
    rng = np.random.default_rng(11)
    for count in [*range(2, 80), 257]:
        directions = rng.uniform(-25.0, 25.0, count)
        for function in (np.sin, np.cos):
            whole = function(directions)
            assert whole[:-1].tobytes() == function(directions[:-1]).tobytes()
            assert whole[1:].tobytes() == function(directions[1:]).tobytes()
