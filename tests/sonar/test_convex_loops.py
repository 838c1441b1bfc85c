""":func:`~sonar_gym.sonar.echo_tables.convex_loops` equals its reference bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.geometry import build_static_geometry
from sonar_gym.scenario import Box, Cylinder, Room, Scenario, Wall, builtin_names
from sonar_gym.sonar.echo_tables import (
    LOOP_TOLERANCE_M,
    _closer_than,
    _pairwise_distances,
    convex_loops,
)
from sonar_gym.sonar.loop_kernels import closer_than
from tests.random_static_scenarios import builtin_with_obstacles, random_scenario
from tests.sonar.convex_loops_arrays_reference import reference_array_convex_loops
from tests.sonar.convex_loops_reference import reference_convex_loops


def _assert_same_loops(scenario_name: str, geometry_args: tuple[np.ndarray, ...]) -> None:
    solid_side, encloses = convex_loops(*geometry_args)
    for reference in (reference_convex_loops, reference_array_convex_loops):
        expected_side, expected_encloses = reference(*geometry_args)
        assert solid_side.dtype == expected_side.dtype, scenario_name
        assert solid_side.tobytes() == expected_side.tobytes(), scenario_name
        assert encloses.dtype == expected_encloses.dtype, scenario_name
        assert np.array_equal(encloses, expected_encloses), scenario_name


@pytest.mark.parametrize("seed", range(4))
def test_convex_loops_equal_the_reference_on_random_scenarios(seed: int) -> None:
    rng = np.random.default_rng(seed)
    solid = 0
    for _ in range(100):
        geometry = build_static_geometry(random_scenario(rng))
        args = (geometry.segment_starts, geometry.segment_ends, geometry.circles[:, :2])
        _assert_same_loops("random", args)
        solid += int(np.count_nonzero(convex_loops(*args)[0]))
    assert solid > 0, "the cases must hold closed loops"


@pytest.mark.parametrize("name", builtin_names())
def test_convex_loops_equal_the_reference_on_the_builtin_scenarios(name: str) -> None:
    for each in builtin_with_obstacles(name, seed=0):
        geometry = build_static_geometry(each)
        args = (geometry.segment_starts, geometry.segment_ends, geometry.circles[:, :2])
        _assert_same_loops(name, args)


def test_convex_loops_of_nothing_are_empty() -> None:
    empty = np.zeros((0, 2))
    _assert_same_loops("empty", (empty, empty, empty))


def _chain(*points: tuple[float, float]) -> list[Wall]:
    return [Wall(a, b) for a, b in zip(points[:-1], points[1:], strict=True)]


@pytest.mark.parametrize(
    "walls",
    [
        _chain((0.0, 0.0), (1.0, 0.0), (0.5, 1.0), (0.0, 0.0)),  # a triangle, counter-clockwise
        _chain((0.0, 0.0), (0.5, 1.0), (1.0, 0.0), (0.0, 0.0)),  # and clockwise
        _chain((0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 0.5), (0.0, 1.0), (0.0, 0.0)),  # concave
        _chain((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.5, 1.5), (0.0, 1.0), (1.0, 0.0)),  # rho
        _chain((0.0, 0.0), (1.0, 0.0), (1.0, 1.0)),  # open
    ],
)
def test_convex_loops_equal_the_reference_on_closed_chains_of_free_walls(
    walls: list[Wall],
) -> None:
    for room in (None, Room((-3.0, -3.0), (3.0, 3.0))):
        scenario = Scenario(
            "chains",
            room,
            tuple(walls),
            (Box((-2.0, -2.0), (0.5, 0.5)),),
            (Cylinder((2.0, 2.0), 0.1),),
        )
        geometry = build_static_geometry(scenario)
        args = (geometry.segment_starts, geometry.segment_ends, geometry.circles[:, :2])
        _assert_same_loops("chains", args)


@pytest.mark.parametrize("seed", range(3))
def test_convex_loops_equal_the_references_on_forked_and_touching_chains(seed: int) -> None:
    """Chains whose ends meet several starts (forks: no successor), loops that a walk enters
    from outside, and loops a point of the geometry touches from outside (on a side's line,
    outside the loop)."""
    rng = np.random.default_rng(seed)
    corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (2.0, 0.0), (2.0, 1.0), (0.5, 2.0)]
    for _ in range(150):
        picks = rng.integers(len(corners), size=int(rng.integers(3, 12)))
        walls = [
            Wall(corners[a], corners[b])
            for a, b in zip(picks[:-1], picks[1:], strict=True)
            if a != b
        ]
        if rng.random() < 0.5:  # a square loop, sometimes with a fork at a corner
            walls += _chain((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.0, 0.0))
        room = Room((-3.0, -3.0), (3.0, 3.0)) if rng.random() < 0.5 else None
        geometry = build_static_geometry(Scenario("forks", room, tuple(walls)))
        args = (geometry.segment_starts, geometry.segment_ends, geometry.circles[:, :2])
        _assert_same_loops("forks", args)


def test_points_closer_than_the_tolerance_are_those_numpys_hypot_finds() -> None:
    """The compiled test, with numpy for the pairs it leaves, against ``hypot < tolerance``:
    offsets around half the tolerance and the tolerance, signed zeros, infinities, NaNs."""
    rng = np.random.default_rng(6)
    offsets = np.array([0.0, -0.0, 1e-16, 0.3e-9, 0.5e-9, 0.7e-9, 0.9e-9, 1e-9, 1.2e-9, np.inf])
    undecided = 0
    for _ in range(2000):
        base = rng.choice(
            [0.0, -0.0, 1.0, -2.5, 1e6, np.nan, np.inf], size=(int(rng.integers(5)), 2)
        )
        with np.errstate(invalid="ignore"):  # inf - inf, in numpy's path as here
            shift = rng.choice(offsets, size=base.shape) * rng.choice([-1.0, 1.0], size=base.shape)
            to_points = (base + shift)[rng.permutation(len(base))]
            expected = _pairwise_distances(base, to_points) < LOOP_TOLERANCE_M
            closer = _closer_than(base, to_points, LOOP_TOLERANCE_M)
        assert np.array_equal(closer, expected)
        undecided += int(closer_than(base, to_points, LOOP_TOLERANCE_M)[1])
    assert undecided > 10  # the numpy path ran too
