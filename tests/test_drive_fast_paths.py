"""The compiled draws and dead reckoning of a run of drive commands against the Python loops
they replaced: the same numbers, the same generator state, the same poses, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.drive_kernels import dead_reckon_straight, draw_commands
from sonar_gym.pose import wrap_angle
from sonar_gym.straight_drive import CommandDraws


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


def _reference_dead_reckoning(
    rng: np.random.Generator,
    pose: tuple[float, float, float],
    count: int,
    step_m: float,
    step_noise: float,
    base: float,
) -> tuple[float, float, float]:
    """The Python loop: draw a command's numbers, move the estimate, in turn."""
    x, y, theta = pose
    for _ in range(count):
        normals, _ = rng.standard_normal(2), rng.random(4)
        noise_left, noise_right = normals.tolist()
        left = step_m + step_noise * noise_left
        right = step_m + step_noise * noise_right
        distance, turn = 0.5 * (right + left), (right - left) / base
        heading = theta + 0.5 * turn
        x, y = x + distance * math.cos(heading), y + distance * math.sin(heading)
        theta = wrap_angle(theta + turn)
    return x, y, theta


@pytest.mark.parametrize("theta", [0.3, math.pi - 1e-4, -math.pi + 1e-4])
@pytest.mark.parametrize("step_noise", [0.0, 2e-3, 0.05])
def test_compiled_dead_reckoning_is_the_python_loops(theta: float, step_noise: float) -> None:
    reference, compiled_rng = np.random.default_rng(8), np.random.default_rng(8)
    expected = _reference_dead_reckoning(reference, (1.0, -2.0, theta), 300, 0.02, step_noise, 0.3)
    pose, normals, uniforms = dead_reckon_straight(
        compiled_rng, (1.0, -2.0, theta), 300, 0.02, step_noise, 0.3
    )
    assert pose == expected
    assert -math.pi < pose[2] <= math.pi
    assert compiled_rng.bit_generator.state == reference.bit_generator.state
    assert normals.shape == (300, 2) and uniforms.shape == (300, 4)


@pytest.mark.parametrize("index", [0, 1, 5, 12, 19])
def test_rewind_puts_the_generator_before_the_command(index: int) -> None:
    """Commands drawn in a block and one by one; rewound to each, the generator draws them
    again."""
    rng = np.random.default_rng(3)
    draws = CommandDraws.start(rng)
    draws.extend(*draw_commands(rng, 12))
    for _ in range(8):
        draws.draw(rng)
    draws.finish(rng)
    draws.rewind(rng, index)
    normals, uniforms = rng.standard_normal(2), rng.random(4)
    assert np.array_equal(normals, draws.normals[index])
    assert np.array_equal(uniforms, draws.uniforms[index])
