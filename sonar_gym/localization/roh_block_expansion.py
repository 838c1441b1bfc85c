"""Block expansion of Roh et al.: three-point extraction and the area-to-area runner.

The robot starts in a triangular area whose three beacons it knows (Table I, beacons A-C)
and localizes by trilateration (Sec. III.A). Approaching the boundary to the next area, it
saves three of its own (estimated) positions at user-chosen distances d1, d2, d3 from the
boundary (Sec. III.C, Figs. 1-2), ranges the next area's new beacon there, and
auto-calibrates it (Sec. III.B). Once past the boundary it trilaterates with the new beacon
and the two boundary beacons, and repeats the procedure for the next area (Sec. II, Fig. 3).

Areas of Table I. The beacons form the parallelogram A-C-D-B; its diagonal BC splits it into
Area 1 = (A, B, C) and Area 2 = (B, C, D), and beacon E adds Area 3 = (B, D, E) across BD.
Fig. 3 agrees for Area 3 (B, D, E) but prints Area 2 as (A, B, D); with Table I that
triangle overlaps Area 1 and does not share the boundary the text describes (the new area
is "the fourth beacon and the two beacons at the end of the border line segment"), so the
partition (A, B, C), (B, C, D), (B, D, E) is used. Any other chain of triangles can be
configured.

Conditioning. The three saved positions lie on a short stretch of a gently curved path, so
they are nearly collinear (condition numbers of 20-100 on the default parabola). The spheres
then pin the new beacon only up to a rotation about the line of the positions, resolved by
the path's few millimetres of bow: millimetres of range noise move the calibrated beacon by
decimetres, and sometimes the three spheres miss each other (``"no_intersection"``). Which
d's keep this in check is the free choice the paper leaves to its user (Sec. IV.E).

Units: metres inside; Table I and Tables II-V are kept in millimetres as printed and
converted here.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import numpy.typing as npt
from scipy.optimize import brentq

from sonar_gym.localization import roh_kernels
from sonar_gym.localization.result import OK
from sonar_gym.localization.roh_path_errors import (
    distances_to_polyline,
    path_errors,
    points_array,
)
from sonar_gym.localization.roh_path_errors import (
    distances_to_polyline_reference as distances_to_polyline_reference,
)
from sonar_gym.localization.roh_trilateration import (
    DEFAULT_COLLINEARITY_TOLERANCE,
    DEFAULT_HEIGHT_TOLERANCE_M,
    DEFAULT_INTERSECTION_TOLERANCE_M,
    DEFAULT_MAX_CALIBRATION_CONDITION,
    DEFAULT_SENSOR_HEIGHT_M,
    TRILATERATION_METHODS,
    CalibrationResult,
    TrilaterationResult,
    _auto_calibrate_checked,
    _calibration_positions,
    _frozen,
    _trilaterate_rows,
    trilaterate,
)
from sonar_gym.pose import FloatArray, Pose, vector_norm

IntArray = npt.NDArray[np.int64]

# ---------------------------------------------------------------------------------------------
# The paper's numbers (millimetres as printed, converted at this edge)
# ---------------------------------------------------------------------------------------------

TABLE_I_BEACONS_MM: dict[str, tuple[float, float, float]] = {
    "A": (3467.0, 101.0, 825.0),
    "B": (1551.0, 139.0, 1441.0),
    "C": (2459.0, 1870.0, 1457.0),
    "D": (921.0, 2065.0, 1341.0),
    "E": (351.0, 132.0, 835.0),
}
"""Table I: initial beacon coordinates (x, y, z), millimetres."""

TABLE_I_BEACONS_M: dict[str, tuple[float, float, float]] = {
    name: (x / 1000.0, y / 1000.0, z / 1000.0) for name, (x, y, z) in TABLE_I_BEACONS_MM.items()
}
"""Table I in metres."""

PAPER_TWO_AREAS: tuple[tuple[str, str, str], ...] = (("A", "B", "C"), ("B", "C", "D"))
"""Areas 1-2 of Sec. IV.B (see the module docstring for the reading of Fig. 3)."""

PAPER_THREE_AREAS: tuple[tuple[str, str, str], ...] = (
    ("A", "B", "C"),
    ("B", "C", "D"),
    ("B", "D", "E"),
)
"""Areas 1-3 of Sec. IV.D and Fig. 3."""

TABLE_II_III_D_MM: tuple[tuple[float, float, float], ...] = (
    (450.0, 320.0, 100.0),
    (450.0, 250.0, 150.0),
    (450.0, 250.0, 50.0),
    (450.0, 250.0, 20.0),
    (450.0, 210.0, 150.0),
    (450.0, 200.0, 110.0),
)
"""(d1, d2, d3) of Tables II and III, millimetres."""

TABLE_II_SIGMA_MM: tuple[float, ...] = (44.4, 43.4, 29.3, 31.3, 35.4, 28.2)
"""Table II: sigma (RMS y difference) per row of :data:`TABLE_II_III_D_MM`; mean 33.3 mm."""

TABLE_III_SIGMA_PRIME_MM: tuple[float, ...] = (30.2, 29.1, 16.3, 19.3, 22.8, 13.9)
"""Table III: sigma' (mean distance to the true path); mean 21.9 mm."""

TABLE_IV_V_D_MM: tuple[tuple[float, float, float, float, float, float], ...] = (
    (450.0, 250.0, 50.0, 200.0, 200.0, 200.0),
    (450.0, 250.0, 20.0, 300.0, 400.0, 700.0),
    (450.0, 250.0, 20.0, 300.0, 600.0, 750.0),
)
"""(d1, ..., d6) of Tables IV and V, millimetres."""

TABLE_IV_SIGMA_MM: tuple[float, ...] = (34.9, 66.9, 37.6)
"""Table IV: sigma over three areas; mean 46.5 mm."""

TABLE_V_SIGMA_PRIME_MM: tuple[float, ...] = (14.8, 17.9, 19.1)
"""Table V: sigma' over three areas; mean 17.3 mm."""

PAPER_D123_M: tuple[float, float, float] = (0.45, 0.25, 0.05)
"""The (d1, d2, d3) of Figs. 6-7, metres."""

STATUS_NOT_REACHED = "not_reached"
STATUS_NOT_ATTEMPTED = "not_attempted"
STATUS_CALIBRATION_FAILED = "calibration_failed"
STATUS_LOCALIZATION_FAILED = "localization_failed"

# ---------------------------------------------------------------------------------------------
# Plane geometry helpers
# ---------------------------------------------------------------------------------------------


def _planar_point(point: npt.ArrayLike, name: str) -> FloatArray:
    array = np.asarray(point, dtype=np.float64).reshape(-1)
    if array.shape not in ((2,), (3,)) or not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be a finite (x, y) or (x, y, z) point in metres")
    return array[:2].copy()


def distance_to_segment(
    points: npt.ArrayLike, start: npt.ArrayLike, end: npt.ArrayLike
) -> FloatArray:
    """Euclidean distance (metres) of each 2D point to the segment ``start``-``end``.

    Args:
        points: ``(n, 2)`` or ``(2,)`` points in metres.
        start, end: the segment's end points ``(2,)``.

    Returns:
        ``(n,)`` distances (a 0-d array for a single point).
    """
    p = np.asarray(points, dtype=np.float64)
    a = np.asarray(start, dtype=np.float64).reshape(2)
    b = np.asarray(end, dtype=np.float64).reshape(2)
    direction = b - a
    length_sq = float(direction @ direction)
    if length_sq == 0.0:
        return np.hypot(p[..., 0] - a[0], p[..., 1] - a[1])
    t = np.clip(((p - a) @ direction) / length_sq, 0.0, 1.0)
    foot_x, foot_y = a[0] + t * direction[0], a[1] + t * direction[1]
    return np.hypot(p[..., 0] - foot_x, p[..., 1] - foot_y)


MAX_PATH_SAMPLES = 1_000_000
"""Most samples :func:`parabolic_path` returns (a 40 km drive at the paper's 4 mm step)."""


def parabolic_path(
    x_start_m: float = 2.75,
    x_end_m: float = 0.55,
    vertex_m: tuple[float, float] = (1.6, 1.45),
    quadratic_coefficient_per_m: float = -0.9,
    step_m: float = 0.004,
) -> FloatArray:
    """A parabolic path ``y = y_v + a (x - x_v)^2`` sampled at equal arc-length steps.

    The robot of Sec. IV.A drove a parabola, localizing every 40 ms. The paper does not print
    the curve; the defaults cross Areas 1-3 of Table I (A-B-C, B-C-D, B-D-E) from right to
    left, and ``step_m = 0.004`` is 0.1 m/s over a 40 ms step.

    Args:
        x_start_m, x_end_m: x of the first and last point, metres (either order).
        vertex_m: the vertex ``(x_v, y_v)``, metres.
        quadratic_coefficient_per_m: ``a`` in 1/m (negative opens downwards).
        step_m: arc length between samples, metres (> 0).

    Returns:
        ``(n, 2)`` points from ``x_start_m`` towards ``x_end_m``; the last is the end point.

    Raises:
        ValueError: for non-finite arguments, equal ends, a non-positive step, or a curve
            whose arc length is not finite or needs more than :data:`MAX_PATH_SAMPLES` steps.
    """
    for name, value in (
        ("x_start_m", x_start_m),
        ("x_end_m", x_end_m),
        ("quadratic_coefficient_per_m", quadratic_coefficient_per_m),
    ):
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite, got {value!r}")
    if not (math.isfinite(step_m) and step_m > 0.0):
        raise ValueError(f"step_m must be a positive finite number of metres, got {step_m!r}")
    vertex = _planar_point(vertex_m, "vertex_m")
    if x_start_m == x_end_m:
        raise ValueError("x_start_m and x_end_m must differ")

    def curve(x: FloatArray) -> FloatArray:
        return np.column_stack([x, vertex[1] + quadratic_coefficient_per_m * (x - vertex[0]) ** 2])

    with np.errstate(over="ignore", invalid="ignore"):
        dense = curve(np.linspace(x_start_m, x_end_m, 20001))
        arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(dense, axis=0).T))])
    if not np.all(np.isfinite(dense)) or not math.isfinite(arc[-1]):
        raise ValueError(
            "the parabola's arc length is not finite in float64: choose smaller coordinates "
            f"or coefficient (x_start_m={x_start_m!r}, x_end_m={x_end_m!r}, "
            f"quadratic_coefficient_per_m={quadratic_coefficient_per_m!r})"
        )
    length = float(arc[-1])
    if length > MAX_PATH_SAMPLES * step_m:
        raise ValueError(
            f"the path is {length:.3g} m long, more than MAX_PATH_SAMPLES "
            f"({MAX_PATH_SAMPLES}) steps of step_m = {step_m!r} m: increase step_m or shorten it"
        )
    stations = np.arange(0.0, arc[-1], step_m)
    if arc[-1] - stations[-1] > 1e-9:
        stations = np.append(stations, arc[-1])
    x = np.interp(stations, arc, dense[:, 0])
    return curve(x)


# ---------------------------------------------------------------------------------------------
# Three-point extraction (Sec. III.C, Figs. 1-2)
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class ThreePoints:
    """Outcome of the three-point extraction.

    Attributes:
        status: ``"ok"`` when all three distances were crossed, else ``"not_reached"``.
        distances_m: the (d1, d2, d3) searched for, metres.
        indices: for each crossing found, the index of the first sample at which it was
            observed: the position the robot of Fig. 1 saves.
        sample_points: ``(k, 2)`` those samples, metres.
        points: ``(k, 2)`` the crossings interpolated on the segment from the previous
            sample to the saved one, where ``D`` equals the distance exactly, metres.
        fractions: for each crossing, ``t`` in [0, 1] along that segment
            (``point = previous + t (saved - previous)``; 1.0 means the sample itself).
        message: explanation when not ok.
    """

    status: str
    distances_m: tuple[float, ...]
    indices: tuple[int, ...]
    sample_points: FloatArray
    points: FloatArray
    fractions: tuple[float, ...]
    message: str = ""

    @property
    def ok(self) -> bool:
        """Whether all three points were found."""
        return self.status == OK


_CROSSING_RTOL = 4.0 * float(np.finfo(float).eps)
"""brentq's relative tolerance for a crossing fraction: its smallest allowed (4 eps)."""


def _sign(value: float) -> float:
    """``np.sign`` of a float: 1.0, -1.0, 0.0, or NaN for NaN."""
    if value > 0.0:
        return 1.0
    if value < 0.0:
        return -1.0
    return 0.0 if value == 0.0 else math.nan


def _read_only(array: FloatArray) -> FloatArray:
    """A float64 array the runner made and hands over, marked read-only in place (a result
    keeps it; :func:`_frozen` would copy it first)."""
    array.flags.writeable = False
    return array


def _require_distinct(boundary_a: FloatArray, boundary_b: FloatArray) -> None:
    """A ValueError unless the ``(2,)`` boundary points differ."""
    if boundary_a.tolist() == boundary_b.tolist():
        raise ValueError("boundary_a and boundary_b must be distinct points")


class ThreePointExtractor:
    """The online three-point extraction of Sec. III.C, one position at a time.

    ``D(x, y)`` is the (unsigned) distance from the robot to the boundary segment A'B', the
    projections of the two boundary beacons on the sensor plane. Following the text, a
    position is saved "when D(x, y) becomes bigger than d1 for the first time or becomes
    smaller than d1 for the first time": the search for ``d_k`` starts at the sample where
    ``d_(k-1)`` was saved (at the first sample for d1), notes on which side of ``d_k`` that
    sample's D lies, and saves the first later sample on the other side (or exactly on it).
    Decreasing d's are thus met approaching the boundary; a d larger than the previous one is
    met moving away from the boundary, e.g. on its far side, since D is unsigned; a repeated
    d (Table IV's 200/200/200 mm) needs the path to cross that distance again. Because the
    data are discrete, the saved sample overshoots the exact crossing; the crossing on the
    last segment is also found (``D`` along a segment is convex, so it is the one root there)
    for users who prefer to interpolate.
    """

    def __init__(
        self, boundary_a: npt.ArrayLike, boundary_b: npt.ArrayLike, distances: npt.ArrayLike
    ) -> None:
        planar_a = _planar_point(boundary_a, "boundary_a")
        planar_b = _planar_point(boundary_b, "boundary_b")
        _require_distinct(planar_a, planar_b)
        targets = np.asarray(distances, dtype=np.float64)
        if targets.shape != (3,) or not np.all(np.isfinite(targets)) or np.any(targets < 0.0):
            raise ValueError(
                f"distances must be three finite non-negative metres, got {distances!r}"
            )
        self._start(planar_a, planar_b, tuple(float(d) for d in targets))

    @classmethod
    def _of_checked(
        cls, boundary_a: FloatArray, boundary_b: FloatArray, distances: tuple[float, ...]
    ) -> ThreePointExtractor:
        """An extractor for inputs already checked: finite ``(2,)`` or ``(3,)`` boundary
        beacons and three finite non-negative distances, metres (the runner's, which its
        config validated). Only the distinctness of the boundary points is checked here."""
        planar_a, planar_b = boundary_a[:2].copy(), boundary_b[:2].copy()
        _require_distinct(planar_a, planar_b)
        extractor = cls.__new__(cls)
        extractor._start(planar_a, planar_b, distances)
        return extractor

    def _start(
        self, boundary_a: FloatArray, boundary_b: FloatArray, distances: tuple[float, ...]
    ) -> None:
        """Set up for the distinct ``(2,)`` boundary points and the distances, metres."""
        self.boundary_a = boundary_a
        self.boundary_b = boundary_b
        self.distances_m: tuple[float, ...] = distances
        self._direction = self.boundary_b - self.boundary_a
        self._length_sq = float(self._direction @ self._direction)
        # A' and A'B' as floats, for the per-point arithmetic on plain floats.
        ax, ay = boundary_a.tolist()
        self._corner = (ax, ay)
        self._side_vector = (boundary_b.tolist()[0] - ax, boundary_b.tolist()[1] - ay)
        self._indices: list[int] = []
        self._samples: list[FloatArray] = []
        self._points: list[FloatArray] = []
        self._fractions: list[float] = []
        self._reference_sign: float | None = None
        self._previous: FloatArray | None = None

    @property
    def done(self) -> bool:
        """Whether all three points have been saved."""
        return len(self._indices) == len(self.distances_m)

    @property
    def found(self) -> int:
        """How many points have been saved so far."""
        return len(self._indices)

    @property
    def indices(self) -> tuple[int, ...]:
        """Sample indices of the points saved so far (see :class:`ThreePoints`)."""
        return tuple(self._indices)

    @property
    def fractions(self) -> tuple[float, ...]:
        """Fractions of the crossings saved so far (see :class:`ThreePoints`)."""
        return tuple(self._fractions)

    @property
    def points(self) -> FloatArray:
        """Interpolated crossings saved so far, ``(k, 2)`` metres."""
        return np.array(self._points, dtype=np.float64).reshape(-1, 2)

    def boundary_distance(self, position: npt.ArrayLike) -> float:
        """``D(x, y)``: distance from a position to the boundary segment A'B', metres."""
        return float(distance_to_segment(position, self.boundary_a, self.boundary_b))

    def update(self, position: npt.ArrayLike, index: int) -> int:
        """Feed the next position (metres) with its sample index; returns how many were saved."""
        point = np.asarray(position, dtype=np.float64).reshape(2)
        saved_before = self.found
        self._update(point, index)
        return self.found - saved_before

    def update_path(self, positions: npt.ArrayLike, indices: npt.ArrayLike) -> int:
        """Feed positions in order, as :meth:`update` one by one would, until all are saved.

        The boundary distances of all positions are computed at once and the stretches where
        ``D`` stays on one side of the distance sought are skipped; the samples where it
        changes side go through :meth:`update`'s own step.

        Args:
            positions: ``(m, 2)`` positions in the order visited, metres.
            indices: ``(m,)`` their sample indices.

        Returns:
            How many positions were used: all ``m``, or up to and including the one at which
            the third point was saved.
        """
        points = points_array(positions, "positions", min_count=0)
        index_array = np.asarray(indices, dtype=np.int64).reshape(-1)
        if index_array.shape != (len(points),):
            raise ValueError(
                f"indices must hold one index per position ({len(points)}), "
                f"got shape {index_array.shape}"
            )
        return self._update_path_checked(points, index_array)

    def _update_path_checked(self, points: FloatArray, index_array: npt.NDArray[np.int64]) -> int:
        """:meth:`update_path` of finite ``(m, 2)`` float64 positions (metres) and their
        ``(m,)`` int64 indices, as the runner passes them (its successful fixes)."""
        distances = distance_to_segment(points, self.boundary_a, self.boundary_b)
        current = 0
        while current < len(points) and not self.done:
            if self._reference_sign is not None:
                target = self.distances_m[self.found]
                change = roh_kernels.first_side_change(
                    distances, current, target, self._reference_sign
                )
                if change == len(points):
                    self._previous = points[-1].copy()
                    return len(points)
                if change > current:
                    current = change
                    self._previous = points[current - 1].copy()
            self._update(points[current].copy(), int(index_array[current]))
            current += 1
        return current

    def _point_distance(self, point: FloatArray) -> float:
        """:meth:`boundary_distance` of one ``(2,)`` point, with :func:`distance_to_segment`'s
        arithmetic on floats."""
        if self._length_sq == 0.0:
            return self.boundary_distance(point)
        along = float((point - self.boundary_a) @ self._direction) / self._length_sq
        t = min(max(along, 0.0), 1.0)
        (ax, ay), (ux, uy) = self._corner, self._side_vector
        x, y = point.tolist()
        return float(np.hypot(x - (ax + t * ux), y - (ay + t * uy)))

    def _update(self, point: FloatArray, index: int) -> None:
        boundary_distance = self._point_distance(point)
        if self._reference_sign is not None and not self.done:
            target = self.distances_m[self.found]
            side = _sign(boundary_distance - target)
            if side != self._reference_sign:
                assert self._previous is not None
                fraction = self._crossing_fraction(self._previous, point, target, side)
                self._save(index, point, fraction)
                self._reference_sign = None
        while not self.done and self._reference_sign is None:
            side = _sign(boundary_distance - self.distances_m[self.found])
            if side == 0.0:
                self._save(index, point, 1.0)
            else:
                self._reference_sign = side
        self._previous = point

    def result(self) -> ThreePoints:
        """The points saved so far, with status ``"ok"`` or ``"not_reached"``."""
        message = ""
        if not self.done:
            missing = self.distances_m[self.found]
            message = f"the distance {missing:.4g} m to the boundary was never crossed"
        return ThreePoints(
            status=OK if self.done else STATUS_NOT_REACHED,
            distances_m=self.distances_m,
            indices=tuple(self._indices),
            sample_points=_frozen(np.array(self._samples).reshape(-1, 2)),
            points=_frozen(self.points),
            fractions=tuple(self._fractions),
            message=message,
        )

    def _save(self, index: int, sample: FloatArray, fraction: float) -> None:
        previous = self._previous if self._previous is not None else sample
        self._indices.append(int(index))
        self._samples.append(sample.copy())
        self._points.append(previous + fraction * (sample - previous))
        self._fractions.append(float(fraction))

    def _crossing_fraction(
        self, previous: FloatArray, current: FloatArray, target: float, current_side: float
    ) -> float:
        if current_side == 0.0:
            return 1.0

        (ax, ay), (ux, uy) = self._corner, self._side_vector
        length_sq = ux * ux + uy * uy
        (previous_x, previous_y), (current_x, current_y) = previous.tolist(), current.tolist()
        px, py = previous_x - ax, previous_y - ay
        qx, qy = current_x - previous_x, current_y - previous_y

        def excess(t: float) -> float:
            # D(previous + t (current - previous)) - target, in plain floats.
            rx, ry = px + t * qx, py + t * qy
            s = min(max((rx * ux + ry * uy) / length_sq, 0.0), 1.0)
            return math.hypot(rx - s * ux, ry - s * uy) - target

        # D carries rounding noise of about 1e-16 m, which moves its root along the segment
        # by more than 1e-15: the root is asked to 1e-12, and brentq is not asked to raise if
        # the noise keeps it from meeting even that.
        return float(brentq(excess, 0.0, 1.0, xtol=1e-12, rtol=_CROSSING_RTOL, disp=False))


def extract_three_points(
    path: npt.ArrayLike,
    boundary_a: npt.ArrayLike,
    boundary_b: npt.ArrayLike,
    distances: npt.ArrayLike,
) -> ThreePoints:
    """Three-point extraction of Sec. III.C over a whole path.

    Args:
        path: ``(n, 2)`` positions in the order visited, metres (the robot uses its own
            localized positions).
        boundary_a, boundary_b: the boundary beacons (``(x, y)`` or ``(x, y, z)``; only their
            projections A', B' on the sensor plane are used), metres.
        distances: ``(3,)`` the user's (d1, d2, d3), metres (the paper: 0.45, 0.25, 0.05).

    Returns:
        :class:`ThreePoints` with the saved sample indices, the samples and the crossings
        interpolated on the segment where each happened (see :class:`ThreePointExtractor`).

    Raises:
        ValueError: on wrong shapes, non-finite values, a degenerate boundary or negative
            distances.
    """
    positions = points_array(path, "path")
    extractor = ThreePointExtractor(boundary_a, boundary_b, distances)
    for index, position in enumerate(positions):
        extractor.update(position, index)
        if extractor.done:
            break
    return extractor.result()


# ---------------------------------------------------------------------------------------------
# The block expansion runner (Sec. II, Fig. 3)
# ---------------------------------------------------------------------------------------------

RangeFunction = Callable[[FloatArray, FloatArray], float]
"""``measure(xy, beacon_xyz) -> range``: a slant range in metres (NaN for a dropout) from the
sensor at the robot's true ``xy`` to a beacon at its true ``beacon_xyz``."""


@dataclass(frozen=True)
class BlockExpansionConfig:
    """Setup of a block expansion run.

    Attributes:
        beacons_m: true beacon positions ``name -> (x, y, z)``, metres; defaults to Table I.
            Only the first area's beacons are known to the robot; the others are used only to
            simulate ranges and to score their calibration.
        areas: the chain of triangular areas as beacon-name triples. Consecutive areas share
            two beacons (their boundary) and the later one adds one beacon not used before.
        calibration_distances_m: (d1, d2, d3) per boundary, metres; one triple per boundary
            (the paper's d4..d6 are the second boundary's triple).
        sensor_height_m: sensor height above the floor, metres (not printed in the paper).
        range_noise_std_m: standard deviation of the Gaussian noise the runner adds to each
            simulated range, metres (not added to a precomputed table).
        trilateration_method: ``"paper"`` or ``"least_squares"`` (see :func:`trilaterate`).
        max_calibration_condition: passed to :func:`auto_calibrate` as ``max_condition``.
    """

    beacons_m: Mapping[str, tuple[float, float, float]] = field(
        default_factory=lambda: dict(TABLE_I_BEACONS_M)
    )
    areas: tuple[tuple[str, str, str], ...] = PAPER_TWO_AREAS
    calibration_distances_m: tuple[tuple[float, float, float], ...] = (PAPER_D123_M,)
    sensor_height_m: float = DEFAULT_SENSOR_HEIGHT_M
    range_noise_std_m: float = 0.0
    trilateration_method: str = "paper"
    max_calibration_condition: float = DEFAULT_MAX_CALIBRATION_CONDITION

    def __post_init__(self) -> None:
        beacons: dict[str, tuple[float, float, float]] = {}
        for name, xyz in dict(self.beacons_m).items():
            if (
                isinstance(xyz, tuple)
                and len(xyz) == 3
                and type(xyz[0]) is float
                and type(xyz[1]) is float
                and type(xyz[2]) is float
            ):
                triple = xyz  # already three floats (the usual case): no array needed
            else:
                values = np.asarray(xyz, dtype=np.float64)
                if values.shape != (3,):
                    triple = (math.nan, math.nan, math.nan)
                else:
                    triple = (float(values[0]), float(values[1]), float(values[2]))
            finite = (
                math.isfinite(triple[0]) and math.isfinite(triple[1]) and math.isfinite(triple[2])
            )
            if not isinstance(name, str) or not finite:
                raise ValueError(
                    f"beacons_m must map names to finite (x, y, z) metres; bad entry {name!r}"
                )
            beacons[name] = triple
        object.__setattr__(self, "beacons_m", beacons)
        areas = tuple(tuple(area) for area in self.areas)
        if not areas:
            raise ValueError("areas must hold at least one beacon-name triple")
        seen: set[str] = set()
        for number, area in enumerate(areas):
            if len(area) != 3 or len(set(area)) != 3 or not set(area) <= beacons.keys():
                raise ValueError(
                    f"areas[{number}] must be three distinct names from beacons_m, got {area!r}"
                )
            if number > 0:
                shared = set(area) & set(areas[number - 1])
                added = set(area) - shared
                if len(shared) != 2 or added & seen:
                    raise ValueError(
                        f"areas[{number}] must share two beacons with areas[{number - 1}] and "
                        f"add one beacon not used before, got {area!r}"
                    )
            seen |= set(area)
        object.__setattr__(self, "areas", areas)
        triples = tuple(tuple(float(d) for d in triple) for triple in self.calibration_distances_m)
        if len(triples) != len(areas) - 1 or any(
            len(t) != 3 or not all(math.isfinite(d) and d >= 0.0 for d in t) for t in triples
        ):
            raise ValueError(
                f"calibration_distances_m must hold one (d1, d2, d3) of non-negative metres per "
                f"boundary ({len(areas) - 1}), got {self.calibration_distances_m!r}"
            )
        object.__setattr__(self, "calibration_distances_m", triples)
        if not math.isfinite(self.sensor_height_m):
            raise ValueError(f"sensor_height_m must be finite, got {self.sensor_height_m!r}")
        if not (math.isfinite(self.range_noise_std_m) and self.range_noise_std_m >= 0.0):
            raise ValueError(
                f"range_noise_std_m must be a finite non-negative number of metres, "
                f"got {self.range_noise_std_m!r}"
            )
        if self.trilateration_method not in TRILATERATION_METHODS:
            raise ValueError(
                f"trilateration_method must be one of {TRILATERATION_METHODS}, "
                f"got {self.trilateration_method!r}"
            )
        if not self.max_calibration_condition > 1.0:
            raise ValueError(
                f"max_calibration_condition must be > 1, got {self.max_calibration_condition!r}"
            )

    @classmethod
    def paper(
        cls, distances_mm: Sequence[float] = (450.0, 250.0, 50.0), **overrides: object
    ) -> BlockExpansionConfig:
        """The Table I setup with the paper's d's in millimetres.

        Three d's give the two areas of Sec. IV.B; six give the three areas of Sec. IV.D.
        """
        values = tuple(float(d) / 1000.0 for d in distances_mm)
        if len(values) not in (3, 6):
            raise ValueError(f"distances_mm must hold 3 or 6 values, got {len(values)}")
        areas = PAPER_TWO_AREAS if len(values) == 3 else PAPER_THREE_AREAS
        triples = tuple((values[i], values[i + 1], values[i + 2]) for i in range(0, len(values), 3))
        return cls(areas=areas, calibration_distances_m=triples, **overrides)  # type: ignore[arg-type]

    @property
    def beacon_names(self) -> tuple[str, ...]:
        """Beacon names in the column order of a distance table."""
        return tuple(self.beacons_m)

    @property
    def boundaries(self) -> tuple[tuple[str, str], ...]:
        """The boundary beacon pair between each area and the next."""
        return tuple(
            tuple(name for name in self.areas[k] if name in self.areas[k + 1])  # type: ignore[misc]
            for k in range(len(self.areas) - 1)
        )

    @property
    def new_beacons(self) -> tuple[str, ...]:
        """The beacon each later area adds, to be auto-calibrated."""
        return tuple(
            next(name for name in self.areas[k + 1] if name not in self.areas[k])
            for k in range(len(self.areas) - 1)
        )


@dataclass(frozen=True, eq=False)
class BoundaryCalibration:
    """What happened at one boundary.

    Attributes:
        boundary: the two boundary beacons' names.
        new_beacon: the name of the beacon calibrated there.
        status: ``"ok"``, ``"not_reached"`` (a d, or after calibrating the boundary itself,
            was never crossed), ``"not_attempted"`` (an
            earlier boundary failed or was never passed), or the calibration's status
            (``"collinear_positions"``, ``"no_intersection"``, ``"missing_distance"``).
        three_points: the extraction's result, ``None`` if not attempted.
        calibration_points_xy: ``(k, 2)`` the estimated positions used to calibrate, metres.
        calibration_ranges_m: ``(k,)`` the ranges to the new beacon there (NaN for a dropout).
        calibration: the auto-calibration result, ``None`` if it was not run.
        true_position_m: the new beacon's true ``(x, y, z)``, metres.
        error_m: distance between the calibrated and the true beacon, metres; ``None``
            unless calibrated.
        switch_index: the path index from which the next area's beacons were used, or
            ``None``.
    """

    boundary: tuple[str, str]
    new_beacon: str
    status: str
    three_points: ThreePoints | None
    calibration_points_xy: FloatArray
    calibration_ranges_m: FloatArray
    calibration: CalibrationResult | None
    true_position_m: FloatArray
    error_m: float | None
    switch_index: int | None


@dataclass(frozen=True)
class PathFixLog:
    """What the runner needs to rebuild each fix's full :class:`TrilaterationResult`.

    Attributes:
        statuses: ``(n,)`` the trilateration status per path point.
        positions: ``(n, 2)`` the fixes, metres; NaN where not ok.
        used_radical_centre: ``(n,)`` whether the paper method fell back to the radical centre.
        ranges_m: ``(n, beacons)`` the ranges the runner used, metres (NaN for a dropout).
        area_beacons_m: per area, ``(3, 3)`` the beacon positions the robot used there.
        area_columns: per area, the table columns of its three beacons.
        sensor_height_m: the sensor height, metres.
        method: the trilateration method.
    """

    statuses: tuple[str, ...]
    positions: FloatArray
    used_radical_centre: npt.NDArray[np.bool_]
    ranges_m: FloatArray
    area_beacons_m: tuple[FloatArray, ...]
    area_columns: tuple[tuple[int, int, int], ...]
    sensor_height_m: float
    method: str

    def result(self, index: int, area: int) -> TrilaterationResult:
        """The :func:`trilaterate` result of path point ``index``, localized in ``area``."""
        if self.statuses[index] != OK:
            columns = list(self.area_columns[area])
            return trilaterate(
                self.area_beacons_m[area],
                self.ranges_m[index, columns],
                self.sensor_height_m,
                self.method,
            )
        x, y = (float(v) for v in self.positions[index])
        return TrilaterationResult(
            status=OK,
            pose=Pose(x, y, 0.0),
            position=_frozen(self.positions[index]),
            method=self.method,
            has_heading=False,
            beacon_indices=(0, 1, 2),
            used_radical_centre=bool(self.used_radical_centre[index]),
        )


@dataclass(frozen=True, eq=False)
class BlockExpansionResult:
    """Outcome of :meth:`BlockExpansion.run`.

    Attributes:
        status: ``"ok"``; ``"calibration_failed"`` when some boundary was not calibrated or
            not passed; ``"localization_failed"`` when every boundary succeeded but some
            fix did not.
        fixes: the per-point trilateration outcome as arrays (see :attr:`localizations`).
        area_indices: ``(n,)`` index of the area whose beacons were used at each point.
        estimated_indices: ``(k,)`` path indices of the successful fixes.
        estimated_xy: ``(k, 2)`` those fixes, metres.
        calibrations: one :class:`BoundaryCalibration` per boundary.
        message: explanation when not ok.
    """

    status: str
    fixes: PathFixLog
    area_indices: IntArray
    estimated_indices: IntArray
    estimated_xy: FloatArray
    calibrations: tuple[BoundaryCalibration, ...]
    message: str = ""

    @cached_property
    def localizations(self) -> tuple[TrilaterationResult, ...]:
        """Per path point, the trilateration result (built on first use)."""
        return tuple(
            self.fixes.result(index, int(area)) for index, area in enumerate(self.area_indices)
        )

    @property
    def ok(self) -> bool:
        """Whether every boundary was calibrated and passed and every fix succeeded."""
        return self.status == OK

    @property
    def statuses(self) -> tuple[str, ...]:
        """Per path point, the trilateration status."""
        return self.fixes.statuses

    @property
    def calibrated_beacons_m(self) -> dict[str, FloatArray]:
        """Calibrated positions of the new beacons, metres."""
        return {
            c.new_beacon: c.calibration.position
            for c in self.calibrations
            if c.calibration is not None and c.calibration.position is not None
        }

    @property
    def calibration_errors_m(self) -> dict[str, float]:
        """Distance between calibrated and true position per calibrated beacon, metres."""
        return {c.new_beacon: c.error_m for c in self.calibrations if c.error_m is not None}

    def path_errors(self, true_path: npt.ArrayLike) -> tuple[float, float]:
        """``(sigma, sigma_prime)`` of the successful fixes against the true path, metres."""
        return path_errors(self.estimated_xy, true_path)

    def errors_along_path(self, true_path: npt.ArrayLike) -> FloatArray:
        """Per successful fix, its distance to the true path (Figs. 5, 7, 8), metres."""
        return distances_to_polyline(self.estimated_xy, true_path)


class _BoundaryProgress:
    """Mutable bookkeeping for one boundary while the runner walks the path."""

    def __init__(
        self, config: BlockExpansionConfig, number: int, known: Mapping[str, FloatArray]
    ) -> None:
        self.boundary = config.boundaries[number]
        self.new_beacon = config.new_beacons[number]
        self.new_column = config.beacon_names.index(self.new_beacon)
        self.extractor = ThreePointExtractor._of_checked(
            known[self.boundary[0]], known[self.boundary[1]], config.calibration_distances_m[number]
        )
        opposite = next(n for n in config.areas[number] if n not in self.boundary)
        self.origin = known[self.boundary[0]][:2]
        self.direction = known[self.boundary[1]][:2] - self.origin
        self.inner_side = self._side(known[opposite][:2])
        self.points: list[FloatArray] = []
        self.ranges: list[float] = []
        self.calibration: CalibrationResult | None = None
        self.switch_index: int | None = None

    def _side(self, xy: FloatArray) -> float:
        offset = xy - self.origin
        return float(np.sign(self.direction[0] * offset[1] - self.direction[1] * offset[0]))

    def is_past(self, xy: FloatArray) -> bool:
        """Whether a position lies strictly on the far side of the boundary line."""
        side = self._side(xy)
        return side != 0.0 and side != self.inner_side

    def first_past(self, xy: FloatArray) -> int | None:
        """Index of the first of ``(m, 2)`` positions that :meth:`is_past`, or None."""
        offset = xy - self.origin
        sides = np.sign(self.direction[0] * offset[:, 1] - self.direction[1] * offset[:, 0])
        past = np.flatnonzero((sides != 0.0) & (sides != self.inner_side))
        return int(past[0]) if len(past) else None


class BlockExpansion:
    """The block expansion algorithm of Sec. II over a chain of triangular areas (Fig. 3).

    At each path point the robot trilaterates with the current area's beacons (true
    positions for the first area, calibrated ones after). While the next area's beacon is
    not yet calibrated, its estimated positions feed the three-point extraction for the
    boundary ahead; when the three points are saved it auto-calibrates the new beacon from
    the ranges measured there. It switches to the next area's beacons at the first fix past
    the boundary (by its own estimate) once the new beacon is calibrated; the next boundary's
    extraction starts at that fix. A failed calibration is recorded and the robot carries on
    with the beacons it has.

    >>> config = BlockExpansionConfig.paper((450.0, 250.0, 50.0))
    >>> run = BlockExpansion(config).run(parabolic_path(x_end_m=1.3))
    >>> run.status, sorted(run.calibrated_beacons_m)
    ('ok', ['D'])
    """

    def __init__(self, config: BlockExpansionConfig) -> None:
        if not isinstance(config, BlockExpansionConfig):
            raise ValueError(f"config must be a BlockExpansionConfig, got {type(config).__name__}")
        self.config = config

    def slant_range_m(self, xy: FloatArray, beacon_xyz: FloatArray) -> float:
        """Noise-free slant range from the sensor at ``xy`` (configured height) to a beacon."""
        dx, dy = xy[0] - beacon_xyz[0], xy[1] - beacon_xyz[1]
        dz = self.config.sensor_height_m - beacon_xyz[2]
        return math.sqrt(dx * dx + dy * dy + dz * dz)

    def measure_ranges(
        self,
        path: npt.ArrayLike,
        rng: np.random.Generator | None = None,
        measure: RangeFunction | None = None,
    ) -> FloatArray:
        """``(n, beacons)`` simulated ranges along a true path, metres (NaN for dropouts).

        Columns follow :attr:`BlockExpansionConfig.beacon_names`. ``measure`` (default: the
        noise-free slant range) is called with the true position and the true beacon
        position; the runner adds Gaussian noise of ``range_noise_std_m`` drawn from ``rng``
        (one draw per point and beacon, row by row). Negative or infinite values become NaN.
        """
        positions = points_array(path, "path")
        noise = self.config.range_noise_std_m
        if noise > 0.0 and not isinstance(rng, np.random.Generator):
            raise ValueError("rng must be a numpy.random.Generator when range_noise_std_m > 0")
        range_of = measure if measure is not None else self.slant_range_m
        if not callable(range_of):
            raise ValueError("measure must be callable as measure(xy, beacon_xyz) -> metres")
        beacons = np.array([self.config.beacons_m[n] for n in self.config.beacon_names])
        table = np.array([[float(range_of(xy, b)) for b in beacons] for xy in positions])
        if noise > 0.0:
            assert rng is not None
            table = table + rng.normal(0.0, noise, size=table.shape)
        return np.where(np.isfinite(table) & (table >= 0.0), table, np.nan)

    def run(
        self,
        path: npt.ArrayLike,
        rng: np.random.Generator | None = None,
        measure: RangeFunction | None = None,
        distance_table: npt.ArrayLike | None = None,
    ) -> BlockExpansionResult:
        """Localize along a true path, calibrating each new beacon on the way.

        Args:
            path: ``(n, 2)`` true positions of the sensor in order, metres.
            rng: source of the range noise (required when ``range_noise_std_m > 0`` and no
                table is given).
            measure: ``measure(xy, beacon_xyz) -> metres``, the ranging sensor (see
                :meth:`measure_ranges`); default the noise-free slant range.
            distance_table: instead of ``measure``, precomputed measured ranges
                ``(n, beacons)`` in the column order of ``config.beacon_names`` (NaN for a
                dropout); used as given, without added noise.

        Returns:
            A :class:`BlockExpansionResult`.

        Raises:
            ValueError: on wrong shapes, a missing ``rng`` when noise is configured, or both
                ``measure`` and ``distance_table``.
        """
        positions = points_array(path, "path")
        config = self.config
        names = config.beacon_names
        if distance_table is not None:
            if measure is not None:
                raise ValueError("give either measure or distance_table, not both")
            table = np.array(distance_table, dtype=np.float64)
            if table.shape != (len(positions), len(names)):
                raise ValueError(
                    f"distance_table must have shape ({len(positions)}, {len(names)}) "
                    f"(path points x beacons {names}), got {table.shape}"
                )
            table[~np.isfinite(table) | (table < 0.0)] = np.nan
        else:
            table = self.measure_ranges(positions, rng, measure)

        known: dict[str, FloatArray] = {
            name: np.array(config.beacons_m[name]) for name in config.areas[0]
        }
        boundary_count = len(config.areas) - 1
        n_points = len(positions)
        progress: list[_BoundaryProgress] = []
        statuses = [OK] * n_points
        fixes_xy = np.full((n_points, 2), np.nan)
        used_radical_centre = np.zeros(n_points, dtype=bool)
        area_indices = np.empty(n_points, dtype=np.int64)
        area_beacons: list[FloatArray] = []
        area_columns: list[tuple[int, int, int]] = []
        start, area = 0, 0
        # Each area's beacons localize every point from its first one on; the next area takes
        # over from the fix after the switch (Sec. II, Fig. 3).
        while True:
            columns = tuple(names.index(n) for n in config.areas[area])
            beacons = np.array([known[n] for n in config.areas[area]])
            area_beacons.append(_read_only(beacons))
            area_columns.append(columns)  # type: ignore[arg-type]
            # The config validated the beacons, height and method, the table is checked above
            # and a calibrated beacon is finite: trilaterate_path's checks would repeat.
            fixes = _trilaterate_rows(
                beacons,
                table[start:, list(columns)],
                config.sensor_height_m,
                config.trilateration_method,
                DEFAULT_HEIGHT_TOLERANCE_M,
                DEFAULT_COLLINEARITY_TOLERANCE,
            )
            statuses[start:] = fixes.statuses
            fixes_xy[start:] = fixes.positions
            used_radical_centre[start:] = fixes.used_radical_centre
            area_indices[start:] = area
            if area >= boundary_count:
                break
            current = _BoundaryProgress(config, area, known)
            progress.append(current)
            switch = self._cross(current, fixes.positions, start, table)
            if switch is None:
                break
            known[current.new_beacon] = np.array(current.calibration.position)  # type: ignore[union-attr]
            current.switch_index = switch + 1
            start, area = switch + 1, area + 1

        log = PathFixLog(
            statuses=tuple(statuses),
            positions=_read_only(fixes_xy),
            used_radical_centre=used_radical_centre,
            ranges_m=_read_only(table),
            area_beacons_m=tuple(area_beacons),
            area_columns=tuple(area_columns),
            sensor_height_m=config.sensor_height_m,
            method=config.trilateration_method,
        )
        return self._result(log, area_indices, progress, positions)

    def _cross(
        self, current: _BoundaryProgress, fixes_xy: FloatArray, start: int, table: FloatArray
    ) -> int | None:
        """Extract, calibrate and find where the robot passes one boundary.

        The successful fixes (``fixes_xy``, NaN for a failed one, from path index ``start``)
        feed the three-point extraction; once the three samples are saved the new beacon is
        auto-calibrated from them. As in Fig. 1 the robot keeps the saved samples themselves
        (its estimate and the range to the new beacon measured there): no range was measured
        at an interpolated crossing. Returns the path index of the first fix, from the third
        saved sample on, past the boundary, or None (not reached or not calibrated).
        """
        ok = np.flatnonzero(np.isfinite(fixes_xy[:, 0]))
        ok_xy = fixes_xy[ok]
        used = current.extractor._update_path_checked(ok_xy, start + ok)
        if not current.extractor.done:
            return None
        for index in current.extractor.indices:
            current.points.append(np.array(fixes_xy[index - start]))
            current.ranges.append(float(table[index, current.new_column]))
        # The saved fixes are finite, the ranges non-negative or NaN (the table is checked)
        # and the config validated the height and condition: auto_calibrate's checks repeat.
        current.calibration = _auto_calibrate_checked(
            _calibration_positions(current.points, self.config.sensor_height_m),
            np.array(current.ranges),
            self.config.max_calibration_condition,
            DEFAULT_INTERSECTION_TOLERANCE_M,
        )
        if not current.calibration.ok:
            return None
        past = current.first_past(ok_xy[used - 1 :])
        return None if past is None else int(start + ok[used - 1 + past])

    def _result(
        self,
        log: PathFixLog,
        area_indices: IntArray,
        progress: list[_BoundaryProgress],
        positions: FloatArray,
    ) -> BlockExpansionResult:
        config = self.config
        calibrations: list[BoundaryCalibration] = []
        new_beacons = config.new_beacons
        for number in range(len(config.areas) - 1):
            new_beacon = new_beacons[number]
            truth = _frozen(config.beacons_m[new_beacon])
            if number >= len(progress):
                calibrations.append(
                    BoundaryCalibration(
                        boundary=config.boundaries[number],
                        new_beacon=new_beacon,
                        status=STATUS_NOT_ATTEMPTED,
                        three_points=None,
                        calibration_points_xy=_frozen(np.empty((0, 2))),
                        calibration_ranges_m=_frozen(np.empty(0)),
                        calibration=None,
                        true_position_m=truth,
                        error_m=None,
                        switch_index=None,
                    )
                )
                continue
            item = progress[number]
            three_points = item.extractor.result()
            calibration = item.calibration
            if calibration is None:
                status = three_points.status
            elif not calibration.ok:
                status = calibration.status
            elif item.switch_index is None:
                status = STATUS_NOT_REACHED
            else:
                status = OK
            error = None
            if calibration is not None and calibration.position is not None:
                error = vector_norm(calibration.position - truth)
            calibrations.append(
                BoundaryCalibration(
                    boundary=item.boundary,
                    new_beacon=new_beacon,
                    status=status,
                    three_points=three_points,
                    calibration_points_xy=_read_only(
                        np.array(item.points, dtype=np.float64).reshape(-1, 2)
                    ),
                    calibration_ranges_m=_read_only(np.array(item.ranges, dtype=np.float64)),
                    calibration=calibration,
                    true_position_m=truth,
                    error_m=error,
                    switch_index=item.switch_index,
                )
            )
        ok_indices = np.flatnonzero(np.isfinite(log.positions[:, 0])).astype(np.int64, copy=False)
        estimated = log.positions[ok_indices]
        failed_boundaries = [c for c in calibrations if c.status != OK]
        if failed_boundaries:
            status = STATUS_CALIBRATION_FAILED
            first = failed_boundaries[0]
            message = f"beacon {first.new_beacon}: {first.status}"
        elif len(ok_indices) < len(positions):
            status = STATUS_LOCALIZATION_FAILED
            message = f"{len(positions) - len(ok_indices)} of {len(positions)} fixes failed"
        else:
            status, message = OK, ""
        area_indices.flags.writeable = False  # the run's own array, handed over
        ok_indices.flags.writeable = False
        return BlockExpansionResult(
            status=status,
            fixes=log,
            area_indices=area_indices,
            estimated_indices=ok_indices,
            estimated_xy=_read_only(estimated),
            calibrations=tuple(calibrations),
            message=message,
        )
