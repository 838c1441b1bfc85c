"""The drive to a point planned inside the compiled call
(:meth:`sonar_gym.robot.DifferentialDriveRobot.drive_to_and_predict`, with
:data:`sonar_gym.drive_kernels.move_commands`) against the plan of
:func:`sonar_gym.robot.move_commands` driven and predicted by
:func:`tests.drive_and_predict_reference.drive_and_predict_reference`: same commands,
motions, predictions, poses and generator state, bit for bit."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from hypothesis import given
from hypothesis import strategies as st

from sonar_gym import drive_kernels
from sonar_gym.pose import Pose
from sonar_gym.robot import move_commands
from tests.drive_and_predict_reference import drive_and_predict_reference
from tests.fuzzing import fuzz_settings
from tests.test_follow_route_kernels import _episode

WHEEL_BASE_M = 0.37

_coordinates = st.floats(-5.0, 5.0, allow_nan=False)


def _planned(belief: Pose, target: tuple[float, float], wheel_base_m: float) -> np.ndarray:
    distance = math.hypot(target[0] - belief.x, target[1] - belief.y)
    return drive_kernels.move_commands(  # type: ignore[no-any-return]
        (belief.x, belief.y, belief.theta), target, distance, wheel_base_m
    )


def _same_plan(belief: Pose, target: tuple[float, float], wheel_base_m: float) -> None:
    got = _planned(belief, target, wheel_base_m)
    expected = np.array(move_commands(belief, target, wheel_base_m), dtype=np.float64)
    assert got.shape == expected.shape
    assert got.tobytes() == expected.tobytes()


@fuzz_settings(300)
@given(
    x=_coordinates,
    y=_coordinates,
    theta=st.floats(-math.pi, math.pi),
    dx=_coordinates,
    dy=_coordinates,
    scale=st.sampled_from([1.0, 1e-3, 1e-9, 1e-10, 1e-12, 0.0]),
    wheel_base_m=st.floats(0.05, 1.0),
)
def test_the_compiled_plan_is_move_commands(
    x: float, y: float, theta: float, dx: float, dy: float, scale: float, wheel_base_m: float
) -> None:
    belief = Pose(x, y, theta)
    _same_plan(belief, (x + scale * dx, y + scale * dy), wheel_base_m)


@pytest.mark.parametrize(
    ("belief", "target"),
    [
        (Pose(0.0, 0.0, 0.0), (0.0, 0.0)),  # on the point
        (Pose(0.1, 0.2, 1.0), (0.1 + 1e-9, 0.2)),  # the 1 nm limit
        (Pose(0.1, 0.2, 1.0), (0.1 + 2e-9, 0.2)),
        (Pose(0.0, 0.0, math.pi), (-1.0, 0.0)),  # straight ahead at the wrap
        (Pose(0.0, 0.0, -3.0), (-1.0, -1e-17)),  # a turn across the wrap
        (Pose(0.0, 0.0, 3.0), (-1.0, 0.0)),
        (Pose(0.0, 0.0, 0.5), (-1.0, -0.0)),  # a bearing of -0 / pi
        (Pose(1.0, 1.0, -0.5), (1.0, 3.0)),  # straight up, dx = 0
    ],
)
def test_the_compiled_plan_is_move_commands_at_the_edges(
    belief: Pose, target: tuple[float, float]
) -> None:
    _same_plan(belief, target, WHEEL_BASE_M)


@pytest.mark.parametrize("seed", range(8))
def test_driving_to_a_point_is_driving_move_commands_plan(seed: int) -> None:
    """Targets anywhere in the room (through walls and obstacles, so some commands need
    pymunk), repeated ones and the estimate itself."""
    fast, reference = _episode(seed), _episode(seed)
    draw = np.random.default_rng(100 + seed)
    estimates = [Pose(-0.5, -0.2, 0.4)] * 2
    covariances = [np.diag([1e-4, 2e-4, 1e-3])] * 2
    targets = [tuple(point) for point in draw.uniform((-1.9, -1.4), (1.9, 1.4), (12, 2)).tolist()]
    targets[3] = targets[2]
    for target in targets:
        world, robot, rng = fast
        motions, estimates[0], covariances[0] = robot.drive_to_and_predict(
            world, target, rng, estimates[0], covariances[0], 2.5e-5
        )
        world, robot, rng = reference
        wheel_base = float(robot.wheel_base_for(world))
        plan = np.array(move_commands(estimates[1], target, wheel_base), dtype=np.float64)
        expected, estimates[1], covariances[1] = drive_and_predict_reference(
            robot, world, plan, rng, estimates[1], covariances[1], 2.5e-5
        )
        assert motions.tobytes() == expected.tobytes()
        assert estimates[0] == estimates[1]
        assert covariances[0].tobytes() == covariances[1].tobytes()
        assert fast[0].robot_pose == reference[0].robot_pose
        assert fast[1].odometry_pose == reference[1].odometry_pose
        assert fast[2].bit_generator.state == reference[2].bit_generator.state


def test_driving_to_a_point_takes_the_generators_numbers() -> None:
    world, robot, rng = _episode(0)
    twin = copy.deepcopy(rng)
    robot.drive_to_and_predict(world, (0.3, 0.1), rng, Pose(-0.5, -0.2, 0.4), np.eye(3), 1e-5)
    twin.standard_normal(2)
    twin.random(4)
    twin.standard_normal(2)
    twin.random(4)
    assert rng.bit_generator.state == twin.bit_generator.state
