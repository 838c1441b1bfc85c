"""The ``gym.make`` argument contract of every env: a clean ``ValueError`` or an env that runs.

Pins the cases a new user hit: ``-0.0`` reaching numpy as a negative scale, denormals passing
"> 0", integers past float range, numpy scalars refused, empty or odd ``scenario`` values
raising OS errors, and tuple arguments coming back as lists from ``EnvSpec.to_json``.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.registration import ENVIRONMENTS
from sonar_gym.validation import checked_number

BEACON_SCAN = "SonarGym/BeaconScan-v0"
SWEEP = "SonarGym/SweepLocalization-v0"
TRILATERATION = "SonarGym/Trilateration-v0"
BLOCK_EXPANSION = "SonarGym/BlockExpansion-v0"
WALL_CORRECTION = "SonarGym/WallCorrection-v0"


def assert_resets_and_steps(env: gym.Env) -> None:
    observation, _ = env.reset(seed=0)
    assert np.all(np.isfinite(observation))
    observation, reward, *_ = env.step(env.action_space.sample())
    assert np.all(np.isfinite(observation))
    assert math.isfinite(float(reward))


# -- the validator itself ----------------------------------------------------------------------


def test_negative_zero_comes_back_as_positive_zero() -> None:
    value = checked_number("x", -0.0, low=0.0)
    assert value == 0.0 and math.copysign(1.0, value) == 1.0


@pytest.mark.parametrize("value", [np.int64(8), np.int32(8), np.uint8(8)])
def test_numpy_integers_come_back_as_python_ints(value: object) -> None:
    result = checked_number("n", value, low=1, high=10, integer=True)
    assert type(result) is int and result == 8


def test_numpy_floats_come_back_as_python_floats() -> None:
    result = checked_number("t", np.float32(21.0), low=-20.0, high=50.0)
    assert type(result) is float and result == 21.0


@pytest.mark.parametrize("value", [True, np.bool_(True), "1", 1j, None, [1.0]])
def test_non_numbers_are_refused(value: object) -> None:
    with pytest.raises(ValueError, match="'x' must be a finite number"):
        checked_number("'x'", value)


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, 10**400, -(10**400)])
def test_non_finite_and_overflowing_numbers_are_refused(value: object) -> None:
    with pytest.raises(ValueError, match="must be a finite number"):
        checked_number("x", value)


def test_float_is_not_an_integer() -> None:
    with pytest.raises(ValueError, match="an integer"):
        checked_number("n", 8.0, integer=True)


def test_message_names_subject_bounds_and_value_and_cuts_huge_values() -> None:
    with pytest.raises(ValueError) as info:
        checked_number("argument 'speed'", 10**400, low=1e-3, high=10.0)
    message = str(info.value)
    assert message.startswith("argument 'speed' must be a positive number in [0.001, 10]; got 1000")
    assert len(message) < 200


# -- -0.0, denormals, overflow through gym.make --------------------------------------------------

NEGATIVE_ZERO_SCALES = [
    (BEACON_SCAN, "prior_position_std_m"),
    (BEACON_SCAN, "prior_heading_std_deg"),
    (SWEEP, "wheel_scale_error_bound"),
    (TRILATERATION, "wheel_scale_error_std"),
    (TRILATERATION, "initial_position_std_m"),
    (TRILATERATION, "initial_heading_std_deg"),
    (BLOCK_EXPANSION, "beacon_prior_std_m"),
    (WALL_CORRECTION, "wheel_scale_error_std"),
    (WALL_CORRECTION, "initial_position_std_m"),
    (WALL_CORRECTION, "initial_heading_std_deg"),
]


@pytest.mark.parametrize(("env_id", "argument"), NEGATIVE_ZERO_SCALES)
def test_negative_zero_scale_runs_as_zero(env_id: str, argument: str) -> None:
    env = gym.make(env_id, **{argument: -0.0})
    stored = getattr(env.unwrapped.config, argument)
    assert stored == 0.0 and math.copysign(1.0, stored) == 1.0
    assert_resets_and_steps(env)


DENORMAL_PRONE = [
    (TRILATERATION, "heading_scale_deg"),
    (TRILATERATION, "position_scale_m"),
    (TRILATERATION, "robot_speed_mps"),
    (TRILATERATION, "turn_rate_rad_s"),
    (WALL_CORRECTION, "heading_scale_deg"),
    (WALL_CORRECTION, "position_scale_m"),
    (WALL_CORRECTION, "bearing_std_deg"),
]


@pytest.mark.parametrize(("env_id", "argument"), DENORMAL_PRONE)
@pytest.mark.parametrize("value", [5e-324, 1e-300, 1e-9])
def test_denormal_positive_arguments_are_refused_by_name(
    env_id: str, argument: str, value: float
) -> None:
    with pytest.raises(ValueError, match=f"argument '{argument}' must be a positive number"):
        gym.make(env_id, **{argument: value})


def float_arguments(env_id: str) -> list[str]:
    config = gym.make(env_id).unwrapped.config
    return [f.name for f in dataclasses.fields(config) if type(getattr(config, f.name)) is float]


@pytest.mark.parametrize("env_id", sorted(ENVIRONMENTS))
def test_huge_integers_are_refused_by_name_in_every_float_argument(env_id: str) -> None:
    for argument in float_arguments(env_id):
        with pytest.raises(ValueError, match=f"argument '{argument}' must be"):
            gym.make(env_id, **{argument: 10**400})


# -- numpy scalars ------------------------------------------------------------------------------

NUMPY_ARGUMENTS = {
    BEACON_SCAN: {
        "n_range_bins": np.int64(8),
        "temperature_c": np.float32(21.0),
        "allow_calibration": np.bool_(False),
    },
    SWEEP: {
        "max_sweeps": np.int64(5),
        "sweep_width_deg": np.int64(180),
        "temperature_c": np.float32(21.0),
    },
    TRILATERATION: {
        "n_decision_points": np.int32(8),
        "fix_counts": [np.int64(1), np.int64(5)],
        "temperature_c": np.float64(21.0),
    },
    BLOCK_EXPANSION: {"n_areas": np.int64(3), "max_range_m": np.float32(6.0)},
    WALL_CORRECTION: {
        "n_legs": np.int64(3),
        "sample_spacings_cm": np.array([3, 6]),
        "temperature_c": np.float32(21.0),
    },
}


@pytest.mark.parametrize("env_id", sorted(NUMPY_ARGUMENTS))
def test_numpy_scalars_are_accepted_and_stored_as_python_values(env_id: str) -> None:
    env = gym.make(env_id, **NUMPY_ARGUMENTS[env_id])
    config = env.unwrapped.config
    for name in NUMPY_ARGUMENTS[env_id]:
        stored = getattr(config, name)
        items = stored if isinstance(stored, tuple) else (stored,)
        assert all(type(item) in (int, float, bool) for item in items), (name, stored)
    hash(config)
    assert_resets_and_steps(env)


# -- the scenario argument ----------------------------------------------------------------------

SCENARIO_ENVS = [BEACON_SCAN, SWEEP, TRILATERATION, WALL_CORRECTION]


@pytest.mark.parametrize("env_id", SCENARIO_ENVS)
@pytest.mark.parametrize("scenario", ["", "   ", "x" * 5000])
def test_empty_or_overlong_scenario_is_refused_by_name(env_id: str, scenario: str) -> None:
    with pytest.raises(ValueError, match="argument 'scenario' must be"):
        gym.make(env_id, scenario=scenario)


@pytest.mark.parametrize("env_id", SCENARIO_ENVS)
def test_directory_as_scenario_is_a_clean_error(env_id: str, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="not a file"):
        gym.make(env_id, scenario=str(tmp_path))


def test_route_margin_is_blamed_for_a_route_that_touches_the_end_walls() -> None:
    with pytest.raises(ValueError, match="argument 'route_margin_m'"):
        gym.make(WALL_CORRECTION, route_margin_m=0.1)


# -- tuples through EnvSpec JSON -----------------------------------------------------------------

TUPLE_ARGUMENTS = {
    BEACON_SCAN: {
        "increments_deg": (1, 2),
        "temperature_range_c": (10.0, 30.0),
        "sector_widths_deg": (90, 360),
    },
    TRILATERATION: {"fix_counts": (1, 3, 10)},
    BLOCK_EXPANSION: {"distance_range_m": (0.05, 0.7)},
    WALL_CORRECTION: {
        "standoffs_m": (-0.2, 0.0, 0.2),
        "sample_spacings_cm": (3, 6),
        "obstacle_length_range_m": (0.4, 0.8),
        "obstacle_depth_range_m": (0.1, 0.2),
    },
}


@pytest.mark.parametrize("env_id", sorted(TUPLE_ARGUMENTS))
def test_tuple_arguments_survive_a_spec_json_round_trip(env_id: str) -> None:
    env = gym.make(env_id, **TUPLE_ARGUMENTS[env_id])
    spec = gym.envs.registration.EnvSpec.from_json(env.spec.to_json())
    assert any(isinstance(v, list) for v in spec.kwargs.values())
    again = gym.make(spec)
    assert hash(again.unwrapped.config) == hash(env.unwrapped.config)
    assert again.unwrapped.config == env.unwrapped.config
    for name, value in TUPLE_ARGUMENTS[env_id].items():
        assert getattr(again.unwrapped.config, name) == value
