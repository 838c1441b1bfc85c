"""The compiled centroid of the line fit of an ERP group (Yamamoto et al. sec. 4.2.2) gives
numpy's bits."""

from __future__ import annotations

import numpy as np

from sonar_gym.localization import apcs_kernels


def test_centred_group_is_numpys_centroid_and_difference_bit_for_bit() -> None:
    rng = np.random.default_rng(5)
    for count in range(1, 41):
        for _ in range(300):
            scale = 10.0 ** rng.integers(-8, 8, size=(count, 1))
            members = rng.normal(size=(count, 2)) * scale
            if rng.random() < 0.1:
                members[:, rng.integers(2)] = -0.0  # signed zeros
            centroid = np.add.reduce(members, axis=0) / len(members)
            centred, centroid_x, centroid_y = apcs_kernels.centred_group(members)
            assert np.array([centroid_x, centroid_y]).tobytes() == centroid.tobytes()
            assert centred.tobytes() == (members - centroid).tobytes()
