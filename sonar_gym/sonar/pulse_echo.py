"""The pulse-echo ping engine shared by the rotating, swept and side sonars.

A ping fired along a unit direction from a sensor position hears every echo candidate of that
position (:mod:`sonar_gym.sonar.echoes`) with amplitude ``A = A_axis D^2(off-axis angle)``
(:class:`~sonar_gym.sonar.acoustics.PistonBeam`, with the transducer's side-lobe switch and
leakage; ``A_axis`` includes the receiver's time-varying gain, if the transducer has one, so
``A`` is what the comparator sees); it detects those with ``A >= threshold`` and
reports the first of them (smallest time of flight). Many pings from one position are one
``(pings x candidates)`` array computation, with no loop over pings.

The reading of a detected echo (the order the electronics apply):

1. true round-trip time ``t = 2 r / c_true``, ``c_true`` from the world's temperature;
2. threshold-crossing delay ``+ rise_time * threshold / A`` (the envelope rises linearly to
   ``A`` over the rise time, so the comparator fires later on weak echoes);
3. timing jitter, Gaussian with standard deviation ``2 sigma_r / c_true`` (``sigma_r`` is the
   transducer's range noise in metres);
4. the counter: ``t -> floor(t / T0) T0`` (it counts whole periods);
5. conversion with the sensor's *assumed* speed: ``range = c_assumed t / 2`` (Beom & Cho eq. (1)).

A ping without a detection, or whose reading exceeds the transducer's maximum range (it stopped
listening), is a dropout: its range is NaN (never a stand-in maximum range) and its amplitude 0.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from typing import Any, Protocol, TypeVar

import numpy as np

from sonar_gym.geometry import StaticGeometry
from sonar_gym.pose import FloatArray, Pose
from sonar_gym.scenario import Scenario
from sonar_gym.sonar import kernels
from sonar_gym.sonar.acoustics import (
    REFERENCE_TEMPERATURE_C,
    SMALLEST_COSINE,
    TABLE_STEPS_PER_UNIT,
    PistonBeam,
    speed_of_sound_mps,
    wavenumber_per_m,
)
from sonar_gym.sonar.echoes import EDGE_LAWS, EchoCandidates, echo_candidates
from sonar_gym.sonar.presets import Transducer


class WorldLike(Protocol):
    """What the sonars read from a world: static geometry, air temperature, the scenario."""

    @property
    def geometry(self) -> StaticGeometry: ...

    @property
    def temperature_c(self) -> float: ...

    @property
    def scenario(self) -> Scenario: ...


@dataclass(frozen=True)
class Readout:
    """Switches for the non-ideal parts of a reading (all on by default).

    Attributes:
        range_noise: add Gaussian timing jitter (the transducer's ``range_noise_std_m``).
        crossing_delay: delay weak echoes by the threshold-crossing model.
        quantisation: floor the time of flight to the transducer's timer period.
    """

    range_noise: bool = True
    crossing_delay: bool = True
    quantisation: bool = True


IDEAL_READOUT = Readout(range_noise=False, crossing_delay=False, quantisation=False)
"""A readout that returns the exact geometric range (converted with the assumed speed)."""


@dataclass(frozen=True)
class FirstEchoes:
    """The first detected echo of each ping (before the electronics turn it into a range).

    Attributes:
        detected: ``(n,)`` whether any echo reached the threshold.
        path_lengths: ``(n,)`` one-way path length of the first detected echo, metres
            (meaningless where not detected).
        amplitudes: ``(n,)`` its amplitude after the receiver's gain (1/m, the units of the
            threshold), 0 where not detected.
    """

    detected: np.ndarray
    path_lengths: FloatArray
    amplitudes: FloatArray


def first_echoes(
    candidates: EchoCandidates,
    beam_directions: FloatArray,
    beam: PistonBeam,
    threshold: float,
    frame_heading_rad: float = 0.0,
) -> FirstEchoes:
    """Detect, for each ping along ``beam_directions``, its first echo.

    Args:
        candidates: the echo candidates of the sensor position.
        beam_directions: ``(n, 2)`` unit vectors of the pings, in a frame turned by
            ``frame_heading_rad`` from {W} (the robot frame {R} when it is the robot heading).
        beam: the two-way beam pattern.
        threshold: the detection threshold (1/m).
        frame_heading_rad: heading of the frame of ``beam_directions`` in {W}, radians.
    """
    n = len(beam_directions)
    if len(candidates) == 0:
        return FirstEchoes(np.zeros(n, dtype=bool), np.zeros(n), np.zeros(n))
    c, s = math.cos(frame_heading_rad), math.sin(frame_heading_rad)
    in_frame = np.array(((c, s), (-s, c))) @ candidates.directions.T  # (2, candidates)
    cosines = beam_directions @ in_frame  # (pings, candidates)
    rows = _ping_rows(n)
    if beam.side_lobes:
        amplitude = beam.two_way_from_cos(cosines) * candidates.amplitudes
        detected = amplitude >= threshold
        first = detected.argmax(axis=1)  # candidates are sorted nearest first
        hit = detected[rows, first]
        first_amplitude = amplitude[rows, first]
    else:
        detected = cosines >= beam.main_lobe_cos_limits(threshold / candidates.amplitudes)
        first = detected.argmax(axis=1)
        flat = rows * len(candidates) + first  # index of (ping, first) in the flat arrays
        hit = detected.ravel().take(flat)
        first_amplitude = beam.two_way_from_cos(
            cosines.ravel().take(flat)
        ) * candidates.amplitudes.take(first)
    return FirstEchoes(
        detected=hit,
        path_lengths=candidates.path_lengths.take(first),
        amplitudes=np.where(hit, first_amplitude, 0.0),
    )


@functools.lru_cache(maxsize=64)
def _ping_rows(n: int) -> np.ndarray:
    """``arange(n)``, read-only (cached: pans repeat their ping counts)."""
    rows = np.arange(n)
    rows.flags.writeable = False
    return rows


@functools.lru_cache(maxsize=256)
def _ping_offsets(n: int, n_candidates: int) -> np.ndarray:
    """``arange(n) * n_candidates``: where each ping's row starts in a flattened
    ``(n, n_candidates)`` array, read-only (cached: pans repeat their ping counts)."""
    offsets = _ping_rows(n) * n_candidates
    offsets.flags.writeable = False
    return offsets


def measured_times(
    echoes: FirstEchoes,
    transducer: Transducer,
    true_speed_mps: float,
    readout: Readout,
    rng: np.random.Generator | None,
) -> FloatArray:
    """Round-trip times the counter reads for the first echoes, seconds (steps 1-4 above)."""
    # Out-of-place arithmetic: on pan-sized arrays numpy's in-place operators cost more.
    tof = echoes.path_lengths * (2.0 / true_speed_mps)
    if readout.crossing_delay and transducer.echo_rise_time_s > 0.0:
        safe = np.where(echoes.detected, echoes.amplitudes, transducer.detection_threshold)
        tof = tof + (transducer.echo_rise_time_s * transducer.detection_threshold) / safe
    if readout.range_noise and transducer.range_noise_std_m > 0.0:
        if rng is None:
            raise ValueError("argument 'rng' is needed: the readout adds range noise")
        jitter_s = 2.0 * transducer.range_noise_std_m / true_speed_mps
        tof = tof + rng.standard_normal(len(tof)) * jitter_s
    if readout.quantisation and transducer.timer_period_s > 0.0:
        period = transducer.timer_period_s
        tof = np.floor(tof * (1.0 / period)) * period
    return tof


def echo_readings(
    echoes: FirstEchoes,
    transducer: Transducer,
    true_speed_mps: float,
    assumed_speed_mps: float,
    readout: Readout,
    rng: np.random.Generator | None,
) -> tuple[FloatArray, FloatArray]:
    """Turn first echoes into ``(ranges, amplitudes)`` (metres, 1/m): the steps listed above."""
    ranges = measured_times(echoes, transducer, true_speed_mps, readout, rng) * (
        assumed_speed_mps / 2.0
    )
    valid = echoes.detected & (ranges <= transducer.max_range_m)
    return np.where(valid, ranges, np.nan), np.where(valid, echoes.amplitudes, 0.0)


_Sonar = TypeVar("_Sonar", bound="PulseEchoSonar")

SensorPoint = FloatArray | tuple[float, float]
"""A sensor position ``(x, y)`` in {W}, metres: an array or a pair of floats."""

_LAST_CANDIDATES: dict[
    str, tuple[StaticGeometry, Transducer, tuple[float | str, ...], EchoCandidates]
] = {}
"""The last sensor position's echo candidates (see :meth:`PulseEchoSonar.candidates`)."""
_LAST_AIR: list[tuple[Transducer, float, tuple[float, float, PistonBeam]]] = []
"""The last transducer and air temperature asked of :func:`air_at` and its answer."""


def air_at(transducer: Transducer, temperature_c: float) -> tuple[float, float, PistonBeam]:
    """``(speed of sound m/s, wavenumber rad/m, two-way beam)`` of ``transducer`` in air at
    ``temperature_c`` (deg C).

    Remembered for the last transducer object and temperature: every ping of a pan, sweep or
    sample asks again, and the answer depends on nothing else.
    """
    if _LAST_AIR:
        last_transducer, last_temperature, answer = _LAST_AIR[0]
        if last_transducer is transducer and last_temperature == temperature_c:
            return answer
    speed = speed_of_sound_mps(temperature_c)
    answer = (
        speed,
        wavenumber_per_m(transducer.frequency_hz, speed),
        PistonBeam.for_ka(
            transducer.wavenumber_ka(speed), transducer.side_lobes, transducer.side_lobe_leakage
        ),
    )
    _LAST_AIR[:] = [(transducer, temperature_c, answer)]
    return answer


@dataclass(frozen=True)
class PulseEchoSonar:
    """Common part of every pulse-echo sonar: a transducer, an assumed speed, a readout.

    Attributes:
        transducer: the transducer and its electronics.
        assumed_speed_of_sound_mps: the speed the sensor converts times of flight with, m/s
            (default: the speed at 20 deg C, 343.2 m/s).
        readout: which non-ideal parts of a reading are simulated.
        edge_law: the echo law of convex edges, ``"weak"`` or ``"gtd"``
            (:mod:`sonar_gym.sonar.echoes`).
    """

    transducer: Transducer
    assumed_speed_of_sound_mps: float = speed_of_sound_mps(REFERENCE_TEMPERATURE_C)
    readout: Readout = Readout()
    edge_law: str = "weak"

    def __post_init__(self) -> None:
        if not isinstance(self.transducer, Transducer):
            raise ValueError(
                f"argument 'transducer' must be a Transducer; got {type(self.transducer).__name__}"
            )
        if self.edge_law not in EDGE_LAWS:
            raise ValueError(
                f"argument 'edge_law' must be one of {list(EDGE_LAWS)}; got {self.edge_law!r}"
            )
        speed = self.assumed_speed_of_sound_mps
        if not (isinstance(speed, (int, float)) and math.isfinite(speed) and speed > 0):
            raise ValueError(
                f"argument 'assumed_speed_of_sound_mps' must be positive (m/s); got {speed!r}"
            )

    def with_assumed_speed(self: _Sonar, speed_mps: float) -> _Sonar:
        """The same sonar converting with ``speed_mps`` (m/s), e.g. after a calibration."""
        return dataclasses.replace(self, assumed_speed_of_sound_mps=float(speed_mps))

    def with_readout(self: _Sonar, **switches: Any) -> _Sonar:
        """The same sonar with some :class:`Readout` switches changed."""
        return dataclasses.replace(self, readout=dataclasses.replace(self.readout, **switches))

    def candidates(
        self, world: WorldLike, robot_pose: Pose, sensor_xy: SensorPoint
    ) -> EchoCandidates:
        """Echo candidates of a sensor at ``sensor_xy`` ({W}) on a robot at ``robot_pose``.

        They depend on where the sensor is, not where it points, so successive pans from one
        pose (sector pans, a pan after a calibration) reuse the last position's candidates: the
        memory holds one entry, matched on the very geometry and transducer objects, the
        sensor and robot positions, the robot radius, the temperature and the edge law. The
        arrays are read-only (as :func:`~sonar_gym.sonar.echoes.echo_candidates` hands them).
        """
        geometry, temperature_c = world.geometry, world.temperature_c
        key = (
            float(sensor_xy[0]),
            float(sensor_xy[1]),
            robot_pose.x,
            robot_pose.y,
            world.scenario.robot.radius,
            temperature_c,
            self.edge_law,
        )
        last = _LAST_CANDIDATES.get("entry")
        if (
            last is not None
            and last[0] is geometry
            and last[1] is self.transducer
            and last[2] == key
        ):
            return last[3]
        candidates = self._search_candidates(world, robot_pose, sensor_xy)
        _LAST_CANDIDATES["entry"] = (geometry, self.transducer, key, candidates)
        return candidates

    def _search_candidates(
        self, world: WorldLike, robot_pose: Pose, sensor_xy: SensorPoint
    ) -> EchoCandidates:
        transducer = self.transducer
        _, wavenumber, _ = air_at(transducer, world.temperature_c)
        return echo_candidates(
            world.geometry,
            sensor_xy,
            wavenumber=wavenumber,
            absorption_db_per_m=transducer.absorption_db_per_m,
            min_range_m=transducer.min_range_m,
            detection_threshold=transducer.detection_threshold,
            footprint_center=(robot_pose.x, robot_pose.y),
            footprint_radius_m=world.scenario.robot.radius,
            edge_law=self.edge_law,
            receiver_gain=transducer.time_varying_gain,
        )

    def first_echoes_at(
        self,
        world: WorldLike,
        robot_pose: Pose,
        sensor_xy: SensorPoint,
        beam_directions: FloatArray,
    ) -> FirstEchoes:
        """First echoes of pings from ``sensor_xy`` ({W}) along ``beam_directions`` (``(n, 2)``
        unit vectors in the robot frame {R}), before the electronics read them."""
        true_speed = speed_of_sound_mps(world.temperature_c)
        candidates = self.candidates(world, robot_pose, sensor_xy)
        transducer = self.transducer
        beam = PistonBeam.for_ka(
            transducer.wavenumber_ka(true_speed),
            transducer.side_lobes,
            transducer.side_lobe_leakage,
        )
        return first_echoes(
            candidates, beam_directions, beam, transducer.detection_threshold, robot_pose.theta
        )

    def readings(
        self, world: WorldLike, echoes: FirstEchoes, rng: np.random.Generator | None
    ) -> tuple[FloatArray, FloatArray]:
        """``(ranges, amplitudes)`` the electronics report for ``echoes`` (metres, 1/m)."""
        return echo_readings(
            echoes,
            self.transducer,
            speed_of_sound_mps(world.temperature_c),
            self.assumed_speed_of_sound_mps,
            self.readout,
            rng,
        )

    def ping(
        self,
        world: WorldLike,
        robot_pose: Pose,
        sensor_xy: SensorPoint,
        beam_directions: FloatArray,
        rng: np.random.Generator | None,
    ) -> tuple[FloatArray, FloatArray]:
        """Fire pings from ``sensor_xy`` ({W}) along ``beam_directions`` (``(n, 2)`` unit vectors
        in the robot frame {R}): ``(ranges, amplitudes)`` in metres and 1/m.

        The same numbers as :meth:`readings` of :meth:`first_echoes_at`, in one pass.
        """
        transducer = self.transducer
        true_speed, _, beam = air_at(transducer, world.temperature_c)
        candidates = self.candidates(world, robot_pose, sensor_xy)
        if beam.side_lobes or len(candidates.path_lengths) == 0:
            echoes = first_echoes(
                candidates,
                beam_directions,
                beam,
                transducer.detection_threshold,
                robot_pose.theta,
            )
            return echo_readings(
                echoes,
                transducer,
                true_speed,
                self.assumed_speed_of_sound_mps,
                self.readout,
                rng,
            )
        return _main_lobe_readings(
            candidates,
            beam_directions,
            beam,
            transducer,
            true_speed,
            self.assumed_speed_of_sound_mps,
            self.readout,
            rng,
            robot_pose.theta,
        )


def _main_lobe_readings(
    candidates: EchoCandidates,
    beam_directions: FloatArray,
    beam: PistonBeam,
    transducer: Transducer,
    true_speed_mps: float,
    assumed_speed_mps: float,
    readout: Readout,
    rng: np.random.Generator | None,
    frame_heading_rad: float,
) -> tuple[FloatArray, FloatArray]:
    """``echo_readings(first_echoes(...))`` for a beam without side lobes, fused.

    The same arithmetic in the same order, minus the steps whose results are discarded: the
    amplitude of a ping that detects nothing is never read (it is masked at the end), so it
    is neither zeroed nor checked for lying behind the transducer (a detected echo is in
    front: its cosine reaches a positive limit). Two or more pings at two or more candidates
    go through the compiled loop :func:`sonar_gym.sonar.kernels.main_lobe_readings`, the
    same numbers ping by ping.
    """
    threshold = transducer.detection_threshold
    amplitudes, path_lengths = candidates.amplitudes, candidates.path_lengths
    n, n_candidates = len(beam_directions), len(path_lengths)
    c, s = math.cos(frame_heading_rad), math.sin(frame_heading_rad)
    # np.dot: the products first_echoes takes with @, through one call layer less.
    in_frame = np.dot(np.array(((c, s), (-s, c))), candidates.directions.T)  # (2, candidates)
    jitter, jitter_s, delay, period, constants = _readout_steps(
        transducer, true_speed_mps, assumed_speed_mps, readout
    )
    normals = _NO_NORMALS  # one standard normal per ping, drawn alike on both paths
    if jitter:
        if rng is None:
            raise ValueError("argument 'rng' is needed: the readout adds range noise")
        normals = rng.standard_normal(n)
    if n >= 2 and n_candidates >= 2:  # there numpy's products round as the loop's fma
        compiled = kernels.main_lobe_readings(
            beam_directions,
            in_frame,
            beam.main_lobe_rising,
            beam.main_lobe_cells,
            amplitudes,
            path_lengths,
            beam.cells,
            normals,
            constants,
        )
        return compiled[0], compiled[1]
    limits = beam.main_lobe_cos_limits(
        threshold / amplitudes, reachable=candidates.threshold >= threshold
    )
    cosines = np.dot(beam_directions, in_frame)  # (pings, candidates)
    detected = cosines >= limits
    first = detected.argmax(axis=1)  # candidates are sorted nearest first
    flat = _ping_offsets(n, n_candidates) + first  # index of (ping, first) in the flat arrays
    hit = detected.ravel().take(flat)
    # Ranges and amplitudes in the rows of one array, so that one np.where masks both.
    readings = np.empty((2, n))
    first_amplitude = np.multiply(
        beam.two_way_in_front(cosines.ravel().take(flat)), amplitudes.take(first), out=readings[1]
    )
    # measured_times and echo_readings, steps 1-5 of the module docstring:
    tof = path_lengths.take(first) * (2.0 / true_speed_mps)
    if delay:
        safe = np.where(hit, first_amplitude, threshold)
        tof = tof + (transducer.echo_rise_time_s * threshold) / safe
    if jitter:
        tof = tof + normals * jitter_s
    if period > 0.0:
        tof = np.floor(tof * (1.0 / period)) * period
    ranges = np.multiply(tof, assumed_speed_mps / 2.0, out=readings[0])
    valid = hit & (ranges <= transducer.max_range_m)
    masked = np.where(valid, readings, _DROPOUT_READING)
    return masked[0], masked[1]


def _readout_steps(
    transducer: Transducer, true_speed_mps: float, assumed_speed_mps: float, readout: Readout
) -> tuple[bool, float, bool, float, FloatArray]:
    """Which readout steps apply and their constants: ``(whether readings jitter, the jitter in
    seconds per standard normal (0 without), whether weak echoes are delayed, the counter's
    period in seconds (0 without a counter), the constants of
    :func:`sonar_gym.sonar.kernels.main_lobe_readings`)``.

    Remembered for the last transducer object, speeds and readout: every ping of a pan or sweep
    asks again, and the answer depends on nothing else.
    """
    key = (true_speed_mps, assumed_speed_mps, readout)
    if _LAST_READOUT_STEPS:
        last_transducer, last_key, answer = _LAST_READOUT_STEPS[0]
        if last_transducer is transducer and last_key == key:
            return answer
    threshold = transducer.detection_threshold
    jitter = readout.range_noise and transducer.range_noise_std_m > 0.0
    jitter_s = 2.0 * transducer.range_noise_std_m / true_speed_mps if jitter else 0.0
    delay = readout.crossing_delay and transducer.echo_rise_time_s > 0.0
    period = transducer.timer_period_s if readout.quantisation else 0.0
    constants = np.array(
        (
            float(TABLE_STEPS_PER_UNIT),
            2.0 / true_speed_mps,
            transducer.echo_rise_time_s * threshold if delay else 0.0,
            jitter_s,
            1.0 / period if period > 0.0 else 0.0,
            period,
            assumed_speed_mps / 2.0,
            transducer.max_range_m,
            threshold,
            1.0 / TABLE_STEPS_PER_UNIT,
            SMALLEST_COSINE,
        )
    )
    constants.flags.writeable = False
    answer = (jitter, jitter_s, delay, period, constants)
    _LAST_READOUT_STEPS[:] = [(transducer, key, answer)]
    return answer


_LAST_READOUT_STEPS: list[
    tuple[Transducer, tuple[float, float, Readout], tuple[bool, float, bool, float, FloatArray]]
] = []
"""The last transducer, speeds and readout asked of :func:`_readout_steps` and its answer."""

_NO_NORMALS = np.empty(0)
_NO_NORMALS.flags.writeable = False

_DROPOUT_READING = np.array([[np.nan], [0.0]])
"""The ``(range, amplitude)`` column of a dropout: NaN metres, amplitude 0."""
_DROPOUT_READING.flags.writeable = False


def concatenate_echoes(parts: list[FirstEchoes]) -> FirstEchoes:
    """The pings of several :class:`FirstEchoes`, one after the other."""
    return FirstEchoes(
        detected=np.concatenate([part.detected for part in parts]),
        path_lengths=np.concatenate([part.path_lengths for part in parts]),
        amplitudes=np.concatenate([part.amplitudes for part in parts]),
    )
