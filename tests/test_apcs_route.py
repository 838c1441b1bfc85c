"""The batched motion and side-sonar paths of an APCS route against their per-command references."""

from __future__ import annotations

import dataclasses
import math
import tomllib

import numpy as np
import pytest

from sonar_gym.apcs_route import LegCommand, check_route_clearance, with_wall_obstacles
from sonar_gym.maps import map_ahead_features, map_wall_vectors
from sonar_gym.pose import Pose
from sonar_gym.robot import DifferentialDriveRobot, OdometryNoise
from sonar_gym.scenario import Scenario, load_scenario, scenario_from_dict
from sonar_gym.sonar.presets import preset
from sonar_gym.sonar.swept import SideSonars
from sonar_gym.straight_drive import drive_straight_run, turn_run
from sonar_gym.straight_drive_kernels import clearance
from sonar_gym.world import World
from tests.wall_obstacles_reference import reference_with_wall_obstacles

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


def _straight_corridor(half_width_m: float, boxes: str = "") -> Scenario:
    return scenario_from_dict(
        tomllib.loads(
            f"[room]\nmin = [0.0, {-half_width_m}]\nmax = [10.0, {half_width_m}]\n\n{boxes}"
            "[robot]\nradius = 0.2\nwheel_base = 0.3\n"
        ),
        default_name="straight_corridor",
    )


def test_a_straight_corridor_faces_every_leg_with_one_wall_each_side() -> None:
    scenario = _straight_corridor(1.0)
    legs = np.array([1.0, 3.0, 5.0])
    features = map_ahead_features(map_wall_vectors(scenario), legs, 2.0, 0.25, 0.02, 5.0)
    assert features.shape == (2, 4)
    # one wall runs along each whole leg: full continuity; the walls are 0.75 and 1.25 m away
    np.testing.assert_allclose(features[:, [0, 2]], 1.0, atol=0.011)
    np.testing.assert_allclose(features[:, 1], 0.75 / 5.0)
    np.testing.assert_allclose(features[:, 3], 1.25 / 5.0)


def test_route_clearance_names_the_stand_off_that_meets_a_mapped_box() -> None:
    box = "[[boxes]]\ncenter = [5.0, 0.8]\nsize = [0.4, 0.4]\nmapped = true\n\n"
    check_route_clearance(_straight_corridor(1.0), (0.5, 9.5), 0.0, (-0.4, 0.0, 0.4), 0.05)
    with pytest.raises(ValueError, match=r"'standoffs_m': 0.4 m"):
        check_route_clearance(_straight_corridor(1.0, box), (0.5, 9.5), 0.0, (-0.4, 0.0, 0.4), 0.05)
    unmapped = box.replace("mapped = true", "mapped = false")
    check_route_clearance(_straight_corridor(1.0, unmapped), (0.5, 9.5), 0.0, (0.4,), 0.05)


def test_apcs_side_sonars_take_the_given_timing_jitter_and_keep_the_rest_of_the_preset() -> None:
    ma40b8 = preset("ma40b8")
    sonars = SideSonars.apcs(range_noise_std_m=0.002, lateral_offset_m=0.1)
    assert sonars.transducer.range_noise_std_m == 0.002
    assert dataclasses.replace(sonars.transducer, range_noise_std_m=ma40b8.range_noise_std_m) == (
        ma40b8
    )
    assert sonars.lateral_offset_m == 0.1
    assert SideSonars.apcs().transducer == ma40b8


def test_a_leg_command_runs_the_sonars_it_names() -> None:
    assert LegCommand("none", 3, 0.0).active_sides == ()
    assert LegCommand("left", 3, 0.0).active_sides == ("left",)
    assert LegCommand("right", 6, 0.2).active_sides == ("right",)
    assert LegCommand("both", 9, -0.2).active_sides == ("left", "right")


@pytest.mark.parametrize("within_m", [0.05, 0.3, 1.0])
def test_clearance_within_a_bound_is_exact_up_to_it_and_above_it_beyond(within_m: float) -> None:
    world = World(load_scenario("beom_cho_lab"))  # segments and cylinders
    assert world.geometry.n_segments and world.geometry.n_circles
    rng = np.random.default_rng(7)
    for _ in range(30):
        start = world.sample_free_pose(rng).position
        path = start + np.cumsum(rng.normal(0.0, 0.05, (40, 2)), axis=0)
        geometry = world.geometry
        shapes = (geometry.segment_starts, geometry.segment_ends, geometry.circles)
        exact = clearance(path, math.inf, *shapes)
        bounded = clearance(path, within_m, *shapes)
        close = exact <= within_m
        np.testing.assert_array_equal(bounded[close], exact[close])
        assert np.all(bounded[~close] > within_m)


@pytest.mark.parametrize("name", ["apcs_corridor", "beom_cho_lab", "kim_arena"])
def test_wall_obstacles_are_drawn_as_the_reference_draws_them(name: str) -> None:
    scenario = load_scenario(name)
    assert scenario.room is not None
    (x0, _), (x1, _) = scenario.room.min, scenario.room.max
    x_range = (x0 + 0.5, np.float64(x1) - 0.2)
    for seed in range(40):
        count = seed % 6
        rng, reference_rng = np.random.default_rng(seed), np.random.default_rng(seed)
        drawn = with_wall_obstacles(scenario, rng, count, (0.3, 1.0), (0.05, 0.35), x_range)
        expected = reference_with_wall_obstacles(
            scenario, reference_rng, count, (0.3, 1.0), (0.05, 0.35), x_range
        )
        assert drawn == expected
        assert rng.bit_generator.state == reference_rng.bit_generator.state
