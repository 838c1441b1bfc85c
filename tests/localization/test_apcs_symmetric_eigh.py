""":func:`symmetric_eigh` gives exactly the bits of ``np.linalg.eigh``, which it stands in for in
the line fit of an ERP group (Yamamoto et al. sec. 4.2.2), and the fit's compiled centroid
gives numpy's bits."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.localization import apcs_kernels
from sonar_gym.localization.apcs_walls import symmetric_eigh


def _scatters(rng: np.random.Generator) -> list[np.ndarray]:
    """Scatter matrices of ERP groups as the fit builds them, and degenerate ones."""
    scatters = []
    for count in range(2, 12):
        for _ in range(200):
            points = rng.normal(size=(count, 2)) * rng.choice([1e-4, 1e-2, 1.0, 10.0], size=2)
            centred = points - np.add.reduce(points, axis=0) / count
            scatters.append(centred.T @ centred / count)
    scatters += [
        np.zeros((2, 2)),
        np.eye(2),
        np.diag([3.0, 3.0]),
        np.array([[1.0, 1.0], [1.0, 1.0]]),
    ]
    return scatters


def test_symmetric_eigh_has_the_bits_of_numpy_eigh() -> None:
    for scatter in _scatters(np.random.default_rng(17)):
        values, vectors = np.linalg.eigh(scatter)
        got_values, got_vectors = symmetric_eigh(scatter)
        assert np.array(got_values).tobytes() == values.tobytes()
        assert got_vectors.tobytes() == vectors.tobytes()
        assert got_vectors.dtype == vectors.dtype and got_vectors.shape == (2, 2)


def test_symmetric_eigh_of_a_non_finite_matrix_is_numpy_eigh_of_it() -> None:
    for scatter in (np.array([[np.nan, 0.0], [0.0, 1.0]]), np.full((2, 2), np.inf)):
        try:
            values, vectors = np.linalg.eigh(scatter)
        except np.linalg.LinAlgError:
            with pytest.raises(np.linalg.LinAlgError):
                symmetric_eigh(scatter)
            continue
        got_values, got_vectors = symmetric_eigh(scatter)
        assert np.array(got_values).tobytes() == values.tobytes()
        assert got_vectors.tobytes() == vectors.tobytes()


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
