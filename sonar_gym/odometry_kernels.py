"""The compiled loop of the EKF prediction over a run of commands (Kim et al. sec. 3.1 eqs.
(5)-(6)): ``x = f(x, u)``, ``P = A P A^T + F V F^T`` symmetrised, command by command.

It does :func:`sonar_gym.odometry.predict_step`'s arithmetic in its order: the 3x3 and 3x2
products as numpy's BLAS rounds them (each entry ``a_0 b_0`` plus every further term with one
fused multiply-add, :data:`sonar_gym.compiled.fused_multiply_add`), the rest elementwise, the
cosines and sines from libm as Python's ``math``. So it returns the same bits; numpy's four
small products and three array constructions cost about 35 us per command.

:func:`run_headings`, :func:`run_poses` and :func:`run_covariances` are
:func:`sonar_gym.odometry.predict_run`'s closed form over a whole run (the headings, the poses,
the covariances), element by element in the order numpy evaluates the array form; the cosines
and sines of the midpoint headings stay numpy's, taken between the first two.
"""

from __future__ import annotations

import math

import numpy as np
from numba import types

from sonar_gym.compiled import (
    NUMBERS,
    TABLE,
    compiled,
    fused_multiply_add,
    wrap_angle,
    wrap_to_pi,
)
from sonar_gym.pose import FloatArray

_MATRIX = types.Array(types.float64, 2, "C")


def _product(a: FloatArray, b: FloatArray, b_transposed: bool) -> FloatArray:
    """``a @ b`` (or ``a @ b.T``) as OpenBLAS's ``gemm`` rounds it."""
    rows, inner = a.shape
    columns = b.shape[0] if b_transposed else b.shape[1]
    out = np.empty((rows, columns))
    for i in range(rows):
        for j in range(columns):
            total = a[i, 0] * (b[j, 0] if b_transposed else b[0, j])
            for k in range(1, inner):
                total = fused_multiply_add(a[i, k], b[j, k] if b_transposed else b[k, j], total)
            out[i, j] = total
    return out


_product_compiled = compiled(_MATRIX, TABLE, TABLE, types.boolean, inline=True)(_product)


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.float64, 2, "C"), _MATRIX)),
    types.UniTuple(types.float64, 3),  # pose
    TABLE,  # covariance
    TABLE,  # increments_m
    types.float64,  # wheel_base_m
    types.float64,  # variance_per_m
    types.float64,  # scale_variance
    types.boolean,  # midpoint
)
def predict_commands(
    pose: tuple[float, float, float],
    covariance: FloatArray,
    increments_m: FloatArray,
    wheel_base_m: float,
    variance_per_m: float,
    scale_variance: float,
    midpoint: bool,
) -> tuple[FloatArray, FloatArray]:
    """The EKF prediction over ``increments_m`` (``(n, 2)`` ``(d_left, d_right)`` wheel travel,
    metres) from ``pose`` (``(x, y, theta)``, {W}; metres, radians) and its ``covariance``.

    Returns ``(poses, covariance)``: ``(n, 3)`` the predicted pose after each command (heading
    wrapped to (-pi, pi], as :class:`~sonar_gym.pose.Pose` wraps it between commands) and the
    covariance after the last. ``midpoint``: the Jacobians at the
    heading half way through the turn (:data:`sonar_gym.odometry.FilterIntegration`).
    """
    x, y, theta = pose
    p = covariance.copy()
    n = increments_m.shape[0]
    poses = np.empty((n, 3))
    state_jacobian = np.eye(3)
    wheel_jacobian = np.empty((3, 2))
    wheels = np.zeros((2, 2))
    inverse_base = 1.0 / wheel_base_m
    for command in range(n):
        d_left, d_right = increments_m[command, 0], increments_m[command, 1]
        distance = 0.5 * (d_left + d_right)
        turned = (d_right - d_left) / wheel_base_m
        heading = theta + 0.5 * turned if midpoint else theta
        cos_h, sin_h = math.cos(heading), math.sin(heading)
        state_jacobian[0, 2] = -distance * sin_h
        state_jacobian[1, 2] = distance * cos_h
        half_cos, half_sin = 0.5 * cos_h, 0.5 * sin_h
        if midpoint:  # the lever of the half-turn, added to the first two rows
            lever = distance / (2.0 * wheel_base_m)
            wheel_jacobian[0, 0] = half_cos + -lever * sin_h
            wheel_jacobian[0, 1] = half_cos + lever * sin_h
            wheel_jacobian[1, 0] = half_sin + lever * cos_h
            wheel_jacobian[1, 1] = half_sin + -lever * cos_h
        else:
            wheel_jacobian[0, 0] = wheel_jacobian[0, 1] = half_cos
            wheel_jacobian[1, 0] = wheel_jacobian[1, 1] = half_sin
        wheel_jacobian[2, 0], wheel_jacobian[2, 1] = inverse_base, -inverse_base
        # wheel_increment_covariance: right wheel first
        wheels[0, 0] = variance_per_m * abs(d_right) + scale_variance * d_right * d_right
        wheels[1, 1] = variance_per_m * abs(d_left) + scale_variance * d_left * d_left
        state_part = _product_compiled(
            _product_compiled(state_jacobian, p, False), state_jacobian, True
        )
        wheel_part = _product_compiled(
            _product_compiled(wheel_jacobian, wheels, False), wheel_jacobian, True
        )
        summed = state_part + wheel_part
        p = 0.5 * (summed + summed.T)
        x, y, theta = x + distance * cos_h, y + distance * sin_h, wrap_angle(theta + turned)
        poses[command, 0], poses[command, 1], poses[command, 2] = x, y, theta
    return poses, p


@compiled(  # type: ignore[misc]
    types.UniTuple(types.Array(types.float64, 1, "C"), 3),
    types.float64,  # theta
    NUMBERS,  # left
    NUMBERS,  # right
    types.float64,  # wheel_base_m
)
def run_headings(
    theta: float, left: FloatArray, right: FloatArray, wheel_base_m: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(distance, midpoint_headings, headings)`` of a run of ``K`` commands from ``theta``.

    Per command the distance ``(d_r + d_l)/2`` (metres) and the heading half way through its
    turn ``(d_r - d_l)/l`` (radians, unwrapped); ``(K + 1,)`` the unwrapped headings from
    ``theta + 0`` on, their turns summed left to right as ``cumsum`` sums them.
    """
    count = left.shape[0]
    distance = np.empty(count)
    midpoint_headings = np.empty(count)
    headings = np.empty(count + 1)
    headings[0] = theta + 0.0
    turned = 0.0
    for command in range(count):
        distance[command] = 0.5 * (right[command] + left[command])
        turn = (right[command] - left[command]) / wheel_base_m
        turned = turn if command == 0 else turned + turn
        midpoint_headings[command] = headings[command] + 0.5 * turn
        headings[command + 1] = theta + turned
    return distance, midpoint_headings, headings


@compiled(  # type: ignore[misc]
    types.Array(types.float64, 2, "C"),
    types.UniTuple(types.float64, 3),  # pose
    NUMBERS,  # distance
    NUMBERS,  # cos_h
    NUMBERS,  # sin_h
    NUMBERS,  # headings
)
def run_poses(
    pose: tuple[float, float, float],
    distance: FloatArray,
    cos_h: FloatArray,
    sin_h: FloatArray,
    headings: FloatArray,
) -> FloatArray:
    """``(K + 1, 3)`` rows ``[x, y, theta]`` ({W}; metres, radians) from ``pose`` on: the
    chords ``distance * (cos_h, sin_h)`` summed left to right, the unwrapped ``headings`` of
    :func:`run_headings` wrapped as :func:`sonar_gym.pose.wrap_angles` wraps them."""
    x, y, theta = pose
    count = distance.shape[0]
    poses = np.empty((count + 1, 3))
    poses[0, 0], poses[0, 1], poses[0, 2] = x, y, theta
    step_x = step_y = 0.0
    for command in range(count):
        chord_x = distance[command] * cos_h[command]
        chord_y = distance[command] * sin_h[command]
        step_x = chord_x if command == 0 else step_x + chord_x
        step_y = chord_y if command == 0 else step_y + chord_y
        poses[command + 1, 0] = x + step_x
        poses[command + 1, 1] = y + step_y
        poses[command + 1, 2] = wrap_to_pi(headings[command + 1])
    return poses


@compiled(  # type: ignore[misc]
    types.Array(types.float64, 3, "C"),
    TABLE,  # covariance
    NUMBERS,  # distance
    NUMBERS,  # cos_h
    NUMBERS,  # sin_h
    NUMBERS,  # right
    NUMBERS,  # left
    types.float64,  # wheel_base_m
    types.float64,  # variance_per_m
)
def run_covariances(
    covariance: FloatArray,
    distance: FloatArray,
    cos_h: FloatArray,
    sin_h: FloatArray,
    right: FloatArray,
    left: FloatArray,
    wheel_base_m: float,
    variance_per_m: float,
) -> FloatArray:
    """The ``(K + 1, 3, 3)`` covariances of :func:`sonar_gym.odometry.predict_run`'s closed form.

    Per command ``k``: the distance ``(d_r + d_l)/2`` (metres), the cosine and sine of its
    midpoint heading (numpy's, as the caller computed them), the encoder increments; the
    elements in the closed form's order of operations (each numpy array expression there is
    one element expression here, its prefix sums sequential as ``cumsum``'s), so it returns
    the same bits without the thirty-odd temporary arrays.
    """
    count = distance.shape[0]
    inverse_base = 1.0 / wheel_base_m
    negative_inverse_base = -1.0 / wheel_base_m
    sums = np.zeros((count + 1, 3))
    for command in range(count):
        step_x = -distance[command] * sin_h[command]
        step_y = distance[command] * cos_h[command]
        if command == 0:
            sums[1, 0], sums[1, 1] = step_x, step_y
        else:
            sums[command + 1, 0] = sums[command, 0] + step_x
            sums[command + 1, 1] = sums[command, 1] + step_y
    out = np.empty((count + 1, 3, 3))
    column = np.empty(3)
    for i in range(3):
        column[i] = covariance[i, 2]
    p33 = covariance[2, 2]
    for k in range(count + 1):
        for i in range(3):
            for j in range(3):
                out[k, i, j] = (
                    (covariance[i, j] + sums[k, i] * column[j]) + column[i] * sums[k, j]
                ) + p33 * (sums[k, i] * sums[k, j])
    if count == 0:
        return out
    # The running sums over the commands before k ("before" in the closed form).
    total = np.zeros((3, 3))
    q_sum = np.zeros(3)
    cross = np.zeros((3, 3))
    weighted = np.zeros(3)
    second = np.zeros((3, 3))
    weight = 0.0
    terms = np.empty((3, 3))
    wheels = np.empty((3, 2))
    for k in range(count + 1):
        if k > 0:
            command = k - 1
            lever = distance[command] / (2.0 * wheel_base_m)
            c, s = cos_h[command], sin_h[command]
            wheels[0, 0] = 0.5 * c - lever * s
            wheels[0, 1] = 0.5 * c + lever * s
            wheels[1, 0] = 0.5 * s + lever * c
            wheels[1, 1] = 0.5 * s - lever * c
            wheels[2, 0] = inverse_base
            wheels[2, 1] = negative_inverse_base
            variance_right = variance_per_m * abs(right[command])
            variance_left = variance_per_m * abs(left[command])
            for i in range(3):
                for j in range(3):
                    terms[i, j] = (  # einsum's order: from zero, each product left to right
                        0.0
                        + wheels[i, 0] * variance_right * wheels[j, 0]
                        + wheels[i, 1] * variance_left * wheels[j, 1]
                    )
            later = sums[k]
            q33 = terms[2, 2]
            first = k == 1
            for i in range(3):
                q_i = terms[i, 2]
                q_sum[i] = q_i if first else q_sum[i] + q_i
                weighted_i = q33 * later[i]
                weighted[i] = weighted_i if first else weighted[i] + weighted_i
                for j in range(3):
                    total[i, j] = terms[i, j] if first else total[i, j] + terms[i, j]
                    cross_ij = later[i] * terms[j, 2]
                    cross[i, j] = cross_ij if first else cross[i, j] + cross_ij
                    second_ij = q33 * (later[i] * later[j])
                    second[i, j] = second_ij if first else second[i, j] + second_ij
            weight = q33 if first else weight + q33
        u = sums[k]
        for i in range(3):
            for j in range(3):
                term = total[i, j] + u[i] * q_sum[j]  # left to right, as numpy adds them
                term = term + q_sum[i] * u[j]
                term = term - cross[i, j]
                term = term - cross[j, i]
                term = term + weight * (u[i] * u[j])
                term = term - u[i] * weighted[j]
                term = term - weighted[i] * u[j]
                term = term + second[i, j]
                out[k, i, j] = out[k, i, j] + term
    for k in range(count + 1):
        for i in range(3):
            for j in range(i, 3):
                value = 0.5 * (out[k, i, j] + out[k, j, i])
                out[k, i, j] = value
                out[k, j, i] = value
    return out
