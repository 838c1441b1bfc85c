"""Planar poses and angle helpers shared by the simulator and the localization methods.

A pose is ``(x, y, theta)`` in metres and radians, in the world frame {W} unless a docstring
says otherwise; ``theta`` is the heading of the robot frame {R}'s x-axis, wrapped to (-pi, pi].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sonar_gym.frozen import unchecked_instance

FloatArray = npt.NDArray[np.float64]


def wrap_angle(angle_rad: float) -> float:
    """Wrap an angle in radians to (-pi, pi]."""
    wrapped = math.remainder(angle_rad, 2.0 * math.pi)
    return math.pi if wrapped == -math.pi else wrapped


def wrap_angles(angles_rad: npt.ArrayLike) -> FloatArray:
    """Vectorised :func:`wrap_angle` over an array of angles in radians."""
    wrapped = np.remainder(np.asarray(angles_rad, dtype=np.float64) + np.pi, 2.0 * np.pi) - np.pi
    return np.where(wrapped <= -np.pi, np.pi, wrapped)


def vector_norm(vector: FloatArray) -> float:
    """``np.linalg.norm`` of a 1-d float64 vector (metres), in its own form ``sqrt(x . x)``
    (so the same bits), without its per-call checks."""
    return math.sqrt(float(vector.dot(vector)))


def angle_difference(a_rad: float, b_rad: float) -> float:
    """Signed smallest difference ``a - b`` in radians, in (-pi, pi]."""
    return wrap_angle(a_rad - b_rad)


@dataclass(frozen=True)
class Pose:
    """A planar pose: position ``(x, y)`` in metres and heading ``theta`` in radians.

    The heading is wrapped to (-pi, pi] on construction, so two poses that differ by a full
    turn compare equal.
    """

    x: float
    y: float
    theta: float = 0.0

    def __post_init__(self) -> None:
        for name in ("x", "y", "theta"):
            value = float(getattr(self, name))
            if not math.isfinite(value):
                raise ValueError(f"Pose.{name} must be finite, got {value!r}")
            object.__setattr__(self, name, value)
        object.__setattr__(self, "theta", wrap_angle(self.theta))

    @classmethod
    def unchecked(cls, x: float, y: float, theta: float) -> Pose:
        """The pose ``(x, y, theta)`` from finite Python floats, without the checks.

        For inner loops whose inputs were validated at their boundary (integrators, filters):
        the same pose as ``Pose(x, y, theta)``, heading wrapped to (-pi, pi], at a fraction of
        the cost. Passing anything but finite floats is the caller's error.
        """
        return unchecked_instance(cls, x=x, y=y, theta=wrap_angle(theta))

    @classmethod
    def from_array(cls, values: npt.ArrayLike) -> Pose:
        """Build a pose from ``[x, y, theta]`` (metres, metres, radians)."""
        x, y, theta = np.asarray(values, dtype=np.float64).reshape(3)
        return cls(float(x), float(y), float(theta))

    def as_array(self) -> FloatArray:
        """``[x, y, theta]`` as a float64 array."""
        return np.array((self.x, self.y, self.theta), dtype=np.float64)

    @property
    def position(self) -> FloatArray:
        """``[x, y]`` in metres."""
        return np.array([self.x, self.y], dtype=np.float64)

    def transform_point(self, point_in_pose_frame: npt.ArrayLike) -> FloatArray:
        """Map a point given in this pose's frame to the parent frame (metres)."""
        px, py = np.asarray(point_in_pose_frame, dtype=np.float64).reshape(2)
        c, s = math.cos(self.theta), math.sin(self.theta)
        return np.array([self.x + c * px - s * py, self.y + s * px + c * py])

    def compose(self, relative: Pose) -> Pose:
        """The pose ``relative`` (given in this pose's frame) expressed in the parent frame."""
        c, s = math.cos(self.theta), math.sin(self.theta)  # as transform_point, in floats
        x = self.x + c * relative.x - s * relative.y
        y = self.y + s * relative.x + c * relative.y
        return Pose.unchecked(x, y, self.theta + relative.theta)
