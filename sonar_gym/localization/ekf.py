"""Differential-drive odometry with covariance propagation, and the EKF correction (shared).

Kim, Lee & Jeong, *Self localization of mobile robot using sonar sensing and map building*,
sections 3.1 and 3.2. The paper numbers none of its equations; they are cited here by section
and order of appearance:

- sec. 3.1, eqs. (1)-(3): the motion of a two-wheel robot in one sampling period T,
  ``X(k+1) = X(k) + T (u_r + u_l)/2 cos(theta)``, the same with ``sin`` for ``Y``, and
  ``theta(k+1) = theta(k) + T (u_r - u_l)/l``, with wheel speeds ``u_r, u_l`` (m/s) and
  wheel base ``l`` (m).
- sec. 3.1, eq. (4): ``x(k+1) = f(x(k), u(k) + v(k)) + w(k)``, ``u = [u_r, u_l]^T``, ``v`` the
  wheel-speed error (covariance ``V``), ``w`` the other errors (covariance ``W``).
- sec. 3.1, eqs. (5)-(6): ``x^(k+1) = f(x^(k), u(k))`` and
  ``P(k+1) = A P A^T + F V F^T + W`` with the Jacobians ``A(k)`` (wrt the state) and
  ``F(k)`` (wrt ``u``) printed below them.
- sec. 3.2, eqs. (2)-(6): the EKF: prediction, gain ``K``, state and covariance correction.

Parameterisation. With the encoder increments of one period, ``d_right = T u_r`` and
``d_left = T u_l`` (metres), eqs. (1)-(3) read ``x += (d_right + d_left)/2 cos(theta)``,
``y += (d_right + d_left)/2 sin(theta)``, ``theta += (d_right - d_left)/l``: ``T`` drops out,
``F(k)`` becomes ``[[cos/2, cos/2], [sin/2, sin/2], [1/l, -1/l]]`` (columns ``[right, left]``,
the paper's order of ``u``), and ``V`` is the covariance of the increment errors in m^2
(``V_increment = T^2 V_speed``). The paper's second, "point model" of sec. 3.2 eq. (1)
(``u = [distance, delta_theta]``, ``P = A P A^T + Q``) is the same motion with ``Q`` in place
of ``F V F^T + W``.

Slips in the printed text, and the reading implemented here:

- ``F(k)`` prints ``T/1`` and ``-T/1`` in its last row. Differentiating eq. (3) gives
  ``T/l`` and ``-T/l`` (``l`` the wheel base), so :func:`jacobian_wheels` uses ``1/l``.
- The gain prints ``K = P H^T (H P H^T + G)``, which is not a Kalman gain (its units are
  wrong and it does not shrink as ``G`` grows); :func:`ekf_update` uses
  ``K = P H^T (H P H^T + G)^-1``.

Beside the paper's Euler step (heading taken at the start of the period), ``integration=
"midpoint"`` offers the second-order step that uses the heading at the middle of the period,
which is exact for straight lines and far closer on arcs.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
import numpy.typing as npt

from sonar_gym.pose import FloatArray, Pose, wrap_angle

Integration = Literal["paper", "midpoint"]
INTEGRATIONS: tuple[str, ...] = ("paper", "midpoint")
_IDENTITY = np.eye(3)
"""``I`` over ``[x, y, theta]``; its first rows are the observation ``H`` of a fix."""
_IDENTITY.flags.writeable = False

__all__ = [
    "INTEGRATIONS",
    "Integration",
    "ekf_update",
    "ekf_update_unchecked",
    "jacobian_state",
    "jacobian_wheels",
    "motion_model",
    "predict",
    "proportional_encoder_noise",
]


def _finite_float(value: float, name: str) -> float:
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{name} must be a finite number of metres, got {value!r}")
    return number


def _check_increments(
    d_left_m: float, d_right_m: float, wheel_base_m: float
) -> tuple[float, float, float]:
    left = _finite_float(d_left_m, "d_left_m")
    right = _finite_float(d_right_m, "d_right_m")
    base = float(wheel_base_m)
    if not (math.isfinite(base) and base > 0.0):
        raise ValueError(f"wheel_base_m must be a finite distance > 0 m, got {wheel_base_m!r}")
    return left, right, base


def _check_pose(pose: Pose, name: str) -> Pose:
    if not isinstance(pose, Pose):
        raise ValueError(f"{name} must be a sonar_gym.pose.Pose, got {type(pose).__name__}")
    return pose


def _check_integration(integration: str) -> None:
    if integration not in INTEGRATIONS:
        raise ValueError(f"integration must be one of {INTEGRATIONS}, got {integration!r}")


def _step_heading(
    theta: float, d_left: float, d_right: float, base: float, integration: str
) -> float:
    """Heading at which the step is taken: the start (paper) or the middle of the period."""
    if integration == "paper":
        return theta
    return theta + 0.5 * (d_right - d_left) / base


def motion_model(
    pose: Pose,
    d_left_m: float,
    d_right_m: float,
    wheel_base_m: float,
    integration: Integration = "paper",
) -> Pose:
    """``f(x, u)`` of sec. 3.1 eqs. (1)-(3), written with wheel increments.

    Args:
        pose: robot pose at step k in the world frame {W} (m, m, rad).
        d_left_m, d_right_m: distance rolled by the left / right wheel during the step (m),
            ``T u_l`` and ``T u_r`` in the paper's notation.
        wheel_base_m: distance ``l`` between the two wheels (m).
        integration: ``"paper"`` (heading at the start of the step, eqs. (1)-(3)) or
            ``"midpoint"`` (heading at the middle of the step).

    Returns:
        The pose at step k+1, heading wrapped to (-pi, pi].
    """
    _check_pose(pose, "pose")
    left, right, base = _check_increments(d_left_m, d_right_m, wheel_base_m)
    _check_integration(integration)
    distance = 0.5 * (right + left)
    heading = _step_heading(pose.theta, left, right, base, integration)
    return Pose(
        pose.x + distance * math.cos(heading),
        pose.y + distance * math.sin(heading),
        pose.theta + (right - left) / base,
    )


def jacobian_state(
    pose: Pose,
    d_left_m: float,
    d_right_m: float,
    wheel_base_m: float,
    integration: Integration = "paper",
) -> FloatArray:
    """``A(k)`` of sec. 3.1: the 3x3 Jacobian of :func:`motion_model` wrt ``[x, y, theta]``."""
    _check_pose(pose, "pose")
    left, right, base = _check_increments(d_left_m, d_right_m, wheel_base_m)
    _check_integration(integration)
    distance = 0.5 * (right + left)
    heading = _step_heading(pose.theta, left, right, base, integration)
    return np.array(
        [
            [1.0, 0.0, -distance * math.sin(heading)],
            [0.0, 1.0, distance * math.cos(heading)],
            [0.0, 0.0, 1.0],
        ]
    )


def jacobian_wheels(
    pose: Pose,
    d_left_m: float,
    d_right_m: float,
    wheel_base_m: float,
    integration: Integration = "paper",
) -> FloatArray:
    """``F(k)`` of sec. 3.1: the 3x2 Jacobian of :func:`motion_model` wrt the increments.

    Columns are ``[d_right, d_left]``, the paper's order of ``u = [u_r, u_l]^T``. The last row
    is ``[1/l, -1/l]`` (``T/l`` in the paper's speed form); the printed ``T/1`` is a slip.
    """
    _check_pose(pose, "pose")
    left, right, base = _check_increments(d_left_m, d_right_m, wheel_base_m)
    _check_integration(integration)
    heading = _step_heading(pose.theta, left, right, base, integration)
    cos_h, sin_h = math.cos(heading), math.sin(heading)
    jacobian = np.array(
        [
            [0.5 * cos_h, 0.5 * cos_h],
            [0.5 * sin_h, 0.5 * sin_h],
            [1.0 / base, -1.0 / base],
        ]
    )
    if integration == "midpoint":
        # d(heading)/d(d_right) = +1/(2l), d(heading)/d(d_left) = -1/(2l).
        distance = 0.5 * (right + left)
        lever = distance / (2.0 * base)
        jacobian[0] += np.array([-lever * sin_h, lever * sin_h])
        jacobian[1] += np.array([lever * cos_h, -lever * cos_h])
    return jacobian


def proportional_encoder_noise(
    d_left_m: float, d_right_m: float, variance_per_metre_m: float
) -> FloatArray:
    """A common choice of ``V``: each wheel's variance grows with the distance it rolled.

    Returns ``diag(k |d_right|, k |d_left|)`` in m^2 (order ``[right, left]`` as ``F(k)``),
    with ``k = variance_per_metre_m`` (m^2 of variance per metre rolled). The paper gives no
    value for ``V``.
    """
    left = _finite_float(d_left_m, "d_left_m")
    right = _finite_float(d_right_m, "d_right_m")
    k = float(variance_per_metre_m)
    if not (math.isfinite(k) and k >= 0.0):
        raise ValueError(
            "variance_per_metre_m must be finite and >= 0 (m^2 per m), "
            f"got {variance_per_metre_m!r}"
        )
    return np.diag([k * abs(right), k * abs(left)])


def _covariance(value: npt.ArrayLike | float | None, size: int, name: str) -> FloatArray:
    """A ``size`` x ``size`` covariance from None (zero), a scalar, a diagonal or a matrix."""
    if value is None:
        return np.zeros((size, size))
    array = np.asarray(value, dtype=np.float64)
    if array.ndim == 0:
        array = float(array) * np.eye(size)
    elif array.shape == (size,):
        array = np.diag(array)
    if array.shape != (size, size):
        raise ValueError(
            f"{name} must be a scalar variance, a length-{size} diagonal or a {size}x{size} "
            f"matrix, got shape {np.shape(value)}"
        )
    # The checks on Python floats: a 2x2 or 3x3 matrix costs more in numpy calls than in
    # arithmetic, and these run at every EKF step.
    rows = array.tolist()
    if not all(math.isfinite(value) for row in rows for value in row):
        raise ValueError(f"{name} must be finite")
    if any(rows[i][i] < 0.0 for i in range(size)):
        raise ValueError(f"{name} must have a non-negative diagonal (variances)")
    # np.allclose(array, array.T, rtol=1e-9, atol) for a finite array, without its overhead
    atol = 1e-12 * max(1.0, *(abs(value) for row in rows for value in row))
    for i in range(size):
        for j in range(i + 1, size):
            upper, lower = rows[i][j], rows[j][i]
            difference = abs(upper - lower)
            if not (
                difference <= atol + 1e-9 * abs(lower) and difference <= atol + 1e-9 * abs(upper)
            ):
                raise ValueError(f"{name} must be symmetric")
    return array


def _state_covariance(covariance: npt.ArrayLike, name: str) -> FloatArray:
    array = np.asarray(covariance, dtype=np.float64)
    if array.shape != (3, 3):
        raise ValueError(f"{name} must be a 3x3 matrix over [x, y, theta], got shape {array.shape}")
    return _covariance(array, 3, name)


def _symmetrised(matrix: FloatArray) -> FloatArray:
    """``0.5 * (matrix + matrix.T)``, the halving done in place on the sum (the same products)."""
    total = matrix + matrix.T
    total *= 0.5
    return total


def predict(
    pose: Pose,
    covariance: npt.ArrayLike,
    d_left_m: float,
    d_right_m: float,
    wheel_base_m: float,
    process_noise: npt.ArrayLike | float | None = None,
    encoder_noise: npt.ArrayLike | float | None = None,
    integration: Integration = "paper",
) -> tuple[Pose, FloatArray]:
    """Dead-reckoning prediction of sec. 3.1 eqs. (5)-(6).

    ``x^(k+1) = f(x^(k), u(k))`` and ``P(k+1) = A P A^T + F V F^T + W``.

    Args:
        pose: estimated pose at step k in {W} (m, m, rad).
        covariance: 3x3 covariance ``P(k)`` over ``[x, y, theta]`` (m^2, m rad, rad^2).
        d_left_m, d_right_m: wheel increments of the step (m).
        wheel_base_m: wheel base ``l`` (m).
        process_noise: ``W`` over ``[x, y, theta]``: None (zero), a scalar variance for each
            component, a length-3 diagonal or a 3x3 matrix.
        encoder_noise: ``V``, covariance of the wheel-increment errors in m^2, order
            ``[right, left]``: None (zero), a scalar variance for each wheel, a length-2
            diagonal or a 2x2 matrix. See :func:`proportional_encoder_noise`.
        integration: ``"paper"`` or ``"midpoint"`` (see :func:`motion_model`).

    Returns:
        ``(pose, covariance)`` at step k+1; the covariance is symmetrised.
    """
    _check_pose(pose, "pose")
    state_covariance = _state_covariance(covariance, "covariance")
    process = _covariance(process_noise, 3, "process_noise")
    wheels = _covariance(encoder_noise, 2, "encoder_noise")
    state_jacobian = jacobian_state(pose, d_left_m, d_right_m, wheel_base_m, integration)
    wheel_jacobian = jacobian_wheels(pose, d_left_m, d_right_m, wheel_base_m, integration)
    new_pose = motion_model(pose, d_left_m, d_right_m, wheel_base_m, integration)
    new_covariance = (
        state_jacobian @ state_covariance @ state_jacobian.T
        + wheel_jacobian @ wheels @ wheel_jacobian.T
        + process
    )
    return new_pose, _symmetrised(new_covariance)


def ekf_update(
    pose: Pose,
    covariance: npt.ArrayLike,
    measured_pose: Pose,
    measurement_covariance: npt.ArrayLike,
    joseph_form: bool = False,
) -> tuple[Pose, FloatArray]:
    """EKF correction of sec. 3.2 eqs. (3)-(5) with a pose fix from the voting localization.

    The fix measures the state directly, ``h(r) = H r``: with a 3x3 ``measurement_covariance``
    ``H = I`` (position and heading); with a 2x2 one ``H`` keeps the rows of ``x`` and ``y``
    (position only, ``measured_pose.theta`` is ignored).

    - gain ``K = P H^T (H P H^T + G)^-1`` (the printed gain lacks the inverse);
    - ``r = r^- + K (z - H r^-)`` with the heading innovation wrapped to (-pi, pi];
    - ``P = (I - K H) P^-`` (the paper's form), or with ``joseph_form=True`` the Joseph form
      ``(I - K H) P^- (I - K H)^T + K G K^T``, which stays positive semi-definite under
      rounding. Either is symmetrised.

    When ``H P H^T + G`` is singular (both certain), the pseudo-inverse is used.

    Args:
        pose: predicted pose ``r^-`` in {W} (m, m, rad).
        covariance: its 3x3 covariance ``P^-``.
        measured_pose: the fix ``z`` in {W}.
        measurement_covariance: ``G``, 3x3 over ``[x, y, theta]`` or 2x2 over ``[x, y]``.
        joseph_form: use the Joseph-form covariance update.

    Returns:
        ``(pose, covariance)`` after the correction.
    """
    _check_pose(pose, "pose")
    _check_pose(measured_pose, "measured_pose")
    prior = _state_covariance(covariance, "covariance")
    noise_array = np.asarray(measurement_covariance, dtype=np.float64)
    if noise_array.shape not in ((3, 3), (2, 2)):
        raise ValueError(
            "measurement_covariance must be 3x3 (x, y, theta) or 2x2 (x, y), "
            f"got shape {noise_array.shape}"
        )
    rows = noise_array.shape[0]
    noise = _covariance(noise_array, rows, "measurement_covariance")
    return ekf_update_unchecked(pose, prior, measured_pose, noise, joseph_form)


def ekf_update_unchecked(
    pose: Pose,
    covariance: FloatArray,
    measured_pose: Pose,
    measurement_covariance: FloatArray,
    joseph_form: bool = False,
) -> tuple[Pose, FloatArray]:
    """:func:`ekf_update` without its argument checks, for a filter's own state.

    ``covariance`` must be a finite symmetric 3x3 float64 array and ``measurement_covariance``
    a finite symmetric 3x3 or 2x2 one with a non-negative diagonal (as the filter's
    predictions and a checked fix covariance are); the checks cost a third of the update.
    """
    prior, noise = covariance, measurement_covariance
    rows = noise.shape[0]
    innovation_theta = wrap_angle(measured_pose.theta - pose.theta)
    if rows == 3 and not joseph_form and prior.flags.c_contiguous and _kept_by_identity(prior):
        innovation = np.array(
            [measured_pose.x - pose.x, measured_pose.y - pose.y, innovation_theta]
        )
        dx, dy, dtheta, posterior = _position_and_heading_update(prior, noise, innovation)
    else:
        dx, dy, dtheta, posterior = _general_update(
            pose, prior, measured_pose, noise, innovation_theta, joseph_form
        )
    x, y, theta = pose.x + dx, pose.y + dy, pose.theta + dtheta
    if math.isfinite(x) and math.isfinite(y) and math.isfinite(theta):
        return Pose.unchecked(x, y, theta), _symmetrised(posterior)
    return Pose(x, y, theta), _symmetrised(posterior)  # raises, naming the non-finite field


def _position_and_heading_update(
    prior: FloatArray, noise: FloatArray, innovation: FloatArray
) -> tuple[float, float, float, FloatArray]:
    """``(K nu, (I - K) P)`` of a 3x3 fix (``H = I``) on a C-ordered ``P`` that
    :func:`_kept_by_identity` keeps: ``H P H^T`` and ``P H^T`` are ``P`` itself, bit for bit.

    The products are ``ndarray.dot``: on C-ordered operands it makes the BLAS calls of ``@``
    (the same bits) at half its per-call cost. Returns the state correction (m, m, rad) and
    the posterior before symmetrising.
    """
    gain = prior.dot(_inverse_or_pseudo_inverse(prior + noise))
    dx, dy, dtheta = gain.dot(innovation).tolist()
    # K @ H is K itself when K is kept by the identity; the product otherwise
    correction = _IDENTITY - (gain if _kept_by_identity(gain) else gain @ _IDENTITY)
    return dx, dy, dtheta, correction.dot(prior)


def _general_update(
    pose: Pose,
    prior: FloatArray,
    measured_pose: Pose,
    noise: FloatArray,
    innovation_theta: float,
    joseph_form: bool,
) -> tuple[float, float, float, FloatArray]:
    """The state correction ``K nu`` (m, m, rad) and the posterior covariance before
    symmetrising, for any layout of ``P``, a 3x3 or 2x2 ``G`` and either covariance form."""
    rows = noise.shape[0]
    observation = _IDENTITY[:rows]
    full_innovation = [measured_pose.x - pose.x, measured_pose.y - pose.y, innovation_theta]
    innovation = np.array(full_innovation)[:rows]
    if rows == 3 and prior.flags.c_contiguous and _kept_by_identity(prior):
        # H = I: H P H^T and P H^T are P itself, bit for bit
        innovation_covariance = prior + noise
        gain = prior @ _inverse_or_pseudo_inverse(innovation_covariance)
    else:
        innovation_covariance = observation @ prior @ observation.T + noise
        gain = prior @ observation.T @ _inverse_or_pseudo_inverse(innovation_covariance)
    dx, dy, dtheta = (gain @ innovation).tolist()
    held = rows == 3 and _kept_by_identity(gain)
    correction = _IDENTITY - (gain if held else gain @ observation)
    if joseph_form:
        posterior = correction @ prior @ correction.T + gain @ noise @ gain.T
    else:
        posterior = correction @ prior
    return dx, dy, dtheta, posterior


def _kept_by_identity(matrix: FloatArray) -> bool:
    """Whether ``I @ matrix`` and ``matrix @ I`` give back ``matrix`` bit for bit: so when every
    entry is finite and nonzero. Each entry of such a product sums that entry and products
    with 0, signed zeros, which leave a nonzero sum as it is in any order of summation; a zero
    entry could come back with the other sign, a non-finite one as NaN. (The C order that the
    product's result has is the caller's to check where the layout matters.)"""
    values = matrix.ravel().tolist()
    return all(values) and all(map(math.isfinite, values))


def _inverse_or_pseudo_inverse(matrix: FloatArray) -> FloatArray:
    """``np.linalg.inv(matrix)``, or its pseudo-inverse where that fails or is not finite."""
    try:
        inverse = np.linalg.inv(matrix)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(matrix)  # type: ignore[return-value]
    if all(map(math.isfinite, inverse.ravel().tolist())):
        return inverse  # type: ignore[return-value]
    return np.linalg.pinv(matrix)  # type: ignore[return-value]
