""":func:`sonar_gym.polyline.follow_route` (each target's plan, drive and EKF prediction in
one compiled call, :func:`sonar_gym.drive_kernels.drive_to_and_predict`) against the public
robot and odometry calls it replaced (:mod:`tests.follow_route_reference`), bit for bit."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from sonar_gym import drive_kernels, odometry_kernels
from sonar_gym.odometry import OdometryConfig
from sonar_gym.polyline import Route, follow_route
from sonar_gym.pose import Pose
from sonar_gym.robot import DifferentialDriveRobot, _command_draws, move_commands
from sonar_gym.world import World
from tests.command_draws_reference import command_draws_reference
from tests.follow_route_reference import follow_route_reference
from tests.test_generator_handles import BIT_GENERATORS, _same_state
from tests.test_drive_command_kernels import ROOM


def _episode(seed: int) -> tuple[World, DifferentialDriveRobot, np.random.Generator]:
    world = World(ROOM)
    world.set_robot_pose(Pose(-0.5, -0.2, 0.4))
    robot = DifferentialDriveRobot(
        OdometryConfig(slip_probability_per_m=0.3, scale_error_left=0.01),
        odometry_pose=Pose(-0.48, -0.21, 0.38) if seed % 2 else None,
    )
    return world, robot, np.random.default_rng(seed)


@pytest.mark.parametrize("seed", range(12))
def test_following_a_route_is_the_plan_drive_and_prediction_of_each_target(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    moves = 0
    move_robot = World.move_robot

    def counted_move(world: World, *args: object) -> object:
        nonlocal moves
        moves += 1
        return move_robot(world, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(World, "move_robot", counted_move)
    draw = np.random.default_rng(100 + seed)
    # corners anywhere in the room (through walls and obstacles, so some commands need pymunk),
    # a repeated one (a target the estimate already stands on) and the start itself
    corners = draw.uniform((-1.9, -1.4), (1.9, 1.4), (6, 2))
    corners = np.vstack([[(-0.5, -0.2)], corners[:3], corners[2:3], corners[3:]])
    route = Route.through(corners)
    fast, reference = _episode(seed), _episode(seed)
    estimates = [Pose(-0.5, -0.2, 0.4)] * 2
    covariances = [np.diag([1e-4, 2e-4, 1e-3])] * 2
    stations = np.sort(draw.uniform(0.0, route.length_m + 0.5, 8)).tolist()
    for start, stop in zip([0.0, *stations], stations, strict=False):
        legs = []
        for index, ((world, robot, rng), follow) in enumerate(
            zip((fast, reference), (follow_route, follow_route_reference), strict=True)
        ):
            leg = follow(
                robot,
                world,
                route,
                (start, stop),
                estimates[index],
                covariances[index],
                2.5e-5,
                rng,
            )
            estimates[index], covariances[index] = leg.estimate, leg.covariance
            legs.append(leg)
        assert legs[0].estimate == legs[1].estimate
        assert np.array_equal(legs[0].covariance, legs[1].covariance)
        assert legs[0].rolled_m == legs[1].rolled_m
        assert fast[0].robot_pose == reference[0].robot_pose
        assert fast[1].odometry_pose == reference[1].odometry_pose
        assert fast[2].bit_generator.state == reference[2].bit_generator.state
    assert moves > 0, "some commands must go through pymunk"


@pytest.mark.parametrize("seed", range(5))
def test_the_fused_call_is_the_plan_the_drive_then_the_prediction(seed: int) -> None:
    """The one compiled call plans the commands of :func:`sonar_gym.robot.move_commands`,
    draws their numbers from the caller's generator (as ``_command_draws`` draws them from a
    copy), drives as the draws-taking loop does and predicts as
    :func:`~sonar_gym.odometry_kernels.predict_commands` does."""
    setup = np.random.default_rng(seed)
    noise = np.array([0.005, 0.01, -0.002, 0.3, 0.2, 0.02, math.radians(3.0)])
    world = World(ROOM)
    common = (
        noise,
        0.37,
        0,
        1,
        tuple(setup.uniform(-1.0, 1.0, 3).tolist()),
        (-0.5, -0.2, 0.4),
        world.robot_radius,
        *world.static_shape_table.arrays,
    )
    estimate = tuple(setup.uniform(-1.0, 1.0, 3).tolist())
    # a point ahead, or (seed 0) the estimate itself: one command of no travel
    target = estimate[:2] if seed == 0 else tuple(setup.uniform(-1.5, 1.5, 2).tolist())
    distance = math.hypot(target[0] - estimate[0], target[1] - estimate[1])
    root = setup.standard_normal((3, 3))
    covariance = root @ root.T
    rng = np.random.default_rng(100 + seed)
    rng.random(seed)  # somewhere along the stream
    twin = copy.deepcopy(rng)
    motions, blocked, end, predicted_covariance = drive_kernels.drive_to_and_predict(
        rng, target, distance, *common, estimate, covariance, 3e-5
    )
    commands = np.array(move_commands(Pose(*estimate), target, 0.37), dtype=np.float64)
    draws = _command_draws(twin, len(commands))
    assert rng.bit_generator.state == twin.bit_generator.state
    expected_motions, expected_blocked = drive_kernels.drive_commands(commands, draws, *common)
    poses, expected_covariance = odometry_kernels.predict_commands(
        estimate, covariance, expected_motions[:, :2], 0.37, 3e-5, 0.0, False
    )
    assert blocked == expected_blocked
    # the true poses and path lengths of the commands from the blocked one on are not written
    written = drive_kernels.TRUE_POSE
    assert np.array_equal(motions[:, :written], expected_motions[:, :written])
    assert np.array_equal(motions[:blocked], expected_motions[:blocked])
    assert end == tuple(poses[-1].tolist())
    assert np.array_equal(predicted_covariance, expected_covariance)


@pytest.mark.parametrize("kind", [*BIT_GENERATORS, np.random.MT19937])
@pytest.mark.parametrize("count", [0, 1, 2, 9, 300])
def test_a_compiled_run_of_draws_is_the_draws_of_drive(
    kind: type[np.random.BitGenerator], count: int
) -> None:
    """The compiled loop's numbers, in its flat layout, and the generator state after them
    are those of ``_command_draws`` (kept as the robot's draws of a run), bit for bit."""
    rng, expected_rng = np.random.Generator(kind(count)), np.random.Generator(kind(count))
    for _ in range(3):  # and again from where the last run left the generator
        draws = np.empty(6 * count)
        drive_kernels._draw_run_compiled(rng, draws)
        assert draws.tobytes() == _command_draws(expected_rng, count).tobytes()
        assert _same_state(rng.bit_generator.state, expected_rng.bit_generator.state)


def test_the_draws_of_a_run_are_drives_draws_in_its_order() -> None:
    fast, reference = np.random.default_rng(7), np.random.default_rng(7)
    for count in (1, 2, 3, 50):
        expected = np.concatenate(
            [
                reference.standard_normal(2) if slot % 2 == 0 else reference.random(4)
                for slot in range(2 * count)
            ]
        )
        assert np.array_equal(_command_draws(fast, count), expected)
        assert fast.bit_generator.state == reference.bit_generator.state


@pytest.mark.parametrize("count", [1, 2, 3, 7])
def test_the_draws_have_the_bits_of_the_table_form(count: int) -> None:
    fast, reference = np.random.default_rng(count), np.random.default_rng(count)
    for _ in range(5):
        got, expected = _command_draws(fast, count), command_draws_reference(reference, count)
        assert got.shape == expected.shape == (6 * count,)
        assert got.flags.c_contiguous
        assert got.tobytes() == expected.tobytes()
        assert fast.bit_generator.state == reference.bit_generator.state
