"""One-way ultrasonic ranging from fixed emitters to receivers on the robot (Wu & Tsai, Roh et al.).

Wu & Tsai sec. 3: an RF link starts the counter and fires transmitter ``i``; receiver ``j``
stops it, so ``TOF_ij = d_ij / V_E + d_ij / V_U`` (eq. (10)), ``= d_ij / V_U`` since radio is
about a million times faster (eq. (11)). Their 8051 counts at 50 kHz: a 20 us period, a 6.9 mm
range step. Here, for every emitter of the scenario (``scenario.emitters``, 3D points in {W})
and every receiver on the robot:

1. the 3D distance ``d`` from the emitter to the receiver, the receiver at ``(x, y)`` in {R}
   and ``height_m`` above the floor;
2. ``TOF = d / c_true`` (``c_true`` from the world's temperature), plus Gaussian jitter of
   standard deviation ``sigma / c_true``, and at least 0 (the counter cannot stop before the
   emitter fires; only a jitter of the order of the distance reaches that);
3. the counter: ``floor(TOF / T0) T0``;
4. ``distance = c_assumed * TOF``.

Dropouts (NaN): the true distance exceeds ``max_range_m``, or the path is blocked. Occlusion
rule (the scenario has no heights): room walls and free walls are full height and block when
the path's projection on the floor crosses them; boxes and cylinders are furniture below the
receivers and block nothing.

Timing: the emitters fire one after another, ``firing_interval_s`` apart, in the order asked
for; every receiver listens to every firing. ``timestamps_s[j, i]`` is the time since the call
started at which measurement ``(j, i)`` completed: ``i * interval + the measured TOF``, or the
end of the firing's interval for a dropout. The pose is taken as fixed during the call.

A whole route in one call: :meth:`BeaconRanger.measure_route` ranges ``n`` receiver poses at
once, as arrays ``(samples, receivers, emitters)``. It is the same model as ``n`` calls of
:meth:`BeaconRanger.measure`, one per sample in route order, and draws its jitter in the same
order (sample, then receiver, then emitter), so for one seed both give the same numbers.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt
from numba import types

from sonar_gym.compiled import NUMBERS, TABLE, compiled
from sonar_gym.pose import FloatArray, Pose
from sonar_gym.scenario import Emitter
from sonar_gym.sonar.acoustics import REFERENCE_TEMPERATURE_C, speed_of_sound_mps
from sonar_gym.sonar.echoes import PATH_END_TOLERANCE
from sonar_gym.sonar.pulse_echo import WorldLike
from sonar_gym.validation import MIN_TIMER_PERIOD_S

if TYPE_CHECKING:
    from sonar_gym.geometry import StaticGeometry
    from sonar_gym.scenario import Scenario

WU_TSAI_TIMER_PERIOD_S = 1.0 / 50e3
"""Wu & Tsai sec. 4: "the counting rate of the 8051 chip is 50 kHz"."""
WU_TSAI_RECEIVERS_XY = ((0.0, 0.2), (0.0, -0.2))
"""Wu & Tsai sec. 4: receivers at [0, 20, 0] and [0, -20, 0] cm in the robot frame."""


@dataclass(frozen=True)
class RangingWorld:
    """The least world a :class:`BeaconRanger` reads (a
    :class:`~sonar_gym.sonar.pulse_echo.WorldLike`): a room's static geometry, which can be
    shared while only the beacons (the scenario's emitters) change, and the air temperature
    (deg C)."""

    geometry: StaticGeometry
    temperature_c: float
    scenario: Scenario


@dataclass(frozen=True)
class RangeMeasurement:
    """One round of one-way ranging.

    Attributes:
        distances: ``(n_receivers, n_emitters)`` measured distances, metres; NaN = dropout.
        timestamps_s: same shape; when each measurement completed, seconds since the call.
        duration_s: time the round took, seconds.
        emitter_names: the emitters, in column order.
    """

    distances: FloatArray
    timestamps_s: FloatArray
    duration_s: float
    emitter_names: tuple[str, ...]


@dataclass(frozen=True)
class RouteGeometry:
    """The noise-free part of ranging a route (:meth:`BeaconRanger.route_geometry`).

    Attributes:
        true_distances: ``(n_samples, n_receivers, n_emitters)`` exact 3D distances, metres.
        heard: same shape; in range and not blocked by a wall.
        emitter_names: the emitters, in column order.
    """

    true_distances: FloatArray
    heard: npt.NDArray[np.bool_]
    emitter_names: tuple[str, ...]


@dataclass(frozen=True)
class RouteMeasurement:
    """One ranging round at every sample of a route.

    Attributes:
        distances: ``(n_samples, n_receivers, n_emitters)`` measured distances, metres;
            NaN = dropout.
        true_distances: same shape; the exact 3D distances, metres (also for dropouts).
        timestamps_s: same shape; when each measurement completed, seconds since the start of
            its sample's round.
        round_duration_s: time one round (one sample) takes, seconds.
        emitter_names: the emitters, in column order.
    """

    distances: FloatArray
    true_distances: FloatArray
    timestamps_s: FloatArray
    round_duration_s: float
    emitter_names: tuple[str, ...]

    @property
    def round_durations_s(self) -> FloatArray:
        """``(n_samples,)`` the duration of each sample's round, seconds."""
        return np.full(len(self.distances), self.round_duration_s)


@dataclass(frozen=True)
class BeaconRanger:
    """Receivers on the robot timing pulses from fixed emitters (see the module docstring).

    Attributes:
        receivers_xy: receiver positions ``(x, y)`` in the robot frame {R}, metres.
        height_m: receiver height above the floor, metres; None takes
            ``scenario.robot.sensor_height``.
        timer_period_s: period of the time-of-flight counter, seconds (0 = exact, else at least
            :data:`~sonar_gym.validation.MIN_TIMER_PERIOD_S`).
        range_noise_std_m: standard deviation of the timing jitter as a distance, metres.
        max_range_m: emitters farther than this are not heard, metres.
        assumed_speed_of_sound_mps: the speed the receiver converts with, m/s.
        firing_interval_s: time between two emitters' firings, seconds.
        noise: add the jitter.
        quantisation: apply the counter.
    """

    receivers_xy: tuple[tuple[float, float], ...] = ((0.0, 0.0),)
    height_m: float | None = None
    timer_period_s: float = WU_TSAI_TIMER_PERIOD_S
    range_noise_std_m: float = 0.002
    max_range_m: float = 10.0
    assumed_speed_of_sound_mps: float = speed_of_sound_mps(REFERENCE_TEMPERATURE_C)
    firing_interval_s: float = 0.05
    noise: bool = True
    quantisation: bool = True
    _firing_cache: _Firing | None = field(
        default=None, init=False, repr=False, compare=False, hash=False
    )

    def __post_init__(self) -> None:
        receivers = np.asarray(self.receivers_xy, dtype=np.float64)
        if (
            receivers.ndim != 2
            or receivers.shape[1] != 2
            or len(receivers) == 0
            or not np.isfinite(receivers).all()
        ):
            raise ValueError(
                "argument 'receivers_xy' must be one or more finite (x, y) pairs in metres; "
                f"got {self.receivers_xy!r}"
            )
        object.__setattr__(self, "receivers_xy", tuple((float(x), float(y)) for x, y in receivers))
        if self.height_m is not None and not math.isfinite(self.height_m):
            raise ValueError(
                f"argument 'height_m' must be finite (metres) or None; got {self.height_m!r}"
            )
        for name in ("max_range_m", "assumed_speed_of_sound_mps", "firing_interval_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"argument '{name}' must be positive; got {value!r}")
        if not (math.isfinite(self.range_noise_std_m) and self.range_noise_std_m >= 0):
            raise ValueError(
                f"argument 'range_noise_std_m' must be >= 0; got {self.range_noise_std_m!r}"
            )
        period = self.timer_period_s
        if not (math.isfinite(period) and (period == 0 or period >= MIN_TIMER_PERIOD_S)):
            raise ValueError(
                "argument 'timer_period_s' must be 0 (no counter) or at least "
                f"{MIN_TIMER_PERIOD_S:g} s; got {period!r}"
            )

    @classmethod
    def wu_tsai(cls, **options: object) -> BeaconRanger:
        """Wu & Tsai's two receivers at (0, +-0.2) m in {R}, with their 50 kHz counter."""
        return cls(receivers_xy=WU_TSAI_RECEIVERS_XY, **options)  # type: ignore[arg-type]

    def with_assumed_speed(self, speed_mps: float) -> BeaconRanger:
        """The same ranger converting with ``speed_mps`` (m/s)."""
        return dataclasses.replace(self, assumed_speed_of_sound_mps=float(speed_mps))

    @property
    def range_quantum_m(self) -> float:
        """Distance step of one timer count, ``c_assumed T0`` metres."""
        return self.assumed_speed_of_sound_mps * self.timer_period_s

    def measure(
        self,
        world: WorldLike,
        pose: Pose,
        rng: np.random.Generator | None,
        emitter_names: Sequence[str] | None = None,
    ) -> RangeMeasurement:
        """Range every receiver to every emitter (``emitter_names``, default all, in order).

        Args:
            world: the world (its scenario's emitters, walls and temperature are read).
            pose: the robot pose in {W}.
            rng: the random generator for the jitter (None only when the noise is off).
            emitter_names: which emitters fire, in firing order.
        """
        route = self.measure_route(
            world, pose.position[None, :], rng, emitter_names, headings_rad=[pose.theta]
        )
        return RangeMeasurement(
            distances=route.distances[0],
            timestamps_s=route.timestamps_s[0],
            duration_s=route.round_duration_s,
            emitter_names=route.emitter_names,
        )

    def measure_route(
        self,
        world: WorldLike,
        xy: npt.ArrayLike,
        rng: np.random.Generator | None,
        emitter_names: Sequence[str] | None = None,
        headings_rad: npt.ArrayLike | None = None,
    ) -> RouteMeasurement:
        """One ranging round at every sample of a route, as arrays (see the module docstring).

        Args:
            world: the world (its scenario's emitters, walls and temperature are read).
            xy: ``(n, 2)`` robot positions in {W}, metres, in route order.
            rng: the random generator for the jitter (None only when the noise is off); drawn
                as ``n`` calls of :meth:`measure` would draw it.
            emitter_names: which emitters fire, in firing order (default all).
            headings_rad: ``(n,)`` robot headings in {W}, radians (default 0: only matters for
                receivers off the robot centre).
        """
        return self.measure_geometry(
            self.route_geometry(world, xy, emitter_names, headings_rad), world.temperature_c, rng
        )

    def measure_repeated(
        self,
        world: WorldLike,
        pose: Pose,
        n_rounds: int,
        rng: np.random.Generator | None,
        emitter_names: Sequence[str] | None = None,
    ) -> RouteMeasurement:
        """``n_rounds`` ranging rounds at one fixed pose ({W}), as :meth:`measure_route` of a
        route that repeats ``pose`` ``n_rounds`` times would give them (same jitter draws).

        The geometry (distances, occlusion) is worked out once and shared by every round.
        """
        if isinstance(n_rounds, bool) or int(n_rounds) != n_rounds or n_rounds < 1:
            raise ValueError(f"argument 'n_rounds' must be an integer >= 1; got {n_rounds!r}")
        # a Pose is finite: the checks of route_geometry's arguments have nothing to catch
        single = self._geometry(
            self._firing(world, emitter_names),
            np.array([[pose.x, pose.y]]),
            np.array([pose.theta]),
        )
        return self._rounds(single, int(n_rounds), world.temperature_c, rng)

    def route_geometry(
        self,
        world: WorldLike,
        xy: npt.ArrayLike,
        emitter_names: Sequence[str] | None = None,
        headings_rad: npt.ArrayLike | None = None,
    ) -> RouteGeometry:
        """The noise-free part of :meth:`measure_route`: true distances and what is heard.

        A task that ranges the same route among the same emitters again (a new episode, new
        noise) computes this once and passes it to :meth:`measure_geometry`.
        """
        positions = _route_positions(xy)
        n_samples = len(positions)
        if headings_rad is None:
            headings = np.zeros(n_samples)
        else:
            headings = np.asarray(headings_rad, dtype=np.float64)
            if headings.shape != (n_samples,) or not np.isfinite(headings).all():
                raise ValueError(
                    f"argument 'headings_rad' must be {n_samples} finite radians (one per "
                    f"sample); got shape {headings.shape}"
                )
        return self._geometry(self._firing(world, emitter_names), positions, headings)

    def _firing(self, world: WorldLike, emitter_names: Sequence[str] | None) -> _Firing:
        """The pose-independent part of ranging ``world`` among ``emitter_names``, kept from the
        last call while the world's scenario and geometry are the same (immutable) objects."""
        if isinstance(emitter_names, str):
            self._emitters(world, emitter_names)  # raises: one name is not a sequence of names
        requested = None if emitter_names is None else tuple(emitter_names)
        cached = self._firing_cache
        if (
            cached is not None
            and cached.scenario is world.scenario
            and cached.geometry is world.geometry
            and cached.requested == requested
        ):
            return cached
        firing = _Firing.of(self, world, self._emitters(world, requested), requested)
        object.__setattr__(self, "_firing_cache", firing)
        return firing

    def _geometry(
        self, firing: _Firing, positions: FloatArray, headings: FloatArray
    ) -> RouteGeometry:
        """:meth:`route_geometry` of checked ``(n, 2)`` positions and ``(n,)`` headings."""
        distance, heard = _route_geometry_loop(
            positions,
            np.cos(headings),
            np.sin(headings),
            firing.receivers,
            firing.emitters,
            firing.walls,
            firing.constants,
        )
        distance.flags.writeable = False
        heard.flags.writeable = False
        return RouteGeometry(distance, heard, firing.emitter_names)

    def measure_geometry(
        self, geometry: RouteGeometry, temperature_c: float, rng: np.random.Generator | None
    ) -> RouteMeasurement:
        """One ranging round at every sample of a route whose geometry is known (see
        :meth:`route_geometry`), in air at ``temperature_c`` degrees Celsius; the jitter is
        drawn as :meth:`measure_route` draws it."""
        return self._rounds(geometry, None, temperature_c, rng)

    def _rounds(
        self,
        geometry: RouteGeometry,
        n_repeats: int | None,
        temperature_c: float,
        rng: np.random.Generator | None,
    ) -> RouteMeasurement:
        """:meth:`measure_geometry`, or with ``n_repeats`` given, that many rounds at the one
        sample of ``geometry`` (its arrays broadcast over the rounds)."""
        distance, heard = geometry.true_distances, geometry.heard
        shape = distance.shape if n_repeats is None else (n_repeats, *distance.shape[1:])
        n_emitters = len(geometry.emitter_names)
        true_speed = speed_of_sound_mps(temperature_c)
        normals = _NO_NORMALS
        if self.noise and self.range_noise_std_m > 0.0:
            if rng is None:
                raise ValueError("argument 'rng' is needed: the ranger adds noise")
            normals = rng.standard_normal(shape)
        quantised = self.quantisation and self.timer_period_s > 0.0
        constants = np.array(
            [
                true_speed,
                self.range_noise_std_m / true_speed,
                self.timer_period_s if quantised else 0.0,
                self.assumed_speed_of_sound_mps,
                self.firing_interval_s,
            ]
        )
        distances, timestamps = _rounds_loop(distance, heard, normals, constants, shape[0])
        if n_repeats is not None:
            distance = np.broadcast_to(distance, shape)
        return RouteMeasurement(
            distances=distances,
            true_distances=distance,
            timestamps_s=timestamps,
            round_duration_s=n_emitters * self.firing_interval_s,
            emitter_names=geometry.emitter_names,
        )

    @staticmethod
    def _emitters(world: WorldLike, emitter_names: Sequence[str] | None) -> tuple[Emitter, ...]:
        """The firing emitters: ``emitter_names`` in order, default all of the scenario."""
        scenario = world.scenario
        if emitter_names is None:
            return tuple(scenario.emitters)
        if isinstance(emitter_names, str):
            raise ValueError("argument 'emitter_names' must be a sequence of names, not one string")
        return tuple(scenario.emitter(name) for name in emitter_names)


def _route_positions(xy: npt.ArrayLike) -> FloatArray:
    """``xy`` as an ``(n, 2)`` float array of finite metres, or a ValueError naming it."""
    positions = np.asarray(xy, dtype=np.float64)
    if positions.ndim != 2 or positions.shape[1] != 2 or not np.isfinite(positions).all():
        raise ValueError(
            "argument 'xy' must be an (n, 2) array of finite positions in metres; "
            f"got shape {positions.shape}"
        )
    return positions


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.float64, 3, "C"), types.Array(types.boolean, 3, "C"))),
    TABLE,  # positions
    NUMBERS,  # cos
    NUMBERS,  # sin
    TABLE,  # receivers
    TABLE,  # emitters
    TABLE,  # walls
    NUMBERS,  # constants
)
def _route_geometry_loop(
    positions: FloatArray,
    cos: FloatArray,
    sin: FloatArray,
    receivers: FloatArray,
    emitters: FloatArray,
    walls: FloatArray,
    constants: FloatArray,
) -> tuple[FloatArray, npt.NDArray[np.bool_]]:
    """``(n, R, E)`` true 3D distances (metres) and whether each path is heard.

    A path is heard when it is no longer than the maximum range and its floor projection, from
    the receiver to the emitter, crosses no room or free wall: it meets a wall's segment at a
    fraction ``u`` of the path strictly inside ``(tol, 1 - tol)`` and at a fraction ``v`` of the
    wall in ``[0, 1]``. Elementwise IEEE arithmetic in numpy's order, so numpy's bits.

    Args:
        positions: ``(n, 2)`` robot positions in {W}, metres.
        cos, sin: ``(n,)`` cosine and sine of the robot headings.
        receivers: ``(2, R)`` receiver ``x`` and ``y`` in the robot frame {R}, metres.
        emitters: ``(3, E)`` emitter ``x``, ``y`` in {W} and height above the receivers, metres.
        walls: ``(4, S)`` each wall's start ``x``, ``y`` and direction ``x``, ``y`` (metres).
        constants: the maximum range (metres) and the path-end tolerance ``tol``.
    """
    n_samples, n_receivers, n_emitters = positions.shape[0], receivers.shape[1], emitters.shape[1]
    n_walls = walls.shape[1]
    max_range, tolerance = constants[0], constants[1]
    limit = 1.0 - tolerance
    distance = np.empty((n_samples, n_receivers, n_emitters))
    heard = np.empty((n_samples, n_receivers, n_emitters), dtype=np.bool_)
    for i in range(n_samples):
        c, s, x, y = cos[i], sin[i], positions[i, 0], positions[i, 1]
        for j in range(n_receivers):
            offset_x, offset_y = receivers[0, j], receivers[1, j]
            receiver_x = x + c * offset_x - s * offset_y
            receiver_y = y + s * offset_x + c * offset_y
            for k in range(n_emitters):
                path_x = emitters[0, k] - receiver_x  # receiver to emitter
                path_y = emitters[1, k] - receiver_y
                rise = emitters[2, k]
                length = math.sqrt((path_x * path_x + path_y * path_y) + rise * rise)
                distance[i, j, k] = length
                blocked = False
                for w in range(n_walls):
                    d_x, d_y = walls[2, w], walls[3, w]
                    w_x, w_y = walls[0, w] - receiver_x, walls[1, w] - receiver_y
                    denominator = path_x * d_y - path_y * d_x
                    u = (w_x * d_y - w_y * d_x) / denominator
                    v = (w_x * path_y - w_y * path_x) / denominator
                    if u > tolerance and u < limit and v >= 0.0 and v <= 1.0:
                        blocked = True
                        break
                heard[i, j, k] = length <= max_range and not blocked
    return distance, heard


_DISTANCES = types.Array(types.float64, 3, "A", readonly=True)
_NO_NORMALS = np.zeros((0, 0, 0))
_NO_NORMALS.flags.writeable = False


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.float64, 3, "C"), types.Array(types.float64, 3, "C"))),
    _DISTANCES,  # distance
    types.Array(types.boolean, 3, "A", readonly=True),  # heard
    _DISTANCES,  # normals
    NUMBERS,  # constants
    types.int64,  # n_rounds
)
def _rounds_loop(
    distance: FloatArray,
    heard: npt.NDArray[np.bool_],
    normals: FloatArray,
    constants: FloatArray,
    n_rounds: int,
) -> tuple[FloatArray, FloatArray]:
    """``(n_rounds, R, E)`` measured distances (metres, NaN = dropout) and timestamps (s).

    Steps 2-4 of the module docstring for every measurement: ``TOF = d / c_true`` plus the
    jitter (at least 0), the counter ``floor(TOF / T0) T0``, ``c_assumed TOF``; emitter ``k``
    fires at ``k`` intervals and its measurement completes a TOF later (a dropout: an interval
    later). Elementwise IEEE arithmetic in numpy's order, so numpy's bits.

    Args:
        distance, heard: ``(n_rounds, R, E)`` true distances (metres) and what is heard, or
            ``(1, R, E)`` shared by every round.
        normals: ``(n_rounds, R, E)`` standard normals of the jitter, or empty without jitter.
        constants: ``c_true`` (m/s), seconds of jitter per normal, ``T0`` (0: no counter),
            ``c_assumed`` (m/s), the firing interval (s).
        n_rounds: the rounds.
    """
    n_receivers, n_emitters = distance.shape[1], distance.shape[2]
    true_speed, jitter, period = constants[0], constants[1], constants[2]
    assumed_speed, interval = constants[3], constants[4]
    noisy = normals.size > 0
    shared = distance.shape[0] == 1
    distances = np.empty((n_rounds, n_receivers, n_emitters))
    timestamps = np.empty((n_rounds, n_receivers, n_emitters))
    for i in range(n_rounds):
        source = 0 if shared else i
        for j in range(n_receivers):
            for k in range(n_emitters):
                tof = distance[source, j, k] / true_speed
                if noisy:  # the counter cannot stop before the emitter fires
                    tof = max(tof + normals[i, j, k] * jitter, 0.0)
                if period > 0.0:
                    tof = np.floor(tof / period) * period
                start = interval * k
                if heard[source, j, k]:
                    distances[i, j, k] = tof * assumed_speed
                    timestamps[i, j, k] = start + tof
                else:
                    distances[i, j, k] = np.nan
                    timestamps[i, j, k] = start + interval
    return distances, timestamps


@dataclass(frozen=True)
class _Firing:
    """What ranging in one world among chosen emitters needs that no pose changes (metres).

    Attributes:
        scenario, geometry: the world's, which this was read from (both immutable).
        requested: the emitter names asked for (None: all of the scenario's).
        emitter_names: the firing emitters, in column order.
        receivers: ``(2, R)`` the receivers' ``x`` and ``y`` in the robot frame {R}.
        emitters: ``(3, E)`` the emitters' ``x``, ``y`` in {W} and height above the receivers.
        walls: ``(4, S)`` the start ``x``, ``y`` and direction ``x``, ``y`` of each room wall
            and free wall (the walls that block a path).
        constants: the ranger's maximum range (metres) and the path-end tolerance.
    """

    scenario: Scenario
    geometry: StaticGeometry
    requested: tuple[str, ...] | None
    emitter_names: tuple[str, ...]
    receivers: FloatArray
    emitters: FloatArray
    walls: FloatArray
    constants: FloatArray

    @classmethod
    def of(
        cls,
        ranger: BeaconRanger,
        world: WorldLike,
        emitters: tuple[Emitter, ...],
        requested: tuple[str, ...] | None,
    ) -> _Firing:
        """Read ``world`` for ``ranger`` firing ``emitters`` (asked for as ``requested``)."""
        scenario = world.scenario
        height = scenario.robot.sensor_height if ranger.height_m is None else ranger.height_m
        offsets = np.asarray(ranger.receivers_xy, dtype=np.float64)  # (R, 2) in {R}
        emitter_xyz = np.array([e.position for e in emitters], dtype=np.float64).reshape(-1, 3)
        # StaticGeometry lists the room's four walls first, then the free walls, then the boxes.
        n_walls = (4 if scenario.room is not None else 0) + len(scenario.walls)
        geometry = world.geometry
        a = geometry.segment_starts[:n_walls]
        d = geometry.segment_ends[:n_walls] - a
        tables = (
            np.ascontiguousarray(offsets.T),
            np.array([emitter_xyz[:, 0], emitter_xyz[:, 1], emitter_xyz[:, 2] - height]),
            np.array([a[:, 0], a[:, 1], d[:, 0], d[:, 1]]).reshape(4, n_walls),
            np.array([ranger.max_range_m, PATH_END_TOLERANCE]),
        )
        for table in tables:
            table.flags.writeable = False
        return cls(scenario, geometry, requested, tuple(e.name for e in emitters), *tables)
