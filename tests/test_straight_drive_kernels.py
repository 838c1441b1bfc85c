"""The compiled straight drive (:mod:`sonar_gym.straight_drive_kernels`) against the numpy form
it replaced (:mod:`tests.straight_drive_reference`): the same clearances, the same free
commands and end poses, the same runs, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sonar_gym.geometry import StaticGeometry
from sonar_gym.pose import Pose
from sonar_gym.robot import DifferentialDriveRobot, OdometryNoise
from sonar_gym.scenario import load_scenario
from sonar_gym.straight_drive import (
    CommandDraws,
    StraightRun,
    _free_commands,
    drive_commands,
)
from sonar_gym.straight_drive_kernels import clearance, wheel_travel
from sonar_gym.world import World
from tests.fuzzing import fuzz_settings
from tests.straight_drive_reference import (
    clearance_arrays,
    drive_commands_arrays,
    free_commands_arrays,
)

SCENARIOS = ("apcs_corridor", "beom_cho_lab", "kim_arena", "wu_tsai_room")


def _shapes(geometry: StaticGeometry) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return geometry.segment_starts, geometry.segment_ends, geometry.circles


def _assert_same_bits(actual: np.ndarray, expected: np.ndarray) -> None:
    assert actual.shape == expected.shape and actual.dtype == expected.dtype
    assert np.array_equal(actual, expected, equal_nan=True)
    assert np.array_equal(np.signbit(actual), np.signbit(expected))


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_clearance_is_the_arrays_clearance_on_the_maps(scenario: str) -> None:
    world = World(load_scenario(scenario))
    rng = np.random.default_rng(11)
    for trial in range(60):
        start = world.sample_free_pose(rng).position
        count = int(rng.integers(1, 80))
        path = start + np.cumsum(rng.normal(0.0, 0.02 * (1 + trial % 5), (count, 2)), axis=0)
        for within_m in (None, 0.0, 0.05, float(rng.uniform(0.0, 1.0)), 3.0):
            expected = clearance_arrays(world.geometry, path, within_m)
            bound = math.inf if within_m is None else within_m
            _assert_same_bits(clearance(path, bound, *_shapes(world.geometry)), expected)


_COORDINATES = st.floats(-3.0, 3.0, allow_nan=False, allow_infinity=False)


@given(
    points=st.lists(st.tuples(_COORDINATES, _COORDINATES), min_size=1, max_size=12),
    segments=st.lists(
        st.tuples(_COORDINATES, _COORDINATES, _COORDINATES, _COORDINATES), max_size=6
    ),
    circles=st.lists(st.tuples(_COORDINATES, _COORDINATES, st.floats(0.0, 1.0)), max_size=4),
    within_m=st.one_of(st.none(), st.floats(0.0, 4.0)),
    degenerate=st.booleans(),
)
@fuzz_settings(400)
def test_clearance_is_the_arrays_clearance_on_any_shapes(
    points: list[tuple[float, float]],
    segments: list[tuple[float, float, float, float]],
    circles: list[tuple[float, float, float]],
    within_m: float | None,
    degenerate: bool,
) -> None:
    """Random segments (zero-length ones too), circles and points, some on the shapes."""
    table = np.array(segments, dtype=np.float64).reshape(-1, 4)
    if degenerate and len(table):
        table[0, 2:] = table[0, :2]
    at = np.array(points, dtype=np.float64)
    if len(table):
        at[0] = table[-1, :2]  # on a segment's end
    geometry = StaticGeometry(
        segment_starts=np.ascontiguousarray(table[:, :2]),
        segment_ends=np.ascontiguousarray(table[:, 2:]),
        segment_mapped=np.ones(len(table), dtype=bool),
        circles=np.array(circles, dtype=np.float64).reshape(-1, 3),
        circle_mapped=np.ones(len(circles), dtype=bool),
        vertices=np.zeros((0, 2)),
        vertex_arms=np.zeros((0, 2, 2)),
    )
    expected = clearance_arrays(geometry, at, within_m)
    bound = math.inf if within_m is None else within_m
    _assert_same_bits(clearance(at, bound, *_shapes(geometry)), expected)


@pytest.mark.parametrize("seed", range(8))
def test_wheel_travel_is_the_wheel_models_arrays(seed: int) -> None:
    """Encoder increments and ground travel of random commands (zero, negative, turns in
    place, metres long), slip draws on and around the slip probability."""
    rng = np.random.default_rng(seed)
    noise = OdometryNoise(
        float(rng.uniform(0.0, 0.02)),
        float(rng.uniform(-0.4, 0.4)),
        float(rng.uniform(-0.4, 0.4)),
        float(rng.choice([0.0, 0.01, rng.uniform(0.0, 1.0), 1.0])),
        float(rng.uniform(0.0, 1.0)),
    )
    for count in (1, 2, 7, 60, 300):
        commanded = rng.normal(0.0, 10.0 ** rng.uniform(-4.0, 0.5), (count, 2))
        commanded[rng.random((count, 2)) < 0.1] = 0.0
        normals = rng.standard_normal((count, 2))
        uniforms = rng.random((count, 4))
        probability = noise.slip_probability(commanded)
        on_edge = rng.random((count, 2)) < 0.2
        uniforms[:, :2][on_edge] = probability[on_edge]
        encoder, ground = wheel_travel(
            commanded,
            normals,
            uniforms,
            probability,
            noise.encoder_std_m_per_sqrt_m,
            noise.scale_error_left,
            noise.scale_error_right,
            noise.slip_fraction_max,
        )
        scale_errors = np.array([noise.scale_error_left, noise.scale_error_right])
        _assert_same_bits(encoder, noise.encoder_increments(commanded, normals))
        _assert_same_bits(
            ground,
            noise.ground_travel(commanded, scale_errors, uniforms[:, :2], uniforms[:, 2:]),
        )


def _ground(rng: np.random.Generator, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Ground travel of straight steps, slight curves, near-series and zero turns and turns
    in place, and their heading changes on a 0.3 m wheel base."""
    kind = rng.integers(0, 5, count)
    step = rng.uniform(-0.08, 0.08, count)
    spread = np.select(
        [kind == 0, kind == 1, kind == 2, kind == 3],
        [
            np.zeros(count),
            rng.normal(0.0, 1e-3, count),
            rng.normal(0.0, 1e-5, count),  # half turns below the series bound
            rng.uniform(-0.2, 0.2, count) - step,  # about a turn in place
        ],
        rng.normal(0.0, 0.02, count),
    )
    ground = np.column_stack([step - spread, step + spread])
    return ground, (ground[:, 1] - ground[:, 0]) / 0.3


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_free_commands_are_the_arrays_free_commands(scenario: str) -> None:
    """From free poses, near walls and in them: the same count and the same end poses."""
    world = World(load_scenario(scenario))
    rng = np.random.default_rng(5)
    counts = {"all free": 0, "blocked": 0}
    for trial in range(120):
        world.set_robot_pose(world.sample_free_pose(rng))
        ground, ground_turn = _ground(rng, int(rng.integers(1, 70)))
        ground *= 1 + trial % 6
        ground_turn *= 1 + trial % 6
        expected_out = np.full((len(ground) + 2, 3), np.nan)
        actual_out = expected_out.copy()
        expected = free_commands_arrays(world, ground, ground_turn, expected_out[1:])
        actual = _free_commands(world, ground, ground_turn, actual_out[1:])
        assert actual == expected
        _assert_same_bits(actual_out, expected_out)
        counts["all free" if expected == len(ground) else "blocked"] += 1
    assert min(counts.values()) >= 10  # both outcomes are exercised


def _drive_pair(
    scenario: str, start: Pose, odometry: Pose | None, noise: OdometryNoise
) -> tuple[tuple[World, DifferentialDriveRobot], tuple[World, DifferentialDriveRobot]]:
    def one() -> tuple[World, DifferentialDriveRobot]:
        world = World(load_scenario(scenario), robot_pose=start)
        robot = DifferentialDriveRobot(
            noise, max_substep_m=0.01, max_substep_rad=0.05, odometry_pose=odometry
        )
        return world, robot

    return one(), one()


def _assert_same_runs(actual: StraightRun, expected: StraightRun) -> None:
    for name in ("encoder_left_m", "encoder_right_m", "true_poses", "odometry_poses", "collided"):
        _assert_same_bits(getattr(actual, name), getattr(expected, name))


@pytest.mark.parametrize("scenario", ["apcs_corridor", "beom_cho_lab"])
@pytest.mark.parametrize("seed", range(6))
def test_drive_commands_is_the_arrays_drive(scenario: str, seed: int) -> None:
    """Runs of mixed commands (some into walls, through pymunk): the same encoder readings,
    true and odometry poses, contacts, robot, odometry and generator state."""
    rng = np.random.default_rng(seed)
    noise = OdometryNoise(0.0005 * seed, 0.003, -0.002, 0.3 * (seed % 2), 0.3)
    layout = World(load_scenario(scenario))
    for _ in range(4):
        start = layout.sample_free_pose(rng)
        odometry = None if seed % 3 == 0 else Pose(start.x + 0.01, start.y - 0.02, 3.1)
        (world, robot), (reference_world, reference_robot) = _drive_pair(
            scenario, start, odometry, noise
        )
        commanded, _ = _ground(rng, int(rng.integers(0, 60)))
        commanded *= 1 + seed % 3
        motion_rng = np.random.default_rng(100 + seed)
        reference_rng = np.random.default_rng(100 + seed)
        draws, reference_draws = CommandDraws.start(motion_rng), CommandDraws.start(reference_rng)
        for _ in commanded:
            draws.draw(motion_rng)
            reference_draws.draw(reference_rng)
        actual = drive_commands(robot, world, commanded, draws, motion_rng)
        expected = drive_commands_arrays(
            reference_robot, reference_world, commanded, reference_draws, reference_rng
        )
        _assert_same_runs(actual, expected)
        assert world.robot_pose == reference_world.robot_pose
        assert robot.odometry_pose == reference_robot.odometry_pose
        assert motion_rng.bit_generator.state == reference_rng.bit_generator.state
