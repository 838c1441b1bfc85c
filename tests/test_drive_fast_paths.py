"""The compiled draws of a run of drive commands and the compiled plan of an APCS route against
the Python loops they replaced: the same numbers, the same generator state, the same commands
and poses, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hypothesis import given
from hypothesis import strategies as st

from sonar_gym.apcs_route import REAIM_TOLERANCE_RAD
from sonar_gym.drive_kernels import draw_commands, plan_to_targets
from sonar_gym.pose import angle_difference, wrap_angle
from sonar_gym.straight_drive import CommandDraws
from tests.fuzzing import fuzz_settings


@pytest.mark.parametrize("count", [0, 1, 7, 500])
@pytest.mark.parametrize("seed", [0, 1, 12345])
def test_compiled_draws_are_drives_draws_in_its_order(count: int, seed: int) -> None:
    reference, compiled_rng = np.random.default_rng(seed), np.random.default_rng(seed)
    expected = [(reference.standard_normal(2), reference.random(4)) for _ in range(count)]
    normals, uniforms = draw_commands(compiled_rng, count)
    assert normals.shape == (count, 2) and uniforms.shape == (count, 4)
    for row, (expected_normals, expected_uniforms) in enumerate(expected):
        assert np.array_equal(normals[row], expected_normals)
        assert np.array_equal(uniforms[row], expected_uniforms)
    assert compiled_rng.bit_generator.state == reference.bit_generator.state
    assert compiled_rng.random() == reference.random()  # and both go on alike


def _reference_plan(
    rng: np.random.Generator,
    targets: list[tuple[float, float]],
    waypoint: int,
    pose: tuple[float, float, float],
    step_m: float,
    steps_per_aim: int,
    base: float,
    encoder_std: float,
) -> tuple[list[tuple[float, float]], list[np.ndarray], list[list[int]], tuple[float, ...]]:
    """The Python loop: steer from the estimate, draw each command's numbers, dead-reckon it."""
    x, y, theta = pose
    commanded: list[tuple[float, float]] = []
    drawn: list[np.ndarray] = []
    stops: list[list[int]] = []

    def command(d_left: float, d_right: float) -> None:
        nonlocal x, y, theta
        normals, uniforms = rng.standard_normal(2), rng.random(4)
        drawn.append(np.concatenate([normals, uniforms]))
        left = d_left + encoder_std * math.sqrt(abs(d_left)) * float(normals[0])
        right = d_right + encoder_std * math.sqrt(abs(d_right)) * float(normals[1])
        distance, turn = 0.5 * (right + left), (right - left) / base
        heading = theta + 0.5 * turn
        x, y = x + distance * math.cos(heading), y + distance * math.sin(heading)
        theta = wrap_angle(theta + turn)
        commanded.append((d_left, d_right))

    while waypoint < len(targets):
        dx, dy = targets[waypoint][0] - x, targets[waypoint][1] - y
        remaining = round(math.hypot(dx, dy) / step_m)
        if remaining == 0:
            waypoint += 1
            continue
        turn = angle_difference(math.atan2(dy, dx), theta)
        if abs(turn) > REAIM_TOLERANCE_RAD:
            half = 0.5 * turn * base
            command(-half, half)
        count = min(remaining, steps_per_aim)
        for _ in range(count):
            command(step_m, step_m)
        if count < steps_per_aim:
            waypoint += 1
        stops.append([len(commanded), waypoint])
    return commanded, drawn, stops, (x, y, theta)


@fuzz_settings(150)
@given(
    seed=st.integers(0, 2**32 - 1),
    n_targets=st.integers(1, 4),
    first=st.integers(0, 1),
    theta=st.sampled_from([0.0, 0.3, math.pi - 1e-4, -math.pi + 1e-4]),
    step_m=st.sampled_from([0.01, 0.03, 0.07]),
    steps_per_aim=st.integers(1, 12),
    encoder_std=st.sampled_from([0.0, 5e-4, 0.02]),
)
def test_compiled_plan_is_the_python_loops(
    seed: int,
    n_targets: int,
    first: int,
    theta: float,
    step_m: float,
    steps_per_aim: int,
    encoder_std: float,
) -> None:
    targets = np.random.default_rng(seed).uniform(-1.5, 1.5, (n_targets, 2))
    start = (0.1, -0.2, theta)
    waypoint = min(first, n_targets - 1)
    reference, compiled_rng = np.random.default_rng(seed), np.random.default_rng(seed)
    expected = _reference_plan(
        reference, targets.tolist(), waypoint, start, step_m, steps_per_aim, 0.3, encoder_std
    )
    commanded, normals, uniforms, stops, pose = plan_to_targets(
        compiled_rng,
        targets,
        waypoint,
        start,
        step_m,
        steps_per_aim,
        0.3,
        encoder_std,
        REAIM_TOLERANCE_RAD,
    )
    expected_commanded, expected_draws, expected_stops, expected_pose = expected
    assert commanded.tolist() == [list(pair) for pair in expected_commanded]
    assert np.hstack([normals, uniforms]).tolist() == [row.tolist() for row in expected_draws]
    assert stops.tolist() == expected_stops
    assert pose == expected_pose
    assert -math.pi < pose[2] <= math.pi
    assert compiled_rng.bit_generator.state == reference.bit_generator.state


def test_a_plan_longer_than_its_first_buffers_is_whole() -> None:
    """Hundreds of commands and steering points: the loop's arrays grow without losing rows."""
    rng = np.random.default_rng(4)
    targets = np.array([[6.0, 0.0], [6.0, 4.0]])
    commanded, normals, uniforms, stops, _ = plan_to_targets(
        rng, targets, 0, (0.0, 0.0, 0.0), 0.01, 3, 0.3, 5e-4, REAIM_TOLERANCE_RAD
    )
    straight = commanded[:, 0] == commanded[:, 1]
    assert 990 <= int(straight.sum()) <= 1010  # 6 m + 4 m of 1 cm steps
    assert len(normals) == len(uniforms) == len(commanded)
    assert np.all(np.diff(stops[:, 0]) > 0) and stops[-1, 0] == len(commanded)
    assert stops[-1, 1] == 2
    assert np.isfinite(normals).all() and ((uniforms >= 0.0) & (uniforms < 1.0)).all()


@pytest.mark.parametrize("index", [0, 1, 5, 12, 19])
def test_rewind_puts_the_generator_before_the_command(index: int) -> None:
    """Commands drawn in a block and one by one; rewound to each, the generator draws them
    again."""
    rng = np.random.default_rng(3)
    draws = CommandDraws.start(rng)
    draws.extend(*draw_commands(rng, 12))
    for _ in range(8):
        draws.draw(rng)
    draws.rewind(rng, index)
    normals, uniforms = rng.standard_normal(2), rng.random(4)
    assert np.array_equal(normals, draws.normals[index])
    assert np.array_equal(uniforms, draws.uniforms[index])


def test_draws_join_their_blocks_in_drawing_order() -> None:
    """Blocks drawn elsewhere and commands drawn one by one read back as one table per kind,
    in the order drawn (the rows the per-command lists held)."""
    rng, reference = np.random.default_rng(5), np.random.default_rng(5)
    draws = CommandDraws.start(rng)
    assert draws.normals.shape == (0, 2) and draws.uniforms.shape == (0, 4)
    normal_rows: list[np.ndarray] = []
    uniform_rows: list[np.ndarray] = []
    for block in (3, 0, 2):
        draws.extend(*draw_commands(rng, block))
        normals, uniforms = draw_commands(reference, block)
        normal_rows.extend(normals)
        uniform_rows.extend(uniforms)
        draws.draw(rng)
        normal_rows.append(reference.standard_normal(2))
        uniform_rows.append(reference.random(4))
    assert draws.count == len(normal_rows) == 8
    assert np.array_equal(draws.normals, np.array(normal_rows))
    assert np.array_equal(draws.uniforms, np.array(uniform_rows))
    single = CommandDraws.start(rng)
    single.extend(*draw_commands(rng, 4))
    assert single.normals.shape == (4, 2) and single.uniforms.shape == (4, 4)
