"""The compiled EKF prediction (Kim et al. sec. 3.1 eqs. (5)-(6)) and the compiled covariances
of the run prediction's closed form against the array forms they replaced, bit for bit, and the
compiled angle helpers against Python's."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sonar_gym.compiled import remainder, wrap_angle
from sonar_gym.odometry import (
    FilterIntegration,
    predict_over_motion,
    predict_run,
    predict_step,
    wheel_increment_covariance,
)
from sonar_gym.pose import FloatArray, Pose
from tests.fuzzing import fuzz_settings


def reference_predict_step(
    pose: Pose,
    covariance: FloatArray,
    d_left_m: float,
    d_right_m: float,
    wheel_base_m: float,
    variance_per_m: float,
    scale_variance: float,
    integration: FilterIntegration,
) -> tuple[Pose, FloatArray]:
    """The array form: numpy's Jacobians and products."""
    distance = 0.5 * (d_left_m + d_right_m)
    turned = (d_right_m - d_left_m) / wheel_base_m
    heading = pose.theta + 0.5 * turned if integration == "midpoint" else pose.theta
    cos_h, sin_h = math.cos(heading), math.sin(heading)
    state_jacobian = np.array(
        [[1.0, 0.0, -distance * sin_h], [0.0, 1.0, distance * cos_h], [0.0, 0.0, 1.0]]
    )
    inverse_base = 1.0 / wheel_base_m
    half_cos, half_sin = 0.5 * cos_h, 0.5 * sin_h
    if integration == "midpoint":
        lever = distance / (2.0 * wheel_base_m)
        wheel_rows = [
            [half_cos + -lever * sin_h, half_cos + lever * sin_h],
            [half_sin + lever * cos_h, half_sin + -lever * cos_h],
        ]
    else:
        wheel_rows = [[half_cos, half_cos], [half_sin, half_sin]]
    wheel_jacobian = np.array([*wheel_rows, [inverse_base, -inverse_base]])
    wheels = wheel_increment_covariance(d_left_m, d_right_m, variance_per_m, scale_variance)
    p = state_jacobian @ covariance @ state_jacobian.T + wheel_jacobian @ wheels @ wheel_jacobian.T
    moved = Pose(pose.x + distance * cos_h, pose.y + distance * sin_h, pose.theta + turned)
    return moved, 0.5 * (p + p.T)


def _covariance(rng: np.random.Generator) -> FloatArray:
    root = rng.normal(0.0, 0.05, (3, 3))
    return root @ root.T


@pytest.mark.parametrize("integration", ["paper", "midpoint"])
@pytest.mark.parametrize("scale_variance", [0.0, 1e-4])
def test_compiled_prediction_is_the_array_forms_bit_for_bit(
    integration: FilterIntegration, scale_variance: float
) -> None:
    rng = np.random.default_rng(3)
    for _ in range(300):
        pose = Pose(*rng.uniform(-5.0, 5.0, 2), rng.uniform(-math.pi, math.pi))
        covariance = _covariance(rng)
        count = int(rng.integers(1, 6))
        increments = rng.normal(0.0, 0.2, (count, 2))
        increments[rng.random(count) < 0.3, 1] *= -1.0  # turns in place among them
        increments[rng.random(count) < 0.2] = 0.0
        expected_pose, expected = pose, covariance
        expected_poses = []
        for left, right in increments.tolist():
            expected_pose, expected = reference_predict_step(
                expected_pose, expected, left, right, 0.3, 2e-4, scale_variance, integration
            )
            expected_poses.append(expected_pose)
        end, p, poses = predict_over_motion(
            pose, covariance, increments, 0.3, 2e-4, scale_variance, integration
        )
        assert np.array_equal(p, expected)
        assert poses == expected_poses
        assert end == expected_poses[-1]
        one_pose, one = predict_step(
            pose, covariance, *increments[0].tolist(), 0.3, 2e-4, scale_variance, integration
        )
        assert one_pose == expected_poses[0]
        assert np.array_equal(
            one,
            reference_predict_step(
                pose, covariance, *increments[0].tolist(), 0.3, 2e-4, scale_variance, integration
            )[1],
        )


def reference_run_covariances(
    covariance: FloatArray, left: FloatArray, right: FloatArray, base: float, k: float
) -> FloatArray:
    """The array form of :func:`predict_run`'s closed-form covariances: one numpy expression
    per term (see its comments for the algebra)."""
    distance = 0.5 * (right + left)
    turn = (right - left) / base
    thetas = np.concatenate([[0.0], np.cumsum(turn)])
    heading = thetas[:-1] + 0.5 * turn
    cos_h, sin_h = np.cos(heading), np.sin(heading)
    lever = distance / (2.0 * base)
    wheels = np.empty((len(left), 3, 2))
    wheels[:, 0, 0] = 0.5 * cos_h - lever * sin_h
    wheels[:, 0, 1] = 0.5 * cos_h + lever * sin_h
    wheels[:, 1, 0] = 0.5 * sin_h + lever * cos_h
    wheels[:, 1, 1] = 0.5 * sin_h - lever * cos_h
    wheels[:, 2, 0] = 1.0 / base
    wheels[:, 2, 1] = -1.0 / base
    variances = np.stack([k * np.abs(right), k * np.abs(left)], axis=1)
    encoder_terms = np.einsum("kij,kj,klj->kil", wheels, variances, wheels)
    sums = np.zeros((len(left) + 1, 3))
    sums[1:, 0] = np.cumsum(-distance * sin_h)
    sums[1:, 1] = np.cumsum(distance * cos_h)

    def before(values: FloatArray) -> FloatArray:
        return np.concatenate([np.zeros((1, *values.shape[1:])), np.cumsum(values, axis=0)])

    def outer(a: FloatArray, b: FloatArray) -> FloatArray:
        return a[:, :, None] * b[:, None, :]

    column = np.broadcast_to(covariance[:, 2], sums.shape)
    result = (
        covariance
        + outer(sums, column)
        + outer(column, sums)
        + covariance[2, 2] * outer(sums, sums)
    )
    if len(left):
        q, q33, later = encoder_terms[:, :, 2], encoder_terms[:, 2, 2], sums[1:]
        total, q_sum, weight = before(encoder_terms), before(q), before(q33)
        cross = before(outer(later, q))
        weighted = before(q33[:, None] * later)
        second = before(q33[:, None, None] * outer(later, later))
        result += (
            total
            + outer(sums, q_sum)
            + outer(q_sum, sums)
            - cross
            - cross.transpose(0, 2, 1)
            + weight[:, None, None] * outer(sums, sums)
            - outer(sums, weighted)
            - outer(weighted, sums)
            + second
        )
    return np.asarray(0.5 * (result + result.transpose(0, 2, 1)))


@fuzz_settings(200)
@given(
    seed=st.integers(0, 2**32 - 1),
    count=st.integers(0, 80),
    variance_per_m=st.sampled_from([0.0, 3e-7, 1e-3]),
    turns=st.booleans(),
)
def test_compiled_run_covariances_are_the_array_forms_bit_for_bit(
    seed: int, count: int, variance_per_m: float, turns: bool
) -> None:
    rng = np.random.default_rng(seed)
    left = 0.03 + rng.normal(0.0, 0.002, count)
    right = 0.03 + rng.normal(0.0, 0.002, count)
    if turns:  # turns in place and standstills among the steps
        spins = rng.random(count) < 0.2
        left[spins], right[spins] = -0.04, 0.04
        left[rng.random(count) < 0.1] = 0.0
    covariance = _covariance(rng)
    start = Pose(0.0, 0.0, 0.0)  # the reference integrates the heading from 0
    _, covariances = predict_run(start, covariance, left, right, 0.3, variance_per_m)
    expected = reference_run_covariances(covariance, left, right, 0.3, variance_per_m)
    assert covariances.shape == expected.shape
    assert covariances.tobytes() == expected.tobytes()


def test_headings_are_wrapped_between_commands() -> None:
    """Three half-turn commands from near pi: each step starts from the wrapped heading."""
    pose = Pose(0.0, 0.0, math.pi - 1e-3)
    turn = [(-0.2, 0.2)] * 3
    _, _, poses = predict_over_motion(pose, np.eye(3) * 1e-4, turn, 0.3, 1e-4)
    expected = pose
    for left, right in turn:
        expected, _ = reference_predict_step(
            expected, np.eye(3), left, right, 0.3, 1e-4, 0.0, "paper"
        )
        assert -math.pi < expected.theta <= math.pi
    assert poses[-1] == expected


def test_no_command_predicts_nothing() -> None:
    covariance = np.eye(3)
    pose, p, poses = predict_over_motion(Pose(1.0, 2.0, 0.5), covariance, [], 0.3, 1e-4)
    assert pose == Pose(1.0, 2.0, 0.5) and poses == []
    assert np.array_equal(p, covariance)


_ANGLES = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)


@fuzz_settings(2000)
@given(angle=_ANGLES)
def test_compiled_remainder_and_wrap_are_pythons(angle: float) -> None:
    expected = math.remainder(angle, 2.0 * math.pi)
    got = remainder(angle, 2.0 * math.pi)
    assert got == expected and math.copysign(1.0, got) == math.copysign(1.0, expected)
    assert wrap_angle(angle) == Pose(0.0, 0.0, angle).theta


@pytest.mark.parametrize("multiple", [-5, -3, -1, 1, 3, 5])
def test_wrap_of_odd_multiples_of_pi_is_pi(multiple: int) -> None:
    """Half way between two multiples of 2 pi: remainder takes the even one."""
    angle = multiple * math.pi
    assert remainder(angle, 2.0 * math.pi) == math.remainder(angle, 2.0 * math.pi)
    assert wrap_angle(angle) == Pose(0.0, 0.0, angle).theta
