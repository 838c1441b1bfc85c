"""The compiled drive of :meth:`DifferentialDriveRobot.drive_commands` against the Python forms
it replaced: the wheel model of :class:`OdometryConfig`, :func:`integrate_substeps`, the
substep rule, and the clearance test through pymunk's bounding-box query, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pymunk
import pytest

from sonar_gym import drive_kernels
from sonar_gym.odometry import INTEGRATIONS, OdometryConfig, integrate_substeps
from sonar_gym.path_clearance import PATH_CLEARANCE_M, StaticShapeTable
from sonar_gym.pose import Pose
from sonar_gym.robot import DifferentialDriveRobot
from sonar_gym.scenario import scenario_from_dict
from sonar_gym.world import STATIC_ONLY, World
from tests.test_odometry import compiled_arc_is_clear

ROOM = scenario_from_dict(
    {
        "room": {"min": [-2.0, -1.5], "max": [2.0, 1.5]},
        "walls": [{"a": [-1.0, 0.2], "b": [0.4, 0.9]}, {"a": [1.2, -1.0], "b": [1.2, -0.2]}],
        "boxes": [{"center": [-1.2, -0.8], "size": [0.4, 0.3]}],
        "cylinders": [
            {"center": [0.6, -0.7], "radius": 0.12},
            {"center": [-0.3, 1.1], "radius": 0.05},
        ],
        "robot": {"radius": 0.2, "wheel_base": 0.4},
    }
)


def _reference_path_is_clear(
    world: World, start: Pose, ground: tuple[float, float], base: float, end: Pose
) -> bool:
    """The Python test: pymunk's bounding-box query, then each shape's exact distance."""
    turned = abs(ground[1] - ground[0]) / base
    if turned > math.pi:
        return False
    radius = world.robot_radius + 0.5 * abs(ground[0] + ground[1]) * turned / 8.0 + PATH_CLEARANCE_M
    a, b = (start.x, start.y), (end.x, end.y)
    box = pymunk.BB(
        min(a[0], b[0]) - radius,
        min(a[1], b[1]) - radius,
        max(a[0], b[0]) + radius,
        max(a[1], b[1]) + radius,
    )
    for shape in world.space.bb_query(box, STATIC_ONLY):
        if isinstance(shape, pymunk.Segment):
            gap = _segment_distance(a, b, (shape.a.x, shape.a.y), (shape.b.x, shape.b.y))
        else:
            assert isinstance(shape, pymunk.Circle) and shape.body is not None
            centre = shape.body.local_to_world(shape.offset)
            gap = _point_segment_distance((centre.x, centre.y), a, b) - shape.radius
        if gap <= radius:
            return False
    return True


def _point_segment_distance(
    point: tuple[float, float], a: tuple[float, float], b: tuple[float, float]
) -> float:
    ex, ey = b[0] - a[0], b[1] - a[1]
    length2 = ex * ex + ey * ey
    t = 0.0 if length2 == 0.0 else ((point[0] - a[0]) * ex + (point[1] - a[1]) * ey) / length2
    t = min(max(t, 0.0), 1.0)
    return math.hypot(point[0] - a[0] - t * ex, point[1] - a[1] - t * ey)


def _segment_distance(
    a: tuple[float, float], b: tuple[float, float], p: tuple[float, float], q: tuple[float, float]
) -> float:
    def side(o: tuple[float, float], u: tuple[float, float], v: tuple[float, float]) -> float:
        return (u[0] - o[0]) * (v[1] - o[1]) - (u[1] - o[1]) * (v[0] - o[0])

    if side(a, b, p) * side(a, b, q) < 0.0 and side(p, q, a) * side(p, q, b) < 0.0:
        return 0.0
    return min(
        _point_segment_distance(a, p, q),
        _point_segment_distance(b, p, q),
        _point_segment_distance(p, a, b),
        _point_segment_distance(q, a, b),
    )


def test_the_clearance_test_is_the_bounding_box_query_and_the_exact_distances() -> None:
    world = World(ROOM)
    rng = np.random.default_rng(4)
    verdicts = []
    for _ in range(3000):
        start = Pose(*rng.uniform((-1.9, -1.4, -math.pi), (1.9, 1.4, math.pi)).tolist())
        left, right = rng.uniform(-0.6, 0.6, 2).tolist()
        if rng.random() < 0.2:
            right = -left  # turns in place, some of them more than pi
            left *= 5.0
            right *= 5.0
        end = integrate_substeps(start, left, right, 0.4, 1, "arc")
        expected = _reference_path_is_clear(world, start, (left, right), 0.4, end)
        compiled = compiled_arc_is_clear(world, start, left, right)
        assert compiled == expected, (start, left, right)
        verdicts.append(expected)
    assert 0.2 < np.mean(verdicts) < 0.8, "the cases must hold both verdicts"


def test_the_shape_table_holds_pymunks_boxes_and_refuses_other_shapes() -> None:
    world = World(ROOM)
    table = world.static_shape_table
    shapes = world.space.bb_query(pymunk.BB(-10, -10, 10, 10), STATIC_ONLY)
    assert len(table.kinds) == len(shapes) == 4 + 2 + 4 + 2
    assert sorted(map(tuple, table.bounds.tolist())) == sorted(
        (s.bb.left, s.bb.bottom, s.bb.right, s.bb.top) for s in shapes
    )
    assert not table.bounds.flags.writeable
    poly = pymunk.Poly.create_box(pymunk.Body(body_type=pymunk.Body.STATIC), (1.0, 1.0))
    with pytest.raises(ValueError, match="Segment or Circle; got Poly"):
        StaticShapeTable.of([poly])


def _reference_wheels(
    noise: OdometryConfig,
    commands: list[tuple[float, float]],
    draws: list[tuple[np.ndarray, np.ndarray]],
    base: float,
    integration: str,
    odometry: Pose,
) -> list[tuple[float, ...]]:
    """The Python drive's wheel model, substep rule and odometry, command by command."""
    rows = []
    for (left, right), (normals, uniforms) in zip(commands, draws, strict=True):
        normal_left, normal_right = normals.tolist()
        slip_left, slip_right, size_left, size_right = uniforms.tolist()
        encoder = (
            float(noise.encoder_increments(left, normal_left)),
            float(noise.encoder_increments(right, normal_right)),
        )
        ground = (
            float(noise.ground_travel(left, noise.scale_error_left, slip_left, size_left)),
            float(noise.ground_travel(right, noise.scale_error_right, slip_right, size_right)),
        )
        travel = max(abs(ground[0]), abs(ground[1]), abs(encoder[0]), abs(encoder[1]))
        turn = abs(ground[1] - ground[0]) / base
        n = max(1, math.ceil(travel / 0.02), math.ceil(turn / math.radians(3.0)))
        odometry = integrate_substeps(odometry, *encoder, base, n, integration)  # type: ignore[arg-type]
        rows.append((*encoder, *ground, float(n), odometry.x, odometry.y, odometry.theta))
    return rows


@pytest.mark.parametrize("integration", INTEGRATIONS)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_compiled_wheels_are_the_wheel_model_and_the_odometry(
    integration: str, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    noise = OdometryConfig(slip_probability_per_m=0.4, scale_error_left=0.01)
    commands = [tuple(rng.uniform(-1.5, 1.5, 2).tolist()) for _ in range(40)]
    commands += [(0.0, 0.0), (0.3, 0.3), (-0.2, 0.2), (1e-12, -1e-12)]
    draws = [(rng.standard_normal(2), rng.random(4)) for _ in commands]
    odometry = Pose(0.2, -0.1, math.pi - 1e-3)
    expected = _reference_wheels(noise, commands, draws, 0.37, integration, odometry)  # type: ignore[arg-type]
    world = World(ROOM)
    motions, _ = drive_kernels.drive_commands(
        np.array(commands),
        np.concatenate([np.concatenate(pair) for pair in draws]),
        np.array(
            [*(getattr(noise, f) for f in noise.__dataclass_fields__), 0.02, math.radians(3.0)]
        ),
        0.37,
        0,
        INTEGRATIONS.index(integration),
        (odometry.x, odometry.y, odometry.theta),
        (0.0, 0.0, 0.0),
        world.robot_radius,
        *world.static_shape_table.arrays,
    )
    assert [tuple(row) for row in motions[:, :8].tolist()] == expected


def test_a_run_of_commands_is_the_same_as_driving_them_one_by_one() -> None:
    together_world, apart_world = World(ROOM), World(ROOM)
    for world in (together_world, apart_world):
        world.set_robot_pose(Pose(-0.5, -0.2, 0.4))
    together_robot = DifferentialDriveRobot(OdometryConfig(slip_probability_per_m=0.3))
    apart_robot = DifferentialDriveRobot(OdometryConfig(slip_probability_per_m=0.3))
    commands = [(0.4, 0.4), (-0.3, 0.3), (1.5, 1.5), (0.2, 0.6), (-2.0, -2.0), (0.0, 0.0)]
    together_rng, apart_rng = np.random.default_rng(3), np.random.default_rng(3)
    run = together_robot.drive_commands(together_world, commands, together_rng)
    apart = [apart_robot.drive(apart_world, left, right, apart_rng) for left, right in commands]
    assert run.collided.any() and not run.collided.all(), "the run must meet a wall and not only"
    assert [run.result(k) for k in range(len(commands))] == apart
    assert together_world.robot_pose == apart_world.robot_pose
    assert together_robot.odometry_pose == apart_robot.odometry_pose
    assert together_rng.bit_generator.state == apart_rng.bit_generator.state


def test_a_run_refuses_a_non_finite_command_before_drawing() -> None:
    world, robot, rng = World(ROOM), DifferentialDriveRobot(), np.random.default_rng(0)
    before = rng.bit_generator.state
    with pytest.raises(ValueError, match=r"must be finite \(metres\); got 0.1, nan"):
        robot.drive_commands(world, [(0.2, 0.2), (0.1, math.nan)], rng)
    assert rng.bit_generator.state == before
