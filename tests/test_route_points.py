"""Route points in floats are the NumPy interpolation along the polyline, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.localization.kim import TABLE_1_TRUE_POSITIONS_M
from sonar_gym.polyline import Route, leg_is_free


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


@pytest.mark.parametrize(
    "points",
    [TABLE_1_TRUE_POSITIONS_M, np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [1.3, -0.7]])],
    ids=["table1", "repeated_vertex"],
)
def test_targets_between_are_the_vertices_strictly_inside_then_the_stop(
    points: np.ndarray,
) -> None:
    route = Route.through(points)
    stations = [*np.linspace(-0.5, route.length_m + 0.5, 41).tolist(), *route.cumulative_m]
    inside = 0
    for start in stations:
        for stop in stations:
            between = (route.cumulative_m > start) & (route.cumulative_m < stop)
            expected = [*route.vertices[between], _reference_point(route, float(stop))]
            targets = route.targets_between(float(start), float(stop))
            assert np.array(targets).tobytes() == np.array(expected).tobytes()
            inside += len(targets) - 1
    assert inside > 0


class _RecordingWorld:
    """A world whose every point is free; it records the points a leg check asks about."""

    robot_radius = 0.25

    def __init__(self, blocked_after: int | None = None) -> None:
        self.asked: list[tuple[float, float]] = []
        self.blocked_after = blocked_after

    def is_free(self, position_xy: tuple[float, float], radius: float) -> bool:
        x, y = position_xy
        self.asked.append((float(x), float(y)))
        return self.blocked_after is None or len(self.asked) <= self.blocked_after


@pytest.mark.parametrize("step_m", [0.02, 0.1, 0.37])
def test_a_leg_check_asks_about_the_numpy_points_in_order(step_m: float) -> None:
    rng = np.random.default_rng(6)
    for _ in range(200):
        start, stop = rng.uniform(-3.0, 3.0, 2), rng.uniform(-3.0, 3.0, 2)
        world = _RecordingWorld()
        assert leg_is_free(world, start, stop, 0.1, step_m)  # type: ignore[arg-type]
        count = max(2, int(np.ceil(float(np.linalg.norm(stop - start)) / step_m)) + 1)
        expected = start + np.linspace(0.0, 1.0, count)[:, None] * (stop - start)
        assert np.array(world.asked).tobytes() == expected.tobytes()


def test_a_leg_check_stops_at_the_first_point_that_is_not_free() -> None:
    world = _RecordingWorld(blocked_after=3)
    assert not leg_is_free(world, np.zeros(2), np.array([1.0, 0.0]), 0.1)  # type: ignore[arg-type]
    assert len(world.asked) == 4
