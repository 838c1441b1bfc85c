"""The single rotating sonar of Beom & Cho: a pan of pings, and speed-of-sound self-calibration.

Pan (Beom & Cho sec. III.A)
    The pan-tilt unit turns the transducer by ``Delta phi`` between pings, with the pan angle in
    ``-pi <= alpha_p < pi`` and the tilt at zero. :meth:`RotatingSonar.pan` takes the pings at
    ``start + k * increment`` for every ``k >= 0`` with angle ``< stop``: ``start`` is included,
    ``stop`` is not, so ``start=-pi, stop=pi, increment=radians(1)`` gives the paper's 360 pings
    at -180 ... 179 deg. Angles are in the robot frame {R} and not wrapped. The pan axis sits at
    ``pose`` composed with ``scenario.robot.sensor_offset``. The whole pan is one array
    computation over ``pings x echo candidates`` (:mod:`sonar_gym.sonar.pulse_echo`).

    Duration: stop-and-ping; the head turns ``(n - 1) * increment`` at the transducer's pan
    speed and every ping takes its listening time: ``(n-1) increment / pan_speed + n listen``.
    For the Polaroid preset (90 deg/s, 23.3 ms) a full 1-deg pan takes 12.4 s.

Calibration (Beom & Cho sec. II.A)
    A small reflector on the robot's front face at ``d_c = 0.515 m`` (tilt 53.1 deg, pan 0)
    echoes well above the threshold. :meth:`RotatingSonar.calibrate` times ``n_pings`` echoes
    with the true speed of sound, the counter and the noise, averages them and estimates
    ``v_s = 2 d_c / t`` (eq. (1) read backwards). The counter counts whole periods, so a count
    ``n`` means a time in ``[n T0, (n + 1) T0)``: the default reading ``t = (mean n + 1/2) T0``
    is the unbiased time; ``count_reading="floor"`` uses ``mean n * T0``, the plain count,
    which reads the speed high by half a period over the 3 ms round trip (about 0.5 % for
    the Polaroid's 32 us period). The calibrated sensor is
    ``sonar.with_assumed_speed(result.estimated_speed_mps)``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from sonar_gym.pose import FloatArray, Pose
from sonar_gym.sonar.acoustics import speed_of_sound_from_round_trip, speed_of_sound_mps
from sonar_gym.sonar.echoes import plane_echo_amplitude
from sonar_gym.sonar.presets import Transducer
from sonar_gym.sonar.presets import preset as transducer_preset
from sonar_gym.sonar.pulse_echo import (
    FirstEchoes,
    PulseEchoSonar,
    WorldLike,
    measured_times,
)
from sonar_gym.sonar.scan import Scan

CALIBRATION_TILT_RAD = math.radians(53.1)
"""Beom & Cho sec. II.A: tilt angle at which the sonar faces the calibration reflector."""
_ANGLE_TOLERANCE = 1e-9


@dataclass(frozen=True)
class SpeedCalibration:
    """Result of a speed-of-sound self-calibration.

    Attributes:
        tof_s: the averaged round-trip time of flight to the reflector, seconds.
        estimated_speed_mps: ``2 d_c / tof_s``, m/s.
        duration_s: time the calibration took (tilt down and back, the pings), seconds.
    """

    tof_s: float
    estimated_speed_mps: float
    duration_s: float


def pan_angles(start_rad: float, stop_rad: float, increment_rad: float) -> FloatArray:
    """Pan angles ``start, start + increment, ...`` below ``stop`` (radians, {R}).

    Raises:
        ValueError: ``increment_rad <= 0``, ``start_rad >= stop_rad``, a span over a full
            turn, or a non-finite argument.
    """
    for name, value in (("start", start_rad), ("stop", stop_rad), ("increment", increment_rad)):
        if not math.isfinite(value):
            raise ValueError(f"argument '{name}' must be a finite angle in radians; got {value!r}")
    if not increment_rad > 0.0:
        raise ValueError(f"argument 'increment' must be positive (radians); got {increment_rad!r}")
    if not start_rad < stop_rad:
        raise ValueError(
            f"argument 'start' must be below 'stop'; got start={start_rad!r}, stop={stop_rad!r}"
        )
    if stop_rad - start_rad > 2.0 * math.pi + _ANGLE_TOLERANCE:
        raise ValueError(
            "argument 'stop': a pan spans at most a full turn (2 pi); "
            f"got stop - start = {stop_rad - start_rad!r}"
        )
    n = max(1, math.ceil((stop_rad - start_rad) / increment_rad - _ANGLE_TOLERANCE))
    return start_rad + increment_rad * np.arange(n, dtype=np.float64)


@functools.lru_cache(maxsize=1024)
def _pan_grid(
    start_rad: float, stop_rad: float, increment_rad: float
) -> tuple[FloatArray, FloatArray]:
    """Pan angles and their unit vectors in {R} (cached: agents repeat their sectors; room for
    every sector of BeaconScan's default action set, 36 centres x 5 widths x 3 increments)."""
    angles = pan_angles(start_rad, stop_rad, increment_rad)
    directions = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    angles.flags.writeable = False
    directions.flags.writeable = False
    return angles, directions


@functools.lru_cache(maxsize=16)
def _reflector_echo_amplitude(transducer: Transducer, distance_m: float) -> float:
    """The amplitude the receiver compares with its threshold for the calibration reflector
    at ``distance_m`` metres: the plane echo, the air's absorption over the round trip and
    the time-varying gain (cached: it depends on the transducer and the distance alone)."""
    absorption = 10.0 ** (-transducer.absorption_db_per_m * 2.0 * distance_m / 20.0)
    amplitude = float(plane_echo_amplitude(distance_m)) * absorption
    if transducer.time_varying_gain is not None:
        amplitude *= float(transducer.time_varying_gain.gain(distance_m))
    return amplitude


@dataclass(frozen=True)
class RotatingSonar(PulseEchoSonar):
    """A single transducer on a pan unit (Beom & Cho); see the module docstring.

    Build one with ``RotatingSonar.preset("polaroid-6500")`` or ``RotatingSonar(transducer)``.
    """

    @classmethod
    def preset(cls, name: str, **options: object) -> RotatingSonar:
        """A rotating sonar with the transducer preset ``name`` (other fields as keywords)."""
        return cls(transducer_preset(name), **options)  # type: ignore[arg-type]

    def pan(
        self,
        world: WorldLike,
        pose: Pose,
        start: float,
        stop: float,
        increment: float,
        rng: np.random.Generator | None,
    ) -> Scan:
        """Pan from ``start`` (included) towards ``stop`` (excluded) by ``increment`` (rad, {R}).

        Args:
            world: the world (its geometry, temperature and scenario are read).
            pose: the robot pose in {W}.
            start, stop, increment: pan angles in radians in {R}.
            rng: the random generator for the noise (None only when the noise is off).
        """
        angles, directions = _pan_grid(start, stop, increment)
        offset_x, offset_y = world.scenario.robot.sensor_offset
        c, s = math.cos(pose.theta), math.sin(pose.theta)  # as Pose.transform_point
        sensor_xy = (pose.x + c * offset_x - s * offset_y, pose.y + s * offset_x + c * offset_y)
        ranges, amplitudes = self.ping(world, pose, sensor_xy, directions, rng)
        transducer = self.transducer
        duration = (len(angles) - 1) * increment / transducer.pan_speed_rad_s + len(
            angles
        ) * transducer.listen_time_s
        return Scan(
            angles=angles.copy(), ranges=ranges, amplitudes=amplitudes, duration_s=float(duration)
        )

    def calibrate(
        self,
        world: WorldLike,
        pose: Pose,
        rng: np.random.Generator | None,
        n_pings: int = 5,
        count_reading: Literal["centred", "floor"] = "centred",
    ) -> SpeedCalibration:
        """Estimate the speed of sound from ``n_pings`` echoes of the reflector at ``d_c``.

        The reflector rides on the robot, so ``pose`` does not change the result; it is taken
        for a uniform interface with :meth:`pan`.

        Args:
            world: the world (its temperature and ``scenario.reflector.distance`` are read).
            pose: the robot pose in {W}.
            rng: the random generator for the noise (None only when the noise is off).
            n_pings: number of echoes averaged (>= 1).
            count_reading: ``"centred"`` (default) reads a count ``n`` as ``(n + 1/2) T0``;
                ``"floor"`` as ``n T0``.
        """
        if not (isinstance(n_pings, (int, np.integer)) and n_pings >= 1):
            raise ValueError(f"argument 'n_pings' must be an integer >= 1; got {n_pings!r}")
        if count_reading not in ("centred", "floor"):
            raise ValueError(
                f"argument 'count_reading' must be 'centred' or 'floor'; got {count_reading!r}"
            )
        distance = world.scenario.reflector.distance
        transducer = self.transducer
        true_speed = speed_of_sound_mps(world.temperature_c)
        amplitude = _reflector_echo_amplitude(transducer, distance)
        echoes = FirstEchoes(
            detected=np.ones(n_pings, dtype=bool),
            path_lengths=np.full(n_pings, distance),
            amplitudes=np.full(n_pings, amplitude),
        )
        tof = float(np.mean(measured_times(echoes, transducer, true_speed, self.readout, rng)))
        if count_reading == "centred" and self.readout.quantisation:
            tof += transducer.timer_period_s / 2.0
        tilt_time = 2.0 * CALIBRATION_TILT_RAD / transducer.pan_speed_rad_s
        return SpeedCalibration(
            tof_s=tof,
            estimated_speed_mps=speed_of_sound_from_round_trip(distance, tof),
            duration_s=tilt_time + n_pings * transducer.listen_time_s,
        )
