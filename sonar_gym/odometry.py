"""Dead reckoning of a differential-drive robot: one noise vocabulary, whole motions at once.

The motion model is that of Kim, Lee & Jeong, section 3.1 (after Komoriya et al.): over one
sampling period the wheels roll ``d_l`` and ``d_r`` (metres) and

    x += (d_r + d_l)/2 cos(theta),   y += (d_r + d_l)/2 sin(theta),   theta += (d_r - d_l)/l

with ``l`` the wheel base. A command of :class:`~sonar_gym.robot.DifferentialDriveRobot` is
``n`` equal substeps; the functions here integrate all of them in one call (closed forms over
arrays, no per-substep Python), and :func:`predict_over_motion` carries the EKF prediction of
sec. 3.1 eqs. (5)-(6) over the elementary commands of a motion.

:class:`OdometryConfig` is the one vocabulary of the odometry's errors (encoder noise per
square-root metre, wheel scale errors, slip); :func:`wheel_increment_covariance` is the one
model of the filter's wheel-increment covariance ``V``.

Units: metres, radians; poses in the world frame {W}, the heading wrapped to (-pi, pi].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from sonar_gym.pose import FloatArray, Pose, wrap_angle

Integration = Literal["euler", "midpoint", "arc"]
INTEGRATIONS: tuple[str, ...] = ("euler", "midpoint", "arc")
FilterIntegration = Literal["paper", "midpoint"]


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
    distance = 0.5 * (d_left_m + d_right_m) / n
    delta = (d_right_m - d_left_m) / (wheel_base_m * n)
    if delta == 0.0:
        heading = pose.theta
        return Pose(
            pose.x + n * distance * math.cos(heading),
            pose.y + n * distance * math.sin(heading),
            heading,
        )
    lead = 0.0 if integration == "euler" else 0.5
    if integration == "arc":
        half = 0.5 * delta
        distance *= 1.0 - half * half / 6.0 if abs(half) < 1e-4 else math.sin(half) / half
    # sum_k cos(theta + (k + lead) delta) = sin(n delta / 2) / sin(delta / 2) cos(theta + c delta)
    # with c = lead + (n - 1) / 2 (the Dirichlet kernel; the same for sin)
    half = 0.5 * delta
    gain = n if abs(half) < 1e-300 else math.sin(n * half) / math.sin(half)
    heading = pose.theta + (lead + 0.5 * (n - 1)) * delta
    return Pose(
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
    small = np.abs(half) < 1e-4
    safe = np.where(small, 1.0, half)
    sinc = np.where(small, 1.0 - half * half / 6.0, np.sin(safe) / safe)
    direction = pose.theta + half
    points = np.stack(
        [distance * sinc * np.cos(direction), distance * sinc * np.sin(direction)], axis=1
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
    return np.diag(
        [
            variance_per_m * abs(d_right_m) + scale_variance * d_right_m * d_right_m,
            variance_per_m * abs(d_left_m) + scale_variance * d_left_m * d_left_m,
        ]
    )


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
    argument checks (the increments come from the robot, finite by construction).
    """
    distance = 0.5 * (d_left_m + d_right_m)
    turned = (d_right_m - d_left_m) / wheel_base_m
    heading = pose.theta + 0.5 * turned if integration == "midpoint" else pose.theta
    cos_h, sin_h = math.cos(heading), math.sin(heading)
    state_jacobian = np.array(
        [[1.0, 0.0, -distance * sin_h], [0.0, 1.0, distance * cos_h], [0.0, 0.0, 1.0]]
    )
    inverse_base = 1.0 / wheel_base_m
    wheel_jacobian = np.array(
        [[0.5 * cos_h, 0.5 * cos_h], [0.5 * sin_h, 0.5 * sin_h], [inverse_base, -inverse_base]]
    )
    if integration == "midpoint":
        lever = distance / (2.0 * wheel_base_m)
        wheel_jacobian[0] += (-lever * sin_h, lever * sin_h)
        wheel_jacobian[1] += (lever * cos_h, -lever * cos_h)
    wheels = wheel_increment_covariance(d_left_m, d_right_m, variance_per_m, scale_variance)
    p = state_jacobian @ covariance @ state_jacobian.T + wheel_jacobian @ wheels @ wheel_jacobian.T
    moved = Pose(
        pose.x + distance * cos_h, pose.y + distance * sin_h, wrap_angle(pose.theta + turned)
    )
    return moved, 0.5 * (p + p.T)


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
    p = np.asarray(covariance, dtype=np.float64)
    poses: list[Pose] = []
    for d_left, d_right in np.asarray(increments_m, dtype=np.float64).reshape(-1, 2):
        pose, p = predict_step(
            pose,
            p,
            float(d_left),
            float(d_right),
            float(wheel_base_m),
            variance_per_m,
            scale_variance,
            integration,
        )
        poses.append(pose)
    return pose, p, poses


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
    "integrate_substeps",
    "predict_over_motion",
    "predict_step",
    "propagate_covariance",
    "wheel_increment_covariance",
]
