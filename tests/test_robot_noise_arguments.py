"""The robot's kept ``noise`` array of the drive kernels against the array built anew each call
(:mod:`tests.noise_arguments_reference`), bit for bit, as the noise and the substep limits
change between calls."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.odometry import OdometryConfig
from sonar_gym.robot import DifferentialDriveRobot
from tests.noise_arguments_reference import noise_arguments_reference


def _same(robot: DifferentialDriveRobot) -> None:
    got, expected = robot._noise_arguments(), noise_arguments_reference(robot)
    assert got.dtype == expected.dtype and got.shape == expected.shape
    assert got.tobytes() == expected.tobytes()
    assert not got.flags.writeable  # shared between calls: nobody may write into it


def test_the_kept_array_follows_every_change_of_its_inputs() -> None:
    robot = DifferentialDriveRobot(OdometryConfig(slip_probability_per_m=0.3))
    _same(robot)
    assert robot._noise_arguments() is robot._noise_arguments()  # kept while nothing changes
    robot.noise = OdometryConfig(scale_error_left=0.01)
    _same(robot)
    robot.noise = OdometryConfig(scale_error_left=0.01)  # an equal config, another object
    _same(robot)
    robot.max_substep_m = 0.05
    _same(robot)
    robot.max_substep_rad = math.radians(1.0)
    _same(robot)
    robot.max_substep_m = 0.05 + 1e-17  # the same float
    _same(robot)
    robot.max_substep_m = np.nextafter(0.05, 1.0)
    _same(robot)


@pytest.mark.parametrize("seed", range(5))
def test_random_noise_and_limits_give_the_arrays_of_the_reference(seed: int) -> None:
    draw = np.random.default_rng(seed)
    robot = DifferentialDriveRobot()
    for _ in range(20):
        change = int(draw.integers(0, 4))
        if change == 1:
            robot.noise = OdometryConfig(*draw.uniform(0.0, 0.5, 5).tolist())
        elif change == 2:
            robot.max_substep_m = float(draw.uniform(0.001, 0.1))
        elif change == 3:
            robot.max_substep_rad = float(draw.uniform(0.001, 0.1))
        _same(robot)
