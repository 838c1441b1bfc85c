"""Differential-drive kinematics (Kim et al. sec. 3.1), odometry noise, slip, collisions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.pose import Pose
from sonar_gym.robot import DifferentialDriveRobot, MotionResult, OdometryNoise, unicycle_step
from sonar_gym.scenario import scenario_from_dict
from sonar_gym.world import World

OPEN_ROOM = scenario_from_dict(
    {"room": {"min": [-5.0, -5.0], "max": [5.0, 5.0]}, "robot": {"radius": 0.2, "wheel_base": 0.4}}
)
WALLED = scenario_from_dict(
    {
        "room": {"min": [-2.0, -2.0], "max": [2.0, 2.0]},
        "walls": [{"a": [1.0, -2.0], "b": [1.0, 2.0]}],
        "robot": {"radius": 0.2, "wheel_base": 0.4},
    }
)
NOISELESS = OdometryNoise.none()


def rng(seed: int = 0) -> np.random.Generator:
    return np.random.default_rng(seed)


# --- unicycle_step -------------------------------------------------------------------------


@pytest.mark.parametrize("integration", ["euler", "midpoint", "arc"])
def test_straight_move_is_exact_in_every_integration(integration: str) -> None:
    pose = Pose(1.0, -2.0, 0.7)
    moved = unicycle_step(pose, 0.5, 0.5, 0.4, integration)  # type: ignore[arg-type]
    assert moved.x == pytest.approx(1.0 + 0.5 * math.cos(0.7), abs=1e-12)
    assert moved.y == pytest.approx(-2.0 + 0.5 * math.sin(0.7), abs=1e-12)
    assert moved.theta == pytest.approx(0.7, abs=1e-15)


@pytest.mark.parametrize("integration", ["euler", "midpoint", "arc"])
def test_turn_in_place_divides_by_the_wheel_base(integration: str) -> None:
    """Kim et al. print T/1 in F(k); the heading change is (d_r - d_l)/l, l the wheel base."""
    moved = unicycle_step(Pose(0.0, 0.0, 0.0), -0.05, 0.05, 0.4, integration)  # type: ignore[arg-type]
    assert moved.theta == pytest.approx(0.25, abs=1e-15)  # the literal "/1" would give 0.1
    assert (moved.x, moved.y) == (0.0, 0.0)


def test_euler_is_the_printed_model() -> None:
    """x(k+1) = x(k) + T (u_r + u_l)/2 cos(theta(k)), theta(k+1) = theta(k) + T (u_r - u_l)/l."""
    pose = Pose(0.3, 0.1, 0.2)
    d_left, d_right, wheel_base = 0.10, 0.16, 0.4
    moved = unicycle_step(pose, d_left, d_right, wheel_base, "euler")
    assert moved.x == pytest.approx(0.3 + 0.13 * math.cos(0.2), abs=1e-15)
    assert moved.y == pytest.approx(0.1 + 0.13 * math.sin(0.2), abs=1e-15)
    assert moved.theta == pytest.approx(0.2 + 0.06 / 0.4, abs=1e-15)


def test_midpoint_uses_the_mean_heading() -> None:
    pose = Pose(0.0, 0.0, 0.4)
    moved = unicycle_step(pose, 0.1, 0.3, 0.5, "midpoint")
    dtheta = 0.2 / 0.5
    assert moved.x == pytest.approx(0.2 * math.cos(0.4 + dtheta / 2), abs=1e-15)
    assert moved.y == pytest.approx(0.2 * math.sin(0.4 + dtheta / 2), abs=1e-15)


@settings(max_examples=60, deadline=None)
@given(
    d_left=st.floats(-1.0, 1.0),
    d_right=st.floats(-1.0, 1.0),
    theta=st.floats(-3.0, 3.0),
)
def test_arc_lies_on_the_instantaneous_centre_of_rotation_circle(
    d_left: float, d_right: float, theta: float
) -> None:
    wheel_base = 0.4
    if abs(d_right - d_left) < 1e-3:
        return
    start = Pose(0.5, -0.2, theta)
    moved = unicycle_step(start, d_left, d_right, wheel_base, "arc")
    radius = wheel_base / 2 * (d_right + d_left) / (d_right - d_left)  # signed, to the left
    centre = np.array([start.x - radius * math.sin(theta), start.y + radius * math.cos(theta)])
    angle = (d_right - d_left) / wheel_base
    expected = centre + radius * np.array([math.sin(theta + angle), -math.cos(theta + angle)])
    assert moved.x == pytest.approx(expected[0], abs=1e-9)
    assert moved.y == pytest.approx(expected[1], abs=1e-9)


def test_arc_composes_exactly() -> None:
    start = Pose(0.0, 0.0, 0.3)
    whole = unicycle_step(start, 0.4, 0.9, 0.4, "arc")
    halves = unicycle_step(unicycle_step(start, 0.2, 0.45, 0.4, "arc"), 0.2, 0.45, 0.4, "arc")
    assert halves.as_array() == pytest.approx(whole.as_array(), abs=1e-12)


def test_unicycle_step_rejects_bad_arguments() -> None:
    with pytest.raises(ValueError, match="wheel_base_m"):
        unicycle_step(Pose(0, 0), 0.1, 0.1, 0.0)
    with pytest.raises(ValueError, match="integration"):
        unicycle_step(Pose(0, 0), 0.1, 0.1, 0.4, "rk4")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="finite"):
        unicycle_step(Pose(0, 0), math.nan, 0.1, 0.4)


# --- OdometryNoise -------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("encoder_std_m_per_sqrt_m", -0.1),
        ("scale_error_left", 0.6),
        ("scale_error_right", math.nan),
        ("slip_probability_per_m", 1.5),
        ("slip_fraction_max", -0.1),
    ],
)
def test_odometry_noise_validation_names_the_field(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        OdometryNoise(**{field: value})


def test_default_noise_is_small_but_present() -> None:
    noise = OdometryNoise()
    assert 0.0 < noise.encoder_std_m_per_sqrt_m <= 0.02
    assert abs(noise.scale_error_left) <= 0.01 and abs(noise.scale_error_right) <= 0.01
    assert 0.0 < noise.slip_probability_per_m < 0.1


# --- DifferentialDriveRobot.drive -----------------------------------------------------------


@pytest.mark.parametrize(
    ("d_left", "d_right"), [(0.6, 0.6), (-0.4, -0.4), (-0.1, 0.1), (0.3, 0.8), (0.9, -0.2)]
)
def test_noise_free_drive_matches_the_arc_model(d_left: float, d_right: float) -> None:
    world = World(OPEN_ROOM, robot_pose=Pose(0.4, -0.3, 1.1))
    robot = DifferentialDriveRobot(NOISELESS, odometry_integration="arc")
    result = robot.drive(world, d_left, d_right, rng())
    expected = unicycle_step(Pose(0.4, -0.3, 1.1), d_left, d_right, 0.4, "arc")
    assert not result.collided
    assert result.true_pose.as_array() == pytest.approx(expected.as_array(), abs=1e-12)
    assert result.odometry_pose.as_array() == pytest.approx(expected.as_array(), abs=1e-12)
    assert world.robot_pose == result.true_pose
    assert (result.encoder_left_m, result.encoder_right_m) == (d_left, d_right)


@pytest.mark.parametrize(("d_left", "d_right"), [(0.6, 0.6), (-0.1, 0.1)])
def test_noise_free_straight_and_turn_match_the_midpoint_model(
    d_left: float, d_right: float
) -> None:
    world = World(OPEN_ROOM)
    robot = DifferentialDriveRobot(NOISELESS)
    result = robot.drive(world, d_left, d_right, rng())
    expected = unicycle_step(Pose(0.0, 0.0, 0.0), d_left, d_right, 0.4, "midpoint")
    assert result.true_pose.as_array() == pytest.approx(expected.as_array(), abs=1e-12)
    assert result.odometry_pose.as_array() == pytest.approx(expected.as_array(), abs=1e-12)


def test_distance_is_the_path_length_of_the_centre() -> None:
    world = World(OPEN_ROOM)
    robot = DifferentialDriveRobot(NOISELESS)
    assert robot.drive(world, 0.5, 0.5, rng()).distance_m == pytest.approx(0.5, rel=1e-9)
    assert robot.drive(world, -0.2, 0.2, rng()).distance_m == pytest.approx(0.0, abs=1e-12)
    arc = robot.drive(world, 0.3, 0.5, rng())  # centre arc length (d_l + d_r)/2
    assert arc.distance_m == pytest.approx(0.4, rel=1e-4)


def test_the_robot_cannot_pass_through_a_wall() -> None:
    world = World(WALLED, robot_pose=Pose(0.0, 0.0, 0.0))
    robot = DifferentialDriveRobot(NOISELESS)
    result = robot.drive(world, 3.0, 3.0, rng())
    assert result.collided
    # Stopped by the wall at x = 1: the centre stays a robot radius short of it.
    assert result.true_pose.x == pytest.approx(1.0 - 0.2, abs=1e-5)
    assert result.true_pose.y == pytest.approx(0.0, abs=1e-12)
    assert world.is_free(result.true_pose.position)
    # The encoders turned the whole time: odometry believes the robot went 3 m.
    assert result.odometry_pose.x == pytest.approx(3.0, abs=1e-12)
    assert result.distance_m == pytest.approx(0.8, abs=1e-5)


def test_a_thin_wall_stops_a_fast_long_command() -> None:
    world = World(WALLED, robot_pose=Pose(-1.5, 0.0, 0.0))
    robot = DifferentialDriveRobot(NOISELESS, max_substep_m=0.15)
    result = robot.drive(world, 10.0, 10.0, rng())
    assert result.collided
    assert result.true_pose.x < 1.0 - 0.2 + 1e-5


@settings(max_examples=30, deadline=None)
@given(heading=st.floats(-math.pi, math.pi), seed=st.integers(0, 1000))
def test_driving_into_walls_keeps_the_robot_inside(heading: float, seed: int) -> None:
    world = World(WALLED, robot_pose=Pose(0.0, 0.5, heading))
    robot = DifferentialDriveRobot(OdometryNoise(slip_probability_per_m=0.0))
    result = robot.drive(world, 5.0, 5.3, np.random.default_rng(seed))  # a 5 m arc cannot fit
    x, y = result.true_pose.x, result.true_pose.y
    assert -2.0 + 0.2 - 1e-5 <= x <= 1.0 - 0.2 + 1e-5
    assert -2.0 + 0.2 - 1e-5 <= y <= 2.0 - 0.2 + 1e-5
    assert result.collided


def test_driving_along_a_wall_slides_without_turning() -> None:
    world = World(WALLED, robot_pose=Pose(0.5, 0.0, math.radians(45.0)))
    robot = DifferentialDriveRobot(NOISELESS)
    result = robot.drive(world, 1.0, 1.0, rng())
    assert result.collided
    assert result.true_pose.theta == pytest.approx(math.radians(45.0), abs=1e-12)
    assert result.true_pose.x == pytest.approx(0.8, abs=1e-5)
    # The component along the wall survives: y advanced by about sin(45 deg) per metre.
    assert result.true_pose.y == pytest.approx(math.sqrt(0.5), abs=1e-5)


def test_a_robot_touching_a_wall_can_turn_and_leave() -> None:
    world = World(WALLED, robot_pose=Pose(0.8, 0.0, 0.0))
    robot = DifferentialDriveRobot(NOISELESS)
    turned = robot.turn(world, math.pi, rng())
    assert not turned.collided
    left = robot.drive_straight(world, 0.5, rng())
    assert not left.collided
    assert left.true_pose.x == pytest.approx(0.3, abs=1e-9)


def test_odometry_does_not_drift_without_noise() -> None:
    world = World(OPEN_ROOM)
    robot = DifferentialDriveRobot(NOISELESS)
    generator = rng(3)
    for _ in range(20):
        result = robot.move_to(
            world, Pose(*generator.uniform(-3, 3, 2), generator.uniform(-3, 3)), generator
        )
        assert result.odometry_pose.as_array() == pytest.approx(
            result.true_pose.as_array(), abs=1e-9
        )


def test_odometry_drifts_under_noise() -> None:
    world = World(OPEN_ROOM)
    robot = DifferentialDriveRobot(
        OdometryNoise(encoder_std_m_per_sqrt_m=0.01, slip_probability_per_m=0.0)
    )
    generator = rng(4)
    errors = []
    for _ in range(10):
        robot.drive_straight(world, 1.0, generator)
        result = robot.turn(world, math.pi / 2, generator)
        errors.append(
            np.hypot(
                result.odometry_pose.x - result.true_pose.x,
                result.odometry_pose.y - result.true_pose.y,
            )
        )
    assert errors[-1] > 1e-3
    assert all(e > 0 for e in errors)


def test_encoder_noise_has_the_documented_spread() -> None:
    """Encoder increment error ~ N(0, std^2 |d|): its spread after 4 m is 2 std."""
    world = World(OPEN_ROOM)
    noise = OdometryNoise(0.01, 0.0, 0.0, 0.0, 0.0)
    generator = rng(5)
    deviations = []
    for _ in range(400):
        robot = DifferentialDriveRobot(noise)
        result = robot.drive(world, 4.0, 4.0, generator, substeps=1)
        deviations.append(result.encoder_left_m - 4.0)
        world.set_robot_pose(Pose(0.0, 0.0, 0.0))
    assert np.std(deviations) == pytest.approx(0.02, rel=0.15)
    assert abs(np.mean(deviations)) < 0.004


def test_slip_affects_truth_not_odometry() -> None:
    world = World(OPEN_ROOM)
    noise = OdometryNoise(0.0, 0.0, 0.0, slip_probability_per_m=1.0, slip_fraction_max=0.5)
    robot = DifferentialDriveRobot(noise)
    result = robot.drive(world, 1.0, 1.0, rng(6))
    assert result.odometry_pose.as_array() == pytest.approx([1.0, 0.0, 0.0], abs=1e-12)
    assert not result.collided
    travelled = math.hypot(result.true_pose.x, result.true_pose.y)
    assert 0.5 - 1e-9 <= travelled < 1.0
    assert result.true_pose != result.odometry_pose


def test_scale_error_curves_the_true_path_only() -> None:
    world = World(OPEN_ROOM)
    noise = OdometryNoise(
        0.0,
        scale_error_left=0.0,
        scale_error_right=0.01,
        slip_probability_per_m=0.0,
        slip_fraction_max=0.0,
    )
    robot = DifferentialDriveRobot(noise)
    result = robot.drive(world, 1.0, 1.0, rng())
    assert result.odometry_pose.theta == 0.0
    assert result.true_pose.theta == pytest.approx(0.01 / 0.4, abs=1e-12)  # (d_r - d_l)/l


def test_drive_is_deterministic() -> None:
    outcomes = []
    for _ in range(2):
        world = World(WALLED, robot_pose=Pose(-1.0, 0.3, 0.2))
        robot = DifferentialDriveRobot(OdometryNoise(slip_probability_per_m=0.5))
        generator = rng(9)
        outcomes.append(
            [
                robot.drive(world, 1.5, 1.7, generator),
                robot.turn(world, 2.0, generator),
                robot.drive_straight(world, 3.0, generator),
            ]
        )
    assert outcomes[0] == outcomes[1]
    assert any(r.collided for r in outcomes[0])


def test_drive_draws_a_fixed_number_of_variates() -> None:
    world = World(OPEN_ROOM)
    a, b = rng(10), rng(10)
    DifferentialDriveRobot(NOISELESS).drive(world, 0.1, 0.2, a)
    DifferentialDriveRobot(OdometryNoise()).drive(world, 0.3, 0.0, b)
    assert a.random() == b.random()


@pytest.mark.parametrize(
    "setting, value",
    [("noise", OdometryNoise(scale_error_left=0.05)), ("max_substep_m", 0.001)],
)
def test_a_replaced_noise_or_substep_limit_takes_effect_at_the_next_drive(
    setting: str, value: object
) -> None:
    used = DifferentialDriveRobot(NOISELESS)
    used.drive(World(OPEN_ROOM), 0.3, 0.2, rng(3))  # drives under the old setting first
    fresh = DifferentialDriveRobot(NOISELESS)
    outcomes = []
    for robot in (used, fresh):
        setattr(robot, setting, value)
        robot.reset_odometry(Pose(0.1, 0.0, 0.2))
        world = World(OPEN_ROOM, robot_pose=Pose(0.1, 0.0, 0.2))
        outcomes.append(robot.drive(world, 0.4, 0.6, rng(4)))
    unchanged = DifferentialDriveRobot(NOISELESS, odometry_pose=Pose(0.1, 0.0, 0.2))
    before = unchanged.drive(World(OPEN_ROOM, robot_pose=Pose(0.1, 0.0, 0.2)), 0.4, 0.6, rng(4))
    assert outcomes[0] == outcomes[1]
    if setting == "noise":
        assert outcomes[0].true_pose != before.true_pose


def test_move_to_reaches_the_target_without_noise() -> None:
    world = World(OPEN_ROOM)
    robot = DifferentialDriveRobot(NOISELESS)
    target = Pose(1.5, -2.0, 2.0)
    result = robot.move_to(world, target, rng())
    assert isinstance(result, MotionResult) and len(result.parts) == 3
    assert result.true_pose.as_array() == pytest.approx(target.as_array(), abs=1e-9)
    assert result.distance_m == pytest.approx(math.hypot(1.5, 2.0), rel=1e-9)
    position_only = robot.move_to(world, (0.0, 0.0), rng())
    assert len(position_only.parts) == 2
    assert (position_only.true_pose.x, position_only.true_pose.y) == pytest.approx(
        (0.0, 0.0), abs=1e-9
    )


def test_move_to_plans_from_the_odometry_belief() -> None:
    world = World(OPEN_ROOM)
    robot = DifferentialDriveRobot(
        NOISELESS, odometry_pose=Pose(0.5, 0.0, 0.0)
    )  # believes it is 0.5 m ahead
    result = robot.move_to(world, (1.0, 0.0), rng())
    assert result.odometry_pose.x == pytest.approx(1.0, abs=1e-12)
    assert result.true_pose.x == pytest.approx(0.5, abs=1e-12)


def test_reset_odometry_sets_the_estimate() -> None:
    world = World(OPEN_ROOM)
    robot = DifferentialDriveRobot(NOISELESS)
    robot.reset_odometry(Pose(1.0, 1.0, 0.0))
    result = robot.drive_straight(world, 0.5, rng())
    assert result.odometry_pose.as_array() == pytest.approx([1.5, 1.0, 0.0], abs=1e-12)
    robot.reset_odometry(None)
    assert robot.drive_straight(world, 0.1, rng()).odometry_pose.x == pytest.approx(0.6, abs=1e-12)


def test_wheel_base_defaults_to_the_scenario() -> None:
    world = World(OPEN_ROOM)
    assert DifferentialDriveRobot().wheel_base_for(world) == 0.4
    assert DifferentialDriveRobot(wheel_base_m=0.3).wheel_base_for(world) == 0.3


def test_drive_rejects_bad_arguments() -> None:
    world = World(OPEN_ROOM)
    robot = DifferentialDriveRobot()
    with pytest.raises(ValueError, match="finite"):
        robot.drive(world, math.inf, 0.0, rng())
    with pytest.raises(ValueError, match="rng"):
        robot.drive(world, 0.1, 0.1, 42)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="substeps"):
        robot.drive(world, 0.1, 0.1, rng(), substeps=0)
    with pytest.raises(ValueError, match="odometry_integration"):
        DifferentialDriveRobot(odometry_integration="rk4")  # type: ignore[arg-type]


def test_every_drive_without_contact_ends_with_the_robot_free_in_a_cluttered_arena() -> None:
    from sonar_gym.scenario import load_scenario

    world = World(load_scenario("kim_arena"))
    robot = DifferentialDriveRobot(OdometryNoise())
    rng = np.random.default_rng(3)
    free_ends = 0
    for _ in range(60):
        world.set_robot_pose(world.sample_free_pose(rng))
        for _ in range(10):
            d_left, d_right = rng.uniform(-0.4, 0.4, 2)
            motion = robot.drive(world, d_left, d_right, rng)
            assert motion.true_pose == world.robot_pose
            if not motion.collided:
                free_ends += 1
                assert world.is_free(motion.true_pose.position)
    assert free_ends > 300
