"""Route.point_at in floats is the NumPy interpolation along the polyline, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.localization.kim import TABLE_1_TRUE_POSITIONS_M
from sonar_gym.polyline import Route


def _reference_point(route: Route, s_m: float) -> np.ndarray:
    s = min(max(s_m, 0.0), route.length_m)
    index = int(np.searchsorted(route.cumulative_m, s, side="right")) - 1
    index = min(max(index, 0), len(route.vertices) - 2)
    span = route.cumulative_m[index + 1] - route.cumulative_m[index]
    fraction = 0.0 if span <= 0.0 else (s - route.cumulative_m[index]) / span
    return route.vertices[index] + fraction * (route.vertices[index + 1] - route.vertices[index])


@pytest.mark.parametrize(
    "points",
    [TABLE_1_TRUE_POSITIONS_M, np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [1.3, -0.7]])],
    ids=["table1", "repeated_vertex"],
)
def test_point_at_matches_the_numpy_interpolation(points: np.ndarray) -> None:
    route = Route.through(points)
    stations = [*np.linspace(-0.5, route.length_m + 0.5, 301).tolist(), *route.cumulative_m]
    for s in stations:
        point = route.point_at(float(s))
        assert point.dtype == np.float64 and point.shape == (2,)
        assert np.array_equal(point, _reference_point(route, float(s)))
