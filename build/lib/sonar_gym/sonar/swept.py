"""Servo-swept and fixed side-looking sonars, on the same echo physics as the rotating pan.

Swept sonar (Kim et al., sec. 4.1)
    An SRF04 on a hobby servo at the pan axis (``scenario.robot.sensor_offset``): "a
    revolution is possible in right and left each 45 deg", and "a 180-degree sweep is
    possible" (sec. 2.1). A sweep takes pings from ``center - half_sweep`` to
    ``center + half_sweep`` *inclusive*, every ``step`` (5 deg by default; the paper gives no
    step). Duration: the servo turns the swept span at the transducer's speed, and every ping
    takes its listening time (50 ms for the SRF04).

Side sonars (Yamamoto et al., APCS, sec. 6)
    Two MA40B8 sensors look left and right (+-90 deg in {R}) from ``lateral_offset_m`` either
    side of the robot centre (0: ranges are measured from the centre, as APCS's estimated
    reflection points assume). "The velocity of the robot was 30 cm/s. The data of
    ultrasonic sensors were taken every 3 cm": :data:`APCS_SAMPLE_SPACING_M`,
    :data:`APCS_SPEED_MPS`. A flat wall parallel to the path reads its perpendicular distance.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from sonar_gym.pose import FloatArray, Pose
from sonar_gym.sonar.presets import preset as transducer_preset
from sonar_gym.sonar.pulse_echo import FirstEchoes, PulseEchoSonar, WorldLike, concatenate_echoes
from sonar_gym.sonar.scan import Scan

KIM_HALF_SWEEP_RAD = math.radians(45.0)
"""Kim et al. sec. 4.1: the servo turns 45 deg right and left of the robot's forward axis."""
KIM_WIDE_HALF_SWEEP_RAD = math.radians(90.0)
"""Kim et al. sec. 2.1: the 180 deg sweep variant."""
APCS_SAMPLE_SPACING_M = 0.03
"""APCS sec. 6: a range sample every 3 cm of travel."""
APCS_SPEED_MPS = 0.3
"""APCS sec. 6: the robot drove at 30 cm/s (so a sample every 0.1 s)."""
_SIDE_DIRECTIONS = np.array([[0.0, 1.0], [0.0, -1.0]])  # left, right in {R}


@dataclass(frozen=True)
class SweptSonar(PulseEchoSonar):
    """A transducer swept by a servo about the robot's forward axis (Kim et al.).

    Attributes:
        half_sweep_rad: half the swept span, radians (45 deg; 90 deg for the 180 deg variant).
        step_rad: angle between pings, radians.
    """

    half_sweep_rad: float = KIM_HALF_SWEEP_RAD
    step_rad: float = math.radians(5.0)

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (math.isfinite(self.half_sweep_rad) and 0.0 < self.half_sweep_rad <= math.pi):
            raise ValueError(
                f"argument 'half_sweep_rad' must be in (0, pi]; got {self.half_sweep_rad!r}"
            )
        if not (math.isfinite(self.step_rad) and self.step_rad > 0.0):
            raise ValueError(
                f"argument 'step_rad' must be positive (radians); got {self.step_rad!r}"
            )

    @classmethod
    def kim(cls, wide: bool = False, **options: object) -> SweptSonar:
        """The SRF04 sweep of Kim et al.: +-45 deg, or 180 deg with ``wide=True``."""
        half = KIM_WIDE_HALF_SWEEP_RAD if wide else KIM_HALF_SWEEP_RAD
        return cls(transducer_preset("srf04"), half_sweep_rad=half, **options)  # type: ignore[arg-type]

    def sweep_angles(self, sector_center: float = 0.0) -> FloatArray:
        """Ping angles in {R}, radians: from ``center - half`` to ``center + half`` inclusive."""
        if not math.isfinite(sector_center):
            raise ValueError(
                f"argument 'sector_center' must be a finite angle in radians; got {sector_center!r}"
            )
        n = math.floor(2.0 * self.half_sweep_rad / self.step_rad + 1e-9) + 1
        return sector_center - self.half_sweep_rad + self.step_rad * np.arange(n, dtype=np.float64)

    def sweep(
        self,
        world: WorldLike,
        pose: Pose,
        rng: np.random.Generator | None,
        sector_center: float = 0.0,
    ) -> Scan:
        """One sweep from the robot at ``pose`` ({W}) about ``sector_center`` (radians, {R})."""
        angles = self.sweep_angles(sector_center)
        sensor_xy = pose.transform_point(world.scenario.robot.sensor_offset)
        directions = np.stack([np.cos(angles), np.sin(angles)], axis=1)
        ranges, amplitudes = self.ping(world, pose, sensor_xy, directions, rng)
        transducer = self.transducer
        duration = (angles[-1] - angles[0]) / transducer.pan_speed_rad_s + len(
            angles
        ) * transducer.listen_time_s
        return Scan(angles=angles, ranges=ranges, amplitudes=amplitudes, duration_s=float(duration))


@dataclass(frozen=True)
class SideReadings:
    """Side-sonar readings along a path (metres from each sensor; NaN = dropout).

    Attributes:
        left_m: ``(n,)`` ranges of the left-looking sensor.
        right_m: ``(n,)`` ranges of the right-looking sensor.
    """

    left_m: FloatArray
    right_m: FloatArray


@dataclass(frozen=True)
class SideSonars(PulseEchoSonar):
    """Fixed left and right looking sonars (APCS).

    Attributes:
        lateral_offset_m: distance of each sensor from the robot centre along the robot's
            y axis, metres (>= 0).
    """

    lateral_offset_m: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (math.isfinite(self.lateral_offset_m) and self.lateral_offset_m >= 0.0):
            raise ValueError(
                "argument 'lateral_offset_m' must be a finite distance >= 0 (metres); "
                f"got {self.lateral_offset_m!r}"
            )

    @classmethod
    def apcs(cls, **options: object) -> SideSonars:
        """The MA40B8 side sonars of APCS."""
        return cls(transducer_preset("ma40b8"), **options)  # type: ignore[arg-type]

    def _echoes(self, world: WorldLike, pose: Pose) -> FirstEchoes:
        """First echoes of the left then the right sensor at ``pose``."""
        if self.lateral_offset_m == 0.0:
            return self.first_echoes_at(world, pose, pose.position, _SIDE_DIRECTIONS)
        return concatenate_echoes(
            [
                self.first_echoes_at(
                    world,
                    pose,
                    pose.transform_point(direction * self.lateral_offset_m),
                    direction[None, :],
                )
                for direction in _SIDE_DIRECTIONS
            ]
        )

    def read(
        self, world: WorldLike, pose: Pose, rng: np.random.Generator | None
    ) -> tuple[float, float]:
        """One sample at ``pose`` ({W}): ``(left_range, right_range)`` in metres, NaN = dropout."""
        ranges, _ = self.readings(world, self._echoes(world, pose), rng)
        return float(ranges[0]), float(ranges[1])

    def sample_along(
        self, world: WorldLike, poses: Sequence[Pose], rng: np.random.Generator | None
    ) -> SideReadings:
        """Samples at each of ``poses`` ({W}); the electronics run once over all of them.

        The echo geometry is found pose by pose (each position has its own echo points); the
        readout (delay, noise, counter) is one array operation over every sample.
        """
        if len(poses) == 0:
            return SideReadings(np.zeros(0), np.zeros(0))
        echoes = concatenate_echoes([self._echoes(world, pose) for pose in poses])
        ranges, _ = self.readings(world, echoes, rng)
        pairs = ranges.reshape(len(poses), 2)
        return SideReadings(left_m=pairs[:, 0].copy(), right_m=pairs[:, 1].copy())
