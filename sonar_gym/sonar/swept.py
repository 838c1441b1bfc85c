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

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from sonar_gym.pose import FloatArray, Pose
from sonar_gym.sonar import side_kernels
from sonar_gym.sonar.acoustics import (
    SMALLEST_COSINE,
    TABLE_STEPS_PER_UNIT,
    PistonBeam,
)
from sonar_gym.sonar.echo_tables import PATH_END_TOLERANCE, echo_tables
from sonar_gym.sonar.echoes import EchoKind, edge_law_constants
from sonar_gym.sonar.presets import preset as transducer_preset
from sonar_gym.sonar.pulse_echo import (
    FirstEchoes,
    PulseEchoSonar,
    WorldLike,
    air_at,
    concatenate_echoes,
)
from sonar_gym.sonar.scan import Scan

KIM_HALF_SWEEP_RAD = math.radians(45.0)
"""Kim et al. sec. 4.1: the servo turns 45 deg right and left of the robot's forward axis."""
KIM_WIDE_HALF_SWEEP_RAD = math.radians(90.0)
"""Kim et al. sec. 2.1: the 180 deg sweep variant."""
APCS_SAMPLE_SPACING_M = 0.03
"""APCS sec. 6: a range sample every 3 cm of travel."""
APCS_SPEED_MPS = 0.3
"""APCS sec. 6: the robot drove at 30 cm/s (so a sample every 0.1 s)."""
SIDE_NAMES = ("left", "right")
"""The side sensors, in the order of their readings: left (+90 deg in {R}), then right."""
_SIDE_DIRECTIONS = np.array([[0.0, 1.0], [0.0, -1.0]])  # left, right in {R}
_UV_CENTRE_SCALAR = (1.0 - PATH_END_TOLERANCE) / 2.0
"""The middle (and half width) of ``[0, 1 - tol]``, where a path's ``u`` blocks it."""
_AT_CENTRE = np.zeros((0, 2))
"""The sensor offsets of :func:`~sonar_gym.sonar.side_kernels.side_sensors` for sensors at the
robot centre."""
_AT_CENTRE.flags.writeable = False
_NO_NORMALS = np.zeros(0)
"""The jitter normals of :func:`~sonar_gym.sonar.side_kernels.side_readings` without jitter."""
_NO_NORMALS.flags.writeable = False


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
    def kim(cls, wide: bool = False, preset: str = "srf04", **options: object) -> SweptSonar:
        """The sweep of Kim et al.: +-45 deg, or 180 deg with ``wide=True``, with the paper's
        SRF04 or the transducer ``preset`` (a scenario's ``[sensor]``)."""
        half = KIM_WIDE_HALF_SWEEP_RAD if wide else KIM_HALF_SWEEP_RAD
        return cls(transducer_preset(preset), half_sweep_rad=half, **options)  # type: ignore[arg-type]

    def sweep_angles(self, sector_center: float = 0.0) -> FloatArray:
        """Ping angles in {R}, radians: from ``center - half`` to ``center + half`` inclusive."""
        return self.sweep_grid(sector_center)[0].copy()

    def sweep_grid(self, sector_center: float = 0.0) -> tuple[FloatArray, FloatArray]:
        """``(angles, unit directions)`` of the pings of a sweep about ``sector_center``
        (radians, {R}), read-only and shared (:meth:`sweep_readings` takes them)."""
        if not math.isfinite(sector_center):
            raise ValueError(
                f"argument 'sector_center' must be a finite angle in radians; got {sector_center!r}"
            )
        return _sweep_grid(float(sector_center), self.half_sweep_rad, self.step_rad)

    def sweep(
        self,
        world: WorldLike,
        pose: Pose,
        rng: np.random.Generator | None,
        sector_center: float = 0.0,
    ) -> Scan:
        """One sweep from the robot at ``pose`` ({W}) about ``sector_center`` (radians, {R})."""
        angles, ranges, amplitudes, duration = self.sweep_readings(
            world, pose, rng, self.sweep_grid(sector_center)
        )
        return Scan(angles=angles.copy(), ranges=ranges, amplitudes=amplitudes, duration_s=duration)

    def sweep_readings(
        self,
        world: WorldLike,
        pose: Pose,
        rng: np.random.Generator | None,
        grid: tuple[FloatArray, FloatArray],
    ) -> tuple[FloatArray, FloatArray, FloatArray, float]:
        """:meth:`sweep` as ``(angles, ranges, amplitudes, duration_s)`` without the
        :class:`Scan`, for a ``grid`` of :meth:`sweep_grid`: the angles are the grid's own
        read-only array (radians, {R}), the ranges (metres, NaN = dropout) and amplitudes
        (1/m) new arrays."""
        angles, directions = grid
        # pose.transform_point of the offset, on floats: the same arithmetic
        offset_x, offset_y = world.scenario.robot.sensor_offset
        c, s = math.cos(pose.theta), math.sin(pose.theta)
        sensor_xy = (pose.x + c * offset_x - s * offset_y, pose.y + s * offset_x + c * offset_y)
        ranges, amplitudes = self.ping(world, pose, sensor_xy, directions, rng)
        transducer = self.transducer
        first, last = float(angles[0]), float(angles[-1])
        duration = (last - first) / transducer.pan_speed_rad_s + len(
            angles
        ) * transducer.listen_time_s
        return angles, ranges, amplitudes, duration


@functools.lru_cache(maxsize=256)
def _sweep_grid(
    sector_center: float, half_sweep_rad: float, step_rad: float
) -> tuple[FloatArray, FloatArray]:
    """Sweep angles and their unit vectors in {R}, read-only (cached: a task sweeps the same
    few sectors again and again)."""
    n = math.floor(2.0 * half_sweep_rad / step_rad + 1e-9) + 1
    angles = sector_center - half_sweep_rad + step_rad * np.arange(n, dtype=np.float64)
    directions = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    angles.flags.writeable = False
    directions.flags.writeable = False
    return angles, directions


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
    def apcs(
        cls, range_noise_std_m: float | None = None, preset: str = "ma40b8", **options: object
    ) -> SideSonars:
        """The side sonars of APCS: the paper's MA40B8 or the transducer ``preset`` (a
        scenario's ``[sensor]``), with the timing jitter set to ``range_noise_std_m`` (as range,
        metres) instead of the preset's when given."""
        transducer = transducer_preset(preset)
        if range_noise_std_m is not None:
            transducer = replace(transducer, range_noise_std_m=float(range_noise_std_m))
        return cls(transducer, **options)  # type: ignore[arg-type]

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
        self,
        world: WorldLike,
        poses: Sequence[Pose] | FloatArray,
        rng: np.random.Generator | None,
        sides: Sequence[str] = SIDE_NAMES,
    ) -> SideReadings:
        """Samples at each of ``poses`` ({W}; Poses or ``(n, 3)`` rows ``[x, y, theta]``);
        geometry and electronics as arrays over all of them.

        The echo geometry of every sensor position is found at once
        (:meth:`first_echoes_along`, the same physics as :meth:`first_echoes_at` pose by pose);
        the readout (delay, noise, counter) is one array operation over every sample, drawing
        the noise in the order of ``len(poses)`` calls of :meth:`read`. The readings of a
        sensor left out of ``sides`` are NaN, with their noise drawn all the same, so that
        the named sensors read what they read with both.
        """
        if len(poses) == 0:
            return SideReadings(np.zeros(0), np.zeros(0))
        return self.read_echoes(world, self.first_echoes_along(world, poses, sides), rng)

    def read_echoes(
        self, world: WorldLike, echoes: FirstEchoes, rng: np.random.Generator | None
    ) -> SideReadings:
        """The readout of first echoes ``(2 n,)`` in the order of :meth:`first_echoes_along`.

        Its first ``2 m`` rows give the readings of the first ``m`` poses, with the draws of
        ``m`` calls of :meth:`read`: a caller that keeps only a prefix of a run of samples
        replays their draws without finding their echoes again.
        """
        count = len(echoes.path_lengths)
        if count % 2:
            raise ValueError(
                f"argument 'echoes' must hold a left and a right echo per sample; got {count}"
            )
        transducer = self.transducer
        air = _side_air(self, world.temperature_c, world.scenario.robot.radius)
        normals = _NO_NORMALS
        if self.readout.range_noise and transducer.range_noise_std_m > 0.0:
            if rng is None:
                raise ValueError("argument 'rng' is needed: the readout adds range noise")
            normals = rng.standard_normal(count)
        left, right = side_kernels.side_readings(
            echoes.detected, echoes.path_lengths, echoes.amplitudes, normals, air.readout_constants
        )
        return SideReadings(left_m=left, right_m=right)

    def sample_along_per_pose(
        self, world: WorldLike, poses: Sequence[Pose], rng: np.random.Generator | None
    ) -> SideReadings:
        """:meth:`sample_along` with the echo geometry found pose by pose (the reference)."""
        if len(poses) == 0:
            return SideReadings(np.zeros(0), np.zeros(0))
        echoes = concatenate_echoes([self._echoes(world, pose) for pose in poses])
        ranges, _ = self.readings(world, echoes, rng)
        pairs = ranges.reshape(len(poses), 2)
        return SideReadings(left_m=pairs[:, 0].copy(), right_m=pairs[:, 1].copy())

    def first_echoes_along(
        self,
        world: WorldLike,
        poses: Sequence[Pose] | FloatArray,
        sides: Sequence[str] = SIDE_NAMES,
    ) -> FirstEchoes:
        """First echoes of the left and right sensor at each of ``poses``, ``(2 n,)`` in the
        order left, right of the first pose, then of the next.

        The echo candidates of :func:`~sonar_gym.sonar.echoes.echo_candidates` (planes,
        cylinders, corners, edges; minimum range, threshold, footprint, occlusion) and the
        detection of :func:`~sonar_gym.sonar.pulse_echo.first_echoes`, evaluated with the same
        constant tables for every sensor position at once. Only the sensors named in
        ``sides`` (``"left"``, ``"right"``) are evaluated; the rows of the others hold no echo.
        """
        unknown = [side for side in sides if side not in SIDE_NAMES]
        if unknown:
            raise ValueError(
                f"argument 'sides' must name sensors of {list(SIDE_NAMES)}; got {list(sides)!r}"
            )
        if isinstance(poses, np.ndarray):
            robot = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
        else:
            robot = np.array([[p.x, p.y, p.theta] for p in poses], dtype=np.float64).reshape(-1, 3)
        n = len(robot)
        if not np.isfinite(robot).all():
            raise ValueError(f"argument 'poses' must hold finite poses; got {poses!r}")
        if len(set(sides)) == len(SIDE_NAMES):
            first, stride = 0, 1
        elif sides:
            first, stride = SIDE_NAMES.index(sides[0]), 2
        else:
            return FirstEchoes(np.zeros(2 * n, dtype=bool), np.zeros(2 * n), np.zeros(2 * n))
        headings = robot[:, 2]
        homogeneous, sensor_frames = side_kernels.side_sensors(
            robot, np.cos(headings), np.sin(headings), self._sensor_offsets(headings), first, stride
        )
        sensed = _side_first_echoes(self, world, homogeneous, sensor_frames)
        if stride == 1:
            return sensed
        echoes = FirstEchoes(np.zeros(2 * n, dtype=bool), np.zeros(2 * n), np.zeros(2 * n))
        rows = slice(first, None, 2)
        echoes.detected[rows] = sensed.detected
        echoes.path_lengths[rows] = sensed.path_lengths
        echoes.amplitudes[rows] = sensed.amplitudes
        return echoes

    def _sensor_offsets(self, headings: FloatArray) -> FloatArray:
        """``(2 n, 2)`` offsets of the left and right sensor from the robot centre at each of
        ``headings`` (metres, {W}; radians), or ``(0, 2)`` when the sensors sit at the centre."""
        if self.lateral_offset_m == 0.0:
            return _AT_CENTRE
        angle = np.repeat(headings, 2) + np.tile([1.0, -1.0], len(headings)) * (math.pi / 2.0)
        return self.lateral_offset_m * np.column_stack([np.cos(angle), np.sin(angle)])


@dataclass(frozen=True)
class _SideAir:
    """What the side sonars' echoes and readout need of a sonar in a world's air and robot,
    besides the geometry: its two-way beam, the edge law's constants and the constant vectors
    of :func:`~sonar_gym.sonar.side_kernels.side_heard`,
    :func:`~sonar_gym.sonar.side_kernels.side_first` and
    :func:`~sonar_gym.sonar.side_kernels.side_readings`."""

    beam: PistonBeam
    edge_law: FloatArray
    absorption_per_m: float
    """``-alpha ln(10) / 10``: the exponent of the air's amplitude loss per metre, 1/m."""
    heard_constants: FloatArray
    first_constants: FloatArray
    readout_constants: FloatArray
    """The constants of :func:`~sonar_gym.sonar.side_kernels.side_readings`."""


_LAST_SIDE_AIR: list[tuple[SideSonars, float, float, _SideAir]] = []
"""The last sonar, air temperature (deg C) and robot radius (m) asked of :func:`_side_air`,
and its answer."""


def _side_air(sonar: SideSonars, temperature_c: float, robot_radius_m: float) -> _SideAir:
    """The :class:`_SideAir` of ``sonar`` at ``temperature_c`` (deg C) on a robot of radius
    ``robot_radius_m`` (metres); remembered for the last sonar object, temperature and radius
    (the samples of an episode all ask the same)."""
    if _LAST_SIDE_AIR:
        last_sonar, last_temperature, last_radius, answer = _LAST_SIDE_AIR[0]
        if (
            last_sonar is sonar
            and last_temperature == temperature_c
            and last_radius == robot_radius_m
        ):
            return answer
    transducer = sonar.transducer
    speed, wavenumber, beam = air_at(transducer, temperature_c)
    heard_constants = np.array(
        (
            max(transducer.min_range_m, 1e-9),
            transducer.detection_threshold,
            robot_radius_m,
            transducer.min_range_m,
            beam.widest_main_lobe_cos,
            1.0 if beam.side_lobes else 0.0,
            float(TABLE_STEPS_PER_UNIT),
            1.0 / TABLE_STEPS_PER_UNIT,
            SMALLEST_COSINE,
            1.0 if beam.reaches_back else 0.0,
        )
    )
    first_constants = np.array(
        (_UV_CENTRE_SCALAR, float(TABLE_STEPS_PER_UNIT), 1.0 if beam.reaches_back else 0.0)
    )
    readout_constants = _readout_constants(sonar, speed)
    heard_constants.flags.writeable = False
    first_constants.flags.writeable = False
    answer = _SideAir(
        beam=beam,
        edge_law=edge_law_constants(sonar.edge_law, wavenumber),
        absorption_per_m=-transducer.absorption_db_per_m * math.log(10.0) / 10.0,
        heard_constants=heard_constants,
        first_constants=first_constants,
        readout_constants=readout_constants,
    )
    _LAST_SIDE_AIR[:] = [(sonar, temperature_c, robot_radius_m, answer)]
    return answer


def _readout_constants(sonar: SideSonars, speed_mps: float) -> FloatArray:
    """The constants of :func:`~sonar_gym.sonar.side_kernels.side_readings` for ``sonar`` in air
    where sound travels at ``speed_mps`` (m/s); read-only."""
    transducer, readout = sonar.transducer, sonar.readout
    delay = readout.crossing_delay and transducer.echo_rise_time_s > 0.0
    period = transducer.timer_period_s if readout.quantisation else 0.0
    constants = np.array(
        (
            2.0 / speed_mps,
            1.0 if delay else 0.0,
            transducer.echo_rise_time_s * transducer.detection_threshold,
            2.0 * transducer.range_noise_std_m / speed_mps,
            1.0 / period if period > 0.0 else 0.0,
            period if period > 0.0 else 0.0,
            sonar.assumed_speed_of_sound_mps / 2.0,
            transducer.max_range_m,
        )
    )
    constants.flags.writeable = False
    return constants


def map_at_points(linear_map: FloatArray, homogeneous: FloatArray) -> FloatArray:
    """``homogeneous @ linear_map.T``: ``(P, M)`` the ``(M, 3)`` map of an echo table at each
    of the ``(P, 3)`` points ``(x, y, 1)`` ({W}, metres), as a transposed view.

    Taken as ``(linear_map @ homogeneous.T).T``: BLAS forms every entry as the same
    three-term sum either way (the tests check the bits), and for a few dozen points against
    a few hundred map rows this order costs OpenBLAS less than half as much.
    """
    return (linear_map @ homogeneous.T).T  # type: ignore[no-any-return]


def _side_first_echoes(
    sonar: SideSonars, world: WorldLike, homogeneous: FloatArray, sensor_frames: FloatArray
) -> FirstEchoes:
    """First echoes of pings along ``heading + side_sign pi/2`` from each sensor.

    Row by row :func:`~sonar_gym.sonar.echoes.echo_candidates` then
    :func:`~sonar_gym.sonar.pulse_echo.first_echoes`, through the compiled loops of
    :mod:`sonar_gym.sonar.side_kernels` (the same numbers, bit for bit, as the array form in
    ``tests/sonar/side_echoes_reference.py``). numpy keeps the steps
    it rounds its own way: the BLAS products, the absorption's ``exp`` and the receiver's gain.

    Args:
        homogeneous: ``(P, 3)`` each sensor's ``(x, y, 1)`` in {W} (metres).
        sensor_frames: ``(P, 5)`` ``cos`` and ``sin`` of the robot heading, the side sign (+1
            left, -1 right) and the sensor's offset from the robot centre (m, {W}), as
            :func:`~sonar_gym.sonar.side_kernels.side_sensors` gives them.
    """
    transducer = sonar.transducer
    air = _side_air(sonar, world.temperature_c, world.scenario.robot.radius)
    beam = air.beam
    tables = echo_tables(world.geometry, EchoKind.PLANE, EchoKind.CYLINDER, EchoKind.EDGE)
    layout = tables.search_layout[:4]
    mapped = map_at_points(tables.position_map, homogeneous)  # (P, M)
    rel, ranges, safe, amplitudes, centre_distance, concave = side_kernels.side_ranges(
        mapped, layout, tables.radius, air.edge_law
    )
    if transducer.absorption_db_per_m > 0.0:
        amplitudes = amplitudes * np.exp(air.absorption_per_m * safe)
    if transducer.time_varying_gain is not None:
        amplitudes = amplitudes * transducer.time_varying_gain.gain(safe)
    heard, cosines, facing = side_kernels.side_heard(
        mapped,
        rel,
        ranges,
        safe,
        amplitudes,
        concave,
        sensor_frames,
        layout,
        tables.solid_side,
        tables.twin,
        tables.twin_comes_first,
        air.heard_constants,
        beam.cells,
        beam.main_lobe_rising,
        beam.main_lobe_cells,
    )
    sensor_rows, candidate_rows, path_sensors = side_kernels.heard_paths(heard, homogeneous)
    matrix = map_at_points(tables.occlusion_map, path_sensors).reshape(
        len(sensor_rows), 3 * tables.n_segments + tables.n_circles, 3
    )
    detected, path_lengths, first_amplitudes = side_kernels.side_first(
        matrix,
        rel,
        sensor_rows,
        candidate_rows,
        ranges,
        cosines,
        amplitudes,
        facing,
        tables.encloses,
        centre_distance,
        tables.radius_sq,
        air.first_constants,
        beam.cells,
    )
    return FirstEchoes(detected=detected, path_lengths=path_lengths, amplitudes=first_amplitudes)
