"""The batched motion and side-sonar paths of an APCS route against their per-command references."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from sonar_gym.pose import Pose
from sonar_gym.robot import DifferentialDriveRobot, OdometryNoise
from sonar_gym.scenario import load_scenario
from sonar_gym.sonar.presets import preset
from sonar_gym.sonar.swept import SideSonars
from sonar_gym.straight_drive import drive_straight_run, turn_run
from sonar_gym.world import World

NOISE = OdometryNoise(0.0005, 0.003, -0.002, 0.3, 0.3)  # slips are frequent on purpose


def _pair(start: Pose) -> tuple[World, World, DifferentialDriveRobot, DifferentialDriveRobot]:
    scenario = load_scenario("apcs_corridor")
    odometry = Pose(start.x + 0.01, start.y, start.theta)
    return (
        World(scenario, robot_pose=start),
        World(scenario, robot_pose=start),
        DifferentialDriveRobot(NOISE, odometry_pose=odometry),
        DifferentialDriveRobot(NOISE, odometry_pose=odometry),
    )


@pytest.mark.parametrize(
    ("start", "contacts"),
    [
        (Pose(1.0, 0.0, 0.0), False),
        (Pose(1.0, 0.55, 0.05), False),
        (Pose(1.0, 0.62, 0.1), True),  # runs into the first pillar and slides along it
    ],
)
def test_straight_run_is_drive_straight_command_by_command(start: Pose, contacts: bool) -> None:
    world, reference_world, robot, reference_robot = _pair(start)
    rng, reference_rng = np.random.default_rng(3), np.random.default_rng(3)
    reference = [
        reference_robot.drive_straight(reference_world, 0.03, reference_rng) for _ in range(40)
    ]
    run = drive_straight_run(robot, world, 0.03, 40, rng)
    assert any(r.collided for r in reference) == contacts
    np.testing.assert_array_equal(run.collided, [r.collided for r in reference])
    np.testing.assert_allclose(
        run.true_poses, [r.true_pose.as_array() for r in reference], atol=1e-12
    )
    np.testing.assert_allclose(
        run.odometry_poses, [r.odometry_pose.as_array() for r in reference], atol=1e-12
    )
    np.testing.assert_allclose(
        run.encoder_left_m, [r.encoder_left_m for r in reference], atol=1e-15
    )
    assert world.robot_pose.as_array() == pytest.approx(
        reference_world.robot_pose.as_array(), abs=1e-12
    )
    assert robot.odometry_pose is not None and reference_robot.odometry_pose is not None
    assert robot.odometry_pose.as_array() == pytest.approx(
        reference_robot.odometry_pose.as_array(), abs=1e-12
    )
    assert rng.random() == reference_rng.random()  # the random stream is where drive leaves it


def test_turn_run_is_turn() -> None:
    world, reference_world, robot, reference_robot = _pair(Pose(3.0, 0.1, 0.2))
    rng, reference_rng = np.random.default_rng(8), np.random.default_rng(8)
    reference = reference_robot.turn(reference_world, -0.7, reference_rng)
    run = turn_run(robot, world, -0.7, rng)
    assert run.true_poses[0] == pytest.approx(reference.true_pose.as_array(), abs=1e-12)
    assert run.odometry_poses[0] == pytest.approx(reference.odometry_pose.as_array(), abs=1e-12)
    assert rng.random() == reference_rng.random()


@pytest.mark.parametrize("scenario_name", ["apcs_corridor", "beom_cho_lab"])
@pytest.mark.parametrize("offset_m", [0.0, 0.15])
@pytest.mark.parametrize("transducer", ["ma40b8", "polaroid-6500", "ma40b8 side lobes"])
def test_side_samples_as_arrays_are_the_per_pose_readings(
    scenario_name: str, offset_m: float, transducer: str
) -> None:
    world = World(load_scenario(scenario_name))
    rng = np.random.default_rng(1)
    poses = [world.sample_free_pose(rng) for _ in range(150)]
    chosen = preset(transducer.split()[0])
    if transducer.endswith("side lobes"):
        chosen = dataclasses.replace(chosen, side_lobes=True, side_lobe_leakage=0.0)
    sonars = SideSonars(chosen, lateral_offset_m=offset_m)
    fast = sonars.sample_along(world, poses, np.random.default_rng(2))
    slow = sonars.sample_along_per_pose(world, poses, np.random.default_rng(2))
    for got, want in ((fast.left_m, slow.left_m), (fast.right_m, slow.right_m)):
        np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
        np.testing.assert_allclose(got[~np.isnan(got)], want[~np.isnan(want)], rtol=0, atol=1e-12)
    hits = ~np.isnan(np.concatenate([fast.left_m, fast.right_m]))
    assert 0.1 < hits.mean() < 0.95  # both echoes and dropouts are exercised


def test_no_poses_give_no_samples() -> None:
    world = World(load_scenario("apcs_corridor"))
    readings = SideSonars.apcs().sample_along(world, [], np.random.default_rng(0))
    assert readings.left_m.shape == readings.right_m.shape == (0,)
