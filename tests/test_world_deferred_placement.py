"""World's body placed when next read equals the body placed at every teleport
(:class:`tests.eager_teleport_reference.EagerTeleportWorld`): same motions, contacts, path
lengths, query answers, bodies and shapes, bit for bit, over runs of teleports between motions."""

from __future__ import annotations

import numpy as np
import pymunk
import pytest

from sonar_gym.polyline import Route, follow_route
from sonar_gym.pose import Pose
from sonar_gym.robot import DifferentialDriveRobot, OdometryNoise
from sonar_gym.scenario import Scenario, load_scenario
from sonar_gym.world import MotionOutcome, World
from tests.eager_teleport_reference import EagerTeleportWorld
from tests.test_world import CLUTTERED
from tests.test_world_lazy_space import _body_state


def _scenarios() -> list[Scenario]:
    return [CLUTTERED, load_scenario("beom_cho_lab"), load_scenario("kim_arena")]


def _outcome(outcome: MotionOutcome) -> tuple[float, ...]:
    pose = outcome.pose
    return (pose.x, pose.y, pose.theta, float(outcome.collided), outcome.path_length_m)


def _everything_seen(world: World) -> tuple[object, ...]:
    """What the space shows of the robot: its body and shape, and a query that sees it."""
    space, pose = world.space, world.robot_pose  # the space first: it shows the body
    hits = space.point_query((pose.x, pose.y), 0.5, pymunk.ShapeFilter())
    seen = sorted((info.distance, tuple(info.point)) for info in hits)
    return (seen, len(space.shapes), len(space.bodies), _body_state(world))


def _session(world: World, seed: int, count: int) -> list[object]:
    """Runs of teleports (with static queries in between, which need no body), then motions
    long enough to reach walls, boxes and cylinders; the body read only now and then."""
    rng = np.random.default_rng(seed)
    record: list[object] = []
    world.is_free((0.0, 0.0))  # the space built before the first teleport, or not
    if seed % 2:
        world.space  # noqa: B018
    for _ in range(count):
        for _ in range(int(rng.integers(0, 4))):
            pose = world.sample_free_pose(rng)
            world.place_robot_on_clear_path(pose)
            record.append(world.robot_pose)
            record.append(world.is_free((pose.x + 0.3, pose.y), 0.1))
            if rng.uniform() < 0.2:
                record.append(_everything_seen(world))
        heading = float(rng.uniform(-np.pi, np.pi))
        substeps = int(rng.integers(1, 40))
        step = float(rng.uniform(0.005, 0.05))
        turn = float(rng.uniform(-0.05, 0.05))
        displacements = np.tile(
            [step * np.cos(heading), step * np.sin(heading), turn], (substeps, 1)
        )
        record.append(_outcome(world.move_robot(displacements)))
        if rng.uniform() < 0.5:
            record.append(_everything_seen(world))
    record.append(_everything_seen(world))
    return record


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("index", range(3))
def test_runs_of_teleports_then_motions_equal_teleports_placing_the_body(
    index: int, seed: int
) -> None:
    scenario = _scenarios()[index]
    assert _session(World(scenario), seed, 30) == _session(EagerTeleportWorld(scenario), seed, 30)


@pytest.mark.parametrize("seed", range(4))
def test_following_routes_through_walls_equals_teleports_placing_the_body(seed: int) -> None:
    """Clear stretches teleport the body, commands into the shapes move it through pymunk."""

    def follow(world: World) -> list[object]:
        world.set_robot_pose(Pose(0.0, 0.0, 0.3))
        robot = DifferentialDriveRobot(OdometryNoise(slip_probability_per_m=0.3))
        rng = np.random.default_rng(seed)
        draw = np.random.default_rng(100 + seed)
        route = Route.through(draw.uniform((-2.5, -2.5), (2.5, 2.5), (8, 2)))
        estimate, covariance = world.robot_pose, np.diag([1e-4, 1e-4, 1e-3])
        record: list[object] = []
        stations = np.linspace(0.0, route.length_m, 12).tolist()
        for start, stop in zip(stations, stations[1:], strict=False):
            leg = follow_route(robot, world, route, (start, stop), estimate, covariance, 2e-5, rng)
            estimate, covariance = leg.estimate, leg.covariance
            record += [estimate, covariance.tobytes(), leg.rolled_m, world.robot_pose]
        record.append(_everything_seen(world))
        return record

    assert follow(World(CLUTTERED)) == follow(EagerTeleportWorld(CLUTTERED))


def test_a_teleport_is_what_the_body_shows_when_read() -> None:
    world = World(CLUTTERED)
    world.move_robot(np.tile([0.01, 0.0, 0.01], (3, 1)))
    for pose in (Pose(0.5, 0.2, 1.0), Pose(-0.4, 0.1, -2.0)):
        world.place_robot_on_clear_path(pose)
        robot = world.space.point_query_nearest((pose.x, pose.y), 0.0, pymunk.ShapeFilter())
        assert robot is not None and robot.shape is world._robot_shape
        body = world.robot_body
        assert (*body.position, body.angle) == (pose.x, pose.y, pose.theta)
