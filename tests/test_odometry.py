"""Dead reckoning over whole commands (Kim et al. sec. 3.1) against step-by-step references."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym import drive_kernels
from sonar_gym.localization.ekf import predict, proportional_encoder_noise
from sonar_gym.odometry import (
    OdometryConfig,
    arc_displacements,
    integrate_substeps,
    predict_over_motion,
    predict_run,
    wheel_increment_covariance,
)
from sonar_gym.path_clearance import arc_is_clear
from sonar_gym.pose import Pose
from sonar_gym.robot import DifferentialDriveRobot, OdometryNoise, unicycle_step
from sonar_gym.scenario import scenario_from_dict
from sonar_gym.world import World

ROOM = scenario_from_dict(
    {
        "room": {"min": [-3.0, -3.0], "max": [3.0, 3.0]},
        "walls": [{"a": [1.0, -3.0], "b": [1.0, 0.5]}],
        "cylinders": [{"center": [-1.5, 1.5], "radius": 0.2}],
        "robot": {"radius": 0.2, "wheel_base": 0.4},
    }
)
COMMANDS = [(0.5, 0.5), (0.3, 0.45), (-0.2, 0.2), (0.8, -0.1), (0.0, 0.0), (-0.4, -0.35)]


def _stepwise(pose: Pose, left: float, right: float, base: float, n: int, integration: str) -> Pose:
    for _ in range(n):
        pose = unicycle_step(pose, left / n, right / n, base, integration)  # type: ignore[arg-type]
    return pose


@pytest.mark.parametrize("integration", ["euler", "midpoint", "arc"])
@pytest.mark.parametrize(("left", "right"), COMMANDS)
@pytest.mark.parametrize("n", [1, 7, 40])
def test_substeps_in_one_call_match_the_step_by_step_integration(
    integration: str, left: float, right: float, n: int
) -> None:
    start = Pose(0.3, -1.2, 2.9)
    fast = integrate_substeps(start, left, right, 0.4, n, integration)  # type: ignore[arg-type]
    slow = _stepwise(start, left, right, 0.4, n, integration)
    assert fast.x == pytest.approx(slow.x, abs=1e-12)
    assert fast.y == pytest.approx(slow.y, abs=1e-12)
    assert math.isclose(math.cos(fast.theta - slow.theta), 1.0, abs_tol=1e-15)


@pytest.mark.parametrize(("left", "right"), COMMANDS)
def test_arc_displacements_are_the_differences_of_points_on_the_arc(
    left: float, right: float
) -> None:
    start, n = Pose(-0.7, 0.4, -1.1), 12
    points = np.array(
        [
            unicycle_step(start, f * left, f * right, 0.4, "arc").as_array()
            for f in np.arange(n + 1) / n
        ]
    )
    expected = np.diff(points, axis=0)
    displacements = arc_displacements(start, left, right, 0.4, n)
    np.testing.assert_allclose(displacements[:, :2], expected[:, :2], atol=1e-14)
    np.testing.assert_allclose(displacements[:, 2], (right - left) / 0.4 / n, atol=1e-15)


@pytest.mark.parametrize("integration", ["paper", "midpoint"])
def test_prediction_over_a_motion_matches_the_ekf_step_by_step(integration: str) -> None:
    start = Pose(0.2, 0.1, 0.5)
    covariance = np.diag([1e-4, 2e-4, 3e-3])
    covariance[0, 1] = covariance[1, 0] = 5e-5
    pose, expected = start, covariance
    for left, right in COMMANDS:
        noise = np.diag([2e-5 * abs(right) + 4e-6 * right**2, 2e-5 * abs(left) + 4e-6 * left**2])
        pose, expected = predict(
            pose, expected, left, right, 0.4, encoder_noise=noise, integration=integration
        )  # type: ignore[arg-type]
    end, propagated, poses = predict_over_motion(
        start,
        covariance,
        COMMANDS,
        0.4,
        2e-5,
        4e-6,
        integration,  # type: ignore[arg-type]
    )
    assert len(poses) == len(COMMANDS) and poses[-1] == end
    assert (end.x, end.y, end.theta) == pytest.approx((pose.x, pose.y, pose.theta), abs=1e-15)
    np.testing.assert_allclose(propagated, expected, rtol=1e-13, atol=1e-18)


def test_one_wheel_covariance_model_covers_the_proportional_one() -> None:
    np.testing.assert_array_equal(
        wheel_increment_covariance(-0.3, 0.2, 1e-4), proportional_encoder_noise(-0.3, 0.2, 1e-4)
    )
    assert np.diag(wheel_increment_covariance(-0.3, 0.2, 0.0, 0.01)) == pytest.approx(
        [0.01 * 0.04, 0.01 * 0.09]
    )


def test_the_robot_noise_is_the_odometry_config() -> None:
    assert OdometryNoise is OdometryConfig
    with pytest.raises(ValueError, match="encoder_std_m_per_sqrt_m"):
        OdometryConfig(encoder_std_m_per_sqrt_m=-1.0)


def _drive_all(world: World, clear: bool | None, monkeypatch: pytest.MonkeyPatch) -> list:
    if clear is False:  # every command through pymunk: no arc counts as clear
        compiled = drive_kernels.drive_commands
        monkeypatch.setattr(drive_kernels, "drive_commands", lambda *args: (compiled(*args)[0], 0))
        monkeypatch.setattr(drive_kernels, "clear_arcs", lambda motions, first, *rest: first)
    robot = DifferentialDriveRobot(OdometryConfig(slip_probability_per_m=0.3))
    rng = np.random.default_rng(11)
    results = []
    for left, right in [*COMMANDS, (2.5, 2.5), (0.1, 1.2), (-3.0, -3.0), (1.0, 0.2)]:
        results.append(robot.drive(world, left, right, rng))
    monkeypatch.undo()
    return results


def test_free_motion_matches_the_physics_reference(monkeypatch: pytest.MonkeyPatch) -> None:
    fast_world, slow_world = World(ROOM), World(ROOM)
    fast_world.set_robot_pose(Pose(-0.5, -0.5, 0.3))
    slow_world.set_robot_pose(Pose(-0.5, -0.5, 0.3))
    fast = _drive_all(fast_world, None, monkeypatch)
    slow = _drive_all(slow_world, False, monkeypatch)
    assert any(r.collided for r in slow), "the route must also meet walls"
    for a, b in zip(fast, slow, strict=True):
        assert a.collided == b.collided
        assert a.odometry_pose == b.odometry_pose
        assert (a.true_pose.x, a.true_pose.y) == pytest.approx(
            (b.true_pose.x, b.true_pose.y), abs=1e-9
        )
        assert math.cos(a.true_pose.theta - b.true_pose.theta) == pytest.approx(1.0, abs=1e-15)
        assert a.distance_m == pytest.approx(b.distance_m, abs=1e-9)


def compiled_arc_is_clear(world: World, start: Pose, left: float, right: float) -> bool:
    """The compiled verdict of the arc of ``(left, right)`` from ``start`` (0.4 m base)."""
    end = integrate_substeps(start, left, right, 0.4, 1, "arc")
    return bool(
        arc_is_clear(
            start.x,
            start.y,
            end.x,
            end.y,
            left,
            right,
            0.4,
            world.robot_radius,
            *world.static_shape_table.arrays,
        )
    )


def test_a_path_into_a_wall_is_not_clear() -> None:
    world = World(ROOM)
    world.set_robot_pose(Pose(0.5, -1.0, 0.0))
    start = world.robot_pose
    assert not compiled_arc_is_clear(world, start, 0.5, 0.5)
    assert compiled_arc_is_clear(world, start, 0.2, 0.2)
    # turning in place next to the wall: clear only while the disc keeps its clearance
    world.set_robot_pose(Pose(0.79, -1.0, 0.0))
    assert compiled_arc_is_clear(world, world.robot_pose, -0.1, 0.1)
    world.set_robot_pose(Pose(0.7995, -1.0, 0.0))
    assert not compiled_arc_is_clear(world, world.robot_pose, -0.1, 0.1)


def test_covariance_linearised_at_given_poses_matches_the_ekf_per_command() -> None:
    from sonar_gym.odometry import propagate_covariance

    poses = [Pose(0.1 * k, -0.2 * k, 0.3 * k) for k in range(len(COMMANDS))]
    expected = np.diag([1e-4, 1e-4, 1e-3])
    for pose, (left, right) in zip(poses, COMMANDS, strict=True):
        noise = np.diag([3e-5 * abs(right) + 1e-6 * right**2, 3e-5 * abs(left) + 1e-6 * left**2])
        _, expected = predict(
            pose, expected, left, right, 0.4, encoder_noise=noise, integration="midpoint"
        )
    propagated = propagate_covariance(
        poses, COMMANDS, np.diag([1e-4, 1e-4, 1e-3]), 0.4, 3e-5, 1e-6, "midpoint"
    )
    np.testing.assert_allclose(propagated, expected, rtol=1e-13, atol=1e-18)


@pytest.mark.parametrize("count", [1, 5, 250])
def test_the_run_prediction_in_closed_form_matches_the_per_command_prediction(count: int) -> None:
    rng = np.random.default_rng(100 + count)
    left = 0.02 + rng.normal(0.0, 0.003, count)
    right = 0.02 + rng.normal(0.0, 0.003, count)
    spins = rng.random(count) < 0.25  # turns in place among the straight steps
    left[spins], right[spins] = -0.05, 0.05
    start = Pose(-0.5, 2.0, -3.0)  # near -pi: the heading wraps on the way
    covariance = np.array([[2e-4, 1e-5, 3e-6], [1e-5, 1e-4, -1e-6], [3e-6, -1e-6, 4e-5]])
    poses, covariances = predict_run(start, covariance, left, right, 0.25, 2e-6)
    end, end_covariance, reference = predict_over_motion(
        start, covariance, np.stack([left, right], axis=1), 0.25, 2e-6, integration="midpoint"
    )
    for row, pose in zip(poses[1:], reference, strict=True):
        assert row[:2] == pytest.approx(pose.position, abs=1e-12)
        assert math.remainder(row[2] - pose.theta, 2 * math.pi) == pytest.approx(0.0, abs=1e-12)
    assert (poses[-1, 0], poses[-1, 1]) == pytest.approx((end.x, end.y), abs=1e-12)
    np.testing.assert_allclose(covariances[-1], end_covariance, rtol=1e-9, atol=1e-18)


@pytest.mark.parametrize("commanded", [0.3, -0.05, 0.0, 2.5])
def test_one_wheel_in_floats_rolls_and_reports_as_the_same_wheel_in_an_array(
    commanded: float,
) -> None:
    config = OdometryNoise(0.005, 0.01, -0.01, 0.5, 0.3)
    rng = np.random.default_rng(3)
    for slip_draw, size_draw in rng.random((50, 2)).tolist():
        alone = config.ground_travel(commanded, 0.01, slip_draw, size_draw)
        many = config.ground_travel(
            np.array([commanded]), np.array([0.01]), np.array([slip_draw]), np.array([size_draw])
        )
        assert isinstance(alone, float)
        assert alone == float(many[0])
        reported = config.encoder_increments(commanded, slip_draw - 0.5)
        reported_many = config.encoder_increments(
            np.array([commanded]), np.array([slip_draw - 0.5])
        )
        assert reported == float(reported_many[0])
