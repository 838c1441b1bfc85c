"""The result of a rotating-sonar pan."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonar_gym.pose import FloatArray


@dataclass(frozen=True)
class Scan:
    """One pan of a rotating sonar.

    Attributes:
        angles: pan angles in radians, in the robot frame {R} (0 = robot forward, CCW positive),
            in the order the pings were taken.
        ranges: measured range per ping in metres from the pan axis, converted from time of
            flight with the sensor's *assumed* speed of sound; NaN where no echo crossed the
            threshold (a dropout).
        amplitudes: amplitude of the detected echo per ping as the receiver compares it with
            its threshold (after any time-varying gain of the preset; the units of the echo
            model), 0.0 where there was none.
        duration_s: time the pan took in seconds: pan motion plus listening time per ping.
    """

    angles: FloatArray
    ranges: FloatArray
    amplitudes: FloatArray
    duration_s: float

    def __post_init__(self) -> None:
        n = len(self.angles)
        if len(self.ranges) != n or len(self.amplitudes) != n:
            raise ValueError(
                f"Scan: angles, ranges and amplitudes must have one entry per ping "
                f"(got {n}, {len(self.ranges)}, {len(self.amplitudes)})"
            )

    @property
    def detected(self) -> np.ndarray:
        """Boolean mask of pings that returned an echo."""
        return np.isfinite(self.ranges)
