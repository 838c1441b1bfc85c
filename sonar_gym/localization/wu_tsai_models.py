"""Wu & Tsai (2001): what a fix's uncertainty is, and where the transmitter frame sits.

The small models :class:`~sonar_gym.envs.trilateration.TrilaterationEnv` needs to describe a
fix's uncertainty to an agent and to weight a fix against dead reckoning:

- :func:`quantised_range_error`: the error of one counter-quantised, jittered one-way range
  (eq. (11) with the paper's 50 kHz counter), split into the part that repeated fixes average
  out and the part they cannot (eqs (12)-(16) average the same truncation again);
- :func:`predicted_fix_covariance`: the first-order covariance of one fix by Theorem 2
  (eqs (7)-(9) and the heading from two receivers);
- :class:`TransmitterFrame`: the paper's frame {T} (transmitters at ``[0, 0, 0]``,
  ``[a, 0, 0]``, ``[0, a, 0]``) placed in the world {W} of a scenario.

Units: metres, radians; covariances over ``[x, y, theta]`` in m^2, m rad, rad^2.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

from sonar_gym.pose import FloatArray, Pose
from sonar_gym.scenario import Scenario
from sonar_gym.sonar.ranging import WU_TSAI_RECEIVERS_XY

_TRANSMITTER_FRAME_TOLERANCE = 1e-6
_SPREAD_OF_THE_LIMIT = 4.0
"""Jitter, in counter quanta, from which :func:`quantised_range_error` takes its limit form."""


@dataclass(frozen=True)
class RangeErrorModel:
    """Error of one counter-quantised, jittered one-way range (metres^2).

    Attributes:
        total_variance_m2: variance of the range error over jitter and over the position of the
            true distance within a counter step.
        persistent_variance_m2: the part that repeats when the same distance is measured again
            (the conditional mean of the truncation error given the distance); averaging ``n``
            repeated fixes cannot remove it.
    """

    total_variance_m2: float
    persistent_variance_m2: float

    def variance_of_mean(self, n: int) -> float:
        """Variance of the mean of ``n`` repeated ranges of one distance, m^2 (``n >= 1``)."""
        independent = self.total_variance_m2 - self.persistent_variance_m2
        return self.persistent_variance_m2 + independent / n

    def averaging_factor(self, n: int) -> float:
        """``variance_of_mean(n) / variance_of_mean(1)``: how much ``n`` fixes shrink a variance."""
        if self.total_variance_m2 <= 0.0:
            return 1.0 / n
        return self.variance_of_mean(n) / self.total_variance_m2


def quantised_range_error(
    noise_std_m: float, quantum_m: float, n_phases: int = 512
) -> RangeErrorModel:
    """Moments of ``q floor(d / q + nu / q) - d`` with ``nu ~ N(0, noise_std_m^2)``.

    The distance's phase ``f = frac(d / q)`` is taken uniform on [0, 1). Given ``f`` the error
    has the mean ``b(f) = q (E[floor(f + nu / q)] - f)``, which a repeated measurement of the same
    distance repeats; its variance over ``f`` is the persistent part. With no jitter the whole
    truncation error (variance ``q^2 / 12``) is persistent; with jitter much larger than ``q``
    it is all independent, variance ``noise^2 + q^2 / 12``. The constant mean ``-q / 2`` of
    truncation is left out: a common shift of every distance barely moves ``x`` and ``y``
    (eqs (7)-(8) take differences of squared distances).

    Args:
        noise_std_m: standard deviation of the timing jitter as a distance, metres (>= 0).
        quantum_m: range step of one counter period, metres (>= 0; 0 = no counter).
        n_phases: phases ``f`` of the numerical average.
    """
    if not (math.isfinite(noise_std_m) and noise_std_m >= 0.0):
        raise ValueError(f"argument 'noise_std_m' must be >= 0 metres; got {noise_std_m!r}")
    if not (math.isfinite(quantum_m) and quantum_m >= 0.0):
        raise ValueError(f"argument 'quantum_m' must be >= 0 metres; got {quantum_m!r}")
    if quantum_m == 0.0:
        return RangeErrorModel(noise_std_m**2, 0.0)
    spread = noise_std_m / quantum_m
    if spread >= _SPREAD_OF_THE_LIMIT:
        # floor(f + z) - f = z - frac(f + z), and frac(f + z) is uniform and independent of z
        # when f is: variance noise^2 + q^2 / 12, none of it persistent. The average below
        # agrees to 1e-14 there (its persistent part is rounding, under 1e-28 q^2), and its
        # table of 16 spread columns would grow without bound.
        return RangeErrorModel((spread * spread + 1.0 / 12.0) * (quantum_m * quantum_m), 0.0)
    phases = (np.arange(n_phases) + 0.5) / n_phases
    if noise_std_m == 0.0:
        steps = np.zeros((n_phases, 1))
        weights = np.ones((n_phases, 1))
        offsets = np.zeros(1)
    else:
        reach = math.ceil(8.0 * spread) + 1
        offsets = np.arange(-reach, reach + 1, dtype=np.float64)
        # P(floor(f + z) = k) = Phi((k + 1 - f) / s) - Phi((k - f) / s), z ~ N(0, s^2). A
        # spread far below one quantum sends the quotients to +-inf, where Phi is exactly 0 or 1
        # (k - f is never 0: the phases sit at half-integers over n_phases).
        with np.errstate(over="ignore", divide="ignore"):
            upper = ndtr((offsets[None, :] + 1.0 - phases[:, None]) / spread)
            lower = ndtr((offsets[None, :] - phases[:, None]) / spread)
        weights = upper - lower
        steps = np.broadcast_to(offsets, weights.shape)
    error_steps = steps - phases[:, None]  # error in quanta for each (phase, floor value)
    conditional_mean = np.sum(weights * error_steps, axis=1)
    conditional_square = np.sum(weights * error_steps**2, axis=1)
    total = float(np.mean(conditional_square) - np.mean(conditional_mean) ** 2)
    persistent = float(np.var(conditional_mean))
    q2 = quantum_m * quantum_m
    return RangeErrorModel(total * q2, min(persistent, total) * q2)


@dataclass(frozen=True)
class TransmitterFrame:
    """The paper's reference frame {T} placed in the world {W}.

    The first three emitters of the scenario are the paper's transmitters at ``[0, 0, 0]``,
    ``[a, 0, 0]`` and ``[0, a, 0]`` (Theorem 2). {T} has its origin at the first, its x-axis
    towards the second, its y-axis towards the third and z up (Fig. 4), so a point at height
    ``h`` above the floor has ``z = h - ceiling`` in {T}.

    Attributes:
        origin_xyz: the first transmitter in {W}, metres.
        rotation_rad: angle of the {T} x-axis from the {W} x-axis, radians.
        spacing_m: ``a``, metres.
        names: the three emitters' names, in the order of Theorem 2.
    """

    origin_xyz: tuple[float, float, float]
    rotation_rad: float
    spacing_m: float
    names: tuple[str, str, str]

    @classmethod
    def from_scenario(cls, scenario: Scenario) -> TransmitterFrame:
        """Read and check the transmitters; ``ValueError`` naming ``scenario`` if unusable."""
        if len(scenario.emitters) < 3:
            raise ValueError(
                f"argument 'scenario': {scenario.name!r} needs three emitters (the transmitters at "
                f"[0,0,0], [a,0,0], [0,a,0] of Wu & Tsai); it has {len(scenario.emitters)}"
            )
        first, second, third = (
            np.asarray(e.position, dtype=np.float64) for e in scenario.emitters[:3]
        )
        along_x, along_y = second - first, third - first
        spacing = float(np.linalg.norm(along_x))
        tolerance = _TRANSMITTER_FRAME_TOLERANCE * max(1.0, spacing)
        if (
            spacing <= 0.0
            or abs(float(np.linalg.norm(along_y)) - spacing) > tolerance
            or abs(float(np.dot(along_x, along_y))) > tolerance * spacing
            or abs(along_x[2]) > tolerance
            or abs(along_y[2]) > tolerance
            or float(along_x[0] * along_y[1] - along_x[1] * along_y[0]) <= 0.0
        ):
            raise ValueError(
                f"argument 'scenario': the first three emitters of {scenario.name!r} must sit at "
                "[0,0,0], [a,0,0], [0,a,0] of a frame with z up (same height, equal spacing, "
                "a right angle, counter-clockwise seen from above)"
            )
        if scenario.robot.sensor_height >= first[2]:
            raise ValueError(
                f"argument 'scenario': the receivers (robot.sensor_height = "
                f"{scenario.robot.sensor_height} m) must be below the transmitters ({first[2]} m)"
            )
        return cls(
            origin_xyz=(float(first[0]), float(first[1]), float(first[2])),
            rotation_rad=math.atan2(float(along_x[1]), float(along_x[0])),
            spacing_m=spacing,
            names=tuple(e.name for e in scenario.emitters[:3]),  # type: ignore[arg-type]
        )

    def to_world(self, pose_in_t: Pose) -> Pose:
        """A planar pose in {T} expressed in {W}."""
        c, s = self._rotation_cos_sin
        return _pose(
            self.origin_xyz[0] + c * pose_in_t.x - s * pose_in_t.y,
            self.origin_xyz[1] + s * pose_in_t.x + c * pose_in_t.y,
            pose_in_t.theta + self.rotation_rad,
        )

    def to_transmitter(self, pose_in_w: Pose) -> Pose:
        """A planar pose in {W} expressed in {T}."""
        c, s = self._rotation_cos_sin
        dx, dy = pose_in_w.x - self.origin_xyz[0], pose_in_w.y - self.origin_xyz[1]
        return _pose(c * dx + s * dy, -s * dx + c * dy, pose_in_w.theta - self.rotation_rad)

    @functools.cached_property
    def _rotation_cos_sin(self) -> tuple[float, float]:
        """``cos`` and ``sin`` of ``rotation_rad``."""
        return math.cos(self.rotation_rad), math.sin(self.rotation_rad)

    def height_in_t(self, height_above_floor_m: float) -> float:
        """``z`` in {T} of a point ``height_above_floor_m`` above the floor (negative below)."""
        return height_above_floor_m - self.origin_xyz[2]

    def centroid_xy(self) -> FloatArray:
        """The centroid of the three transmitters in {W}, metres."""
        reference = self.to_world(Pose(self.spacing_m / 3.0, self.spacing_m / 3.0, 0.0))
        return reference.position


def _pose(x: float, y: float, theta: float) -> Pose:
    """``Pose(x, y, theta)`` of floats made from a pose's: only an overflow needs the checks."""
    if math.isfinite(x) and math.isfinite(y) and math.isfinite(theta):
        return Pose.unchecked(x, y, theta)
    return Pose(x, y, theta)  # raises, naming the coordinate


def predicted_fix_covariance(
    pose_in_t: Pose,
    z_m: float,
    spacing_m: float,
    range_variance_m2: float,
    receivers_xy: tuple[tuple[float, float], ...] = WU_TSAI_RECEIVERS_XY,
) -> FloatArray:
    """First-order covariance (3x3 over ``[x, y, theta]``, {T}) of one fix by Theorem 2.

    Each receiver ``j`` is placed by eqs (7)-(8): ``x = (d0^2 - d1^2 + a^2) / 2a`` and
    ``y = (d0^2 - d2^2 + a^2) / 2a``, so with independent range errors of variance ``s^2``
    its ``(x, y)`` has covariance ``s^2 J J^T`` with ``J = [[d0, -d1, 0], [d0, 0, -d2]] / a``:
    the error grows with the distances, i.e. away from below the transmitters. The robot's
    position is the receivers' midpoint and its heading the direction of their baseline
    (Theorem 2), whose error is the receivers' error across the baseline over its length.

    Args:
        pose_in_t: the (estimated) robot pose in {T}.
        z_m: height of the receivers in {T} (negative: below the transmitters), metres.
        spacing_m: ``a``, metres.
        range_variance_m2: variance of one range error, m^2.
        receivers_xy: receiver positions in the robot frame, metres (two, apart).
    """
    a = spacing_m
    c, s = math.cos(pose_in_t.theta), math.sin(pose_in_t.theta)
    x, y = pose_in_t.x, pose_in_t.y
    receivers = [(x + c * px - s * py, y + s * px + c * py) for px, py in receivers_xy]
    n_receivers = len(receivers)
    z_sq = z_m * z_m
    ranges_to_xy = []  # per receiver J = [[d0, -d1, 0], [d0, 0, -d2]] / a
    for rx, ry in receivers:
        # the horizontal offsets to the transmitters at (0, 0), (a, 0) and (0, a)
        near_x, near_y, far_x, far_y = 0.0 - rx, 0.0 - ry, a - rx, a - ry
        d0 = math.sqrt((near_x * near_x + near_y * near_y) + z_sq)
        d1 = math.sqrt((far_x * far_x + near_y * near_y) + z_sq)
        d2 = math.sqrt((near_x * near_x + far_y * far_y) + z_sq)
        ranges_to_xy.append(((d0 / a, -d1 / a, 0.0), (d0 / a, 0.0, -d2 / a)))
    jacobians = np.array(ranges_to_xy)  # (R, 2, 3)
    blocks = (range_variance_m2 * jacobians) @ jacobians.transpose(0, 2, 1)
    receiver_covariance = np.zeros((2 * n_receivers, 2 * n_receivers))
    for j in range(n_receivers):
        receiver_covariance[2 * j : 2 * j + 2, 2 * j : 2 * j + 2] = blocks[j]
    # pose = (midpoint of the receivers, direction of the baseline from the last to the first)
    (front_x, front_y), (back_x, back_y) = receivers[0], receivers[-1]
    baseline = np.array([front_x - back_x, front_y - back_y])
    length_sq = float(baseline @ baseline)
    if not length_sq > 0.0:
        raise ValueError(
            "argument 'receivers_xy' must place the first and last receivers apart (their "
            f"baseline gives the heading); got {receivers_xy!r}"
        )
    across_x, across_y = -(front_y - back_y) / length_sq, (front_x - back_x) / length_sq
    heading_row = [0.0] * (2 * n_receivers)
    heading_row[0] += across_x
    heading_row[1] += across_y
    heading_row[-2] -= across_x
    heading_row[-1] -= across_y
    share = 1.0 / n_receivers
    jacobian = np.array(
        [[share, 0.0] * n_receivers, [0.0, share] * n_receivers, heading_row]
    )  # d pose / d (x_1, y_1, ..., x_R, y_R)
    return jacobian @ receiver_covariance @ jacobian.T


def rotate_covariance(covariance: FloatArray, angle_rad: float) -> FloatArray:
    """A 3x3 ``[x, y, theta]`` covariance seen from a frame rotated by ``angle_rad``."""
    rotation = _planar_rotation(float(angle_rad))
    return rotation @ covariance @ rotation.T


@functools.lru_cache(maxsize=64)
def _planar_rotation(angle_rad: float) -> FloatArray:
    """The 3x3 rotation of ``[x, y, theta]`` by ``angle_rad`` (read-only: it is shared)."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    rotation.flags.writeable = False
    return rotation


def position_std_m(covariance: FloatArray) -> float:
    """``sqrt(var x + var y)``: the RMS position error a covariance predicts, metres."""
    return math.sqrt(max(float(covariance[0, 0] + covariance[1, 1]), 0.0))


def heading_std_rad(covariance: FloatArray) -> float:
    """The heading standard deviation a covariance predicts, radians."""
    return math.sqrt(max(float(covariance[2, 2]), 0.0))


__all__ = [
    "RangeErrorModel",
    "TransmitterFrame",
    "heading_std_rad",
    "position_std_m",
    "predicted_fix_covariance",
    "quantised_range_error",
    "rotate_covariance",
]
