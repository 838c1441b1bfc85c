"""Wu & Tsai (2001): position, height and heading from three ceiling transmitters, two receivers.

Paper: C.-J. Wu and C.-C. Tsai, *Localization of an autonomous mobile robot based on
ultrasonic sensory information*, J. Intelligent and Robotic Systems (2001).

Frames and units (SI throughout):
    Transmitter frame {T} (the paper's reference frame): the three transmitters sit at
    ``[0, 0, 0]``, ``[a, 0, 0]`` and ``[0, a, 0]`` (Theorem 2, section 3), on the ceiling.
    ``z = x cross y`` (Fig. 4), so +z points up, from the robot towards the ceiling, and the
    robot is below the transmitters with ``z < 0`` (the paper's receivers are at
    ``z = -1.90 m`` and ``-1.50 m``, Tables I-II); hence the default ``z_sign=-1``. Seen from
    above, x turns to y counter-clockwise and headings are counter-clockwise about +z.
    Robot frame {AMR}: receivers are mounted at ``(x, y, 0)`` in {AMR}, all at the same height
    (the one requirement of section 3), so the {AMR} origin, the robot reference point, has the
    receivers' height. The heading is the angle of the {AMR} x-axis from the {T} x-axis.
    The paper's rig (section 4): ``a = 0.20 m``, receivers at ``[0, +0.20, 0]`` and
    ``[0, -0.20, 0]`` in {AMR}, i.e. on the robot's y-axis.

What the module does, equation by equation:
    eq. (11) (and eq. (10)): distance from a one-way time of flight, :func:`distance_from_tof`.
    eqs (2)-(9), Theorem 2: closed-form receiver position, :func:`receiver_position`.
    Theorem 2's ``theta = Atan2(y2 - y1, x2 - x1)``: heading from two receivers,
    :func:`heading_from_receivers`.
    Theorem 1 (one transmitter cannot give heading, whatever the number of receivers) and its
    counterpart for one receiver: :func:`heading_observable` and the ``"heading_unobservable"``
    status of :func:`localize`.
    eqs (12)-(16): the average of n repeated fixes, :func:`average_fixes`, with the circular
    mean in place of the printed arithmetic mean of headings (eq. (16); see there).

Beside the paper's closed form, :func:`receiver_position_least_squares` offers a nonlinear
least-squares multilateration over any number (three or more) of ceiling transmitters;
:func:`localize` switches between them with ``solver``.

:func:`localize` never raises on bad geometry: it returns a :class:`TransmitterLocalization`
whose ``status`` says what went wrong (``"missing_distance"``, ``"inconsistent_distances"``,
``"heading_unobservable"``). Bad arguments raise :class:`ValueError` naming the argument.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt
from numba import types
from scipy.optimize import least_squares

from sonar_gym.compiled import NUMBERS, TABLE, compiled, nan_max
from sonar_gym.localization.result import OK, Localization
from sonar_gym.pose import FloatArray, Pose, wrap_angle

PAPER_TRANSMITTER_SPACING_M = 0.20
"""``a`` of the paper's experiments (section 4): transmitters at [0,0,0], [20,0,0], [0,20,0] cm."""

PAPER_RECEIVER_OFFSETS_M: tuple[tuple[float, float], ...] = ((0.0, 0.20), (0.0, -0.20))
"""Receiver positions ``(x, y)`` in {AMR} of the paper's experiments: [0, +-20, 0] cm."""

PAPER_COUNTER_RATE_HZ = 50e3
"""Counting rate of the 8051 timer that measures the TOF (section 4): one tick is 20 us."""

PAPER_TEMPERATURE_C = 27.0
"""Room temperature during the experiments (section 4)."""

PAPER_REPEATED_FIXES = 10
"""n of eqs (12)-(16) in Tables I-II."""

STATUS_HEADING_UNOBSERVABLE = "heading_unobservable"
STATUS_INCONSISTENT_DISTANCES = "inconsistent_distances"
STATUS_MISSING_DISTANCE = "missing_distance"

SPEED_OF_LIGHT_MPS = 299_792_458.0
"""Speed of the radio trigger, ``V_E`` of eq. (10)."""

_RELATIVE_RADICAND_TOLERANCE = 1e-9
_MIN_BASELINE_M = 1e-9

Solver = Literal["closed_form", "least_squares"]


class InconsistentDistances(ValueError):
    """The three distances admit no point: the radicand of eq. (9) is clearly negative.

    Raised by :func:`receiver_position`; :func:`localize` catches it and returns the status
    ``"inconsistent_distances"`` instead.
    """


# --------------------------------------------------------------------------------------------
# Ranging: eqs (10)-(11)
# --------------------------------------------------------------------------------------------


def speed_of_sound_from_temperature_mps(temperature_c: float) -> float:
    """Speed of sound in dry air, m/s, at ``temperature_c`` degrees Celsius.

    The paper gives no formula: it states only the room temperature, 27 deg C (section 4), and
    notes that measuring the mean ambient temperature would improve accuracy (section 5). This
    is the ideal-gas model the project uses everywhere, ``c(T) = 331.3 sqrt(1 + T / 273.15)``;
    at 27 deg C it gives 347.3 m/s.
    """
    temperature = float(temperature_c)
    if not math.isfinite(temperature) or temperature <= -273.15:
        raise ValueError(f"temperature_c must be finite and above -273.15, got {temperature_c!r}")
    return 331.3 * math.sqrt(1.0 + temperature / 273.15)


def distance_from_tof(
    tof_s: npt.ArrayLike,
    speed_of_sound_mps: float,
    radio_speed_mps: float | None = None,
) -> FloatArray | float:
    """Transmitter-receiver distance in metres from a one-way time of flight in seconds.

    With ``radio_speed_mps=None`` this is eq. (11), ``d = V_U * TOF``: the radio trigger is
    taken as instantaneous, as the paper does. Given ``radio_speed_mps`` (``V_E``, e.g.
    :data:`SPEED_OF_LIGHT_MPS`), it inverts eq. (10), ``TOF = d / V_E + d / V_U``; the
    difference is about 1e-6 relative.

    Args:
        tof_s: time(s) of flight, seconds, each > 0 (a scalar or an array).
        speed_of_sound_mps: ``V_U``, > 0.
        radio_speed_mps: ``V_E``, > 0, or None for eq. (11).

    Returns:
        The distance(s) in metres, a float for a scalar input, else an array of the same shape.
    """
    tof = np.asarray(tof_s, dtype=np.float64)
    if not np.all(np.isfinite(tof)) or np.any(tof <= 0.0):
        raise ValueError(f"tof_s must be finite and > 0 seconds, got {tof_s!r}")
    _require_positive("speed_of_sound_mps", speed_of_sound_mps)
    if radio_speed_mps is None:
        distance = tof * speed_of_sound_mps
    else:
        _require_positive("radio_speed_mps", radio_speed_mps)
        distance = tof / (1.0 / radio_speed_mps + 1.0 / speed_of_sound_mps)
    return float(distance) if distance.ndim == 0 else distance


# --------------------------------------------------------------------------------------------
# One receiver: Theorem 2, eqs (2)-(9)
# --------------------------------------------------------------------------------------------


def transmitter_positions(a: float) -> FloatArray:
    """``(3, 3)`` positions of the three transmitters in {T}, metres (Theorem 2)."""
    _require_positive("a", a)
    return np.array([[0.0, 0.0, 0.0], [a, 0.0, 0.0], [0.0, a, 0.0]])


def receiver_position(d: npt.ArrayLike, a: float, z_sign: int = -1) -> FloatArray:
    """Closed-form position ``[x, y, z]`` (metres, {T}) of one receiver, Theorem 2.

    ``d = (d0, d1, d2)`` are its distances in metres to the transmitters at ``[0, 0, 0]``,
    ``[a, 0, 0]`` and ``[0, a, 0]`` (the paper's ``d_1, d_2, d_3``). Then

        x = (d0^2 - d1^2 + a^2) / (2a)            eq. (7), from eqs (2)-(3), (5)
        y = (d0^2 - d2^2 + a^2) / (2a)            eq. (8), from eqs (2), (4), (6)
        z = z_sign * sqrt(d0^2 - x^2 - y^2)       eq. (9)

    The square root has two signs; the caller gives the side of the transmitter plane
    (``z_sign=-1``: below the ceiling).

    Inconsistent distances: noise can make the radicand of eq. (9) negative. A radicand above
    ``-1e-9 (d0^2 + a^2)`` (rounding, or a receiver in the transmitter plane) is clamped to 0,
    giving ``z = 0``; a more negative one raises :class:`InconsistentDistances` (a
    :class:`ValueError`), which :func:`localize` turns into the status
    ``"inconsistent_distances"``. No NaN is ever returned.

    Raises:
        ValueError: ``d`` is not three finite, non-negative distances, ``a <= 0`` or
            ``z_sign`` is not +1 or -1.
        InconsistentDistances: the distances admit no point.
    """
    distances = _as_distances(d, "d", expected_count=3)
    _require_positive("a", a)
    _require_z_sign(z_sign)
    if not np.all(np.isfinite(distances)):
        raise ValueError(f"d must be finite (NaN marks a dropout; use localize), got {d!r}")
    with np.errstate(over="ignore", invalid="ignore"):
        d0_sq, d1_sq, d2_sq = distances**2
        x = (d0_sq - d1_sq + a * a) / (2.0 * a)
        y = (d0_sq - d2_sq + a * a) / (2.0 * a)
        radicand = d0_sq - x * x - y * y
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(radicand)):
        return _receiver_position_unsquared(distances, float(a), z_sign)
    if radicand < 0.0:
        if radicand < -_RELATIVE_RADICAND_TOLERANCE * (d0_sq + a * a):
            raise InconsistentDistances(
                f"distances {distances.tolist()} m admit no point: d0^2 - x^2 - y^2 = "
                f"{radicand:.3g} m^2 < 0 in eq. (9)"
            )
        radicand = 0.0
    return np.array([x, y, z_sign * math.sqrt(radicand)])


def _receiver_position_unsquared(distances: FloatArray, a: float, z_sign: int) -> FloatArray:
    """Theorem 2 for distances whose squares leave the float range (eqs (7)-(9) rearranged).

    ``x = (d0 - d1) (d0 + d1) / (2a) + a/2`` (eq. (7)), the same for ``y`` (eq. (8)), and
    ``|z| = sqrt(d0 - r) sqrt(d0 + r)`` with ``r = hypot(x, y)`` (eq. (9)): no square of a
    distance is formed. A point beyond the float range raises :class:`InconsistentDistances`.
    """
    d0, d1, d2 = (float(v) for v in distances)

    def half_difference_of_squares_over_a(d: float, other: float) -> float:
        difference = d - other
        if difference == 0.0:
            return 0.0
        return difference * ((0.5 * d + 0.5 * other) / a)

    with np.errstate(over="ignore", invalid="ignore"):
        x = half_difference_of_squares_over_a(d0, d1) + 0.5 * a
        y = half_difference_of_squares_over_a(d0, d2) + 0.5 * a
    if not (math.isfinite(x) and math.isfinite(y)):
        raise InconsistentDistances(
            f"distances {distances.tolist()} m with a = {a} m put the receiver beyond the "
            "floating-point range in eqs (7)-(8)"
        )
    r = math.hypot(x, y)
    if d0 >= r:
        z = math.sqrt(d0 - r) * math.sqrt(0.5 * d0 + 0.5 * r) * math.sqrt(2.0)
    else:
        scale = max(r, a)
        deficit = ((r - d0) / scale) * ((r + d0) / scale)
        if deficit > _RELATIVE_RADICAND_TOLERANCE * ((d0 / scale) ** 2 + (a / scale) ** 2):
            raise InconsistentDistances(
                f"distances {distances.tolist()} m admit no point: d0 < hypot(x, y) in eq. (9)"
            )
        z = 0.0
    if not math.isfinite(z):
        raise InconsistentDistances(
            f"distances {distances.tolist()} m put the receiver beyond the floating-point range "
            "in eq. (9)"
        )
    return np.array([x, y, z_sign * z])


def receiver_position_least_squares(
    d: npt.ArrayLike, transmitter_xy: npt.ArrayLike, z_sign: int = -1
) -> FloatArray:
    """Least-squares position ``[x, y, z]`` (metres, {T}) of one receiver; not in the paper.

    An alternative to :func:`receiver_position` for three or more transmitters in the ceiling
    plane ``z = 0`` at ``transmitter_xy`` (``(m, 2)``, metres, not all on one line), with
    distances ``d`` (``(m,)``, metres). It minimises ``sum_i (|p - t_i| - d_i)^2`` over ``p``:
    a linear first guess (eq. (2) subtracted from the others, as in eqs (5)-(6), solved for x, y
    by least squares; z from the mean radicand of eq. (9)), refined by Levenberg-Marquardt.
    With the paper's three transmitters and a positive radicand this is eqs (7)-(9) again; with
    more transmitters it averages out range noise, and distances too short for eq. (9) give the
    best point in the plane (``z = 0``) instead of failing. Coplanar transmitters cannot tell
    ``z`` from ``-z``, so ``z_sign`` chooses, as in eq. (9).

    Raises:
        ValueError: wrong shapes, fewer than three or collinear transmitters, non-finite or
            negative distances, or ``z_sign`` not +1 or -1.
    """
    transmitters = np.asarray(transmitter_xy, dtype=np.float64)
    if transmitters.ndim != 2 or transmitters.shape[1] != 2 or transmitters.shape[0] < 3:
        raise ValueError(
            f"transmitter_xy must have shape (m, 2) with m >= 3, got {transmitters.shape}"
        )
    if not np.all(np.isfinite(transmitters)):
        raise ValueError("transmitter_xy must be finite")
    distances = _as_distances(d, "d", expected_count=len(transmitters))
    if not np.all(np.isfinite(distances)):
        raise ValueError(f"d must be finite, got {d!r}")
    _require_z_sign(z_sign)
    offsets = transmitters[1:] - transmitters[0]
    scale = float(np.max(np.linalg.norm(offsets, axis=1)))
    if scale == 0.0 or np.linalg.matrix_rank(offsets, tol=1e-9 * scale) < 2:
        raise ValueError("transmitter_xy must not be collinear: at least three must span a plane")

    # Linear first guess: |p - t_i|^2 - |p - t_0|^2 = d_i^2 - d_0^2 is linear in (x, y).
    squared_norms = np.sum(transmitters**2, axis=1)
    rhs = (squared_norms[1:] - squared_norms[0] - distances[1:] ** 2 + distances[0] ** 2) / 2.0
    xy_guess, *_ = np.linalg.lstsq(offsets, rhs, rcond=None)
    mean_radicand = float(np.mean(distances**2 - np.sum((xy_guess - transmitters) ** 2, axis=1)))
    z_floor = 1e-3 * max(scale, float(np.max(distances)))
    z_guess = math.sqrt(max(mean_radicand, z_floor * z_floor))

    def range_residuals(point: FloatArray) -> FloatArray:
        horizontal = point[:2] - transmitters
        return np.sqrt(np.sum(horizontal**2, axis=1) + point[2] ** 2) - distances

    fit = least_squares(
        range_residuals,
        np.array([xy_guess[0], xy_guess[1], z_guess]),
        method="lm",
        xtol=1e-15,
        ftol=1e-15,
        gtol=1e-15,
    )
    x, y, z = fit.x
    return np.array([x, y, z_sign * abs(z)])


# --------------------------------------------------------------------------------------------
# Two receivers: heading (Theorem 2) and observability (Theorem 1)
# --------------------------------------------------------------------------------------------


def heading_from_receivers(
    p_front: npt.ArrayLike, p_back: npt.ArrayLike, baseline_angle_in_robot_rad: float = 0.0
) -> float:
    """Robot heading in radians, (-pi, pi], from the positions of two receivers in {T}.

    Theorem 2 gives the direction of the receiver baseline, ``Atan2(y2 - y1, x2 - x1)`` from
    point 1 (``p_back``) to point 2 (``p_front``); only x and y are used (the receivers are at
    one height). The heading of the {AMR} x-axis is that direction minus the direction of the
    same baseline in {AMR}, ``baseline_angle_in_robot_rad``:

    * receivers on the robot's x-axis, ``p_front`` ahead of ``p_back``: ``0`` (the default),
      so the heading is the direction from the rear receiver to the front one;
    * the paper's rig, receivers at ``[0, +0.20, 0]`` and ``[0, -0.20, 0]`` in {AMR}: pass the
      +y receiver as ``p_front`` and ``pi / 2``.

    Args:
        p_front: ``(x, y)`` or ``(x, y, z)`` of the receiver the baseline points to, metres.
        p_back: the other receiver, same form.
        baseline_angle_in_robot_rad: angle of the vector from the back to the front receiver
            in {AMR}, radians.

    Raises:
        ValueError: the points are not 2- or 3-vectors, not finite, or coincide in (x, y).
    """
    front = _as_point_xy(p_front, "p_front")
    back = _as_point_xy(p_back, "p_back")
    dx, dy = front - back
    if math.hypot(dx, dy) < _MIN_BASELINE_M:
        raise ValueError(
            "p_front and p_back must differ in (x, y): their baseline has no direction"
        )
    return wrap_angle(math.atan2(dy, dx) - float(baseline_angle_in_robot_rad))


def heading_observable(n_transmitters: int, n_receivers: int) -> bool:
    """Whether fixed transmitters and robot-mounted receivers can determine the heading.

    Theorem 1: with one transmitter the distances do not change when the robot turns about
    the vertical through the transmitter, so heading (indeed the transform) is unobservable
    whatever the number of receivers. Likewise a single receiver is a point and has no
    heading, whatever the number of transmitters: turning the robot about the receiver keeps
    every distance. Theorem 2: three non-collinear transmitters and two receivers at one
    height, at distinct places on the robot, determine position and heading. Two transmitters
    are not covered by the paper and leave a mirror ambiguity, so they count as unobservable.
    """
    for name, value in (("n_transmitters", n_transmitters), ("n_receivers", n_receivers)):
        if int(value) != value or value < 1:
            raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
    return n_transmitters >= 3 and n_receivers >= 2


# --------------------------------------------------------------------------------------------
# Results
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Fix:
    """One position-and-heading fix of the robot in the transmitter frame {T}.

    Attributes:
        x, y, z: position of the robot reference point, the {AMR} origin, metres in {T}
            (``z < 0`` below the ceiling); it is at the receivers' height.
        heading: angle of the {AMR} x-axis from the {T} x-axis, radians, wrapped to (-pi, pi].
        receiver_positions: ``(x, y, z)`` of each receiver in {T}, metres, in the order given.
    """

    x: float
    y: float
    z: float
    heading: float
    receiver_positions: tuple[tuple[float, float, float], ...] = ()

    def __post_init__(self) -> None:
        for name in ("x", "y", "z", "heading"):
            value = float(getattr(self, name))
            if not math.isfinite(value):
                raise ValueError(f"Fix.{name} must be finite, got {value!r}")
            object.__setattr__(self, name, value)
        object.__setattr__(self, "heading", wrap_angle(self.heading))
        rows = self.receiver_positions
        if all(isinstance(row, (tuple, list)) and len(row) == 3 for row in rows):
            triples = tuple((float(row[0]), float(row[1]), float(row[2])) for row in rows)
        else:  # a flat sequence or an array: read as (n, 3)
            receivers = np.asarray(rows, dtype=np.float64).reshape(-1, 3)
            triples = tuple((float(x), float(y), float(z)) for x, y, z in receivers)
        if not all(math.isfinite(value) for row in triples for value in row):
            raise ValueError("Fix.receiver_positions must be finite")
        object.__setattr__(self, "receiver_positions", triples)

    @property
    def position(self) -> FloatArray:
        """``[x, y, z]`` in metres, {T}."""
        return np.array([self.x, self.y, self.z])

    @property
    def pose(self) -> Pose:
        """The planar pose ``(x, y, heading)``."""
        return Pose(self.x, self.y, self.heading)

    @property
    def receiver_array(self) -> FloatArray:
        """``(n_receivers, 3)`` receiver positions in metres, {T}."""
        return np.asarray(self.receiver_positions, dtype=np.float64).reshape(-1, 3)


@dataclass(frozen=True)
class TransmitterLocalization(Localization):
    """A :class:`Localization` that also carries the 3D position and the fix.

    Attributes:
        position_3d: ``(x, y, z)`` of the robot reference point in metres, {T}; set when
            ``status`` is ``"ok"``, and with ``"heading_unobservable"`` (then it is the
            receivers' mean position: the reference point itself if the receivers sit at the
            {AMR} origin, else a point within the receiver offset of it). None otherwise.
        fix: the full :class:`Fix`; set exactly when ``status == "ok"``.
    """

    position_3d: tuple[float, float, float] | None = None
    fix: Fix | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        if (self.status == OK) != (self.fix is not None):
            raise ValueError(
                "TransmitterLocalization: fix must be given exactly when status is 'ok'"
            )


# --------------------------------------------------------------------------------------------
# The method
# --------------------------------------------------------------------------------------------


def localize(
    distances: npt.ArrayLike,
    a: float,
    receiver_offsets: npt.ArrayLike,
    z_sign: int = -1,
    *,
    solver: Solver = "closed_form",
    extra_transmitter_xy: npt.ArrayLike | None = None,
) -> TransmitterLocalization:
    """Position, height and heading of the robot from receiver-transmitter distances.

    Each receiver is placed by Theorem 2 (eqs (7)-(9), :func:`receiver_position`); the pose
    is the planar rigid fit of the receivers' offsets in {AMR} to their measured (x, y) in {T}.
    For two receivers that fit is exactly Theorem 2's heading, the baseline direction minus its
    direction in {AMR} (:func:`heading_from_receivers`), and the reference point is the
    midpoint minus the rotated offset midpoint (for the paper's rig, just the midpoint). The
    height is the receivers' mean z.

    Args:
        distances: ``(n_receivers, 3)`` distances in metres from each receiver to the
            transmitters at ``[0, 0, 0]``, ``[a, 0, 0]``, ``[0, a, 0]`` (then one column per
            extra transmitter). NaN or inf marks a dropout.
        a: transmitter spacing, metres, > 0 (the paper: 0.20 m).
        receiver_offsets: ``(n_receivers, 2)`` receiver positions ``(x, y)`` in {AMR}, metres
            (the paper: :data:`PAPER_RECEIVER_OFFSETS_M`); all receivers at one height.
        z_sign: side of the transmitter plane, -1 (below the ceiling) or +1.
        solver: ``"closed_form"`` (the paper, eqs (7)-(9), using the three transmitters of
            Theorem 2) or ``"least_squares"`` (:func:`receiver_position_least_squares` over all
            transmitters, not in the paper).
        extra_transmitter_xy: ``(k, 2)`` positions in metres of further transmitters in the
            ceiling plane z = 0, for the least-squares solver.

    Returns:
        A :class:`TransmitterLocalization` with status

        * ``"ok"``: ``pose``, ``position_3d`` and ``fix`` set;
        * ``"missing_distance"``: some distance is NaN/inf (a dropout);
        * ``"inconsistent_distances"``: some receiver's distances admit no point (eq. (9)
          radicand < 0), or the receivers' measured (x, y) coincide;
        * ``"heading_unobservable"``: one receiver, or all receivers at one place on the robot
          (Theorem 1 and its counterpart, :func:`heading_observable`); ``position_3d`` set.

    Raises:
        ValueError: wrong shapes, negative distances, ``a <= 0``, ``z_sign`` not +-1, an
            unknown ``solver``.
    """
    _require_positive("a", a)
    _require_z_sign(z_sign)
    if solver not in ("closed_form", "least_squares"):
        raise ValueError(f"solver must be 'closed_form' or 'least_squares', got {solver!r}")
    extra = _as_extra_transmitters(extra_transmitter_xy)
    n_columns = 3 + len(extra)
    table = np.asarray(distances, dtype=np.float64)
    if table.ndim != 2 or table.shape[0] < 1 or table.shape[1] != n_columns:
        raise ValueError(
            f"distances must have shape (n_receivers >= 1, {n_columns}) (one column per "
            f"transmitter), got {table.shape}"
        )
    if np.any(table < 0.0):
        raise ValueError("distances must be >= 0 metres (NaN marks a dropout)")
    offsets = np.asarray(receiver_offsets, dtype=np.float64)
    if offsets.shape != (table.shape[0], 2):
        raise ValueError(
            f"receiver_offsets must have shape ({table.shape[0]}, 2), one (x, y) per row of "
            f"distances, got {offsets.shape}"
        )
    if not np.all(np.isfinite(offsets)):
        raise ValueError("receiver_offsets must be finite")

    missing = ~np.isfinite(table)
    if np.any(missing):
        receivers, transmitters = np.nonzero(missing)
        pairs = ", ".join(
            f"(receiver {r}, transmitter {t})" for r, t in zip(receivers, transmitters, strict=True)
        )
        return TransmitterLocalization(STATUS_MISSING_DISTANCE, message=f"no distance for {pairs}")

    try:
        receivers_xyz = _receiver_positions(table, a, z_sign, solver, extra)
    except InconsistentDistances as error:
        return TransmitterLocalization(STATUS_INCONSISTENT_DISTANCES, message=str(error))

    mean_receiver = _mean_without_overflow(receivers_xyz, axis=0)
    offset_spread = offsets - offsets.mean(axis=0)
    if not np.any(np.hypot(offset_spread[:, 0], offset_spread[:, 1]) >= _MIN_BASELINE_M):
        return TransmitterLocalization(
            STATUS_HEADING_UNOBSERVABLE,
            message=(
                f"{len(offsets)} receiver(s) at one place on the robot: a point has no heading "
                "(cf. Theorem 1); position_3d is the receivers' position"
            ),
            position_3d=_as_triple(mean_receiver),
        )

    measured_spread = receivers_xyz[:, :2] - mean_receiver[:2]
    cross = float(
        np.sum(
            offset_spread[:, 0] * measured_spread[:, 1]
            - offset_spread[:, 1] * measured_spread[:, 0]
        )
    )
    dot = float(np.sum(offset_spread * measured_spread))
    if math.hypot(cross, dot) < _MIN_BASELINE_M**2:
        return TransmitterLocalization(
            STATUS_INCONSISTENT_DISTANCES,
            message="the receivers' measured (x, y) coincide although they are apart on the robot",
        )
    heading = math.atan2(cross, dot)
    c, s = math.cos(heading), math.sin(heading)
    mean_offset = offsets.mean(axis=0)
    x = mean_receiver[0] - (c * mean_offset[0] - s * mean_offset[1])
    y = mean_receiver[1] - (s * mean_offset[0] + c * mean_offset[1])
    if not (math.isfinite(x) and math.isfinite(y)):
        return TransmitterLocalization(
            STATUS_INCONSISTENT_DISTANCES,
            message="the fix lies beyond the floating-point range",
        )
    fix = Fix(
        x=float(x),
        y=float(y),
        z=float(mean_receiver[2]),
        heading=heading,
        receiver_positions=tuple(_as_triple(row) for row in receivers_xyz),
    )
    return TransmitterLocalization(OK, pose=fix.pose, position_3d=_as_triple(fix.position), fix=fix)


@dataclass(frozen=True)
class RepeatedFixes:
    """``n`` fixes by Theorem 2 at once (see :func:`localize_repeated`), as arrays in {T}.

    Attributes:
        statuses: ``(n,)`` the :func:`localize` status of each fix (``"ok"`` or why not).
        poses: ``(n, 3)`` ``[x, y, heading]`` of each fix (metres, radians); NaN where the
            status is not ``"ok"``.
        z: ``(n,)`` height of each fix in {T}, metres; NaN where not ``"ok"``.
        receivers: ``(n, n_receivers, 3)`` receiver positions, metres; NaN where not ``"ok"``.
    """

    statuses: npt.NDArray[np.str_]
    poses: FloatArray
    z: FloatArray
    receivers: FloatArray

    @property
    def ok(self) -> npt.NDArray[np.bool_]:
        """``(n,)`` which fixes succeeded."""
        return self.statuses == OK

    def average(self) -> Fix | None:
        """eqs (12)-(16) over the fixes that succeeded (:func:`average_fixes`); None if none."""
        good = self.ok
        if good.all():
            poses, z, receivers = self.poses, self.z, self.receivers
        elif good.any():
            poses, z, receivers = self.poses[good], self.z[good], self.receivers[good]
        else:
            return None
        count = len(poses)
        positions = np.empty((count, 3))
        positions[:, :2] = poses[:, :2]
        positions[:, 2] = z
        x, y, z_mean = (np.add.reduce(positions, axis=0) / count).tolist()  # eqs (13)-(15)
        headings = poses[:, 2].copy()  # contiguous, as the sums below assume
        heading = math.atan2(
            float(np.add.reduce(np.sin(headings)) / count),
            float(np.add.reduce(np.cos(headings)) / count),
        )
        mean_receivers = np.add.reduce(receivers, axis=0) / count
        return Fix(
            x=x,
            y=y,
            z=z_mean,
            heading=heading,
            receiver_positions=tuple(map(tuple, mean_receivers.tolist())),
        )


_STATUS_CODES = (
    OK,
    STATUS_MISSING_DISTANCE,
    STATUS_INCONSISTENT_DISTANCES,
    STATUS_HEADING_UNOBSERVABLE,
)
_CODE_OK, _CODE_MISSING, _CODE_INCONSISTENT, _CODE_UNOBSERVABLE = range(len(_STATUS_CODES))
_STATUS_NAMES = np.array(_STATUS_CODES)
_STATUS_NAMES.flags.writeable = False


def localize_repeated(
    distances: npt.ArrayLike, a: float, receiver_offsets: npt.ArrayLike, z_sign: int = -1
) -> RepeatedFixes:
    """:func:`localize` (closed form, eqs (7)-(9) and Theorem 2's heading) of ``n`` fixes at once.

    Args:
        distances: ``(n, n_receivers, 3)`` distances in metres, one :func:`localize` table per
            fix; NaN or inf marks a dropout.
        a: transmitter spacing, metres, > 0.
        receiver_offsets: ``(n_receivers, 2)`` receiver positions in {AMR}, metres.
        z_sign: side of the transmitter plane, -1 (below the ceiling) or +1.

    Returns:
        the fixes and their statuses, as :func:`localize` gives them one by one.

    Raises:
        ValueError: wrong shapes, negative distances, ``a <= 0``, ``z_sign`` not +-1.
    """
    _require_positive("a", a)
    _require_z_sign(z_sign)
    table = np.asarray(distances, dtype=np.float64)
    if table.ndim != 3 or table.shape[1] < 1 or table.shape[2] != 3:
        raise ValueError(f"distances must have shape (n, n_receivers >= 1, 3), got {table.shape}")
    if (table < 0.0).any():
        raise ValueError("distances must be >= 0 metres (NaN marks a dropout)")
    n_receivers = table.shape[1]
    layout = _receiver_layout(_offsets_key(receiver_offsets), n_receivers)
    if type(a) is float and n_receivers <= _MAX_COMPILED_RECEIVERS:
        constants = np.array([a * a, 2.0 * a, z_sign, -_RELATIVE_RADICAND_TOLERANCE])
        receivers, mean_receiver, cross, dot, codes = _receiver_fixes_loop(
            table, layout.spread, constants
        )
        if not (codes == _CODE_SAFE_FORM).any():  # else the array form takes every row
            return _fixes_from_receivers(receivers, mean_receiver, cross, dot, codes, layout)
    return _localize_repeated_arrays(table, a, z_sign, layout)


_MAX_COMPILED_RECEIVERS = 3
"""Most receivers :func:`_receiver_fixes_loop` takes: numpy sums up to seven terms in order from
0 (the ``2 R`` of the heading's dot product), as the loop does; longer sums go pairwise."""
_CODE_SAFE_FORM = -1


@compiled(  # type: ignore[misc]
    types.Tuple(
        (
            types.Array(types.float64, 3, "C"),
            types.Array(types.float64, 2, "C"),
            types.Array(types.float64, 1, "C"),
            types.Array(types.float64, 1, "C"),
            types.Array(types.intp, 1, "C"),
        )
    ),
    types.Array(types.float64, 3, "A", readonly=True),  # table
    TABLE,  # spread
    types.Array(types.float64, 1, "A", readonly=True),  # constants
)
def _receiver_fixes_loop(
    table: FloatArray, spread: FloatArray, constants: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, npt.NDArray[np.intp]]:
    """eqs (7)-(9) for every receiver of every fix, then the sums Theorem 2's heading needs.

    The arithmetic of :func:`_localize_repeated_arrays` element by element, in its order (every
    sum from 0 up, as numpy sums up to seven terms), so its bits.

    Args:
        table: ``(n, R, 3)`` distances, metres (NaN or inf: a dropout), ``R`` at most
            :data:`_MAX_COMPILED_RECEIVERS`.
        spread: ``(R, 2)`` the receivers' offsets in {AMR} about their mean, metres.
        constants: ``a^2`` and ``2 a`` (``a`` in metres), ``z_sign`` and the negated relative
            radicand tolerance.

    Returns:
        ``(n, R, 3)`` receiver positions, ``(n, 3)`` their means, ``(n,)`` the cross and dot
        products of the offsets with the measured spread, and ``(n,)`` status codes: OK,
        missing, inconsistent, or :data:`_CODE_SAFE_FORM` where a square leaves the float range.
    """
    n, n_receivers = table.shape[0], table.shape[1]
    a_sq, two_a, z_sign, negative_tolerance = constants[0], constants[1], constants[2], constants[3]
    receivers = np.empty((n, n_receivers, 3))
    mean = np.empty((n, 3))
    cross = np.empty(n)
    dot = np.empty(n)
    codes = np.zeros(n, dtype=np.intp)
    for i in range(n):
        finite = True
        for j in range(n_receivers):
            for k in range(3):
                if not math.isfinite(table[i, j, k]):
                    finite = False
        representable = True
        inconsistent = False
        for j in range(n_receivers):
            d0, d1, d2 = 0.0, 0.0, 0.0  # a dropout's row: the array form's zeros
            if finite:
                d0, d1, d2 = table[i, j, 0], table[i, j, 1], table[i, j, 2]
            d0_sq, d1_sq, d2_sq = d0 * d0, d1 * d1, d2 * d2
            x = (d0_sq - d1_sq + a_sq) / two_a
            y = (d0_sq - d2_sq + a_sq) / two_a
            radicand = d0_sq - x * x - y * y
            representable = representable and math.isfinite(x + y + radicand)
            inconsistent = inconsistent or radicand < negative_tolerance * (d0_sq + a_sq)
            receivers[i, j, 0] = x
            receivers[i, j, 1] = y
            receivers[i, j, 2] = z_sign * math.sqrt(nan_max(radicand, 0.0))
        if not finite:
            codes[i] = _CODE_MISSING
        elif not representable:
            codes[i] = _CODE_SAFE_FORM
        elif inconsistent:
            codes[i] = _CODE_INCONSISTENT
        for k in range(3):
            total = 0.0
            for j in range(n_receivers):
                total += receivers[i, j, k]
            mean[i, k] = total / n_receivers
            if not math.isfinite(mean[i, k]):
                codes[i] = _CODE_SAFE_FORM  # the mean overflows: the array form's fallback
        cross_total = 0.0
        dot_total = 0.0
        for j in range(n_receivers):
            spread_x = receivers[i, j, 0] - mean[i, 0]
            spread_y = receivers[i, j, 1] - mean[i, 1]
            cross_total += spread[j, 0] * spread_y - spread[j, 1] * spread_x
            dot_total += spread[j, 0] * spread_x
            dot_total += spread[j, 1] * spread_y
        cross[i] = cross_total
        dot[i] = dot_total
    return receivers, mean, cross, dot, codes


def _fixes_from_receivers(
    receivers: FloatArray,
    mean_receiver: FloatArray,
    cross: FloatArray,
    dot: FloatArray,
    codes: npt.NDArray[np.intp],
    layout: _ReceiverLayout,
) -> RepeatedFixes:
    """The fixes from their receivers: Theorem 2's heading and the reference point.

    ``receivers`` and ``codes`` are fresh arrays of the caller's, finished in place.
    """
    with np.errstate(over="ignore", invalid="ignore"):
        baseline = np.hypot(cross, dot)
        heading = np.arctan2(cross, dot)
        if layout.centred:  # the reference point is the receivers' mean: nothing to rotate
            c = s = _NO_VALUES
        else:
            c, s = np.cos(heading), np.sin(heading)
    mean_offset = layout.mean
    constants = np.array(
        [_MIN_BASELINE_M**2, float(layout.observable), mean_offset[0], mean_offset[1]]
    )
    poses, z_fix = _finish_fixes_loop(
        receivers, mean_receiver, baseline, heading, c, s, codes, constants
    )
    return RepeatedFixes(_STATUS_NAMES[codes], poses, z_fix, receivers)


_NO_VALUES = np.zeros(0)
_NO_VALUES.flags.writeable = False


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.float64, 2, "C"), types.Array(types.float64, 1, "C"))),
    types.Array(types.float64, 3, "C"),  # receivers
    TABLE,  # mean_receiver
    NUMBERS,  # baseline
    NUMBERS,  # heading
    NUMBERS,  # cos
    NUMBERS,  # sin
    types.Array(types.intp, 1, "C"),  # codes
    NUMBERS,  # constants
)
def _finish_fixes_loop(
    receivers: FloatArray,
    mean_receiver: FloatArray,
    baseline: FloatArray,
    heading: FloatArray,
    cos: FloatArray,
    sin: FloatArray,
    codes: npt.NDArray[np.intp],
    constants: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """``(n, 3)`` poses ``[x, y, heading]`` and ``(n,)`` heights of the fixes; NaN where a fix
    fails, whose receivers are set to NaN and whose code says why (``codes``, in place).

    A fix fails when its code is not OK already, when the receivers cannot give a heading
    (``constants[1] == 0``: they are not apart on the robot, Theorem 1), when their measured
    ``(x, y)`` coincide (``baseline`` below ``constants[0]``), or when its numbers are not
    finite.

    Args:
        receivers: ``(n, R, 3)`` receiver positions in {T}, metres.
        mean_receiver: ``(n, 3)`` their means.
        baseline, heading: ``(n,)`` ``hypot`` and ``atan2`` of the heading's cross and dot
            products (radians).
        cos, sin: ``(n,)`` of ``heading``, or empty when the reference point is the
            receivers' mean.
        codes: ``(n,)`` status codes so far.
        constants: the least baseline, whether the heading is observable (1 or 0), and the
            receivers' mean offset in {AMR} (metres).
    """
    n = codes.shape[0]
    least_baseline, observable = constants[0], constants[1] > 0.0
    offset_x, offset_y = constants[2], constants[3]
    centred = cos.shape[0] == 0
    poses = np.empty((n, 3))
    z_fix = np.empty(n)
    for i in range(n):
        if codes[i] == _CODE_OK and not observable:
            codes[i] = _CODE_UNOBSERVABLE
        if codes[i] == _CODE_OK and not baseline[i] >= least_baseline:
            codes[i] = _CODE_INCONSISTENT
        if centred:
            x, y = mean_receiver[i, 0], mean_receiver[i, 1]
        else:
            c, s = cos[i], sin[i]
            x = mean_receiver[i, 0] - (c * offset_x - s * offset_y)
            y = mean_receiver[i, 1] - (s * offset_x + c * offset_y)
        z = mean_receiver[i, 2]
        finite = math.isfinite(x) and math.isfinite(y) and math.isfinite(heading[i])
        if codes[i] == _CODE_OK and not (finite and math.isfinite(z)):
            codes[i] = _CODE_INCONSISTENT
        if codes[i] == _CODE_OK:
            poses[i, 0], poses[i, 1], poses[i, 2] = x, y, heading[i]
            z_fix[i] = z
        else:
            poses[i, :] = np.nan
            receivers[i, :, :] = np.nan
            z_fix[i] = np.nan
    return poses, z_fix


def _localize_repeated_arrays(
    table: FloatArray, a: float, z_sign: int, layout: _ReceiverLayout
) -> RepeatedFixes:
    """:func:`localize_repeated` as numpy array steps: for any number of receivers, and distances
    whose squares leave the float range (their rows go through :func:`receiver_position`)."""
    n, n_receivers = table.shape[0], table.shape[1]
    codes = np.zeros(n, dtype=np.intp)
    finite = np.all(np.isfinite(table), axis=(1, 2))
    all_finite = bool(finite.all())
    if not all_finite:
        codes[~finite] = _CODE_MISSING
    clean = table if all_finite else np.where(finite[:, None, None], table, 0.0)
    with np.errstate(over="ignore", invalid="ignore"):
        squares = clean * clean
        d0_sq, d1_sq, d2_sq = squares[..., 0], squares[..., 1], squares[..., 2]
        x = (d0_sq - d1_sq + a * a) / (2.0 * a)
        y = (d0_sq - d2_sq + a * a) / (2.0 * a)
        radicand = d0_sq - x * x - y * y
        # a sum that overflows only sends a row through the safe form, which agrees
        representable = np.isfinite(x + y + radicand).all(axis=1)
        z = z_sign * np.sqrt(np.maximum(radicand, 0.0))
    inconsistent = (radicand < -_RELATIVE_RADICAND_TOLERANCE * (d0_sq + a * a)).any(axis=1)
    if inconsistent.any():
        codes[finite & representable & inconsistent] = _CODE_INCONSISTENT
    if not representable.all():
        for index in np.flatnonzero(finite & ~representable):  # beyond float range: safe form
            try:
                point = np.array([receiver_position(row, a, z_sign) for row in table[index]])
            except InconsistentDistances:
                codes[index] = _CODE_INCONSISTENT
                continue
            x[index], y[index], z[index] = point[:, 0], point[:, 1], point[:, 2]
    receivers = np.empty((n, n_receivers, 3))  # (n, R, 3)
    receivers[..., 0], receivers[..., 1], receivers[..., 2] = x, y, z

    offset_spread = layout.spread
    with np.errstate(over="ignore", invalid="ignore"):
        mean_receiver = np.add.reduce(receivers, axis=1) / n_receivers  # (n, 3)
        if not np.isfinite(mean_receiver).all():
            mean_receiver = _mean_without_overflow(receivers, axis=1)
        measured_spread = receivers[:, :, :2] - mean_receiver[:, None, :2]
        cross = np.add.reduce(
            offset_spread[None, :, 0] * measured_spread[:, :, 1]
            - offset_spread[None, :, 1] * measured_spread[:, :, 0],
            axis=1,
        )
        dot = np.add.reduce(offset_spread[None] * measured_spread, axis=(1, 2))
    return _fixes_from_receivers(receivers, mean_receiver, cross, dot, codes, layout)


@dataclass(frozen=True)
class _ReceiverLayout:
    """The receivers' offsets in {AMR} as :func:`localize_repeated` uses them (metres).

    Attributes:
        spread: ``(R, 2)`` offsets about their mean.
        mean: ``(2,)`` their mean.
        observable: whether they are apart on the robot (else no heading, Theorem 1).
        centred: whether their mean is the {AMR} origin (the paper's rig).
    """

    spread: FloatArray
    mean: FloatArray
    observable: bool
    centred: bool


def _offsets_key(receiver_offsets: npt.ArrayLike) -> tuple[tuple[float, ...], ...]:
    """``receiver_offsets`` as nested tuples of floats (a cache key); ValueError if unusable."""
    if isinstance(receiver_offsets, tuple) and all(
        isinstance(row, tuple) and all(type(v) is float for v in row) for row in receiver_offsets
    ):
        return receiver_offsets
    offsets = np.asarray(receiver_offsets, dtype=np.float64)
    if offsets.ndim != 2:
        raise ValueError(f"receiver_offsets must be a finite (n, 2) array, got {offsets.shape}")
    return tuple(tuple(row) for row in offsets.tolist())


@functools.lru_cache(maxsize=32)
def _receiver_layout(
    offsets_key: tuple[tuple[float, ...], ...], n_receivers: int
) -> _ReceiverLayout:
    offsets = np.asarray(offsets_key, dtype=np.float64)
    if offsets.shape != (n_receivers, 2) or not np.isfinite(offsets).all():
        raise ValueError(
            f"receiver_offsets must be a finite ({n_receivers}, 2) array, got {offsets.shape}"
        )
    mean = offsets.mean(axis=0)
    spread = offsets - mean
    observable = bool(np.any(np.hypot(spread[:, 0], spread[:, 1]) >= _MIN_BASELINE_M))
    for array in (mean, spread):
        array.flags.writeable = False
    return _ReceiverLayout(spread, mean, observable, bool(np.all(mean == 0.0)))


def average_fixes(fixes: Sequence[Fix]) -> Fix:
    """The estimate from n repeated fixes, eqs (12)-(16).

    Minimising eq. (12) gives the arithmetic means of x, y and z, eqs (13)-(15), used as
    printed (the receivers' positions are averaged the same way). For the heading, eq. (16)
    prints the arithmetic mean of the angles, which breaks across +-180 deg: fixes at +179 deg
    and -179 deg would average to 0 deg instead of 180 deg. The intended estimate is the mean
    direction, so this uses the circular mean ``atan2(mean sin(theta_i), mean cos(theta_i))``,
    which equals eq. (16) when the headings are close together away from the +-180 deg cut,
    and minimises the chordal form ``sum_i (1 - cos(theta_hat - theta_i))`` of eq. (12)'s
    heading term. (Headings that cancel exactly, e.g. 0 and 180 deg, have no mean direction;
    the result is then whatever ``atan2`` returns for the rounding residue.)

    Raises:
        ValueError: ``fixes`` is empty, holds something other than :class:`Fix`, or the
            fixes have different numbers of receivers.
    """
    fix_list = list(fixes)
    if not fix_list:
        raise ValueError("fixes must hold at least one Fix")
    if not all(isinstance(fix, Fix) for fix in fix_list):
        raise ValueError("fixes must hold only Fix instances")
    receiver_counts = {len(fix.receiver_positions) for fix in fix_list}
    if len(receiver_counts) != 1:
        raise ValueError(f"fixes must all have the same number of receivers, got {receiver_counts}")
    positions = np.array([fix.position for fix in fix_list])
    headings = np.array([fix.heading for fix in fix_list])
    x, y, z = positions.mean(axis=0)  # eqs (13)-(15)
    heading = math.atan2(float(np.mean(np.sin(headings))), float(np.mean(np.cos(headings))))
    receivers = np.mean([fix.receiver_array for fix in fix_list], axis=0)
    return Fix(
        x=float(x),
        y=float(y),
        z=float(z),
        heading=heading,
        receiver_positions=tuple(_as_triple(row) for row in receivers),
    )


# --------------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------------


def _receiver_positions(
    table: FloatArray, a: float, z_sign: int, solver: Solver, extra: FloatArray
) -> FloatArray:
    """``(n_receivers, 3)`` receiver positions by the chosen solver (metres, {T})."""
    if solver == "closed_form":
        return np.array([receiver_position(row[:3], a, z_sign) for row in table])
    all_transmitters = np.vstack([transmitter_positions(a)[:, :2], extra])
    return np.array(
        [receiver_position_least_squares(row, all_transmitters, z_sign) for row in table]
    )


def _mean_without_overflow(values: FloatArray, axis: int) -> FloatArray:
    """``values.mean(axis)``; where the sum overflows, the sum of ``values / count`` instead."""
    with np.errstate(over="ignore", invalid="ignore"):
        mean = values.mean(axis=axis)
        if not np.all(np.isfinite(mean) | ~np.all(np.isfinite(values), axis=axis)):
            safe = np.sum(values / values.shape[axis], axis=axis)
            mean = np.where(np.isfinite(mean), mean, safe)
    return np.asarray(mean)


def _as_distances(values: npt.ArrayLike, name: str, expected_count: int) -> FloatArray:
    array = np.asarray(values, dtype=np.float64)
    if array.shape != (expected_count,):
        raise ValueError(f"{name} must have shape ({expected_count},), got {array.shape}")
    if np.any(array < 0.0):
        raise ValueError(f"{name} must be >= 0 metres, got {array.tolist()}")
    return array


def _as_extra_transmitters(values: npt.ArrayLike | None) -> FloatArray:
    if values is None:
        return np.zeros((0, 2))
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 2 or not np.all(np.isfinite(array)):
        raise ValueError(f"extra_transmitter_xy must be a finite (k, 2) array, got {array.shape}")
    return array


def _as_point_xy(values: npt.ArrayLike, name: str) -> FloatArray:
    array = np.asarray(values, dtype=np.float64)
    if array.shape not in ((2,), (3,)) or not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be a finite (x, y) or (x, y, z) point, got {values!r}")
    return array[:2]


def _as_triple(values: FloatArray) -> tuple[float, float, float]:
    return (float(values[0]), float(values[1]), float(values[2]))


def _require_positive(name: str, value: float) -> None:
    if not isinstance(value, (int, float, np.floating, np.integer)) or not (
        math.isfinite(value) and value > 0.0
    ):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")


def _require_z_sign(z_sign: int) -> None:
    if z_sign not in (-1, 1) or isinstance(z_sign, bool):
        raise ValueError(f"z_sign must be -1 (below the transmitters) or +1, got {z_sign!r}")
