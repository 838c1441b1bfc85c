"""Compiled loops handed a numpy ``Generator`` by its bit generator's handle against the same
loops handed the ``Generator`` itself (``tests/drive_kernels_reference.py``): the same numbers,
the same plans and the same generator state, bit for bit, for every bit generator numpy has."""

from __future__ import annotations

import numpy as np
import pytest

from hypothesis import given
from hypothesis import strategies as st

from sonar_gym.apcs_route import REAIM_TOLERANCE_RAD
from sonar_gym.drive_kernels import draw_commands, plan_to_targets
from sonar_gym.generator_handles import generator_handle
from tests import drive_kernels_reference as reference
from tests.fuzzing import fuzz_settings

BIT_GENERATORS = [np.random.PCG64, np.random.PCG64DXSM, np.random.Philox, np.random.SFC64]


def _same_state(first: object, second: object) -> bool:
    """Whether two bit generator states (dicts of numbers and arrays) are equal."""
    if isinstance(first, dict) and isinstance(second, dict):
        return first.keys() == second.keys() and all(
            _same_state(first[key], second[key]) for key in first
        )
    if isinstance(first, np.ndarray) or isinstance(second, np.ndarray):
        return bool(np.array_equal(first, second))
    return first == second


def _pair(kind: type[np.random.BitGenerator], seed: int) -> tuple[np.random.Generator, ...]:
    return np.random.Generator(kind(seed)), np.random.Generator(kind(seed))


@pytest.mark.parametrize("kind", [*BIT_GENERATORS, np.random.MT19937])
@pytest.mark.parametrize("count", [0, 1, 9, 300])
def test_draws_through_a_handle_are_the_generators_draws(
    kind: type[np.random.BitGenerator], count: int
) -> None:
    rng, expected_rng = _pair(kind, 17)
    for _ in range(3):  # and again from where the last block left the generator
        normals, uniforms = draw_commands(rng, count)
        expected_normals, expected_uniforms = reference.draw_commands(expected_rng, count)
        assert np.array_equal(normals, expected_normals)
        assert np.array_equal(uniforms, expected_uniforms)
        assert _same_state(rng.bit_generator.state, expected_rng.bit_generator.state)


def test_a_handle_follows_a_state_set_from_python() -> None:
    """Setting ``bit_generator.state`` writes into the bit generator the handle points at."""
    rng, expected_rng = _pair(np.random.PCG64, 3)
    handle = generator_handle(rng)
    start = rng.bit_generator.state
    draw_commands(rng, 5)
    rng.bit_generator.state = start
    rng.standard_normal(3)
    expected_rng.standard_normal(3)
    assert generator_handle(rng) == handle
    assert np.array_equal(draw_commands(rng, 4)[1], reference.draw_commands(expected_rng, 4)[1])


def test_many_generators_keep_their_own_streams() -> None:
    """More generators than the handles remembered, used in turn: each draws its own stream."""
    generators = [np.random.default_rng(seed) for seed in range(20)]
    expected = [np.random.default_rng(seed) for seed in range(20)]
    for _ in range(2):
        for rng, expected_rng in zip(generators, expected, strict=True):
            got = draw_commands(rng, 2)[0]
            assert np.array_equal(got, reference.draw_commands(expected_rng, 2)[0])


@fuzz_settings(200)
@given(
    seed=st.integers(0, 2**32 - 1),
    kind=st.sampled_from(BIT_GENERATORS),
    n_targets=st.integers(1, 5),
    first=st.integers(0, 4),
    theta=st.floats(-3.1, 3.1),
    step_m=st.floats(0.01, 0.2),
    steps_per_aim=st.integers(1, 12),
    encoder_std=st.floats(0.0, 0.05),
)
def test_plans_through_a_handle_are_the_generators_plans(
    seed: int,
    kind: type[np.random.BitGenerator],
    n_targets: int,
    first: int,
    theta: float,
    step_m: float,
    steps_per_aim: int,
    encoder_std: float,
) -> None:
    targets = np.random.default_rng(seed).uniform(-1.5, 1.5, (n_targets, 2))
    waypoint = min(first, n_targets - 1)
    rng, expected_rng = _pair(kind, seed)
    arguments = (targets, waypoint, (0.1, -0.2, theta), step_m, steps_per_aim, 0.3, encoder_std)
    got = plan_to_targets(rng, *arguments, REAIM_TOLERANCE_RAD)
    expected = reference.plan_to_targets(expected_rng, *arguments, REAIM_TOLERANCE_RAD)
    for array, expected_array in zip(got[:4], expected[:4], strict=True):
        assert array.dtype == expected_array.dtype
        assert np.array_equal(array, expected_array)
    assert got[4] == expected[4]
    assert _same_state(rng.bit_generator.state, expected_rng.bit_generator.state)
