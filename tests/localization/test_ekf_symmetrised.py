"""The EKF's symmetrisation, halving the sum in place, gives the bits of ``0.5 * (P + P^T)``
(:func:`tests.localization.ekf_update_reference.symmetrised_reference`), the layout too."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.localization.ekf import _symmetrised
from tests.localization.ekf_update_reference import symmetrised_reference

_ODD_VALUES = (0.0, -0.0, 5e-324, -2.2e-308, 1e308, -1e308, np.inf, -np.inf, np.nan, 1.0 / 3.0)


@pytest.mark.parametrize("seed", range(20))
def test_in_place_halving_gives_the_bits_of_the_product_form(seed: int) -> None:
    rng = np.random.default_rng(seed)
    matrix = rng.normal(0.0, 10.0 ** rng.uniform(-12, 3), (3, 3))
    odd = rng.random((3, 3)) < 0.3
    matrix[odd] = rng.choice(_ODD_VALUES, int(odd.sum()))
    for layout in (matrix, np.asfortranarray(matrix), matrix.T):
        before = layout.copy()
        with np.errstate(over="ignore", invalid="ignore"):
            got, want = _symmetrised(layout), symmetrised_reference(layout)
        assert got.dtype == want.dtype and got.shape == want.shape
        assert got.flags.c_contiguous == want.flags.c_contiguous
        assert got.tobytes() == want.tobytes()
        assert layout.tobytes() == before.tobytes()  # the argument is left alone
