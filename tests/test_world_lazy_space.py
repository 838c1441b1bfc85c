"""World's pymunk space built on first use equals the one built with the world
(:class:`tests.eager_world_reference.EagerWorld`): same query answers, same bodies, same motion."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.apcs_route import with_wall_obstacles
from sonar_gym.pose import Pose
from sonar_gym.robot import DifferentialDriveRobot, OdometryNoise
from sonar_gym.scenario import Scenario, load_scenario
from sonar_gym.world import World
from tests.eager_world_reference import EagerWorld
from tests.test_world import CLUTTERED

FIRST_USES = ("move", "is_free", "line_of_sight", "drive", "robot_body")


def _scenarios() -> list[Scenario]:
    corridor = load_scenario("apcs_corridor")
    (x0, _), (x1, _) = corridor.bounds
    rooms = [
        with_wall_obstacles(
            corridor, np.random.default_rng(seed), 4, (0.3, 1.0), (0.05, 0.35), (x0 + 1, x1 - 1)
        )
        for seed in range(3)
    ]
    return [CLUTTERED, load_scenario("beom_cho_lab"), *rooms]


def _body_state(world: World) -> tuple[object, ...]:
    body = world.robot_body
    shape = world._robot_shape
    assert shape is not None
    return (
        tuple(body.position),
        body.angle,
        tuple(body.velocity),
        body.angular_velocity,
        tuple(body.force),
        body.torque,
        tuple(shape.bb),
    )


def _shape_state(shape: object) -> tuple[object, ...]:
    import pymunk

    assert isinstance(shape, pymunk.Segment | pymunk.Circle)
    geometry = (
        (tuple(shape.a), tuple(shape.b))
        if isinstance(shape, pymunk.Segment)
        else tuple(shape.offset)
    )
    return (type(shape).__name__, geometry, shape.radius, shape.filter, tuple(shape.bb))


def _space_content(world: World) -> list[object]:
    """The space's shapes in the order they were added: each static shape's state, the robot's
    place among them."""
    robot = world._robot_shape
    return ["robot" if shape is robot else _shape_state(shape) for shape in world.space.shapes]


def _pair(scenario: Scenario) -> tuple[World, World]:
    return World(scenario), EagerWorld(scenario)


def _points(world: World, rng: np.random.Generator, count: int) -> list[tuple[float, float]]:
    """Points over the scenario's bounds, and points near each shape (where pymunk decides)."""
    (x0, y0), (x1, y1) = world.scenario.bounds
    points = [(float(rng.uniform(x0, x1)), float(rng.uniform(y0, y1))) for _ in range(count)]
    for a, b in zip(
        world.geometry.segment_starts.tolist(), world.geometry.segment_ends.tolist(), strict=True
    ):
        t = float(rng.uniform())
        offset = world.robot_radius + float(rng.uniform(-2e-3, 2e-3))
        along = (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))
        points += [(along[0] + offset, along[1]), (along[0], along[1] - offset)]
    return points


@pytest.mark.parametrize("first_use", FIRST_USES)
@pytest.mark.parametrize("index", range(5))
def test_a_space_built_on_first_use_equals_one_built_with_the_world(
    index: int, first_use: str
) -> None:
    scenario = _scenarios()[index]
    lazy, eager = _pair(scenario)
    rng = np.random.default_rng(index)
    for _ in range(3):  # teleports only: the lazy world keeps no space through them
        pose = eager.sample_free_pose(np.random.default_rng(int(rng.integers(1000))), 0.3)
        lazy.set_robot_pose(pose)
        eager.set_robot_pose(pose)
    assert lazy._space is None
    assert lazy.robot_pose == eager.robot_pose
    drive = np.tile([0.04, 0.03, 0.02], (80, 1))  # long enough to meet something
    robot_noise = OdometryNoise(0.01, 0.01, 0.0, 0.05, 0.2)
    if first_use == "move":
        assert lazy.move_robot(drive) == eager.move_robot(drive)
    elif first_use == "is_free":
        points = _points(lazy, rng, 50)
        assert [lazy.is_free(p) for p in points] == [eager.is_free(p) for p in points]
    elif first_use == "line_of_sight":
        here = lazy.robot_pose.position
        points = _points(lazy, rng, 20)
        assert [lazy.line_of_sight(here, p) for p in points] == [
            eager.line_of_sight(here, p) for p in points
        ]
    elif first_use == "drive":
        commands = np.random.default_rng(9).uniform(-0.2, 0.8, (40, 2))
        runs = [
            DifferentialDriveRobot(robot_noise).drive_commands(world, commands, rng_copy)
            for world, rng_copy in (
                (lazy, np.random.default_rng(3)),
                (eager, np.random.default_rng(3)),
            )
        ]
        np.testing.assert_array_equal(runs[0].motions, runs[1].motions)
        np.testing.assert_array_equal(runs[0].collided, runs[1].collided)
    assert _body_state(lazy) == _body_state(eager)
    assert _space_content(lazy) == _space_content(eager)
    assert lazy.space.collision_slop == eager.space.collision_slop
    assert lazy.space.collision_bias == eager.space.collision_bias
    assert lazy.space.damping == eager.space.damping
    for _ in range(4):  # after the first use: motions into walls, teleports, motions again
        heading = float(rng.uniform(-math.pi, math.pi))
        step = [0.05 * math.cos(heading), 0.05 * math.sin(heading), float(rng.uniform(-0.05, 0.05))]
        steps = np.tile(step, (int(rng.integers(20, 120)), 1))
        outcome = lazy.move_robot(steps)
        assert outcome == eager.move_robot(steps)
        assert _body_state(lazy) == _body_state(eager)
        pose = lazy.sample_free_pose(np.random.default_rng(int(rng.integers(1000))))
        lazy.set_robot_pose(pose)
        eager.set_robot_pose(pose)
    points = _points(lazy, rng, 30)
    assert [lazy.is_free(p) for p in points] == [eager.is_free(p) for p in points]


@pytest.mark.parametrize("index", range(5))
def test_free_pose_answers_of_an_unbuilt_space_equal_pymunk_answers(index: int) -> None:
    scenario = _scenarios()[index]
    eager = EagerWorld(scenario)
    rng = np.random.default_rng(100 + index)
    radii = (None, 0.0, 0.05, 0.4)
    decided_without_space = 0
    for point in _points(eager, rng, 60):
        for radius in radii:
            lazy = World(scenario)
            built_before = lazy._space is not None
            assert lazy.is_free(point, radius) == eager.is_free(point, radius), (point, radius)
            decided_without_space += not built_before and lazy._space is None
    assert decided_without_space > 0


def test_a_robot_driven_along_clear_paths_never_builds_the_space() -> None:
    scenario = _scenarios()[2]
    room = scenario.room
    assert room is not None
    start = Pose(room.min[0] + 1.0, 0.5 * (room.min[1] + room.max[1]), 0.0)
    world = World(scenario, robot_pose=start)
    robot = DifferentialDriveRobot(OdometryNoise(0.0, 0.0, 0.0, 0.0, 0.0))
    robot.drive_commands(world, np.full((10, 2), 0.05), np.random.default_rng(0))
    world.set_robot_pose(Pose(start.x + 0.2, start.y, 0.1))
    assert world._space is None
    assert world.robot_pose == Pose(start.x + 0.2, start.y, 0.1)
