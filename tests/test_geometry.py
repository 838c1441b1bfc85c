"""StaticGeometry: the flat arrays the sonar reads."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.geometry import build_static_geometry
from sonar_gym.scenario import load_scenario, scenario_from_dict

ROOM = {"room": {"min": [0.0, 0.0], "max": [4.0, 3.0]}}


def vertices_at(geometry, point):
    return np.flatnonzero(np.linalg.norm(geometry.vertices - np.asarray(point), axis=1) < 1e-9)


def test_segment_and_circle_counts() -> None:
    scenario = scenario_from_dict(
        {
            **ROOM,
            "walls": [{"a": [1.0, 1.0], "b": [2.0, 1.0]}],
            "boxes": [
                {"center": [3.0, 2.0], "size": [0.4, 0.4]},
                {"center": [1.0, 2.0], "size": [0.2, 0.6], "angle_deg": 20},
            ],
            "cylinders": [{"center": [0.5, 0.5], "radius": 0.1}],
        }
    )
    geometry = build_static_geometry(scenario)
    assert geometry.n_segments == 4 + 1 + 2 * 4
    assert geometry.n_circles == 1
    assert geometry.segments.shape == (13, 2, 2)
    np.testing.assert_array_equal(geometry.circles, [[0.5, 0.5, 0.1]])
    # 4 room corners + 2 free wall ends + 8 box corners
    assert len(geometry.vertices) == 14


def test_room_corners_are_concave_from_inside() -> None:
    geometry = build_static_geometry(scenario_from_dict(ROOM))
    assert len(geometry.vertices) == 4
    for point in ([2.0, 1.5], [0.1, 0.1], [3.9, 2.9]):
        assert geometry.is_concave_from(np.array(point)).all()
    # Seen from outside, beyond its diagonal, a corner is a convex edge.
    top_right = vertices_at(geometry, [4.0, 3.0])
    assert not geometry.is_concave_from(np.array([5.0, 4.0]))[top_right].any()
    # Seen along a wall's line it is not a retro-reflector either.
    assert not geometry.is_concave_from(np.array([2.0, 0.0]))[
        vertices_at(geometry, [0.0, 0.0])
    ].any()


def test_box_corners_are_always_edges() -> None:
    scenario = scenario_from_dict(
        {"boxes": [{"center": [0.0, 0.0], "size": [1.0, 0.5], "angle_deg": 35.0}]}
    )
    geometry = build_static_geometry(scenario)
    for point in ([2.0, 0.0], [0.0, 2.0], [-2.0, -2.0], [0.7, 0.6], [0.0, 0.0]):
        assert not geometry.is_concave_from(np.array(point)).any()


def test_free_wall_ends_are_edges() -> None:
    geometry = build_static_geometry(scenario_from_dict({"walls": [{"a": [0, 0], "b": [1, 0]}]}))
    assert len(geometry.vertices) == 2
    for point in ([0.5, 1.0], [0.5, -1.0], [-1.0, 0.0]):
        assert not geometry.is_concave_from(np.array(point)).any()


def test_t_junction_gives_a_concave_corner_on_each_side() -> None:
    # A partition from the middle of the bottom wall up to y = 1.
    scenario = scenario_from_dict({**ROOM, "walls": [{"a": [2.0, 0.0], "b": [2.0, 1.0]}]})
    geometry = build_static_geometry(scenario)
    junction = vertices_at(geometry, [2.0, 0.0])
    assert len(junction) == 2
    left = geometry.is_concave_from(np.array([1.0, 0.5]))[junction]
    right = geometry.is_concave_from(np.array([3.0, 0.5]))[junction]
    assert left.sum() == 1 and right.sum() == 1
    assert not (left & right).any()
    # A point straight above lies on the partition's line, inside neither wedge.
    above = geometry.is_concave_from(np.array([2.0, 2.0]))[junction]
    assert not above.any()
    free_end = vertices_at(geometry, [2.0, 1.0])
    assert len(free_end) == 1
    assert not geometry.is_concave_from(np.array([1.0, 2.0]))[free_end].any()


def test_l_shaped_walls_make_one_corner_with_two_arms() -> None:
    scenario = scenario_from_dict(
        {"walls": [{"a": [0, 1], "b": [0, 0]}, {"a": [0, 0], "b": [1, 0]}]}
    )
    geometry = build_static_geometry(scenario)
    corner = vertices_at(geometry, [0.0, 0.0])
    assert len(corner) == 1
    arms = geometry.vertex_arms[corner[0]]
    assert {tuple(np.round(a, 12)) for a in arms} == {(0.0, 1.0), (1.0, 0.0)}
    assert geometry.is_concave_from(np.array([0.5, 0.5]))[corner[0]]
    assert not geometry.is_concave_from(np.array([-0.5, -0.5]))[corner[0]]


def test_unmapped_flags_follow_the_scenario() -> None:
    corridor = load_scenario("apcs_corridor")
    geometry = build_static_geometry(corridor)
    assert geometry.segment_mapped.sum() == geometry.n_segments - 1
    unmapped = np.flatnonzero(~geometry.segment_mapped)[0]
    np.testing.assert_allclose(geometry.segment_starts[unmapped], [3.8, 0.7])
    np.testing.assert_allclose(geometry.segment_ends[unmapped], [4.7, 0.7])


def test_pillar_corners_are_edges_and_its_roots_concave() -> None:
    corridor = load_scenario("apcs_corridor")
    geometry = build_static_geometry(corridor)
    robot = np.array([2.2, 0.0])
    concave = geometry.is_concave_from(robot)
    for root in ([2.0, 1.0], [2.4, 1.0]):
        assert concave[vertices_at(geometry, root)].sum() == 1
    for tip in ([2.0, 0.85], [2.4, 0.85]):
        assert not concave[vertices_at(geometry, tip)].any()


@pytest.mark.parametrize("name", ["beom_cho_lab", "kim_arena", "apcs_corridor"])
def test_arms_are_unit_vectors(name: str) -> None:
    geometry = build_static_geometry(load_scenario(name))
    np.testing.assert_allclose(np.linalg.norm(geometry.vertex_arms, axis=2), 1.0, rtol=1e-12)


def test_box_corner_against_a_wall_is_a_concave_dihedral_not_an_edge() -> None:
    scenario = scenario_from_dict(
        {
            "room": {"min": [-3, -2], "max": [3, 2]},
            "boxes": [{"center": [0, 1.7], "size": [1.0, 0.6]}],
        }
    )
    geometry = build_static_geometry(scenario)
    flush_right = int(np.flatnonzero(np.all(np.isclose(geometry.vertices, [0.5, 2.0]), axis=1))[-1])
    free_right = int(np.flatnonzero(np.all(np.isclose(geometry.vertices, [0.5, 1.4]), axis=1))[0])
    beside_the_table = np.array([0.7, 1.5])
    assert geometry.is_concave_from(beside_the_table)[flush_right]
    assert not geometry.is_concave_from(np.array([0.0, 0.0]))[flush_right]  # behind the table face
    assert not geometry.is_concave_from(beside_the_table)[free_right]
