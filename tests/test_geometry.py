"""StaticGeometry: the flat arrays the sonar reads."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from sonar_gym import geometry as geometry_module
from sonar_gym import geometry_kernels
from sonar_gym.geometry import build_static_geometry, static_geometry
from sonar_gym.random_room import random_scenario
from sonar_gym.scenario import Box, Scenario, builtin_names, load_scenario, scenario_from_dict
from sonar_gym.apcs_route import with_wall_obstacles
from tests.box_corner_arms_reference import (
    reference_box_corner_arms,
)
from tests.random_static_scenarios import random_scenario as random_static_scenario

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


# --- the k-d tree build against the direct, quadratic reference ------------------------------


def reference_corner_analysis(scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and arms by direct pairwise search (the definition, O(n^2))."""
    geometry = build_static_geometry(scenario)
    n_walls = geometry.n_segments - 4 * len(scenario.boxes)
    starts, ends = geometry.segment_starts[:n_walls], geometry.segment_ends[:n_walls]
    points: list[np.ndarray] = []
    arm_lists: list[list[np.ndarray]] = []
    for start, end in zip(starts, ends, strict=True):
        direction = (end - start) / np.linalg.norm(end - start)
        for point, arm in ((start, direction), (end, -direction)):
            for k, existing in enumerate(points):
                if np.linalg.norm(existing - point) < 1e-6:
                    arm_lists[k].append(arm)
                    break
            else:
                points.append(point.copy())
                arm_lists.append([arm])
    vertices: list[np.ndarray] = []
    arms: list[list[np.ndarray]] = []
    for point, point_arms in zip(points, arm_lists, strict=True):
        if len(point_arms) > 1:
            vertices.append(point)
            arms.append(point_arms[:2])
            continue
        host = None
        for start, end in zip(starts, ends, strict=True):
            span = end - start
            length = np.sqrt(span @ span)
            t = float((point - start) @ span) / (span @ span)
            if (
                1e-6 < t * length < length - 1e-6
                and np.linalg.norm(start + t * span - point) < 1e-6
            ):
                host = span / length
                break
        if host is None:
            vertices.append(point)
            arms.append([point_arms[0], point_arms[0]])
        else:
            for along in (host, -host):
                vertices.append(point)
                arms.append([point_arms[0], along])
    for box in scenario.boxes:
        corners = np.array(box.corners)
        for i, corner in enumerate(corners):
            to_next = corners[(i + 1) % 4] - corner
            to_previous = corners[(i - 1) % 4] - corner
            to_next /= np.linalg.norm(to_next)
            to_previous /= np.linalg.norm(to_previous)
            wall = None
            for start, end in zip(starts, ends, strict=True):
                span = end - start
                length = float(np.linalg.norm(span))
                t = float((corner - start) @ span) / length
                foot = start + span * t / length
                if -1e-3 <= t <= length + 1e-3 and np.linalg.norm(corner - foot) <= 1e-3:
                    wall = span / length
                    break
            vertices.append(corner)
            if wall is None:
                arms.append([to_next, to_next])
            elif abs(float(wall @ to_next)) > 0.99:
                arms.append([to_previous, -to_next])
            else:
                arms.append([to_next, -to_previous])
    return np.array(vertices).reshape(-1, 2), np.array(arms).reshape(-1, 2, 2)


def cluttered_walls(seed: int, n_walls: int) -> Scenario:
    """A room with short free walls, some chained end to end, some ending on the room walls,
    and boxes, some pushed against the walls."""
    rng = np.random.default_rng(seed)
    walls: list[dict[str, object]] = []
    for _ in range(n_walls):
        x, y = rng.uniform(-2.8, 2.8), rng.uniform(-1.8, 1.8)
        if rng.random() < 0.3 and walls:  # continue the previous wall
            x, y = walls[-1]["b"]  # type: ignore[misc]
        if rng.random() < 0.1:  # a stub from the bottom wall (a T-junction)
            x, y = round(float(x), 2), -2.0
        angle = rng.uniform(0.0, math.pi)
        length = rng.uniform(0.02, 0.3)
        walls.append(
            {"a": [x, y], "b": [x + length * math.cos(angle), y + length * math.sin(angle)]}
        )
    boxes = [
        {"center": [0.0, 1.7], "size": [1.0, 0.6]},
        {"center": [-2.5, 0.0], "size": [0.2, 0.4], "angle_deg": 30.0},
        {"center": [1.0, -1.0], "size": [0.3, 0.3]},
    ]
    return scenario_from_dict(
        {"room": {"min": [-3, -2], "max": [3, 2]}, "walls": walls, "boxes": boxes}
    )


@pytest.mark.parametrize(
    "scenario",
    [
        *(load_scenario(name) for name in builtin_names()),
        *(cluttered_walls(seed, 60) for seed in range(4)),
        *(random_scenario(np.random.default_rng(seed)) for seed in range(6)),
    ],
)
def test_fast_corner_analysis_equals_the_pairwise_reference(scenario: Scenario) -> None:
    geometry = build_static_geometry(scenario)
    vertices, arms = reference_corner_analysis(scenario)
    np.testing.assert_array_equal(geometry.vertices, vertices)
    np.testing.assert_array_equal(geometry.vertex_arms, arms)


def test_hundreds_of_walls_build_like_the_reference() -> None:
    scenario = cluttered_walls(7, 250)
    geometry = build_static_geometry(scenario)
    assert geometry.n_segments == 4 + 250 + 4 * 3
    vertices, arms = reference_corner_analysis(scenario)
    np.testing.assert_array_equal(geometry.vertices, vertices)
    np.testing.assert_array_equal(geometry.vertex_arms, arms)


def test_equal_scenarios_share_one_read_only_geometry() -> None:
    first = static_geometry(cluttered_walls(3, 20))
    assert static_geometry(cluttered_walls(3, 20)) is first
    assert static_geometry(cluttered_walls(4, 20)) is not first
    with pytest.raises(ValueError, match="read-only"):
        first.vertices[0, 0] = 1.0


def test_scenarios_differing_in_boxes_share_the_walls_analysis_and_build_as_the_reference() -> None:
    """An env that draws new boxes every episode reuses the room's and walls' corner analysis;
    each geometry is still the pairwise reference's, and the bits of a fresh build."""
    base = cluttered_walls(5, 40)
    rng = np.random.default_rng(9)
    first_walls = None
    for _ in range(6):
        boxes = tuple(
            Box(
                center=(float(rng.uniform(-2.5, 2.5)), float(rng.choice([-1.7, 1.7]))),
                size=(float(rng.uniform(0.2, 0.8)), 0.6),  # flush with a long wall at 0 deg
                angle_deg=float(rng.choice([0.0, 90.0])),
            )
            for _ in range(3)
        )
        scenario = dataclasses.replace(base, boxes=boxes)
        geometry = build_static_geometry(scenario)
        walls = geometry_module._wall_corners(scenario.room, scenario.walls)
        first_walls = first_walls or walls
        assert walls is first_walls
        vertices, arms = reference_corner_analysis(scenario)
        np.testing.assert_array_equal(geometry.vertices, vertices)
        np.testing.assert_array_equal(geometry.vertex_arms, arms)
        geometry_module._wall_corners.cache_clear()
        fresh = build_static_geometry(scenario)
        for name, array in vars(geometry).items():
            assert array.tobytes() == getattr(fresh, name).tobytes(), name
        first_walls = geometry_module._wall_corners(scenario.room, scenario.walls)


@pytest.mark.parametrize("shape", [(0,), (1,), (4,), (3, 4, 2), (0, 4, 2), (2, 5), (6, 1, 3)])
def test_ring_shift_equals_np_roll(shape: tuple[int, ...]) -> None:
    rng = np.random.default_rng(len(shape))
    values = rng.normal(size=shape)
    for axis in range(len(shape)):
        for step in (1, -1):
            shifted = geometry_module.ring_shift(values, step, axis)
            expected = np.roll(values, -step, axis=axis)
            assert shifted.shape == expected.shape and shifted.tobytes() == expected.tobytes()


def test_segments_near_points_are_the_unique_owners_of_the_samples_in_reach() -> None:
    rng = np.random.default_rng(3)
    for _ in range(50):
        n = int(rng.integers(1, 30))
        starts = rng.uniform(-3.0, 3.0, size=(n, 2))
        ends = starts + rng.normal(size=(n, 2)) * rng.choice([0.05, 1.0, 3.0])
        index = geometry_module._SegmentIndex(starts, ends)
        points = np.concatenate([starts, ends, rng.uniform(-3.0, 3.0, size=(20, 2))])
        tolerance = float(rng.choice([1e-6, 1e-3, 0.3]))
        near = index.near(points, tolerance)
        owner = np.array(index._owner, dtype=np.int64)
        hits = index._tree.query_ball_point(points, index._reach + tolerance)
        assert near == [np.unique(owner[np.asarray(h, dtype=np.int64)]).tolist() for h in hits]
        for point, candidates in zip(points, near, strict=True):  # none within reach left out
            gaps = [_point_segment_gap(point, starts[i], ends[i]) for i in range(n)]
            assert {i for i in range(n) if gaps[i] <= tolerance} <= set(candidates)


def _point_segment_gap(point: np.ndarray, start: np.ndarray, end: np.ndarray) -> float:
    span = end - start
    t = float(np.clip((point - start) @ span / (span @ span), 0.0, 1.0))
    return float(np.linalg.norm(point - (start + t * span)))


def _flattened_in_order(scenario: Scenario) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Start points, end points and map flags of the room's sides, the free walls and the box
    sides, listed one by one from the scenario (the order and the floats the build keeps)."""
    rows: list[tuple[tuple[float, float], tuple[float, float], bool]] = []

    def add_polygon(corners: tuple[tuple[float, float], ...], mapped: bool) -> None:
        rows.extend((corner, corners[(i + 1) % 4], mapped) for i, corner in enumerate(corners))

    if scenario.room is not None:
        add_polygon(scenario.room.corners, True)
    rows.extend((wall.a, wall.b, wall.mapped) for wall in scenario.walls)
    for box in scenario.boxes:
        add_polygon(box.corners, box.mapped)
    return (
        np.array([row[0] for row in rows], dtype=np.float64).reshape(-1, 2),
        np.array([row[1] for row in rows], dtype=np.float64).reshape(-1, 2),
        np.array([row[2] for row in rows], dtype=bool),
    )


@pytest.mark.parametrize("seed", range(3))
def test_segments_are_the_scenarios_sides_in_order_bit_for_bit(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(100):
        scenario = random_static_scenario(rng)
        geometry = build_static_geometry(scenario)
        built = (geometry.segment_starts, geometry.segment_ends, geometry.segment_mapped)
        for array, expected in zip(built, _flattened_in_order(scenario), strict=True):
            assert array.dtype == expected.dtype and array.shape == expected.shape
            assert array.tobytes() == expected.tobytes(), scenario


def test_the_norm_of_a_point_vector_is_np_linalg_norms() -> None:
    """_segment_containing measures an offset as ``np.sqrt(v.dot(v))``: np.linalg.norm's own
    arithmetic for a float vector, without its checks."""
    rng = np.random.default_rng(5)
    scales = rng.choice([1e-9, 1e-6, 1e-3, 1.0, 1e3], size=(20000, 1))
    for offset in rng.normal(size=(20000, 2)) * scales:
        assert np.sqrt(offset.dot(offset)) == np.linalg.norm(offset)


def test_box_corners_against_walls_take_the_walls_direction() -> None:
    rng = np.random.default_rng(8)
    for _ in range(200):
        starts = rng.uniform(-3.0, 3.0, size=(6, 2))
        ends = starts + rng.normal(size=(6, 2))
        index = geometry_module._SegmentIndex(starts, ends)
        pick = rng.integers(6, size=30)
        along = rng.uniform(-0.01, 1.01, size=(30, 1))
        points = (
            starts[pick] + along * (ends[pick] - starts[pick]) + rng.normal(size=(30, 2)) * 1e-3
        )
        for point, candidates in zip(points, index.near(points, 1e-3), strict=True):
            found = geometry_module._segment_containing(point, index, candidates, 1e-3)
            expected = None
            for i in candidates:  # with np.linalg.norm
                span, length = index.spans[i], index.lengths[i]
                t = float((point - index.starts[i]) @ span) / length
                foot = index.starts[i] + span * t / length
                if -1e-3 <= t <= length + 1e-3 and np.linalg.norm(point - foot) <= 1e-3:
                    expected = span / length
                    break
            assert (found is None) == (expected is None)
            assert found is None or found.tobytes() == expected.tobytes()


def _box_corner_cases() -> list[tuple[np.ndarray, geometry_module._SegmentIndex]]:
    """Box corners with the indexed walls they are tested against: the WallCorrection rooms'
    random wall boxes, random scenarios, cluttered rooms and boxes placed flush, off by a hair
    or at the tolerance from random walls."""
    cases = []
    rooms = [cluttered_walls(seed, 30) for seed in range(3)]
    rooms += [random_static_scenario(np.random.default_rng(seed)) for seed in range(150)]
    rooms += [load_scenario(name) for name in builtin_names()]
    rng = np.random.default_rng(21)
    for scenario in rooms:
        walls = geometry_module._wall_corners(scenario.room, scenario.walls).index
        corners = np.array([box.corners for box in scenario.boxes], dtype=np.float64)
        cases.append((corners.reshape(-1, 4, 2), walls))
        if scenario.room is not None:
            for _ in range(4):
                obstacles = with_wall_obstacles(
                    scenario, rng, 4, (0.3, 1.0), (0.05, 0.35), tuple(sorted(rng.uniform(-3, 3, 2)))
                )
                corners = np.array([box.corners for box in obstacles.boxes], dtype=np.float64)
                cases.append((corners.reshape(-1, 4, 2), walls))
    for _ in range(300):
        starts = rng.uniform(-3.0, 3.0, size=(5, 2))
        walls = geometry_module._SegmentIndex(starts, starts + rng.normal(size=(5, 2)))
        pick = rng.integers(5, size=3)
        direction = walls.spans[pick] / walls.lengths[pick][:, None]
        normal = np.stack([-direction[:, 1], direction[:, 0]], axis=1)
        along = rng.uniform(-0.1, 1.1, size=(3, 1)) * walls.spans[pick]
        gap = rng.choice([0.0, 1e-3, -1e-3, 5e-4, 2e-3, 1e-9], size=(3, 1))
        first = walls.starts[pick] + along + gap * normal
        size = rng.uniform(0.01, 0.5, size=(3, 2, 1))
        corners = np.stack(
            [
                first,
                first + size[:, 0] * direction,
                first + size[:, 0] * direction + size[:, 1] * normal,
                first + size[:, 1] * normal,
            ],
            axis=1,
        )
        cases.append((corners, walls))
    return cases


def test_box_corner_arms_equal_the_per_corner_reference_bit_for_bit() -> None:
    """The compiled corner test with its numpy fallback gives the per-corner reference's bits,
    over flush, clear and borderline corners (some of which the compiled loop leaves
    undecided)."""
    on_walls = undecided_cases = 0
    for corners, walls in _box_corner_cases():
        points, arms = geometry_module._box_corner_arms(corners.copy(), walls)
        expected_points, expected_arms = reference_box_corner_arms(corners.copy(), walls)
        assert points.tobytes() == expected_points.tobytes()
        assert arms.tobytes() == expected_arms.tobytes()
        on_walls += int(np.any(arms[:, 0] != arms[:, 1]))
        undecided_cases += int(np.any(_undecided_corners(corners, walls)))
    assert on_walls > 100
    assert undecided_cases > 10


def _undecided_corners(corners: np.ndarray, walls: geometry_module._SegmentIndex) -> np.ndarray:
    """The corners the compiled loop leaves to numpy."""
    points = corners.reshape(-1, 2)
    to_next = geometry_module.ring_shift(corners, 1, axis=1).reshape(-1, 2) - points
    point_index, segment = walls.near_pairs(points, 1e-3)
    _, undecided = geometry_kernels.corner_arms(
        points,
        to_next,
        to_next,
        walls.starts,
        walls.spans,
        walls.lengths,
        point_index,
        segment,
        1e-3,
    )
    return undecided


def test_segment_pairs_hold_the_k_d_trees_candidates() -> None:
    """Every pair: the tree's candidates among them; tree pairs when the points are many."""
    rng = np.random.default_rng(4)
    for n_segments in (3, 12, 40, 300):
        starts = rng.uniform(-3.0, 3.0, size=(n_segments, 2))
        walls = geometry_module._SegmentIndex(starts, starts + rng.normal(size=(n_segments, 2)))
        points = rng.uniform(-3.0, 3.0, size=(int(rng.integers(1, 60)), 2))
        point_index, segment = walls.near_pairs(points, 1e-3)
        pairs = set(zip(point_index.tolist(), segment.tolist(), strict=True))
        for k, candidates in enumerate(walls.near(points, 1e-3)):
            assert {(k, i) for i in candidates} <= pairs
        if len(points) * n_segments > geometry_module._ALL_PAIRS_MAX:
            assert len(pairs) < len(points) * n_segments
