"""World's body moves through the pymunk properties' setters equal the attribute assignments of
:class:`tests.world_setattr_reference.SetattrWorld`: same poses, contacts and path lengths, bit
for bit, over teleports and motions into walls, corners, boxes and cylinders."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.pose import Pose
from sonar_gym.robot import DifferentialDriveRobot, OdometryNoise
from sonar_gym.scenario import Scenario, load_scenario
from sonar_gym.world import MotionOutcome, World
from tests.test_world import CLUTTERED
from tests.world_setattr_reference import SetattrWorld


def _outcome(outcome: MotionOutcome) -> tuple[float, ...]:
    pose = outcome.pose
    return (pose.x, pose.y, pose.theta, float(outcome.collided), outcome.path_length_m)


def _body(world: World) -> tuple[object, ...]:
    body = world.robot_body
    return (tuple(body.position), body.angle, tuple(body.velocity), body.angular_velocity)


def _moves(world: World, seed: int, count: int) -> list[tuple[object, ...]]:
    """Teleports to free poses, then straight and turning substep runs long enough to reach
    the walls, boxes and cylinders (contacts, slides along them, corners)."""
    rng = np.random.default_rng(seed)
    record: list[tuple[object, ...]] = []
    for _ in range(count):
        if rng.uniform() < 0.3:
            world.set_robot_pose(world.sample_free_pose(rng))
            record.append(_body(world))
        heading = float(rng.uniform(-np.pi, np.pi))
        substeps = int(rng.integers(5, 60))
        step = float(rng.uniform(0.005, 0.05))
        turn = float(rng.uniform(-0.05, 0.05))
        displacements = np.tile(
            [step * np.cos(heading), step * np.sin(heading), turn], (substeps, 1)
        )
        record.append(_outcome(world.move_robot(displacements)))
        record.append(_body(world))
    return record


def _scenarios() -> list[Scenario]:
    return [CLUTTERED, load_scenario("beom_cho_lab"), load_scenario("kim_arena")]


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("index", range(3))
def test_motions_through_the_setters_equal_attribute_assignment(index: int, seed: int) -> None:
    scenario = _scenarios()[index]
    assert _moves(World(scenario), seed, 40) == _moves(SetattrWorld(scenario), seed, 40)


@pytest.mark.parametrize("seed", range(3))
def test_robot_drives_through_the_setters_equal_attribute_assignment(seed: int) -> None:
    def drive(world: World) -> list[tuple[float, ...]]:
        robot = DifferentialDriveRobot(OdometryNoise(), odometry_pose=world.robot_pose)
        rng = np.random.default_rng(seed)
        poses = []
        for _ in range(60):
            left, right = rng.uniform(-0.2, 0.8, 2)
            result = robot.drive(world, float(left), float(right), rng)
            pose: Pose = result.true_pose
            poses.append((pose.x, pose.y, pose.theta, float(result.collided)))
        return poses

    assert drive(World(CLUTTERED)) == drive(SetattrWorld(CLUTTERED))
