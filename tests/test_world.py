"""World: pymunk space, free poses, line of sight, temperature, pickling."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.pose import Pose
from sonar_gym.robot import DifferentialDriveRobot, OdometryNoise
from sonar_gym.scenario import Scenario, builtin_names, load_scenario, scenario_from_dict
from sonar_gym.world import NoFreePoseError, World

CLUTTERED = scenario_from_dict(
    {
        "room": {"min": [-2.0, -1.5], "max": [2.0, 1.5]},
        "walls": [{"a": [0.5, -1.5], "b": [0.5, -0.6]}],
        "boxes": [
            {"center": [-1.0, 0.6], "size": [0.8, 0.4], "angle_deg": 25.0},
            {"center": [1.3, 0.8], "size": [0.5, 0.5]},
        ],
        "cylinders": [
            {"center": [-0.6, -0.7], "radius": 0.12},
            {"center": [1.2, -0.4], "radius": 0.03},
        ],
        "robot": {"radius": 0.25},
    }
)


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    t = float(np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + t * (b - a))))


def inside_convex(p: np.ndarray, corners: tuple) -> bool:
    c = np.asarray(corners)
    edges = np.roll(c, -1, axis=0) - c
    rel = p - c
    return bool(np.all(edges[:, 0] * rel[:, 1] - edges[:, 1] * rel[:, 0] > 0))


def footprint_clearance(scenario: Scenario, p: np.ndarray) -> float:
    """Closed-form distance from a robot centre to the nearest static surface minus nothing."""
    distances = []
    if scenario.room is not None:
        (x0, y0), (x1, y1) = scenario.room.min, scenario.room.max
        distances += [p[0] - x0, x1 - p[0], p[1] - y0, y1 - p[1]]
    for wall in scenario.walls:
        distances.append(point_segment_distance(p, np.array(wall.a), np.array(wall.b)))
    for box in scenario.boxes:
        if inside_convex(p, box.corners):
            return -1.0
        corners = [np.array(c) for c in box.corners]
        distances += [point_segment_distance(p, corners[i], corners[(i + 1) % 4]) for i in range(4)]
    for cylinder in scenario.cylinders:
        distances.append(float(np.linalg.norm(p - np.array(cylinder.center))) - cylinder.radius)
    return min(distances)


# --- construction, temperature -------------------------------------------------------------


def test_space_holds_one_static_shape_per_surface_and_a_dynamic_robot() -> None:
    world = World(CLUTTERED)
    import pymunk

    segments = [s for s in world.static_shapes if isinstance(s, pymunk.Segment)]
    circles = [s for s in world.static_shapes if isinstance(s, pymunk.Circle)]
    assert len(segments) == 4 + 1 + 8 and all(s.radius == 0.0 for s in segments)
    assert sorted(c.radius for c in circles) == [0.03, 0.12]
    assert world.robot_body.body_type == pymunk.Body.DYNAMIC
    assert world.geometry.n_segments == 13 and world.geometry.n_circles == 2


@pytest.mark.parametrize("temperature", [-40.0, 0.0, 27.0, 60.0])
def test_temperature_in_range_is_kept(temperature: float) -> None:
    assert World(CLUTTERED, temperature_c=temperature).temperature_c == temperature


@pytest.mark.parametrize("temperature", [-40.1, 60.5, math.nan, math.inf, "warm"])
def test_temperature_out_of_range_names_argument_and_range(temperature: object) -> None:
    with pytest.raises(ValueError, match=r"temperature_c.*\[-40.0, 60.0\]"):
        World(CLUTTERED, temperature_c=temperature)  # type: ignore[arg-type]


def test_temperature_setter_validates() -> None:
    world = World(CLUTTERED)
    world.temperature_c = 35.0
    assert world.temperature_c == 35.0
    with pytest.raises(ValueError, match="temperature_c"):
        world.temperature_c = 100.0


def test_default_start_is_the_origin_when_free() -> None:
    assert World(CLUTTERED).robot_pose == Pose(0.0, 0.0, 0.0)


def test_default_start_is_free_when_the_origin_is_blocked() -> None:
    scenario = scenario_from_dict(
        {
            "room": {"min": [-2, -2], "max": [2, 2]},
            "boxes": [{"center": [0, 0], "size": [1.0, 1.0]}],
        }
    )
    world = World(scenario)
    assert world.is_free(world.robot_pose.position)
    assert footprint_clearance(scenario, world.robot_pose.position) >= scenario.robot.radius - 1e-9


@pytest.mark.parametrize("name", builtin_names())
def test_every_builtin_builds_a_world_at_a_free_start(name: str) -> None:
    world = World(load_scenario(name))
    assert world.is_free(world.robot_pose.position)


# --- set_robot_pose, is_free ---------------------------------------------------------------


def test_set_robot_pose_teleports_and_reads_back() -> None:
    world = World(CLUTTERED)
    pose = Pose(-1.5, -1.0, 3.0)
    world.set_robot_pose(pose)
    assert world.robot_pose == pose
    assert world.is_free(pose.position)


def test_set_robot_pose_rejects_a_blocked_pose() -> None:
    world = World(CLUTTERED)
    with pytest.raises(ValueError, match="pose"):
        world.set_robot_pose(Pose(1.3, 0.8, 0.0))  # inside a box
    with pytest.raises(ValueError, match="pose"):
        world.set_robot_pose(Pose(1.9, 0.0, 0.0))  # through the room wall
    assert world.robot_pose == Pose(0.0, 0.0, 0.0)


def test_is_free_against_closed_form_distances() -> None:
    world = World(CLUTTERED)
    r = CLUTTERED.robot.radius
    cylinder = CLUTTERED.cylinders[0]
    cx, cy = cylinder.center
    # Touching the cylinder is free, overlapping it by a millimetre is not.
    assert world.is_free((cx + cylinder.radius + r, cy))
    assert not world.is_free((cx + cylinder.radius + r - 1e-3, cy))
    # The room wall x = -2.
    assert world.is_free((-2.0 + r, 0.0))
    assert not world.is_free((-2.0 + r - 1e-3, 0.0))
    # The free wall x = 0.5 from y = -1.5 to -0.6: its free end at (0.5, -0.6).
    assert world.is_free((0.5, -0.6 + r + 1e-3))
    assert not world.is_free((0.5 + r - 1e-3, -1.0))
    # A point robot inside a box is not free even though it touches no edge.
    assert not world.is_free((1.3, 0.8), radius=0.0)
    assert world.is_free((0.0, 0.0), radius=0.0)


def test_is_free_rejects_bad_arguments() -> None:
    world = World(CLUTTERED)
    with pytest.raises(ValueError, match="position_xy"):
        world.is_free((0.0, math.nan))
    with pytest.raises(ValueError, match="position_xy"):
        world.is_free((0.0, 1.0, 2.0))
    with pytest.raises(ValueError, match="radius"):
        world.is_free((0.0, 0.0), radius=-0.1)


def test_kim_arena_table_one_positions_are_free() -> None:
    world = World(load_scenario("kim_arena"))
    for x_cm, y_cm in [
        (2.5, 10.0),
        (45.0, 42.5),
        (22.5, 75.0),
        (107.5, 82.5),
        (185.0, 147.5),
        (192.5, 175.0),
        (180.0, 190.0),
    ]:
        assert world.is_free((x_cm / 100, y_cm / 100))


# --- sample_free_pose ----------------------------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), clearance=st.sampled_from([0.0, 0.05, 0.2]))
def test_sampled_free_poses_never_overlap_obstacles(seed: int, clearance: float) -> None:
    world = World(CLUTTERED)
    pose = world.sample_free_pose(np.random.default_rng(seed), clearance=clearance)
    assert (
        footprint_clearance(CLUTTERED, pose.position) >= CLUTTERED.robot.radius + clearance - 1e-9
    )
    assert -math.pi < pose.theta <= math.pi


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_sampled_poses_in_the_paper_lab_are_free(seed: int) -> None:
    lab = load_scenario("beom_cho_lab")
    world = World(lab)
    rng = np.random.default_rng(seed)
    for _ in range(10):
        pose = world.sample_free_pose(rng)
        assert footprint_clearance(lab, pose.position) >= lab.robot.radius - 1e-9


def test_sample_free_pose_is_deterministic_in_the_rng() -> None:
    world = World(CLUTTERED)
    a = [world.sample_free_pose(np.random.default_rng(7)) for _ in range(3)]
    assert a[0] == a[1] == a[2]
    assert world.sample_free_pose(np.random.default_rng(8)) != a[0]


def test_sample_free_pose_respects_the_region() -> None:
    world = World(CLUTTERED)
    rng = np.random.default_rng(3)
    region = ((-2.0, -1.5), (-0.5, 0.0))
    for _ in range(50):
        pose = world.sample_free_pose(rng, region=region)
        r = CLUTTERED.robot.radius
        assert -2.0 + r <= pose.x <= -0.5 - r and -1.5 + r <= pose.y <= 0.0 - r


def test_sample_free_pose_covers_headings_and_space() -> None:
    world = World(CLUTTERED)
    rng = np.random.default_rng(11)
    poses = [world.sample_free_pose(rng) for _ in range(400)]
    thetas = np.array([p.theta for p in poses])
    xs = np.array([p.x for p in poses])
    assert thetas.min() < -2.8 and thetas.max() > 2.8
    assert xs.min() < -1.5 and xs.max() > 1.5


def test_sample_free_pose_reports_impossible_requests() -> None:
    world = World(CLUTTERED)
    with pytest.raises(NoFreePoseError, match="clearance"):
        world.sample_free_pose(np.random.default_rng(0), clearance=2.0)
    tiny = ((1.2, 0.7), (1.4, 0.9))  # inside a box, and narrower than the robot
    with pytest.raises(NoFreePoseError):
        world.sample_free_pose(np.random.default_rng(0), region=tiny)
    with pytest.raises(ValueError, match="region"):
        world.sample_free_pose(np.random.default_rng(0), region=((1.0, 1.0), (0.0, 2.0)))
    with pytest.raises(ValueError, match="rng"):
        world.sample_free_pose(7)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="clearance"):
        world.sample_free_pose(np.random.default_rng(0), clearance=-1.0)


# --- line of sight -------------------------------------------------------------------------


def test_line_of_sight_blocked_by_a_box() -> None:
    scenario = scenario_from_dict(
        {
            "room": {"min": [-3, -3], "max": [3, 3]},
            "boxes": [{"center": [0, 0], "size": [0.4, 0.4]}],
        }
    )
    world = World(scenario)
    assert not world.line_of_sight((-1.0, 0.0), (1.0, 0.0))
    assert not world.line_of_sight((-1.0, 0.19), (1.0, 0.19))
    assert world.line_of_sight((-1.0, 0.21), (1.0, 0.21))
    assert world.line_of_sight((-1.0, -1.0), (1.0, -0.5))


def test_line_of_sight_blocked_by_a_cylinder() -> None:
    scenario = scenario_from_dict({"cylinders": [{"center": [0, 0], "radius": 0.1}]})
    world = World(scenario)
    assert not world.line_of_sight((-1.0, 0.0), (1.0, 0.0))
    assert not world.line_of_sight((-1.0, 0.099), (1.0, 0.099))
    assert world.line_of_sight((-1.0, 0.101), (1.0, 0.101))


def test_line_of_sight_ignores_the_robot() -> None:
    world = World(CLUTTERED)
    world.set_robot_pose(Pose(0.0, 0.0, 0.0))
    assert world.line_of_sight((-0.5, 0.0), (0.5, 0.0))


def test_a_surface_point_is_visible_from_the_free_side() -> None:
    lab = load_scenario("beom_cho_lab")
    world = World(lab)
    sensor = np.array([0.0, 0.0])
    for role in ("small_beacon", "large_beacon"):
        beacon = lab.beacon(role)
        centre = np.array(beacon.center)
        echo = centre + (sensor - centre) * beacon.radius / np.linalg.norm(centre - sensor)
        assert world.line_of_sight(sensor, echo)
        # ... but not through the beacon to its far side.
        far = centre - (sensor - centre) * beacon.radius / np.linalg.norm(centre - sensor)
        assert not world.line_of_sight(sensor, far)
    # A point on the room wall straight ahead is visible; one behind the hexahedral box is not.
    assert world.line_of_sight(sensor, (3.1, 0.0))
    assert not world.line_of_sight(sensor, (-3.1, -0.5))


def test_robot_at_the_origin_sees_both_beacons_within_range() -> None:
    """The Table II scan of Beom & Cho was taken at the origin and found both beacons."""
    lab = load_scenario("beom_cho_lab")
    world = World(lab)
    for role in ("small_beacon", "large_beacon"):
        beacon = lab.beacon(role)
        distance = math.hypot(*beacon.center) - beacon.radius
        assert 0.3 <= distance <= 4.0  # Table I: R_min, R_max
        direction = np.array(beacon.center) / math.hypot(*beacon.center)
        assert world.line_of_sight((0.0, 0.0), np.array(beacon.center) - beacon.radius * direction)


# --- pickling, motion determinism ---------------------------------------------------------


def test_pickle_round_trip_keeps_the_state() -> None:
    world = World(CLUTTERED, temperature_c=31.5)
    robot = DifferentialDriveRobot(OdometryNoise.none())
    world.set_robot_pose(Pose(-1.4, -1.0, 2.5))
    robot.drive(world, 0.7, 0.9, np.random.default_rng(0))
    clone = pickle.loads(pickle.dumps(world))
    assert clone.scenario == world.scenario
    assert clone.temperature_c == 31.5
    assert clone.robot_pose == world.robot_pose
    np.testing.assert_array_equal(clone.geometry.segments, world.geometry.segments)
    np.testing.assert_array_equal(clone.geometry.vertices, world.geometry.vertices)
    assert len(clone.static_shapes) == len(world.static_shapes)


def test_pickled_world_drives_identically() -> None:
    world = World(CLUTTERED)
    world.set_robot_pose(Pose(1.3, -1.0, 0.3))
    robot = DifferentialDriveRobot(OdometryNoise())
    robot.drive(world, 1.0, 1.0, np.random.default_rng(1))  # into the right wall: contacts cached
    clone = pickle.loads(pickle.dumps(world))
    a = DifferentialDriveRobot(OdometryNoise(), odometry_pose=robot.odometry_pose)
    b = DifferentialDriveRobot(OdometryNoise(), odometry_pose=robot.odometry_pose)
    for d_left, d_right in [(0.5, 0.8), (-0.3, 0.3), (1.5, 1.5)]:
        ra = a.drive(world, d_left, d_right, np.random.default_rng(5))
        rb = b.drive(clone, d_left, d_right, np.random.default_rng(5))
        assert ra == rb


def test_move_robot_rejects_bad_displacements() -> None:
    world = World(CLUTTERED)
    with pytest.raises(ValueError, match="substep_displacements"):
        world.move_robot(np.zeros((3, 2)))
    with pytest.raises(ValueError, match="substep_displacements"):
        world.move_robot([[0.0, math.nan, 0.0]])


def test_move_robot_follows_free_displacements_exactly() -> None:
    world = World(CLUTTERED)
    steps = np.tile([0.01, -0.005, 0.02], (50, 1))
    outcome = world.move_robot(steps)
    assert not outcome.collided
    assert outcome.pose.x == pytest.approx(0.5, abs=1e-12)
    assert outcome.pose.y == pytest.approx(-0.25, abs=1e-12)
    assert outcome.pose.theta == pytest.approx(1.0, abs=1e-12)
    assert outcome.path_length_m == pytest.approx(50 * math.hypot(0.01, 0.005), rel=1e-12)
    assert tuple(world.robot_body.velocity) == (0.0, 0.0)


def test_set_scenario_rebuilds_shapes_and_geometry() -> None:
    world = World(CLUTTERED)
    lab = load_scenario("beom_cho_lab")
    world.set_scenario(lab)
    assert world.scenario is lab
    assert world.geometry.n_segments == build_count(lab)
    assert world.robot_pose == Pose(0.0, 0.0, 0.0)
    assert not world.line_of_sight((0.0, 0.0), (-3.1, -0.5))


def test_set_scenario_with_a_blocked_pose_changes_nothing() -> None:
    world = World(CLUTTERED, robot_pose=Pose(-1.5, -1.0, 0.5))
    with pytest.raises(ValueError, match="pose"):
        world.set_scenario(load_scenario("beom_cho_lab"), robot_pose=Pose(-1.25, -0.2, 0.0))
    assert world.scenario is CLUTTERED
    assert world.robot_pose == Pose(-1.5, -1.0, 0.5)
    assert world.geometry.n_segments == build_count(CLUTTERED)


def build_count(scenario: Scenario) -> int:
    return (4 if scenario.room else 0) + len(scenario.walls) + 4 * len(scenario.boxes)


def test_reset_episode_equals_a_newly_built_world() -> None:
    world = World(CLUTTERED, temperature_c=5.0, robot_pose=Pose(-1.5, -1.0, 0.5))
    world.move_robot(np.tile([0.01, 0.0, 0.02], (30, 1)))
    space, geometry = world.space, world.geometry
    world.reset_episode(temperature_c=31.0, robot_pose=Pose(1.5, 0.0, -2.0))
    fresh = World(CLUTTERED, temperature_c=31.0, robot_pose=Pose(1.5, 0.0, -2.0))
    assert world.space is space and world.geometry is geometry
    assert world.temperature_c == fresh.temperature_c == 31.0
    assert world.robot_pose == fresh.robot_pose
    drive = np.tile([0.0, 0.02, 0.01], (80, 1))  # into the box above: both slide alike
    assert world.move_robot(drive) == fresh.move_robot(drive)
    world.reset_episode(temperature_c=12.0)
    assert world.robot_pose == World(CLUTTERED).robot_pose
    with pytest.raises(ValueError, match="temperature_c"):
        world.reset_episode(temperature_c=99.0)
    with pytest.raises(ValueError, match="pose"):
        world.reset_episode(temperature_c=12.0, robot_pose=Pose(-1.0, 0.6, 0.0))


def test_worlds_of_equal_scenarios_share_the_geometry() -> None:
    first = World(load_scenario("beom_cho_lab"))
    assert World(load_scenario("beom_cho_lab")).geometry is first.geometry
    assert World(CLUTTERED).geometry is not first.geometry


def test_box_interiors_are_not_free_even_for_a_point() -> None:
    world = World(CLUTTERED)
    for box in CLUTTERED.boxes:
        assert not world.is_free(box.center, radius=0.0)
        corner = np.array(box.corners[0])
        outward = corner - np.array(box.center)
        assert world.is_free(corner + 0.05 * outward / np.linalg.norm(outward), radius=0.0)


def test_a_teleported_robot_that_never_moved_drives_like_a_new_one() -> None:
    drive = np.tile([0.015, 0.01, 0.03], (60, 1))  # into the box corner above: a collision
    start = Pose(0.9, 0.3, 0.2)
    moved = World(CLUTTERED, robot_pose=Pose(-1.5, -1.0, 0.5))
    moved.set_robot_pose(Pose(1.5, -1.0, 0.0))  # teleports that never step the space
    moved.set_robot_pose(start)
    expected = World(CLUTTERED, robot_pose=start).move_robot(drive)
    assert expected.collided
    assert moved.move_robot(drive) == expected
    moved.set_robot_pose(start)  # after a motion, a teleport gives a fresh body again
    assert moved.move_robot(drive) == expected


def _body_pose(world: World) -> Pose:
    x, y = world.robot_body.position
    return Pose(float(x), float(y), float(world.robot_body.angle))


def test_robot_pose_is_what_the_body_holds_through_teleports_moves_and_pickling() -> None:
    world = World(CLUTTERED)
    robot = DifferentialDriveRobot(OdometryNoise(0.01, 0.01, 0.0, 0.05, 0.2))
    rng = np.random.default_rng(4)
    world.set_robot_pose(Pose(-1.5, -1.0, 3.1))
    assert world.robot_pose == _body_pose(world) == Pose(-1.5, -1.0, 3.1)
    for _ in range(30):  # free arcs teleport; a blocked one steps the space
        robot.drive(world, *rng.uniform(-0.4, 0.6, 2).tolist(), rng)
        assert world.robot_pose == _body_pose(world)
    world.set_robot_pose(Pose(1.5, -1.0, 0.0))
    outcome = world.move_robot(np.tile([0.05, 0.0, 0.01], (40, 1)))  # into the right wall
    assert outcome.collided
    assert world.robot_pose == _body_pose(world) == outcome.pose
    copy = pickle.loads(pickle.dumps(world))
    assert copy.robot_pose == _body_pose(copy) == world.robot_pose
