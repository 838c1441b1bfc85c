"""Dead reckoning of a differential-drive robot: one noise vocabulary, whole motions at once.

The motion model is that of Kim, Lee & Jeong, section 3.1 (after Komoriya et al.): over one
sampling period the wheels roll ``d_l`` and ``d_r`` (metres) and

    x += (d_r + d_l)/2 cos(theta),   y += (d_r + d_l)/2 sin(theta),   theta += (d_r - d_l)/l

with ``l`` the wheel base. A command of :class:`~sonar_gym.robot.DifferentialDriveRobot` is
``n`` equal substeps; the functions here integrate all of them in one call (closed forms over
arrays, no per-substep Python), and :func:`predict_over_motion` carries the EKF prediction of
sec. 3.1 eqs. (5)-(6) over the elementary commands of a motion (:func:`predict_run`: the same
prediction, midpoint integration, over a whole run of commands in closed form).

:class:`OdometryConfig` is the one vocabulary of the odometry's errors (encoder noise per
square-root metre, wheel scale errors, slip); :func:`wheel_increment_covariance` is the one
model of the filter's wheel-increment covariance ``V``.

Units: metres, radians; poses in the world frame {W}, the heading wrapped to (-pi, pi].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from sonar_gym import odometry_kernels
from sonar_gym.pose import FloatArray, Pose
from sonar_gym.validation import checked_array, checked_positive

Integration = Literal["euler", "midpoint", "arc"]
INTEGRATIONS: tuple[str, ...] = ("euler", "midpoint", "arc")
FilterIntegration = Literal["paper", "midpoint"]
Wheels = Any
"""One wheel's value as a float, or many wheels' as a float array (see the wheel-error model)."""


def sinc(x: float) -> float:
    """``sin(x) / x`` with its limit 1 at 0 (the series ``1 - x^2 / 6`` below 1e-4 rad)."""
    if abs(x) < 1e-4:
        return 1.0 - x * x / 6.0
    return math.sin(x) / x


def sinc_of_array(x: FloatArray) -> FloatArray:
    """:func:`sinc` of every entry (NumPy's vectorised sine may differ from it in the last bit)."""
    small = np.abs(x) < 1e-4
    safe = np.where(small, 1.0, x)
    return np.where(small, 1.0 - x * x / 6.0, np.sin(safe) / safe)


@dataclass(frozen=True)
class OdometryConfig:
    """Odometry and wheel-ground errors of a small indoor differential-drive robot.

    Attributes:
        encoder_std_m_per_sqrt_m: random error of each encoder increment: zero-mean Gaussian
            with variance ``encoder_std_m_per_sqrt_m**2 * |d|`` for a wheel increment ``d``
            (metres), i.e. the standard deviation in metres after one metre of travel; the
            variance grows with distance, so splitting a motion does not change it. This is
            the wheel-speed error ``v(k)`` of Kim et al. Default 5 mm per metre.
        scale_error_left, scale_error_right: systematic relative error of each wheel's
            effective radius (dimensionless; 0.002 = the wheel rolls 0.2 % farther than the
            encoder reports). Fixed for the robot, not redrawn. Defaults +/-0.2 %, i.e. a
            heading drift of about 0.6 deg per metre on a 0.4 m wheel base.
        slip_probability_per_m: probability that a wheel slips at least once while rolling one
            metre, in [0, 1]; for an increment ``d`` the probability is
            ``1 - (1 - p)**|d|``. Default 0.01.
        slip_fraction_max: when a wheel slips, it loses a fraction ``U(0, slip_fraction_max)``
            of its ground travel on that command (dimensionless, in [0, 1]). Default 0.3.
    """

    encoder_std_m_per_sqrt_m: float = 0.005
    scale_error_left: float = 0.002
    scale_error_right: float = -0.002
    slip_probability_per_m: float = 0.01
    slip_fraction_max: float = 0.3

    def __post_init__(self) -> None:
        kind = type(self).__name__
        for name in (
            "encoder_std_m_per_sqrt_m",
            "scale_error_left",
            "scale_error_right",
            "slip_probability_per_m",
            "slip_fraction_max",
        ):
            value = getattr(self, name)
            if (
                isinstance(value, bool)
                or not isinstance(value, (int, float))
                or not math.isfinite(value)
            ):
                raise ValueError(f"{kind}.{name} must be a finite number; got {value!r}")
            object.__setattr__(self, name, float(value))
        if self.encoder_std_m_per_sqrt_m < 0.0:
            raise ValueError(
                f"{kind}.encoder_std_m_per_sqrt_m must be >= 0; got {self.encoder_std_m_per_sqrt_m}"
            )
        for name in ("scale_error_left", "scale_error_right"):
            if not -0.5 < getattr(self, name) < 0.5:
                raise ValueError(f"{kind}.{name} must be in (-0.5, 0.5); got {getattr(self, name)}")
        for name in ("slip_probability_per_m", "slip_fraction_max"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"{kind}.{name} must be in [0, 1]; got {getattr(self, name)}")

    @classmethod
    def none(cls) -> OdometryConfig:
        """No noise at all: odometry equals the truth unless the robot is blocked."""
        return cls(0.0, 0.0, 0.0, 0.0, 0.0)

    # The methods below are the one model of the wheel errors. They take one wheel's
    # numbers as Python floats (DifferentialDriveRobot.drive) or many as arrays (a run of
    # commands: sonar_gym.straight_drive takes numpy's slip_probability of them into its
    # compiled loop). ``abs`` and ``**`` stay Python's on floats and NumPy's on arrays, so each
    # caller keeps its arithmetic bit for bit (NumPy's vectorised power can differ from the
    # scalar one in the last bit).

    def encoder_increments(self, commanded_m: Wheels, normals: Wheels) -> Wheels:
        """What the encoders report for wheels commanded ``commanded_m`` metres: the command
        plus Gaussian noise of standard deviation ``encoder_std_m_per_sqrt_m * sqrt(|d|)``,
        from standard normal draws ``normals`` (same shape), metres."""
        # math.sqrt on one wheel's float: the correctly rounded root np.sqrt gives, without a ufunc
        root = math.sqrt if isinstance(commanded_m, float) else np.sqrt
        return commanded_m + self.encoder_std_m_per_sqrt_m * root(abs(commanded_m)) * normals

    def slip_probability(self, commanded_m: Wheels) -> Wheels:
        """Probability that wheels commanded ``commanded_m`` metres slip on the command:
        ``1 - (1 - p)^|d|`` (``p`` per metre)."""
        return 1.0 - (1.0 - self.slip_probability_per_m) ** abs(commanded_m)

    def ground_travel(
        self, commanded_m: Wheels, scale_errors: Wheels, slip_draws: Wheels, size_draws: Wheels
    ) -> Wheels:
        """How far wheels commanded ``commanded_m`` metres roll on the ground, metres: scaled
        by ``1 + scale_errors`` (their radius errors), less any slip. A wheel slips when its
        uniform draw ``slip_draws`` falls below ``1 - (1 - p)^|d|`` (``p`` per metre) and then
        loses the fraction ``size_draws * slip_fraction_max`` of the command (``size_draws``
        uniform in [0, 1))."""
        slip_probability = self.slip_probability(commanded_m)
        if isinstance(slip_draws, float):  # one wheel: a plain branch, no 0-d arrays
            slip_loss = (
                size_draws * self.slip_fraction_max if slip_draws < slip_probability else 0.0
            )
        else:
            slip_loss = np.where(
                slip_draws < slip_probability, size_draws * self.slip_fraction_max, 0.0
            )
        return commanded_m * (1.0 + scale_errors) * (1.0 - slip_loss)


def integrate_substeps(
    pose: Pose,
    d_left_m: float,
    d_right_m: float,
    wheel_base_m: float,
    substeps: int,
    integration: Integration = "midpoint",
) -> Pose:
    """``substeps`` equal steps of :func:`sonar_gym.robot.unicycle_step`, summed in one go.

    Each substep rolls ``d_left_m / n`` and ``d_right_m / n`` and turns by ``delta =
    (d_right_m - d_left_m) / (l n)``; substep ``k`` heads at ``theta + k delta`` (``"euler"``)
    or ``theta + (k + 1/2) delta`` (``"midpoint"``, ``"arc"``; ``"arc"`` also shortens each
    chord by ``sinc(delta / 2)``). The position is the sum of the ``n`` chords, taken in closed
    form.

    Args:
        pose: pose before the command ({W}; metres, radians).
        d_left_m, d_right_m: wheel travel of the whole command, metres.
        wheel_base_m: wheel base ``l``, metres (> 0).
        substeps: number of equal substeps ``n`` (>= 1).
        integration: ``"euler"``, ``"midpoint"`` or ``"arc"`` (see ``unicycle_step``).
    """
    n = int(substeps)
    d_left_m, d_right_m, wheel_base_m = float(d_left_m), float(d_right_m), float(wheel_base_m)
    if not (math.isfinite(d_left_m) and math.isfinite(d_right_m)):
        raise ValueError(
            f"wheel increments must be finite (metres); got {d_left_m!r}, {d_right_m!r}"
        )
    distance = 0.5 * (d_left_m + d_right_m) / n
    delta = (d_right_m - d_left_m) / (wheel_base_m * n)
    if delta == 0.0:
        heading = pose.theta
        return Pose.unchecked(
            pose.x + n * distance * math.cos(heading),
            pose.y + n * distance * math.sin(heading),
            heading,
        )
    lead = 0.0 if integration == "euler" else 0.5
    if integration == "arc":
        distance *= sinc(0.5 * delta)
    # sum_k cos(theta + (k + lead) delta) = sin(n delta / 2) / sin(delta / 2) cos(theta + c delta)
    # with c = lead + (n - 1) / 2 (the Dirichlet kernel; the same for sin)
    half = 0.5 * delta
    gain = n if abs(half) < 1e-300 else math.sin(n * half) / math.sin(half)
    heading = pose.theta + (lead + 0.5 * (n - 1)) * delta
    return Pose.unchecked(
        pose.x + distance * gain * math.cos(heading),
        pose.y + distance * gain * math.sin(heading),
        pose.theta + n * delta,
    )


def arc_displacements(
    pose: Pose, d_left_m: float, d_right_m: float, wheel_base_m: float, substeps: int
) -> FloatArray:
    """``(n, 3)`` ``[dx, dy, dtheta]`` of ``n`` equal stretches of the exact arc, in {W}.

    The points at fractions ``k / n`` of the command lie on the circular arc of constant wheel
    speeds (``unicycle_step(..., "arc")`` of the fraction); the rows are their differences,
    the heading change ``(d_right_m - d_left_m) / (l n)`` in each.
    """
    n = int(substeps)
    fractions = np.arange(n + 1) / n
    distance = 0.5 * (d_left_m + d_right_m) * fractions
    turned = (d_right_m - d_left_m) / wheel_base_m * fractions
    half = 0.5 * turned
    shortening = sinc_of_array(half)
    direction = pose.theta + half
    points = np.stack(
        [distance * shortening * np.cos(direction), distance * shortening * np.sin(direction)],
        axis=1,
    )
    displacements = np.empty((n, 3))
    displacements[:, :2] = np.diff(points, axis=0)
    displacements[:, 2] = (d_right_m - d_left_m) / wheel_base_m / n
    return displacements


def wheel_increment_covariance(
    d_left_m: float,
    d_right_m: float,
    variance_per_m: float,
    scale_variance: float = 0.0,
) -> FloatArray:
    """``V`` of Kim et al. sec. 3.1: 2x2 covariance of the wheel increments, order [right, left].

    ``diag(k |d_r| + s d_r^2, k |d_l| + s d_l^2)`` in m^2: a random error whose variance grows
    by ``k = variance_per_m`` (m^2 per metre rolled) and a scale error of variance ``s =
    scale_variance`` (dimensionless^2) that grows with the square of the increment.
    """
    right = variance_per_m * abs(d_right_m) + scale_variance * d_right_m * d_right_m
    left = variance_per_m * abs(d_left_m) + scale_variance * d_left_m * d_left_m
    return np.array([[right, 0.0], [0.0, left]])


def predict_step(
    pose: Pose,
    covariance: FloatArray,
    d_left_m: float,
    d_right_m: float,
    wheel_base_m: float,
    variance_per_m: float,
    scale_variance: float = 0.0,
    integration: FilterIntegration = "paper",
) -> tuple[Pose, FloatArray]:
    """One EKF prediction (Kim et al. sec. 3.1 eqs. (5)-(6)) over one command's increments.

    ``x = f(x, u)`` and ``P = A P A^T + F V F^T`` (symmetrised), ``V`` from
    :func:`wheel_increment_covariance`: :func:`sonar_gym.localization.ekf.predict` without its
    argument checks (the increments come from the robot, finite by construction), compiled
    (:func:`sonar_gym.odometry_kernels.predict_commands`).
    """
    moved, p, _ = predict_over_motion(
        pose,
        covariance,
        ((d_left_m, d_right_m),),
        wheel_base_m,
        variance_per_m,
        scale_variance,
        integration,
    )
    return moved, p


def predict_over_motion(
    pose: Pose,
    covariance: FloatArray,
    increments_m: Sequence[tuple[float, float]] | FloatArray,
    wheel_base_m: float,
    variance_per_m: float,
    scale_variance: float = 0.0,
    integration: FilterIntegration = "paper",
) -> tuple[Pose, FloatArray, list[Pose]]:
    """:func:`predict_step` over the ``(d_left, d_right)`` commands of one motion, in turn.

    Returns:
        ``(pose, covariance, poses)``: the prediction after the last command, its covariance
        and the predicted pose after each command.
    """
    increments = np.asarray(increments_m, dtype=np.float64).reshape(-1, 2)
    if increments.shape[0] == 0:
        return pose, np.asarray(covariance, dtype=np.float64), []
    predicted, p = odometry_kernels.predict_commands(
        (pose.x, pose.y, pose.theta),
        np.asarray(covariance, dtype=np.float64),
        increments,
        float(wheel_base_m),
        float(variance_per_m),
        float(scale_variance),
        integration == "midpoint",
    )
    poses = [Pose.unchecked(x, y, theta) for x, y, theta in predicted.tolist()]
    return poses[-1], p, poses


def predict_run(
    pose: Pose,
    covariance: npt.ArrayLike,
    encoder_left_m: npt.ArrayLike,
    encoder_right_m: npt.ArrayLike,
    wheel_base_m: float,
    variance_per_m: float,
) -> tuple[FloatArray, FloatArray]:
    """The estimate and its covariance after each of a run of encoder increments, as arrays.

    Kim et al. sec. 3.1, eqs (5)-(6), with the midpoint integration: for the increments
    ``d_l, d_r`` of command ``k``, ``d = (d_r + d_l)/2``, ``dtheta = (d_r - d_l)/l``,
    ``x += d cos(theta + dtheta/2)``, ``y += d sin(theta + dtheta/2)``, ``theta += dtheta`` and
    ``P = A P A^T + F V F^T`` with ``V = diag(k |d_r|, k |d_l|)``. It is
    :func:`sonar_gym.localization.kim.predict` (``integration="midpoint"``,
    ``encoder_noise=proportional_encoder_noise(...)``) over every command at once, and
    :func:`predict_over_motion` (``integration="midpoint"``, no scale variance) in closed form:
    O(K) array operations instead of K matrix products, equal to it to rounding.

    Args:
        pose: the estimate before the first command ({W}; metres, radians).
        covariance: its 3x3 covariance over ``[x, y, theta]``.
        encoder_left_m, encoder_right_m: ``(K,)`` encoder increments of each command, metres.
        wheel_base_m: wheel base ``l``, metres.
        variance_per_m: ``k``, each wheel's variance per metre rolled, m^2/m (>= 0).

    Returns:
        ``(poses, covariances)``: ``(K + 1, 3)`` rows ``[x, y, theta]`` (theta wrapped to
        (-pi, pi]) and ``(K + 1, 3, 3)``; row 0 is the input.
    """
    left = checked_array(encoder_left_m, "encoder_left_m", (None,))
    right = checked_array(encoder_right_m, "encoder_right_m", (len(left),))
    start_covariance = checked_array(covariance, "covariance", (3, 3))
    base = checked_positive(wheel_base_m, "wheel_base_m")
    k = checked_variance_per_m(variance_per_m)
    return predict_run_unchecked(pose, start_covariance, left, right, base, k)


def checked_variance_per_m(variance_per_m: float) -> float:
    """A wheel's variance per metre rolled (m^2/m) as a float if finite and >= 0; else a
    ``ValueError`` naming argument ``variance_per_m``."""
    k = float(variance_per_m)
    if not (math.isfinite(k) and k >= 0.0):
        raise ValueError(
            f"argument 'variance_per_m' must be finite and >= 0; got {variance_per_m!r}"
        )
    return k


def predict_run_unchecked(
    pose: Pose,
    covariance: FloatArray,
    encoder_left_m: FloatArray,
    encoder_right_m: FloatArray,
    wheel_base_m: float,
    variance_per_m: float,
) -> tuple[FloatArray, FloatArray]:
    """:func:`predict_run` on checked arguments: finite float64 ``(K,)`` increments (metres),
    a finite ``(3, 3)`` covariance, a positive wheel base and a variance ``>= 0`` as floats.

    The closed form, in compiled loops (:mod:`sonar_gym.odometry_kernels`) with numpy's
    cosines and sines of the midpoint headings between them.
    """
    distance, midpoint_headings, headings = odometry_kernels.run_headings(
        pose.theta, encoder_left_m, encoder_right_m, wheel_base_m
    )
    cos_h, sin_h = np.cos(midpoint_headings), np.sin(midpoint_headings)
    poses = odometry_kernels.run_poses(
        (pose.x, pose.y, pose.theta), distance, cos_h, sin_h, headings
    )
    # F V F^T per command (F's columns [d_right, d_left], V = k diag(|d_r|, |d_l|)). Every
    # A = I + u e3^T with u = (-d sin h, d cos h, 0): their products add the u's, so
    # P_k = Phi_0k P_0 Phi_0k^T + sum_{i<k} Phi_(i+1)k (F V F^T)_i Phi_(i+1)k^T with
    # Phi_jk = I + (U_k - U_j) e3^T and U_k the sum of the first k u's. For symmetric X,
    # (I + w e3^T) X (I + w e3^T)^T = X + w x^T + x w^T + X_33 w w^T with x = X e3; with
    # w = U_k - U_(i+1) the sums over i < k are running sums, so the whole run is O(K),
    # one compiled loop over the elements.
    covariances = odometry_kernels.run_covariances(
        covariance,
        distance,
        cos_h,
        sin_h,
        encoder_right_m,
        encoder_left_m,
        wheel_base_m,
        variance_per_m,
    )
    return poses, covariances


def propagate_covariance(
    linearisation_poses: Sequence[Pose],
    increments_m: Sequence[tuple[float, float]],
    covariance: FloatArray,
    wheel_base_m: float,
    variance_per_m: float,
    scale_variance: float = 0.0,
    integration: FilterIntegration = "paper",
) -> FloatArray:
    """The covariance of :func:`predict_step` over a motion, linearised at given poses.

    Command ``k`` of ``increments_m`` is linearised at ``linearisation_poses[k]`` (e.g. the
    robot's own odometry before that command) instead of at the filter's prediction.
    """
    for pose, (d_left, d_right) in zip(linearisation_poses, increments_m, strict=True):
        _, covariance = predict_step(
            pose,
            covariance,
            d_left,
            d_right,
            wheel_base_m,
            variance_per_m,
            scale_variance,
            integration,
        )
    return covariance


__all__ = [
    "INTEGRATIONS",
    "FilterIntegration",
    "Integration",
    "OdometryConfig",
    "arc_displacements",
    "checked_variance_per_m",
    "integrate_substeps",
    "predict_over_motion",
    "predict_run",
    "predict_run_unchecked",
    "predict_step",
    "propagate_covariance",
    "sinc",
    "sinc_of_array",
    "wheel_increment_covariance",
]
