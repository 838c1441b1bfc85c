"""TruePath: one true path prepared once scores many localized paths as the reference does."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.localization.roh import TruePath, parabolic_path, path_errors
from sonar_gym.localization.roh_path_errors import distances_to_polyline_reference


def _reference_errors(points: np.ndarray, path: np.ndarray) -> tuple[float, float]:
    """sigma from linear interpolation in x and sigma' from the every-segment search."""
    order = np.argsort(path[:, 0])
    y_true = np.interp(points[:, 0], path[order, 0], path[order, 1])
    sigma = float(np.sqrt(np.mean((points[:, 1] - y_true) ** 2)))
    return sigma, float(np.mean(distances_to_polyline_reference(points, path)))


@pytest.mark.parametrize("decreasing", [False, True])
def test_one_true_path_scores_many_point_sets_like_the_reference(decreasing: bool) -> None:
    path = parabolic_path(x_end_m=1.3)
    if not decreasing:
        path = path[::-1].copy()
    true_path = TruePath(path)
    rng = np.random.default_rng(5)
    # Near points (narrow windows only), far ones (the general search) and mixtures, in an
    # order that builds the general search's blocks midway and then reuses them.
    for noise in (1e-3, 2.0, 1e-2, 0.5, 1e-4, 3.0):
        inside = path[rng.integers(1, len(path) - 1, 150)]
        points = inside + rng.normal(0.0, noise, inside.shape)
        points[:, 0] = np.clip(points[:, 0], path[:, 0].min(), path[:, 0].max())
        sigma, sigma_prime = true_path.errors(points)
        expected_sigma, expected_prime = _reference_errors(points, path)
        assert sigma == pytest.approx(expected_sigma, rel=1e-12)
        assert sigma_prime == pytest.approx(expected_prime, rel=1e-12, abs=1e-15)
        assert (sigma, sigma_prime) == path_errors(points, path)


def test_true_path_rejects_a_path_that_is_not_a_function_of_x() -> None:
    with pytest.raises(ValueError, match="strictly monotonic"):
        TruePath(np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]]))
    with pytest.raises(ValueError, match="estimated"):
        TruePath(np.array([[0.0, 0.0], [1.0, 0.0]])).errors(np.array([[np.nan, 0.0]]))
