"""APCS wall processing: the map, estimated reflection points, wall detection and matching.

Yamamoto, Maeyama, Ohya & Yuta, *APCS: autonomous position correction system using
ultrasonic sensing*, sections 4.1-4.3 and the thresholds of section 6:

- 4.1: the map is a list of oriented wall vectors, occupied on the left (:class:`WallVector`,
  :class:`WallMap`).
- 4.2.1: estimated reflection points (ERP) from two consecutive side-sonar readings, eqs (1)-(6)
  (:func:`estimated_reflection_points`).
- 4.2.2: grouping of consecutive ERPs by continuity, group size limits, least-squares line and
  variance test (:func:`group_erps`, :func:`fit_wall_group`, :func:`detect_walls`).
- 4.2.3: end points of the detected segment, Fig. 6.
- 4.3: matching a detected vector to the map by orientation, inclusion of the projection and
  ``d1^2 + d2^2`` (:func:`match_wall`, every map wall in one compiled loop of
  :mod:`~sonar_gym.localization.apcs_match_kernels`); no match or more than one match means no
  correction.

All coordinates are metres in the world frame {W}; angles are radians, counter-clockwise from
the {W} x-axis, as the paper's angle ``phi`` of eq. (2).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, overload

import numpy as np
import numpy.typing as npt

from sonar_gym.frozen import unchecked_instance
from sonar_gym.localization import apcs_kernels, apcs_match_kernels, scatter_axis
from sonar_gym.pose import FloatArray, wrap_angles

IntArray = npt.NDArray[np.int64]

# A wall or a fitted extent shorter than this is treated as having zero length (metres).
ZERO_LENGTH_M = 1e-9

# Reasons a map wall is rejected by the matching of section 4.3, in the paper's order.
REJECT_ORIENTATION = "orientation"
REJECT_INCLUSION = "inclusion"
REJECT_DISTANCE = "distance"

# Statuses of a match (section 4.3 and Fig. 2).
MATCHED = "matched"
NO_MATCH = "no_match"
AMBIGUOUS = "ambiguous"

# Reasons a group of ERPs yields no wall (section 4.2.2).
GROUP_OK = "ok"
GROUP_TOO_FEW_POINTS = "too_few_points"
GROUP_TOO_MUCH_VARIANCE = "too_much_variance"
GROUP_ZERO_LENGTH = "zero_length"

_CM2_TO_M2 = 1e-4


def _finite_pair(value: npt.ArrayLike, name: str) -> tuple[float, float]:
    if isinstance(value, tuple) and len(value) == 2:  # the common case, without numpy
        x, y = value
        if isinstance(x, float) and isinstance(y, float) and math.isfinite(x + y):
            return x, y
    array = np.asarray(value, dtype=np.float64)
    if array.shape != (2,) or not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be a finite (x, y) pair in metres, got {value!r}")
    return float(array[0]), float(array[1])


def _derived(start: tuple[float, float], end: tuple[float, float], length: float) -> dict[str, Any]:
    """What the matching (sec. 4.3) derives once per wall vector from its end points (metres,
    {W}) and ``length`` (their ``math.hypot`` distance): the length, the unit direction, the
    signed offset of the wall's line from the origin and the direction angle (radians)."""
    unit = ((end[0] - start[0]) / length, (end[1] - start[1]) / length)
    return {
        "_length": length,
        "_unit": unit,
        "_offset": -(unit[1] * start[0] - unit[0] * start[1]),
        "_angle": math.atan2(end[1] - start[1], end[0] - start[0]),
    }


@dataclass(frozen=True)
class WallVector:
    """An oriented wall segment of the map (section 4.1, Fig. 3).

    The side to the *left* of the direction ``start -> end`` is occupied (inside the wall or
    object); the right side is free space, where the robot can be.

    Attributes:
        start: ``(x, y)`` of the first end point, metres in {W}.
        end: ``(x, y)`` of the second end point, metres in {W}.
        name: a label for plots and match reports (e.g. ``"corridor_north"``).

    Raises:
        ValueError: if an end point is not a finite pair or the two coincide (zero length).
    """

    start: tuple[float, float]
    end: tuple[float, float]
    name: str = ""

    def __post_init__(self) -> None:
        start = _finite_pair(self.start, "WallVector.start")
        end = _finite_pair(self.end, "WallVector.end")
        if math.hypot(end[0] - start[0], end[1] - start[1]) <= ZERO_LENGTH_M:
            raise ValueError(
                f"WallVector.start and WallVector.end coincide ({start}): a wall must have "
                f"positive length"
            )
        object.__setattr__(self, "start", start)
        object.__setattr__(self, "end", end)
        object.__setattr__(self, "name", str(self.name))
        self._derive(start, end)

    @classmethod
    def unchecked(
        cls, start: tuple[float, float], end: tuple[float, float], name: str
    ) -> WallVector:
        """The wall vector of ``start``, ``end`` (``(x, y)`` tuples of floats, metres in {W})
        and ``name``, without the conversions of the constructor: equal to
        ``WallVector(start, end, name)``, with the ValueError it raises for end points that
        coincide or (through it) are not finite."""
        length = math.hypot(end[0] - start[0], end[1] - start[1])
        if not (math.isfinite(start[0] + start[1] + end[0] + end[1]) and length > ZERO_LENGTH_M):
            return cls(start, end, name)  # it raises, naming what is wrong
        # The fields, then what _derive sets, in its order
        return unchecked_instance(
            cls, start=start, end=end, name=name, **_derived(start, end, length)
        )

    def _derive(self, start: tuple[float, float], end: tuple[float, float]) -> None:
        """Set what the matching derives from the end points (as :meth:`unchecked` does)."""
        length = math.hypot(end[0] - start[0], end[1] - start[1])
        self.__dict__.update(_derived(start, end, length))

    @property
    def start_point(self) -> FloatArray:
        """``start`` as an array, metres in {W}."""
        return np.array(self.start, dtype=np.float64)

    @property
    def end_point(self) -> FloatArray:
        """``end`` as an array, metres in {W}."""
        return np.array(self.end, dtype=np.float64)

    @property
    def length(self) -> float:
        """Length of the segment, metres."""
        return self._length  # type: ignore[attr-defined, no-any-return]

    @property
    def direction_angle(self) -> float:
        """Angle of ``start -> end`` in {W}, radians in (-pi, pi]."""
        return self._angle  # type: ignore[attr-defined, no-any-return]

    @property
    def unit_direction(self) -> FloatArray:
        """Unit vector along ``start -> end``."""
        return np.array(self._unit)  # type: ignore[attr-defined]

    @property
    def normal(self) -> FloatArray:
        """Outward unit normal of the wall surface: it points to the free (right-hand) side."""
        ux, uy = self.unit_direction
        return np.array([uy, -ux])

    @property
    def line_coefficients(self) -> tuple[float, float, float]:
        """``(a, b, c)`` of the line ``a x + b y + c = 0`` used in eqs (9)-(10).

        ``(a, b)`` is the outward unit normal, so ``a x + b y + c`` is the signed distance of
        ``(x, y)`` from the wall line in metres, positive on the free side.
        """
        ux, uy = self._unit  # type: ignore[attr-defined]
        return float(uy), float(-ux), float(self._offset)  # type: ignore[attr-defined]

    def signed_distance(self, point: npt.ArrayLike) -> float:
        """Signed distance of ``point`` from the wall line, metres, positive on the free side."""
        a, b, c = self.line_coefficients
        x, y = _finite_pair(point, "point")
        return a * x + b * y + c

    def projection_parameter(self, point: npt.ArrayLike) -> float:
        """Where ``point`` projects on the wall: 0 at ``start``, 1 at ``end`` (dimensionless)."""
        x, y = _finite_pair(point, "point")
        ux, uy = self._unit  # type: ignore[attr-defined]
        return ((x - self.start[0]) * ux + (y - self.start[1]) * uy) / self._length  # type: ignore[attr-defined, no-any-return]


@dataclass(frozen=True)
class APCSParameters:
    """The thresholds of APCS, with the values of section 6 (and section 5) in SI units.

    Attributes:
        grouping_distance_squared_m2: two consecutive ERPs join one group when their squared
            distance is at most this. Section 6: 100 cm^2 = 0.01 m^2 (10 cm apart).
        min_group_size: groups with fewer ERPs are ignored. Section 6: "less than 4 points"
            are ignored, so 4.
        max_group_size: a group is closed when it holds this many ERPs (section 4.2.2).
            Section 6: 8 points.
        variance_threshold_m2: a group is a flat wall when the variance of its ERPs about the
            fitted line (mean squared perpendicular residual) is below this. Section 4.2.2
            names the test but section 6 prints no value; the default (2 cm)^2 = 4e-4 m^2 is
            this package's choice.
        orientation_tolerance_rad: largest angle between a detected vector and a map vector
            that still matches. Section 6: +-0.5 deg.
        endpoint_distance_squared_m2: a match needs ``d1^2 + d2^2`` below this (Fig. 7).
            Section 6: 200 cm^2 = 0.02 m^2.
        sampling_interval_m: travel between two range readings. Section 6: every 3 cm.
        robot_speed_mps: speed of the robot in the experiment. Section 6: 30 cm/s.
        sensing_range_m: ``(min, max)`` range of the sensor, metres; readings outside are
            dropouts. Section 5: about 30 cm to 500 cm (Murata MA40B8S/R).
    """

    grouping_distance_squared_m2: float = 100.0 * _CM2_TO_M2
    min_group_size: int = 4
    max_group_size: int = 8
    variance_threshold_m2: float = 0.02**2
    orientation_tolerance_rad: float = math.radians(0.5)
    endpoint_distance_squared_m2: float = 200.0 * _CM2_TO_M2
    sampling_interval_m: float = 0.03
    robot_speed_mps: float = 0.30
    sensing_range_m: tuple[float, float] = (0.30, 5.00)

    def __post_init__(self) -> None:
        for name in (
            "grouping_distance_squared_m2",
            "variance_threshold_m2",
            "orientation_tolerance_rad",
            "endpoint_distance_squared_m2",
            "sampling_interval_m",
            "robot_speed_mps",
        ):
            value = float(getattr(self, name))
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"APCSParameters.{name} must be positive and finite, got {value}")
            object.__setattr__(self, name, value)
        if self.orientation_tolerance_rad >= math.pi:
            raise ValueError(
                "APCSParameters.orientation_tolerance_rad must be below pi, "
                f"got {self.orientation_tolerance_rad}"
            )
        for name in ("min_group_size", "max_group_size"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 2:
                raise ValueError(f"APCSParameters.{name} must be an integer >= 2, got {value!r}")
            object.__setattr__(self, name, int(value))
        if self.max_group_size < self.min_group_size:
            raise ValueError(
                f"APCSParameters.max_group_size ({self.max_group_size}) must be at least "
                f"min_group_size ({self.min_group_size})"
            )
        low, high = (float(v) for v in self.sensing_range_m)
        if not (math.isfinite(low) and math.isfinite(high) and 0.0 <= low < high):
            raise ValueError(
                f"APCSParameters.sensing_range_m must be (min, max) with 0 <= min < max, "
                f"got {self.sensing_range_m!r}"
            )
        object.__setattr__(self, "sensing_range_m", (low, high))

    @property
    def sampling_period_s(self) -> float:
        """Time between two readings, seconds (3 cm at 30 cm/s gives 0.1 s)."""
        return self.sampling_interval_m / self.robot_speed_mps


DEFAULT_PARAMETERS = APCSParameters()


# ---------------------------------------------------------------------------------------------
# 4.2.1 Estimated reflection points, eqs (1)-(6)
# ---------------------------------------------------------------------------------------------


def _readonly(array: np.ndarray) -> np.ndarray:
    array = np.array(array, copy=True)
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class EstimatedReflectionPoints:
    """ERPs in the order they were computed (section 4.2.1).

    Attributes:
        points: ``(M, 2)`` ERP positions, metres in {W}; always finite.
        reflection_directions_rad: ``(M,)`` angle ``phi`` of eq. (2), the direction from the
            sensor to the ERP in {W}, radians in (-pi, pi].
        reading_indices: ``(M,)`` index of the range reading each ERP belongs to.
        pair_indices: ``(M,)`` index ``i`` of the reading pair ``(i, i + 1)`` that gave it.
    """

    points: FloatArray
    reflection_directions_rad: FloatArray
    reading_indices: IntArray
    pair_indices: IntArray

    def __post_init__(self) -> None:
        points = np.asarray(self.points, dtype=np.float64)
        if points.size == 0:
            points = points.reshape(0, 2)
        if points.ndim != 2 or points.shape[1] != 2 or not np.all(np.isfinite(points)):
            raise ValueError(
                f"EstimatedReflectionPoints.points must be a finite (M, 2) array, "
                f"got shape {points.shape}"
            )
        count = points.shape[0]
        directions = np.asarray(self.reflection_directions_rad, dtype=np.float64).reshape(-1)
        if directions.shape != (count,) or not np.all(np.isfinite(directions)):
            raise ValueError(
                "EstimatedReflectionPoints.reflection_directions_rad must be finite with one "
                f"entry per point ({count}), got shape {directions.shape}"
            )
        for name in ("reading_indices", "pair_indices"):
            indices = np.asarray(getattr(self, name)).reshape(-1)
            integral = count == 0 or np.issubdtype(indices.dtype, np.integer)
            if indices.shape != (count,) or not integral:
                raise ValueError(
                    f"EstimatedReflectionPoints.{name} must hold one integer per point ({count})"
                )
            object.__setattr__(self, name, _readonly(indices.astype(np.int64)))
        object.__setattr__(self, "points", _readonly(points))
        object.__setattr__(self, "reflection_directions_rad", _readonly(wrap_angles(directions)))

    def __len__(self) -> int:
        return int(self.points.shape[0])

    @classmethod
    def from_points(
        cls, points: npt.ArrayLike, reflection_directions_rad: npt.ArrayLike
    ) -> EstimatedReflectionPoints:
        """ERPs given directly (e.g. from a plot or another sensor), numbered 0..M-1.

        Args:
            points: ``(M, 2)`` positions, metres in {W}.
            reflection_directions_rad: ``(M,)`` sensor-to-wall directions in {W}, radians, or
                one angle for all.
        """
        array = np.asarray(points, dtype=np.float64)
        count = array.shape[0] if array.ndim == 2 else 0
        directions = np.broadcast_to(
            np.asarray(reflection_directions_rad, dtype=np.float64), (count,)
        )
        indices = np.arange(count, dtype=np.int64)
        return cls(array, directions, indices, indices)


def _check_readings(
    sensor_positions: npt.ArrayLike,
    sensor_directions_rad: npt.ArrayLike,
    ranges_m: npt.ArrayLike,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    positions = np.asarray(sensor_positions, dtype=np.float64)
    if positions.size == 0:
        positions = positions.reshape(0, 2)
    if positions.ndim != 2 or positions.shape[1] != 2:
        raise ValueError(f"sensor_positions must have shape (N, 2), got {positions.shape}")
    if not np.all(np.isfinite(positions)):
        raise ValueError("sensor_positions must be finite (metres in {W})")
    count = positions.shape[0]
    ranges = np.asarray(ranges_m, dtype=np.float64)
    if ranges.shape != (count,):
        raise ValueError(
            f"ranges_m must have shape ({count},), one range per sensor position, "
            f"got {ranges.shape}"
        )
    if np.any(ranges < 0.0):
        raise ValueError("ranges_m must be non-negative metres (NaN or inf for a dropout)")
    try:
        directions = np.broadcast_to(np.asarray(sensor_directions_rad, dtype=np.float64), (count,))
    except ValueError as error:
        raise ValueError(
            f"sensor_directions_rad must be one angle or shape ({count},), "
            f"got {np.shape(sensor_directions_rad)}"
        ) from error
    if not np.all(np.isfinite(directions)):
        raise ValueError("sensor_directions_rad must be finite (radians in {W})")
    return positions, directions, ranges


def reflection_direction_candidates(
    first_position: npt.ArrayLike,
    second_position: npt.ArrayLike,
    first_range_m: npt.ArrayLike,
    second_range_m: npt.ArrayLike,
) -> tuple[FloatArray, FloatArray, npt.NDArray[np.bool_]]:
    """The two solutions ``phi`` of eq. (4), element-wise over pairs of readings.

    Eq. (1) with eqs (2)-(3) gives ``(x2 - x1) cos(phi) + (y2 - y1) sin(phi) = -(r2 - r1)``,
    solved as eq. (4) with ``alpha`` of eqs (5)-(6). The square root in eq. (4) is printed
    ``sqrt((y2 - x2)^2 + (x2 - x1)^2)``; eqs (5)-(6) and the derivation need the length of
    ``P1P2``, ``sqrt((y2 - y1)^2 + (x2 - x1)^2)``, which is the reading used here.

    Args:
        first_position: ``(..., 2)`` sensor position ``P1``, metres in {W}.
        second_position: ``(..., 2)`` sensor position ``P2``, metres in {W}.
        first_range_m: ``(...)`` range ``r1`` measured at ``P1``, metres.
        second_range_m: ``(...)`` range ``r2`` measured at ``P2``, metres.

    Returns:
        ``(phi_plus, phi_minus, solvable)``: the ``+`` and ``-`` roots of eq. (4) in radians,
        wrapped to (-pi, pi], and where a root exists (finite ranges, ``P1 != P2`` and
        ``|r2 - r1| <= |P1P2|``); the angles are 0 where ``solvable`` is False.
    """
    p1 = np.asarray(first_position, dtype=np.float64)
    p2 = np.asarray(second_position, dtype=np.float64)
    r1 = np.asarray(first_range_m, dtype=np.float64)
    r2 = np.asarray(second_range_m, dtype=np.float64)
    dx = p2[..., 0] - p1[..., 0]
    dy = p2[..., 1] - p1[..., 1]
    baseline = np.sqrt(dy**2 + dx**2)  # |P1P2|, the corrected root of eq. (4)
    moved = baseline > ZERO_LENGTH_M
    safe_baseline = np.where(moved, baseline, 1.0)
    sin_alpha = dx / safe_baseline  # eq. (5)
    cos_alpha = dy / safe_baseline  # eq. (6)
    alpha = np.arctan2(sin_alpha, cos_alpha)
    ranged = np.isfinite(r1) & np.isfinite(r2)
    range_step = np.where(ranged, r2, 0.0) - np.where(ranged, r1, 0.0)
    cosine = -range_step / safe_baseline
    solvable = ranged & moved & (np.abs(cosine) <= 1.0)
    offset = np.arccos(np.where(solvable, cosine, 0.0))
    phi_plus = np.where(solvable, wrap_angles(np.pi / 2.0 - alpha + offset), 0.0)  # eq. (4), +
    phi_minus = np.where(solvable, wrap_angles(np.pi / 2.0 - alpha - offset), 0.0)  # eq. (4), -
    return phi_plus, phi_minus, solvable


def estimated_reflection_points(
    sensor_positions: npt.ArrayLike,
    sensor_directions_rad: npt.ArrayLike,
    ranges_m: npt.ArrayLike,
    *,
    points_per_pair: Literal["newest", "both"] = "newest",
    valid_range_m: tuple[float, float] | None = None,
    max_off_axis_rad: float | None = None,
) -> EstimatedReflectionPoints:
    """ERPs from consecutive readings of one side sonar, eqs (1)-(6), vectorised.

    For each pair of consecutive readings ``(i, i + 1)`` taken at sensor positions
    ``P1 = (x1, y1)``, ``P2 = (x2, y2)`` with ranges ``r1``, ``r2``, the reflection direction
    ``phi`` solves eq. (1) (see :func:`reflection_direction_candidates`, which uses the
    corrected eq. (4)). Of the two roots ``+-`` of eq. (4) the one nearer the sensor's beam
    axis is kept (a left-side sensor on a robot moving forward takes ``+``). The ERPs are then
    ``R1 = P1 + r1 (cos phi, sin phi)`` and ``R2 = P2 + r2 (cos phi, sin phi)``, eqs (2)-(3).

    A pair gives no ERP when a range is a dropout (NaN or inf, or outside ``valid_range_m``),
    when the sensor did not move, or when ``|r2 - r1| > |P1P2|`` (no flat wall can explain the
    two ranges). No output is ever NaN.

    Args:
        sensor_positions: ``(N, 2)`` sensor positions at the readings, metres in {W}.
        sensor_directions_rad: ``(N,)`` (or one) beam-axis angle of the sensor in {W}, radians
            (robot heading + pi/2 for a left-side sensor).
        ranges_m: ``(N,)`` measured ranges, metres; NaN or inf for a dropout.
        points_per_pair: ``"newest"`` (default) keeps one ERP per pair, ``R2`` of the newer
            reading, computed when that reading arrives (section 4.2.2); ``"both"`` keeps
            ``R1`` and ``R2`` of every pair, in that order.
        valid_range_m: optional ``(min, max)`` metres; readings outside count as dropouts
            (e.g. :attr:`APCSParameters.sensing_range_m`).
        max_off_axis_rad: optional; drop pairs whose ``phi`` is further than this from the
            beam axis (the sensor's half beam width, +-15-20 deg in section 5). The paper does
            not apply this test; ``None`` (default) follows the paper.

    Returns:
        The ERPs with the readings and pairs they came from.

    Raises:
        ValueError: on wrong shapes, non-finite positions or directions, negative ranges, an
            unknown ``points_per_pair`` or a malformed ``valid_range_m``/``max_off_axis_rad``.
    """
    positions, directions, ranges = _check_readings(
        sensor_positions, sensor_directions_rad, ranges_m
    )
    if points_per_pair not in ("newest", "both"):
        raise ValueError(f"points_per_pair must be 'newest' or 'both', got {points_per_pair!r}")
    if valid_range_m is not None:
        low, high = (float(v) for v in valid_range_m)
        if not (0.0 <= low < high):
            raise ValueError(
                f"valid_range_m must be (min, max) with 0 <= min < max, got {valid_range_m!r}"
            )
        ranges = np.where((ranges >= low) & (ranges <= high), ranges, np.nan)
    if max_off_axis_rad is not None and not (0.0 < float(max_off_axis_rad) <= math.pi):
        raise ValueError(f"max_off_axis_rad must be in (0, pi], got {max_off_axis_rad!r}")

    count = positions.shape[0]
    if count < 2:
        return EstimatedReflectionPoints.from_points(np.zeros((0, 2)), np.zeros(0))
    return _reflection_points(positions, directions, ranges, points_per_pair, max_off_axis_rad)


def newest_reflection_points(
    positions: FloatArray,
    directions: FloatArray,
    ranges: FloatArray,
    valid_range_m: tuple[float, float],
) -> tuple[FloatArray, FloatArray, IntArray]:
    """:func:`estimated_reflection_points` with ``points_per_pair="newest"`` on checked inputs.

    For callers that have validated the readings themselves (``(N, 2)`` finite positions,
    ``(N,)`` finite directions, ``(N,)`` non-negative ranges, ``N >= 2``, ``valid_range_m``
    a ``(min, max)`` of floats): the same numbers without the checks and the dataclass.

    Returns:
        ``(points, reflection_directions_rad, reading_indices)`` as in
        :class:`EstimatedReflectionPoints`.
    """
    if len(positions) < 2:
        return np.zeros((0, 2)), np.zeros(0), np.zeros(0, dtype=np.int64)
    points, reflection_directions, valid = newest_reflection_rows(
        positions, directions, ranges, valid_range_m, 1
    )
    rows = np.flatnonzero(valid)  # row i holds the pair (i, i + 1): ascending, as the pairs
    return points[rows], reflection_directions[rows], rows + 1


def newest_reflection_rows(
    positions: FloatArray,
    directions: FloatArray,
    ranges: FloatArray,
    valid_range_m: tuple[float, float],
    skipped: int,
) -> tuple[FloatArray, FloatArray, npt.NDArray[np.bool_]]:
    """:func:`newest_reflection_points` as one row per reading from reading ``skipped`` on.

    Inputs as :func:`newest_reflection_points` takes them (any ``N``), ``skipped`` 0 or 1.

    Returns:
        ``(points, reflection_directions_rad, valid)``: ``(N - skipped, 2)`` ERPs (metres in
        {W}), ``(N - skipped,)`` their directions (radians) and whether the reading gives an
        ERP (the pair it closes gives one); rows without an ERP are zero.
    """
    if len(positions) < 2:
        rows = len(positions) - skipped
        return np.zeros((rows, 2)), np.zeros(rows), np.zeros(rows, dtype=bool)
    readings = np.empty((4, len(positions)))  # the rows of apcs_kernels.READING_ROWS
    readings[0:2] = positions.T
    readings[2] = directions
    readings[3] = ranges
    return reflection_rows_of_table(newest_reflection_table(readings, valid_range_m, skipped))


def newest_reflection_table(
    readings: FloatArray, valid_range_m: tuple[float, float], skipped: int
) -> FloatArray:
    """:func:`newest_reflection_rows` with each reading's sensor position, as one table.

    Args:
        readings: ``(4, N)`` sensor positions (metres in {W}), beam-axis directions (radians)
            and ranges (metres, NaN for a dropout), as
            :func:`~sonar_gym.localization.apcs_kernels.reading_table` gives them.
        valid_range_m: ranges outside are dropouts, metres.
        skipped: 0 or 1, the readings before the first row.

    Returns:
        ``(N - skipped, 6)`` rows of
        :data:`~sonar_gym.localization.apcs_kernels.ERP_COLUMNS`: the sensor position, the
        ERP and its direction as :func:`newest_reflection_rows` gives them, and whether there
        is one (1.0 or 0.0).
    """
    low, high = valid_range_m
    # numpy's sine and cosine act element by element: those of the first and the second
    # reading of every pair are those of all the readings.
    directions = readings[2]
    pairs = apcs_kernels.pair_table(readings, low, high, np.sin(directions), np.cos(directions))
    # alpha of eqs (5)-(6) and the pair's mean beam axis: numpy's arctan2 acts element by
    # element, so one call on both rows gives each row's angles
    angles = np.arctan2(pairs[0:2], pairs[2:4])
    roots = apcs_kernels.root_table(
        pairs,
        angles,
        np.arccos(pairs[4]),  # the offset of the roots of eq. (4)
    )
    phi = roots[0]
    return apcs_kernels.erp_table(  # type: ignore[no-any-return]
        readings, roots, np.cos(phi), np.sin(phi), skipped
    )


def reflection_rows_of_table(
    table: FloatArray,
) -> tuple[FloatArray, FloatArray, npt.NDArray[np.bool_]]:
    """:func:`newest_reflection_rows`' ``(points, reflection_directions_rad, valid)`` of the
    ``(M, 6)`` rows of a :func:`newest_reflection_table`: ``(M, 2)`` ERPs (metres in {W}),
    ``(M,)`` their directions (radians) and whether the reading gives an ERP."""
    return table[:, 2:4].copy(), table[:, 4].copy(), table[:, 5].astype(bool)


def _newest_points(
    positions: FloatArray,
    directions: FloatArray,
    ranges: FloatArray,
    max_off_axis_rad: float | None = None,
) -> tuple[FloatArray, FloatArray, IntArray]:
    """``(R2, phi, pairs)`` of every reading pair that gives an ERP, eqs (1)-(6)."""
    p1, p2 = positions[:-1], positions[1:]
    r1, r2 = ranges[:-1], ranges[1:]
    phi_plus, phi_minus, solvable = reflection_direction_candidates(p1, p2, r1, r2)

    beam_axis = np.arctan2(
        np.sin(directions[:-1]) + np.sin(directions[1:]),
        np.cos(directions[:-1]) + np.cos(directions[1:]),
    )
    off_axis_plus = np.abs(wrap_angles(phi_plus - beam_axis))
    off_axis_minus = np.abs(wrap_angles(phi_minus - beam_axis))
    phi = np.where(off_axis_plus <= off_axis_minus, phi_plus, phi_minus)
    keep = solvable
    if max_off_axis_rad is not None:
        keep = keep & (np.minimum(off_axis_plus, off_axis_minus) <= float(max_off_axis_rad))

    pairs = np.flatnonzero(keep)
    phi = phi[pairs]
    unit = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    second_erps = p2[pairs] + r2[pairs, None] * unit  # R2, eqs (2)-(3)
    return second_erps, phi, pairs


def _reflection_points(
    positions: FloatArray,
    directions: FloatArray,
    ranges: FloatArray,
    points_per_pair: str,
    max_off_axis_rad: float | None,
) -> EstimatedReflectionPoints:
    """The ERPs of :func:`estimated_reflection_points` on its checked inputs."""
    second_erps, phi, pairs = _newest_points(positions, directions, ranges, max_off_axis_rad)
    if points_per_pair == "newest":
        return EstimatedReflectionPoints(second_erps, phi, pairs + 1, pairs)
    unit = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    first_erps = positions[:-1][pairs] + ranges[:-1][pairs, None] * unit  # R1 = P1 + P1R1, eq. (2)
    points = np.stack([first_erps, second_erps], axis=1).reshape(-1, 2)
    return EstimatedReflectionPoints(
        points,
        np.repeat(phi, 2),
        np.stack([pairs, pairs + 1], axis=1).reshape(-1),
        np.repeat(pairs, 2),
    )


# ---------------------------------------------------------------------------------------------
# 4.2.2-4.2.3 Grouping, line fit, variance test and end points
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class DetectedWall:
    """A flat wall found in one group of ERPs (sections 4.2.2-4.2.3).

    Attributes:
        start: ``T_s`` of Fig. 6, metres in {W}.
        end: ``T_e`` of Fig. 6, metres in {W}; ``start -> end`` has the free side (where the
            sensor was) on its right, like the map's vectors.
        erp_indices: positions, in the ERP sequence, of the ERPs of the group.
        residual_variance_m2: mean squared perpendicular distance of the ERPs from the fitted
            line, square metres (the variance of section 4.2.2).
    """

    start: tuple[float, float]
    end: tuple[float, float]
    erp_indices: tuple[int, ...]
    residual_variance_m2: float

    def __post_init__(self) -> None:
        segment = WallVector(self.start, self.end, name="detected")
        object.__setattr__(self, "start", segment.start)
        object.__setattr__(self, "end", segment.end)
        object.__setattr__(self, "erp_indices", tuple(int(i) for i in self.erp_indices))
        object.__setattr__(self, "residual_variance_m2", float(self.residual_variance_m2))
        # Not a field: the segment, made once for the matching (sec. 4.3) and the observation.
        object.__setattr__(self, "_vector", segment)

    @classmethod
    def unchecked(
        cls,
        start: tuple[float, float],
        end: tuple[float, float],
        erp_indices: tuple[int, ...],
        residual_variance_m2: float,
    ) -> DetectedWall:
        """The wall of float end points ``start``, ``end`` (metres in {W}), a tuple of ints
        ``erp_indices`` and a float ``residual_variance_m2`` (m^2), without the conversions
        of the constructor: equal to ``DetectedWall(start, end, erp_indices,
        residual_variance_m2)``, with its ValueError (:meth:`WallVector.unchecked`)."""
        segment = WallVector.unchecked(start, end, "detected")
        return unchecked_instance(  # the constructor's attributes, in its order
            cls,
            start=start,
            end=end,
            erp_indices=erp_indices,
            residual_variance_m2=residual_variance_m2,
            _vector=segment,
        )

    @property
    def vector(self) -> WallVector:
        """The detected segment ``T_s -> T_e`` as a wall vector named ``"detected"``."""
        return self._vector  # type: ignore[attr-defined, no-any-return]

    @property
    def point_count(self) -> int:
        """Number of ERPs in the group."""
        return len(self.erp_indices)

    @property
    def length(self) -> float:
        """Length of ``T_s T_e``, metres."""
        return self.vector.length

    @property
    def direction_angle(self) -> float:
        """Angle of ``T_s -> T_e`` in {W}, radians."""
        return self.vector.direction_angle

    @property
    def normal(self) -> FloatArray:
        """Outward unit normal (towards the free side, where the sensor was)."""
        return self.vector.normal


@dataclass(frozen=True)
class WallFit:
    """The verdict on one group of ERPs: a wall, or the reason there is none.

    Attributes:
        status: ``"ok"``, ``"too_few_points"``, ``"too_much_variance"`` or ``"zero_length"``.
        erp_indices: the group, as positions in the ERP sequence.
        residual_variance_m2: variance about the fitted line (0.0 when not fitted), m^2.
        wall: the detected wall when ``status == "ok"``, else ``None``.
    """

    status: str
    erp_indices: tuple[int, ...]
    residual_variance_m2: float = 0.0
    wall: DetectedWall | None = None


def _as_erps(
    erps: EstimatedReflectionPoints | npt.ArrayLike,
) -> tuple[FloatArray, FloatArray | None]:
    if isinstance(erps, EstimatedReflectionPoints):
        return erps.points, erps.reflection_directions_rad
    points = np.asarray(erps, dtype=np.float64)
    if points.size == 0:
        points = points.reshape(0, 2)
    if points.ndim != 2 or points.shape[1] != 2 or not np.all(np.isfinite(points)):
        raise ValueError(f"erps must be a finite (M, 2) array in metres, got shape {points.shape}")
    return points, None


def group_erps(
    erps: EstimatedReflectionPoints | npt.ArrayLike,
    params: APCSParameters = DEFAULT_PARAMETERS,
) -> list[tuple[int, ...]]:
    """Split the ERP sequence into groups by continuity (section 4.2.2, Fig. 5).

    An ERP joins the current group when its squared distance to the previous ERP is at most
    ``params.grouping_distance_squared_m2``; otherwise (a discontinuity) it starts a new group.
    A group is also closed when it reaches ``params.max_group_size`` ERPs. Groups of every size
    are returned; :func:`fit_wall_group` drops the small ones.

    Returns:
        The groups as tuples of positions in the ERP sequence, in order.
    """
    points, _ = _as_erps(erps)
    groups: list[tuple[int, ...]] = []
    current: list[int] = []
    for index in range(points.shape[0]):
        if current:
            step = points[index] - points[current[-1]]
            continuous = float(step @ step) <= params.grouping_distance_squared_m2
            if not continuous or len(current) >= params.max_group_size:
                groups.append(tuple(current))
                current = []
        current.append(index)
    if current:
        groups.append(tuple(current))
    return groups


def fit_wall_group(
    erps: EstimatedReflectionPoints | npt.ArrayLike,
    group: Sequence[int],
    params: APCSParameters = DEFAULT_PARAMETERS,
) -> WallFit:
    """Verify one group of ERPs as a flat wall and extract its end points (4.2.2-4.2.3).

    - Size: fewer than ``params.min_group_size`` ERPs gives ``"too_few_points"``.
    - Line: least squares. The paper does not say which; walls take every orientation, so the
      orthogonal (total) least-squares line through the centroid is used (an ordinary
      y-on-x fit fails for walls parallel to the y-axis).
    - Variance: the mean squared perpendicular residual; at or above
      ``params.variance_threshold_m2`` gives ``"too_much_variance"``.
    - End points (Fig. 6): the extreme ERPs ``R_s``, ``R_e`` along the line, projected on it,
      give ``T_s`` and ``T_e``; a group with no extent gives ``"zero_length"``.
    - Orientation: ``T_s -> T_e`` keeps the free side on its right. With reflection
      directions (an :class:`EstimatedReflectionPoints`), the mean sensor-to-ERP direction
      must point to the left (occupied) side. With plain points, the vector follows the ERP
      order, which is the convention for a left-side sensor moving forward (section 6).
    """
    points, directions = _as_erps(erps)
    indices = tuple(int(i) for i in group)
    if any(i < 0 or i >= points.shape[0] for i in indices):
        raise ValueError(f"group must hold positions in 0..{points.shape[0] - 1}, got {indices}")
    if len(indices) < params.min_group_size:
        return WallFit(GROUP_TOO_FEW_POINTS, indices)
    members = points[list(indices)]
    return fit_group_points(
        members, None if directions is None else directions[list(indices)], indices, params
    )


def fit_group_points(
    members: FloatArray,
    directions: FloatArray | None,
    indices: tuple[int, ...],
    params: APCSParameters = DEFAULT_PARAMETERS,
) -> WallFit:
    """:func:`fit_wall_group` of a group given as its own points, on checked inputs.

    Args:
        members: ``(n, 2)`` the group's ERPs, finite, metres in {W}, with
            ``n >= params.min_group_size``.
        directions: ``(n,)`` their reflection directions, radians in (-pi, pi], or ``None``
            for plain points.
        indices: the group's positions in the ERP sequence (kept in the verdict).
    """
    # members.mean(axis=0), as it sums, and the ERPs relative to it, in one compiled loop
    centred, centroid_x, centroid_y = apcs_kernels.centred_group(members)
    scatter = centred.T @ centred
    # np.linalg.eigh(scatter / len(indices)) in one compiled loop, where LAPACK would not rescale
    answered, smallest, along_x, along_y = scatter_axis.principal_axis(scatter, len(indices))
    if not answered:
        np.true_divide(scatter, len(indices), out=scatter)  # `/ len(indices)`, in place
        values, eigenvectors = np.linalg.eigh(scatter)
        smallest = values.tolist()[0]  # ascending
        along_x, along_y = eigenvectors[:, 1].tolist()
    residual_variance = max(smallest, 0.0)
    if residual_variance >= params.variance_threshold_m2:
        return WallFit(GROUP_TOO_MUCH_VARIANCE, indices, residual_variance)

    along = np.array([along_x, along_y])
    occupied_side = np.array([-along_y, along_x])  # left of `along`
    if directions is not None:
        # The sums of the cosines and of the sines, as ndarray.sum of each gives them: a
        # reduction along the rows adds each row as the reduction of that row alone does.
        trig = np.empty((2, len(directions)))
        np.cos(directions, out=trig[0])
        np.sin(directions, out=trig[1])
        towards_wall = np.add.reduce(trig, axis=1)
        flip = float(occupied_side @ towards_wall) < 0.0
    else:
        flip = float((centred[-1] - centred[0]) @ along) < 0.0
    if flip:
        along = -along
        along_x, along_y = -along_x, -along_y

    positions_along = (centred @ along).tolist()
    extent_start, extent_end = min(positions_along), max(positions_along)
    if extent_end - extent_start <= ZERO_LENGTH_M:
        return WallFit(GROUP_ZERO_LENGTH, indices, residual_variance)
    start = (centroid_x + extent_start * along_x, centroid_y + extent_start * along_y)  # T_s
    end = (centroid_x + extent_end * along_x, centroid_y + extent_end * along_y)  # T_e
    # floats from the fit, a tuple of ints: what the constructor's conversions would give
    wall = DetectedWall.unchecked(start, end, indices, residual_variance)
    return WallFit(GROUP_OK, indices, residual_variance, wall)


def fit_wall_groups(
    erps: EstimatedReflectionPoints | npt.ArrayLike,
    params: APCSParameters = DEFAULT_PARAMETERS,
) -> list[WallFit]:
    """Every group of :func:`group_erps` with its verdict, for plots of kept and dropped groups."""
    return [fit_wall_group(erps, group, params) for group in group_erps(erps, params)]


def detect_walls(
    erps: EstimatedReflectionPoints | npt.ArrayLike,
    params: APCSParameters = DEFAULT_PARAMETERS,
) -> list[DetectedWall]:
    """Flat walls in a sequence of ERPs (section 4.2.2-4.2.3): grouping, size, line, variance.

    Args:
        erps: the output of :func:`estimated_reflection_points`, or an ``(M, 2)`` array of ERPs
            in metres in {W} in the order measured (then oriented as for a left-side sensor).
        params: thresholds; section 6 values by default.

    Returns:
        The detected walls in order, each of positive length.
    """
    return [fit.wall for fit in fit_wall_groups(erps, params) if fit.wall is not None]


def detect_walls_from_readings(
    sensor_positions: npt.ArrayLike,
    sensor_directions_rad: npt.ArrayLike,
    ranges_m: npt.ArrayLike,
    params: APCSParameters = DEFAULT_PARAMETERS,
) -> tuple[EstimatedReflectionPoints, list[DetectedWall]]:
    """ERPs (readings outside ``params.sensing_range_m`` are dropouts) and the walls in them."""
    erps = estimated_reflection_points(
        sensor_positions, sensor_directions_rad, ranges_m, valid_range_m=params.sensing_range_m
    )
    return erps, detect_walls(erps, params)


# ---------------------------------------------------------------------------------------------
# 4.3 Selection of landmark: matching to the map
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class WallMap(Sequence[WallVector]):
    """The map's wall vectors (section 4.1) with their numbers as one table, for the matching.

    A sequence of :class:`WallVector` in map order. :func:`match_wall` checks every wall of the
    map against each detected vector in one compiled loop over :attr:`table`; a caller that
    matches many vectors against one map builds this once and passes it as ``wall_map``.

    Attributes:
        walls: the wall vectors, in map order.
        table: ``(n, 7)`` read-only, one row per wall: its direction angle (radians), start
            (metres in {W}), unit direction, line offset ``c`` (metres) and length (metres);
            the columns of :data:`~sonar_gym.localization.apcs_match_kernels.WALL_COLUMNS`.

    Raises:
        ValueError: if an entry of ``walls`` is not a :class:`WallVector`.
    """

    walls: tuple[WallVector, ...]
    table: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        walls = tuple(self.walls)
        for index, wall in enumerate(walls):
            if not isinstance(wall, WallVector):
                raise ValueError(
                    f"wall_map[{index}] must be a WallVector, got {type(wall).__name__}"
                )
        object.__setattr__(self, "walls", walls)
        object.__setattr__(self, "table", _wall_table(walls))

    def __len__(self) -> int:
        return len(self.walls)

    @overload
    def __getitem__(self, index: int) -> WallVector: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[WallVector, ...]: ...

    def __getitem__(self, index: int | slice) -> WallVector | tuple[WallVector, ...]:
        return self.walls[index]

    def __iter__(self) -> Iterator[WallVector]:
        return iter(self.walls)


def _wall_table(walls: Sequence[WallVector]) -> FloatArray:
    """The rows of :attr:`WallMap.table` of ``walls``, read-only."""
    table = np.array(
        [
            (wall._angle, *wall.start, *wall._unit, wall._offset, wall._length)  # type: ignore[attr-defined]
            for wall in walls
        ],
        dtype=np.float64,
    ).reshape(len(walls), len(apcs_match_kernels.WALL_COLUMNS))
    table.setflags(write=False)
    return table


@dataclass(frozen=True)
class WallCheck:
    """How one map wall fared against a detected vector (section 4.3, Fig. 7).

    Attributes:
        map_index: position of the wall in the map.
        wall: the map wall ``a_i``.
        orientation_error_rad: angle from ``a_i`` to ``T_s -> T_e``, radians in (-pi, pi].
        start_parameter: where ``V_s`` lies on ``a_i`` (0 at its start, 1 at its end).
        end_parameter: where ``V_e`` lies on ``a_i``.
        endpoint_distance_squared_m2: ``d1^2 + d2^2``, square metres.
        orientation_ok: ``|orientation_error_rad| <= orientation tolerance``.
        inclusion_ok: ``V_s V_e`` lies within ``a_i`` (both parameters in [0, 1]).
        distance_ok: ``d1^2 + d2^2`` below its threshold.
    """

    map_index: int
    wall: WallVector
    orientation_error_rad: float
    start_parameter: float
    end_parameter: float
    endpoint_distance_squared_m2: float
    orientation_ok: bool
    inclusion_ok: bool
    distance_ok: bool

    @property
    def matched(self) -> bool:
        """Whether all three conditions hold."""
        return self.orientation_ok and self.inclusion_ok and self.distance_ok

    @property
    def reason(self) -> str | None:
        """The first failed condition in the paper's order, or ``None`` when matched."""
        return _FIRST_FAILED[self.orientation_ok, self.inclusion_ok, self.distance_ok]

    @property
    def failed_conditions(self) -> tuple[str, ...]:
        """Every failed condition (``"orientation"``, ``"inclusion"``, ``"distance"``)."""
        failed = []
        if not self.orientation_ok:
            failed.append(REJECT_ORIENTATION)
        if not self.inclusion_ok:
            failed.append(REJECT_INCLUSION)
        if not self.distance_ok:
            failed.append(REJECT_DISTANCE)
        return tuple(failed)


def _first_failed(orientation_ok: bool, inclusion_ok: bool, distance_ok: bool) -> str | None:
    """The first failed condition of section 4.3 in the paper's order, ``None`` if none."""
    if not orientation_ok:
        return REJECT_ORIENTATION
    if not inclusion_ok:
        return REJECT_INCLUSION
    if not distance_ok:
        return REJECT_DISTANCE
    return None


# (orientation_ok, inclusion_ok, distance_ok) -> the first failed condition, for every outcome.
_FIRST_FAILED = {
    (orientation, inclusion, distance): _first_failed(orientation, inclusion, distance)
    for orientation in (False, True)
    for inclusion in (False, True)
    for distance in (False, True)
}


class WallChecks(Sequence[WallCheck]):
    """One :class:`WallCheck` per map wall, in map order, against one detected vector (4.3).

    Held as the arrays of :func:`~sonar_gym.localization.apcs_match_kernels.check_map_walls`;
    the :class:`WallCheck` objects are built when first read. Equal to a tuple (or another
    :class:`WallChecks`) of equal checks, as the tuple of them.

    Args:
        wall_map: the map the detected vector was checked against.
        numbers: ``(n, 4)`` per wall: orientation error (radians), start and end parameters
            and ``d1^2 + d2^2`` (m^2).
        conditions: ``(n, 3)`` per wall: orientation, inclusion and distance passed.
        closest: the wall that came closest to matching, -1 for an empty map.
    """

    __slots__ = ("_built", "_closest", "_conditions", "_numbers", "_wall_map")

    def __init__(
        self, wall_map: WallMap, numbers: FloatArray, conditions: np.ndarray, closest: int
    ) -> None:
        self._wall_map = wall_map
        self._numbers = numbers
        self._conditions = conditions
        self._closest = closest
        self._built: tuple[WallCheck, ...] | None = None

    def _all(self) -> tuple[WallCheck, ...]:
        if self._built is None:
            self._built = tuple(
                WallCheck(index, wall, *numbers, *conditions)
                for index, (wall, numbers, conditions) in enumerate(
                    zip(
                        self._wall_map.walls,
                        self._numbers.tolist(),
                        self._conditions.tolist(),
                        strict=True,
                    )
                )
            )
        return self._built

    def __len__(self) -> int:
        return len(self._wall_map.walls)

    @overload
    def __getitem__(self, index: int) -> WallCheck: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[WallCheck, ...]: ...

    def __getitem__(self, index: int | slice) -> WallCheck | tuple[WallCheck, ...]:
        return self._all()[index]

    def __iter__(self) -> Iterator[WallCheck]:
        return iter(self._all())

    def __eq__(self, other: object) -> bool:
        if isinstance(other, WallChecks):
            return self._all() == other._all()
        if isinstance(other, tuple):
            return self._all() == other
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self._all())

    def __repr__(self) -> str:
        return repr(self._all())

    @property
    def candidate_indices(self) -> tuple[int, ...]:
        """Map positions of every wall that passed all three conditions."""
        return tuple(np.flatnonzero(self._conditions.all(axis=1)).tolist())

    @property
    def rejections(self) -> dict[int, str]:
        """Map position -> first failed condition, for every wall that failed one."""
        return dict(self._rejected())

    def rejection_summary(self) -> str:
        """``"index: reason"`` of every wall in :attr:`rejections`, in map order, joined by
        ``", "`` (the list a no-match message gives), without building the dict."""
        return ", ".join([f"{index}: {reason}" for index, reason in self._rejected()])

    def _rejected(self) -> Iterator[tuple[int, str]]:
        """``(map position, first failed condition)`` of every wall that failed one, in order."""
        for index, passed in enumerate(self._conditions.tolist()):
            if (reason := _FIRST_FAILED[tuple(passed)]) is not None:
                yield index, reason

    @property
    def closest_reason(self) -> str | None:
        """The :attr:`~WallCheck.reason` of :attr:`closest` (``None`` for an empty map),
        without building the check."""
        if self._closest < 0:
            return None
        return _FIRST_FAILED[tuple(self._conditions[self._closest].tolist())]

    @property
    def closest(self) -> WallCheck | None:
        """The check of the wall that came closest to matching, ``None`` for an empty map.

        The most conditions passed, then orientation, then inclusion (the paper's order), then
        the smaller ``d1^2 + d2^2``; the first in map order on a tie.
        """
        if self._closest < 0:
            return None
        if self._built is not None:
            return self._built[self._closest]
        index = self._closest
        numbers = self._numbers[index].tolist()
        return WallCheck(
            index, self._wall_map.walls[index], *numbers, *self._conditions[index].tolist()
        )


@dataclass(frozen=True)
class MatchResult:
    """Outcome of matching one detected vector against the map (section 4.3).

    Attributes:
        status: ``"matched"`` (exactly one map wall passes), ``"no_match"`` (none) or
            ``"ambiguous"`` (more than one; the paper then does not correct, Fig. 2).
        detected: the detected vector ``T_s -> T_e``.
        checks: one :class:`WallCheck` per map wall, in map order (:class:`WallChecks`, equal
            to the tuple of them).
        wall: the matched map wall when ``status == "matched"``, else ``None``.
        wall_index: its position in the map, else ``None``.
    """

    status: str
    detected: WallVector
    checks: WallChecks
    wall: WallVector | None = None
    wall_index: int | None = None

    @property
    def matched(self) -> bool:
        """Whether exactly one map wall matched."""
        return self.status == MATCHED

    @property
    def candidate_indices(self) -> tuple[int, ...]:
        """Map positions of every wall that passed all three conditions."""
        return self.checks.candidate_indices

    @property
    def rejections(self) -> dict[int, str]:
        """Map position -> reason, for every wall that failed a condition."""
        return self.checks.rejections

    @property
    def closest_check(self) -> WallCheck | None:
        """The check of the map wall that came closest to matching, ``None`` for an empty map.

        The most conditions passed, then orientation, then inclusion (the paper's order), then
        the smaller ``d1^2 + d2^2``; the first in map order on a tie.
        """
        return self.checks.closest


def check_wall(
    detected: WallVector,
    map_wall: WallVector,
    map_index: int = 0,
    params: APCSParameters = DEFAULT_PARAMETERS,
) -> WallCheck:
    """The three conditions of section 4.3 for one map wall ``a_i`` (Fig. 7).

    ``T_s`` and ``T_e`` are projected on the line of ``a_i`` to ``V_s`` and ``V_e``;
    ``d1 = |T_s V_s|`` and ``d2 = |T_e V_e|`` are the distances of the detected end points
    from that line.
    """
    numbers, conditions, _, _, _ = _checked(detected, _wall_table((map_wall,)), params)
    return WallCheck(map_index, map_wall, *numbers[0].tolist(), *conditions[0].tolist())


def _checked(
    detected: WallVector, table: FloatArray, params: APCSParameters
) -> tuple[FloatArray, np.ndarray, int, int, int]:
    """:func:`~sonar_gym.localization.apcs_match_kernels.check_map_walls` of ``detected``."""
    (start_x, start_y), (end_x, end_y) = detected.start, detected.end
    return apcs_match_kernels.check_map_walls(  # type: ignore[no-any-return]
        table,
        detected._angle,  # type: ignore[attr-defined]
        start_x,
        start_y,
        end_x,
        end_y,
        params.orientation_tolerance_rad,
        params.endpoint_distance_squared_m2,
    )


def match_wall(
    detected: DetectedWall | WallVector,
    wall_map: Sequence[WallVector],
    params: APCSParameters = DEFAULT_PARAMETERS,
) -> MatchResult:
    """Match a detected vector against every wall of the map (section 4.3).

    A map wall matches when the orientations agree within ``params.orientation_tolerance_rad``
    (+-0.5 deg), the projection ``V_s V_e`` lies within it, and ``d1^2 + d2^2`` is below
    ``params.endpoint_distance_squared_m2`` (200 cm^2). Only a unique match is a match.

    Args:
        detected: the detected vector ``T_s -> T_e``.
        wall_map: the map's wall vectors; a :class:`WallMap` is used as it is, any other
            sequence is made one.
        params: matching thresholds (section 6 by default).

    Raises:
        ValueError: if ``detected`` or an entry of ``wall_map`` has the wrong type.
    """
    if isinstance(detected, DetectedWall):
        vector = detected.vector
    elif isinstance(detected, WallVector):
        vector = detected
    else:
        raise ValueError(
            f"detected must be a DetectedWall or WallVector, got {type(detected).__name__}"
        )
    walls = wall_map if isinstance(wall_map, WallMap) else WallMap(tuple(wall_map))
    numbers, conditions, candidates, first_candidate, closest = _checked(
        vector, walls.table, params
    )
    checks = WallChecks(walls, numbers, conditions, closest)
    if candidates == 1:
        return MatchResult(MATCHED, vector, checks, walls.walls[first_candidate], first_candidate)
    return MatchResult(AMBIGUOUS if candidates else NO_MATCH, vector, checks)
