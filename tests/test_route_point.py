"""``Route.xy_at`` clipped with comparisons has exactly the bits of the ``min``/``max`` form it
replaced, at and between the vertices, beyond both ends, at signed zeros and NaN, on routes
with repeated vertices."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization.kim import TABLE_1_TRUE_POSITIONS_M
from sonar_gym.polyline import Route
from tests.route_point_reference import xy_at_reference

_ROUTES = {
    "table1": Route.through(TABLE_1_TRUE_POSITIONS_M),
    "repeated": Route.through(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [1.0, 2.5]])),
    "single_leg": Route.through(np.array([[0.3, -0.2], [-0.7, 0.9]])),
}


def _stations(route: Route) -> list[float]:
    length = route.length_m
    rng = np.random.default_rng(3)
    vertices = route.cumulative_m.tolist()
    return [
        0.0, -0.0, -1e-300, 1e-300, -2.0, length, length + 1e-12, 3.0 * length, math.nan,
        math.inf, -math.inf, *vertices, *[np.nextafter(v, -1.0) for v in vertices],
        *[float(np.nextafter(v, 99.0)) for v in vertices], *rng.uniform(-0.5, length + 0.5, 40),
    ]  # fmt: skip


@pytest.mark.parametrize("name", sorted(_ROUTES))
def test_the_point_has_the_bits_of_the_min_max_form(name: str) -> None:
    route = _ROUTES[name]
    for s in _stations(route):
        got, expected = route.xy_at(s), xy_at_reference(route, s)
        assert np.array(got).tobytes() == np.array(expected).tobytes(), (s, got, expected)
        assert [type(value) for value in got] == [type(value) for value in expected]
