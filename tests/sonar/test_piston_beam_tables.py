"""The beam tables built on the samples in front as a prefix are the masked-array form's bits."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.sonar.acoustics import (
    FIRST_ZERO_OF_J1,
    TABLE_STEPS_PER_UNIT,
    PistonBeam,
    _table_grid,
)
from tests.sonar.piston_beam_reference import reference_beam_tables


def _wavenumbers(seed: int) -> list[float]:
    """The Polaroid's range over 0-40 deg C, wide beams without a null, and random ``k a``."""
    rng = np.random.default_rng(seed)
    return [
        FIRST_ZERO_OF_J1,
        np.nextafter(FIRST_ZERO_OF_J1, 0.0),
        0.3,
        2.0,
        17.6,
        *rng.uniform(16.5, 18.5, 40),
        *rng.uniform(0.2, 60.0, 40),
    ]


def test_table_grid_is_front_first_and_angles_never_fall() -> None:
    front, theta, sin_front = _table_grid()
    assert front[: TABLE_STEPS_PER_UNIT + 1].all() and not front[TABLE_STEPS_PER_UNIT + 1 :].any()
    assert len(sin_front) == TABLE_STEPS_PER_UNIT + 1
    assert (np.diff(theta) >= 0.0).all()
    assert (np.diff(sin_front) >= 0.0).all()


@pytest.mark.parametrize("side_lobes", [False, True])
@pytest.mark.parametrize("leakage", [0.0, 0.01, 0.07, 0.3, 1.0])
def test_beam_tables_match_the_masked_array_form_bit_for_bit(
    side_lobes: bool, leakage: float
) -> None:
    for ka in _wavenumbers(int(leakage * 100) + side_lobes):
        beam = PistonBeam.for_ka.__wrapped__(float(ka), side_lobes, leakage)
        cells, rising, reaches_back, main_lobe_cells = reference_beam_tables(
            float(ka), side_lobes, leakage
        )
        for got, want in [
            (beam.cells, cells),
            (beam.main_lobe_rising, rising),
            (beam.main_lobe_cells, main_lobe_cells),
        ]:
            assert got.dtype == want.dtype
            assert got.shape == want.shape
            assert got.tobytes() == want.tobytes()
        assert beam.reaches_back is reaches_back
