"""Trilateration and beacon auto-calibration of Roh et al. (Sec. III.A and III.B).

Roh et al. range a robot-mounted ultrasonic receiver against beacons fixed at known 3D
positions. Both coordinate calculations of the paper live here:

* :func:`trilaterate` (Sec. III.A): each slant range ``d`` to a beacon at height ``z_b``,
  measured by a sensor at height ``h``, is cut by the horizontal sensor plane into a circle of
  radius ``r_h = sqrt(d**2 - (z_b - h)**2)`` about the beacon's projection; the robot lies
  where the circles meet.
* :func:`auto_calibrate` (Sec. III.B): three spheres about three robot sensor positions with
  the measured ranges as radii meet in two points, mirror images about the plane of the
  positions; the new beacon is the one above the sensor plane.

Reading of Sec. III.A. The text says the three circles "produce three unique lines of
intersection, which again produces three unique points of intersections", whose triangle's
centroid is the estimate. The line through the two intersection points of two circles is
their radical axis, and the three radical axes of three circles always meet in one point,
the radical centre; a literal reading gives a degenerate triangle whatever the noise. The
reading implemented as ``method="paper"``: for each pair of circles take the intersection
point nearer to the third circle, and return the centroid of those three points (the
centroid of the small triangle the three circles bound near the robot). When a pair of
circles does not meet, the estimate falls back to the radical centre, which for three
circles equals the linearised least-squares solution. ``method="least_squares"`` is offered
beside it: the linearised least squares over all beacons, refined by a Gauss-Newton /
trust-region fit of the slant ranges (``scipy.optimize.least_squares``).

Frames and units: world frame {W}, metres. Trilateration yields a position only; ranges to
point beacons carry no heading, so a result has ``has_heading=False`` and its pose has
``theta = 0.0`` by convention, never an estimate.
"""

from __future__ import annotations

import functools
import itertools
import math
import sys
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.optimize import least_squares

from sonar_gym.localization import roh_kernels
from sonar_gym.localization.result import OK, OUT_OF_FLOAT_RANGE, Localization
from sonar_gym.pose import FloatArray, Pose, vector_norm

TRILATERATION_METHODS: tuple[str, ...] = ("paper", "least_squares")
"""Names accepted by :func:`trilaterate`'s ``method`` argument."""

DEFAULT_SENSOR_HEIGHT_M = 0.3
"""Height of the robot's ultrasonic receiver above the floor, metres. The paper does not print
it; 0.3 m is an assumption that keeps every Table I beacon at least 0.5 m above the sensor."""

DEFAULT_HEIGHT_TOLERANCE_M = 0.01
"""A slant range may fall this far (metres) below the beacon's height above the sensor plane
before :func:`trilaterate` reports ``"distance_below_height"``; within it the horizontal
radius is taken as zero (the robot right under the beacon)."""

DEFAULT_COLLINEARITY_TOLERANCE = 1e-6
"""Beacon projections whose spread across their best-fit line is below this fraction of
their spread along it count as collinear."""

DEFAULT_MAX_CALIBRATION_CONDITION = 1e4
"""Largest accepted condition number (ratio of singular values) of the two displacements
between the three calibration positions; beyond it they count as collinear."""

DEFAULT_INTERSECTION_TOLERANCE_M = 1e-6
"""Three spheres that miss each other by at most this much (metres) are taken to touch. It
only absorbs rounding: a beacon placed in the plane of the positions is far from any real
one, so a genuine miss is reported as ``"no_intersection"``."""

_TANGENCY_RELATIVE_TOLERANCE = 1e-12

STATUS_TOO_FEW_BEACONS = "too_few_beacons"
STATUS_COLLINEAR_BEACONS = "collinear_beacons"
STATUS_DISTANCE_BELOW_HEIGHT = "distance_below_height"
STATUS_NUMERICAL_FAILURE = "numerical_failure"
STATUS_COLLINEAR_POSITIONS = "collinear_positions"
STATUS_NO_INTERSECTION = "no_intersection"
STATUS_MISSING_DISTANCE = "missing_distance"


def _frozen(array: npt.ArrayLike) -> FloatArray:
    """A read-only float64 copy, so results stay immutable."""
    copy = np.array(array, dtype=np.float64)
    copy.flags.writeable = False
    return copy


@dataclass(frozen=True, eq=False)
class TrilaterationResult(Localization):
    """Outcome of :func:`trilaterate` (a status of ``"out_of_float_range"`` when the position
    lies beyond the largest float).

    Attributes:
        position: estimated ``(x, y)`` of the sensor in {W}, metres; ``None`` unless ok.
        method: the method asked for, ``"paper"`` or ``"least_squares"``.
        has_heading: always ``False``: ranges to point beacons give no heading, so
            ``pose.theta`` is 0.0 by convention and must not be read as an estimate.
        beacon_indices: indices (into the ``beacons`` argument) of the beacons used.
        used_radical_centre: ``True`` when the paper method fell back to the radical centre
            because a pair of circles did not intersect.
    """

    position: FloatArray | None = None
    method: str = "paper"
    has_heading: bool = False
    beacon_indices: tuple[int, ...] = ()
    used_radical_centre: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        if (self.position is not None) != self.ok:
            raise ValueError("TrilaterationResult: position must be given exactly when ok")


@dataclass(frozen=True, eq=False)
class CalibrationResult:
    """Outcome of :func:`auto_calibrate`.

    Attributes:
        status: ``"ok"``, ``"collinear_positions"``, ``"no_intersection"``,
            ``"missing_distance"`` or ``"out_of_float_range"`` (inputs near the float limit).
        position: the new beacon's ``(x, y, z)`` in {W}, metres; ``None`` unless ok.
        condition: ratio of the largest to the smallest singular value of the two
            displacements ``p2 - p1``, ``p3 - p1`` between the calibration positions
            (1 for a right isosceles layout, growing as the positions line up; ``inf`` only
            when they are exactly collinear or coincide).
        triangle_area_m2: area of the triangle of the three positions, square metres.
        message: human-readable explanation, empty when ok.
    """

    status: str
    position: FloatArray | None = None
    condition: float = math.inf
    triangle_area_m2: float = 0.0
    message: str = ""

    def __post_init__(self) -> None:
        if (self.status == OK) != (self.position is not None):
            raise ValueError("CalibrationResult: position must be given exactly when ok")

    @property
    def ok(self) -> bool:
        """Whether a beacon position was produced."""
        return self.status == OK


SAFE_EXPONENT = 200
"""Inputs whose magnitudes all lie within ``2**+-200`` are computed as given (their squares stay
far from overflow and underflow); larger or smaller ones are first scaled by a power of two,
which is exact, and the results scaled back."""


_FEW_VALUES = 16
"""Arrays up to this size are scanned as Python floats by :func:`unit_scale`."""


def unit_scale(*arrays: npt.ArrayLike) -> float:
    """The power of two to divide lengths by so that the largest finite magnitude of
    ``arrays`` is about 1, or 1.0 when every magnitude lies within ``2**+-SAFE_EXPONENT``."""
    largest = 0.0
    for values in arrays:
        array = np.asarray(values, dtype=np.float64)
        if array.size <= _FEW_VALUES:  # the same largest magnitude, without numpy's per-call cost
            magnitudes = [abs(value) for value in array.ravel().tolist() if math.isfinite(value)]
            if magnitudes:
                largest = max(largest, max(magnitudes))
            continue
        magnitudes_array = np.abs(array)
        finite = magnitudes_array[np.isfinite(magnitudes_array)]
        if finite.size:
            largest = max(largest, float(finite.max()))
    if largest == 0.0 or math.ldexp(1.0, -SAFE_EXPONENT) <= largest <= math.ldexp(
        1.0, SAFE_EXPONENT
    ):
        return 1.0
    # 2**1024 is past the largest float: magnitudes that high are divided by 2**1023 (< 2 left).
    return math.ldexp(1.0, min(math.frexp(largest)[1], sys.float_info.max_exp - 1))


def _representable(values: FloatArray, what: str) -> FloatArray:
    """``values`` if all finite, else a ValueError: the answer lies beyond the float range."""
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{what} lie beyond the float range (about 1.8e308 m)")
    return values


def _finite_points(values: npt.ArrayLike, shape: tuple[int, ...], name: str) -> FloatArray:
    """``values`` as a float array of ``shape``, or a ValueError naming ``name``."""
    array = np.asarray(values, dtype=np.float64)
    if array.shape != shape and not (array.size == math.prod(shape) and array.ndim <= 1):
        raise ValueError(f"{name} must have shape {shape} (metres), got {array.shape}")
    array = array.reshape(shape)
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite metres, got {array.tolist()!r}")
    return array


def _radius(value: float, name: str) -> float:
    number = float(value)
    if not (math.isfinite(number) and number >= 0.0):
        raise ValueError(f"{name} must be a finite non-negative number of metres, got {value!r}")
    return number


# ---------------------------------------------------------------------------------------------
# Circle geometry in the sensor plane
# ---------------------------------------------------------------------------------------------


def circle_intersections(
    centre_a: npt.ArrayLike, radius_a: float, centre_b: npt.ArrayLike, radius_b: float
) -> FloatArray:
    """Intersection points of two circles in the plane, as a ``(k, 2)`` array, k in {0, 1, 2}.

    Circles that miss each other by a rounding error (relative 1e-12 of the squared radius)
    are taken as tangent and give one point. Concentric circles give no point. Any finite
    input is answered (lengths beyond ``2**+-SAFE_EXPONENT`` are scaled first).

    Raises:
        ValueError: for centres that are not finite ``(2,)`` points or radii that are not
            finite and non-negative.
    """
    ca = _finite_points(centre_a, (2,), "centre_a")
    cb = _finite_points(centre_b, (2,), "centre_b")
    radius_a = _radius(radius_a, "radius_a")
    radius_b = _radius(radius_b, "radius_b")
    scale = unit_scale(ca, cb, radius_a, radius_b)
    if scale != 1.0:
        scaled = _circle_intersections(ca / scale, radius_a / scale, cb / scale, radius_b / scale)
        with np.errstate(over="ignore"):
            return _representable(scale * scaled, "the intersection points")
    return _circle_intersections(ca, radius_a, cb, radius_b)


def _circle_intersections(
    ca: FloatArray, radius_a: float, cb: FloatArray, radius_b: float
) -> FloatArray:
    offset = cb - ca
    separation = math.hypot(offset[0], offset[1])
    if separation == 0.0:
        return np.empty((0, 2))
    # Squares as products, as :func:`trilaterate_path` computes them over arrays.
    ra_sq, rb_sq = radius_a * radius_a, radius_b * radius_b
    along = (ra_sq - rb_sq + separation * separation) / (2.0 * separation)
    half_chord_sq = ra_sq - along * along
    tolerance = _TANGENCY_RELATIVE_TOLERANCE * max(ra_sq, rb_sq, separation * separation)
    if half_chord_sq < -tolerance:
        return np.empty((0, 2))
    unit = offset / separation
    foot = ca + along * unit
    if half_chord_sq <= tolerance:
        return foot.reshape(1, 2)
    half_chord = math.sqrt(half_chord_sq)
    normal = np.array([-unit[1], unit[0]])
    return np.vstack([foot + half_chord * normal, foot - half_chord * normal])


def radical_axis(
    centre_a: npt.ArrayLike, radius_a: float, centre_b: npt.ArrayLike, radius_b: float
) -> tuple[FloatArray, float]:
    """Radical axis of two circles as ``(normal, offset)``: the line ``normal . p = offset``.

    Subtracting the two circle equations ``|p - c|^2 = r^2`` gives
    ``2 (c_b - c_a) . p = r_a^2 - r_b^2 + |c_b|^2 - |c_a|^2``; when the circles meet, this is
    the line through both intersection points (the "line of intersection" of Sec. III.A).
    """
    ca = _finite_points(centre_a, (2,), "centre_a")
    cb = _finite_points(centre_b, (2,), "centre_b")
    radius_a = _radius(radius_a, "radius_a")
    radius_b = _radius(radius_b, "radius_b")
    # The line is unchanged when both sides are divided by a power of two; beyond
    # 2**+-SAFE_EXPONENT the equation is returned divided so, to stay finite.
    scale = unit_scale(ca, cb, radius_a, radius_b)
    ca, cb, radius_a, radius_b = ca / scale, cb / scale, radius_a / scale, radius_b / scale
    normal = 2.0 * (cb - ca)
    offset = float(radius_a * radius_a - radius_b * radius_b + cb @ cb - ca @ ca)
    return normal, offset


def linearised_least_squares(centres: npt.ArrayLike, radii: npt.ArrayLike) -> FloatArray | None:
    """Least-squares solution of the linearised circle equations, ``(2,)`` metres.

    Each circle gives ``|p|^2 - 2 c_i . p + |c_i|^2 = r_i^2``; subtracting the mean equation
    removes ``|p|^2`` and leaves ``-2 (c_i - c_mean) . p = r_i^2 - mean(r^2) - |c_i|^2 +
    mean(|c|^2)``, solved in the least-squares sense. For three circles the equations are
    consistent and the solution is their radical centre. ``None`` when the centres are
    collinear (rank below 2).
    """
    c = np.asarray(centres, dtype=np.float64)
    if c.ndim != 2 or c.shape[1] != 2 or len(c) < 2 or not np.all(np.isfinite(c)):
        raise ValueError(
            f"centres must be an (n, 2) array of finite metres with n >= 2, got shape {c.shape}"
        )
    r = np.asarray(radii, dtype=np.float64)
    if r.shape != (len(c),) or not np.all(np.isfinite(r)):
        raise ValueError(f"radii must be {len(c)} finite metres, got shape {r.shape}")
    scale = unit_scale(c, r)
    if scale != 1.0:
        solution = linearised_least_squares(c / scale, r / scale)
        if solution is None:
            return None
        with np.errstate(over="ignore"):
            return _representable(scale * solution, "the least-squares solution")
    squared_norms = np.einsum("ij,ij->i", c, c)
    design = -2.0 * (c - c.mean(axis=0))
    rhs = (r**2 - np.mean(r**2)) - (squared_norms - squared_norms.mean())
    solution, _, rank, _ = np.linalg.lstsq(design, rhs, rcond=None)
    if rank < 2:
        return None
    return solution


def radical_centre(centres: npt.ArrayLike, radii: npt.ArrayLike) -> FloatArray | None:
    """The point where the three radical axes of three circles meet, ``(2,)`` metres.

    ``None`` when the centres are collinear (the axes are parallel).
    """
    c = _finite_points(centres, (3, 2), "centres")
    return linearised_least_squares(c, _finite_points(radii, (3,), "radii"))


def paper_centroid(centres: npt.ArrayLike, radii: npt.ArrayLike) -> tuple[FloatArray | None, bool]:
    """Sec. III.A as read here: centroid of the pairwise intersections nearest the third circle.

    For each pair (i, j) of the three circles, of their (up to two) intersection points the
    one whose distance to circle k, ``| |p - c_k| - r_k |``, is smaller is kept; the estimate
    is the centroid of the three kept points. If some pair does not intersect, the radical
    centre is returned instead.

    Returns:
        ``(position, used_radical_centre)``; position is ``None`` only for collinear centres
        when the fallback is needed.
    """
    c = _finite_points(centres, (3, 2), "centres")
    r = _finite_points(radii, (3,), "radii")
    if np.any(r < 0.0):
        raise ValueError(f"radii must be non-negative metres, got {r.tolist()!r}")
    kept: list[FloatArray] = []
    for i, j in ((0, 1), (1, 2), (0, 2)):
        k = 3 - i - j
        points = circle_intersections(c[i], float(r[i]), c[j], float(r[j]))
        if len(points) == 0:
            return radical_centre(c, r), True
        miss = np.abs(np.hypot(*(points - c[k]).T) - r[k])
        kept.append(points[int(np.argmin(miss))])
    return np.mean(kept, axis=0), False


# ---------------------------------------------------------------------------------------------
# Trilateration (Sec. III.A)
# ---------------------------------------------------------------------------------------------


def _beacon_array(beacons: npt.ArrayLike, name: str) -> FloatArray:
    array = np.asarray(beacons, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3) of (x, y, z) in metres, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite")
    return array


def _distance_array(distances: npt.ArrayLike, count: int, name: str) -> FloatArray:
    array = np.asarray(distances, dtype=np.float64)
    if array.shape != (count,):
        raise ValueError(f"{name} must have shape ({count},), got {array.shape}")
    if np.any(array[np.isfinite(array)] < 0.0):
        raise ValueError(f"{name} must be non-negative metres (NaN marks a missing range)")
    return array


def _finite_float(value: float, name: str) -> float:
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return number


@functools.lru_cache(maxsize=64)
def _centres_are_collinear(centres: bytes, tolerance: float) -> bool:
    """:func:`_are_collinear` of 2D centres given as the bytes of a float64 ``(k, 2)`` array,
    kept per beacon set (a path's range table is trilaterated with the same beacons)."""
    return _are_collinear(np.frombuffer(centres).reshape(-1, 2), tolerance)


def _are_collinear(points: FloatArray, tolerance: float) -> bool:
    """Whether 2D points lie on one line: spread across the best-fit line vs along it."""
    if _clearly_spread(points, tolerance):
        return False
    centred = points - points.mean(axis=0)
    singular_values = np.linalg.svd(centred, compute_uv=False)
    return bool(singular_values[0] == 0.0 or singular_values[1] <= tolerance * singular_values[0])


_CLEAR_SPREAD_RATIO = 1e-4
""":func:`_clearly_spread` answers only for singular-value ratios above this (and above four
times the tolerance); closer cases are left to the svd."""


def _clearly_spread(points: FloatArray, tolerance: float) -> bool:
    """Whether :func:`_are_collinear` certainly answers False for ``(3, 2)`` points (metres),
    found on floats without its svd (a new calibrated beacon misses the cache every episode).

    The squared ratio of the centred points' singular values is ``det / lambda_max^2`` of
    their 2x2 Gram matrix, at least ``det / trace^2``. When that bound puts the ratio above
    :data:`_CLEAR_SPREAD_RATIO` and four times the tolerance, and the spread is not lost in
    the coordinates' magnitude, the rounding of either computation (relative 1e-8 at most
    here) cannot bring the svd's ratio down to the tolerance. False means: ask the svd.
    """
    if points.shape != (3, 2):
        return False
    (x0, y0), (x1, y1), (x2, y2) = points.tolist()
    mean_x, mean_y = (x0 + x1 + x2) / 3.0, (y0 + y1 + y2) / 3.0
    dx0, dx1, dx2 = x0 - mean_x, x1 - mean_x, x2 - mean_x
    dy0, dy1, dy2 = y0 - mean_y, y1 - mean_y, y2 - mean_y
    a = dx0 * dx0 + dx1 * dx1 + dx2 * dx2
    c = dy0 * dy0 + dy1 * dy1 + dy2 * dy2
    b = dx0 * dy0 + dx1 * dy1 + dx2 * dy2
    trace, det = a + c, a * c - b * b
    magnitude = max(abs(x0), abs(x1), abs(x2), abs(y0), abs(y1), abs(y2))
    if not (math.isfinite(trace) and math.isfinite(det) and det > 0.0):
        return False
    if not trace > (_CLEAR_SPREAD_RATIO * magnitude) ** 2:
        return False
    threshold = max(_CLEAR_SPREAD_RATIO, 4.0 * tolerance)
    return det / (trace * trace) > threshold * threshold


def _dilution_of_precision(
    position: FloatArray, beacons: FloatArray, sensor_height: float
) -> float:
    """Horizontal DOP of slant ranges to ``beacons`` at ``position``: sqrt(trace((H^T H)^-1)).

    Row i of H is ``d(slant range_i)/d(x, y) = (p - c_i) / d_i``.
    """
    offsets = position - beacons[:, :2]
    slant = np.sqrt(np.einsum("ij,ij->i", offsets, offsets) + (beacons[:, 2] - sensor_height) ** 2)
    jacobian = offsets / np.maximum(slant, 1e-12)[:, None]
    normal = jacobian.T @ jacobian
    if np.linalg.cond(normal) > 1e12:
        return math.inf
    return float(math.sqrt(np.trace(np.linalg.inv(normal))))


def _best_triple(
    beacons: FloatArray, radii: FloatArray, sensor_height: float, tolerance: float
) -> tuple[int, int, int] | None:
    """The three beacons with the smallest horizontal DOP at the least-squares position.

    Ties and an unusable least-squares position fall back to the largest triangle of beacon
    projections. ``None`` when every triple is collinear.
    """
    centres = beacons[:, :2]
    candidates = [
        triple
        for triple in itertools.combinations(range(len(beacons)), 3)
        if not _are_collinear(centres[list(triple)], tolerance)
    ]
    if not candidates:
        return None
    rough = linearised_least_squares(centres, radii)

    def area(triple: tuple[int, int, int]) -> float:
        a, b, c = centres[list(triple)]
        return 0.5 * abs(float((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])))

    def score(triple: tuple[int, int, int]) -> tuple[float, float]:
        dop = math.inf
        if rough is not None:
            dop = _dilution_of_precision(rough, beacons[list(triple)], sensor_height)
        return dop, -area(triple)

    return min(candidates, key=score)


def _refine_slant_ranges(
    start: FloatArray, beacons: FloatArray, distances: FloatArray, sensor_height: float
) -> FloatArray:
    """Least-squares fit of the slant ranges ``|(p, h) - b_i| = d_i`` from ``start``."""
    vertical_sq = (beacons[:, 2] - sensor_height) ** 2

    def residuals(p: FloatArray) -> FloatArray:
        offsets = p - beacons[:, :2]
        return np.sqrt(np.einsum("ij,ij->i", offsets, offsets) + vertical_sq) - distances

    def jacobian(p: FloatArray) -> FloatArray:
        offsets = p - beacons[:, :2]
        slant = np.sqrt(np.einsum("ij,ij->i", offsets, offsets) + vertical_sq)
        return offsets / np.maximum(slant, 1e-12)[:, None]

    fit = least_squares(residuals, start, jac=jacobian, method="lm", xtol=1e-15, ftol=1e-15)
    refined = np.asarray(fit.x, dtype=np.float64)
    if not np.all(np.isfinite(refined)):
        return start
    return refined


def trilaterate(
    beacons: npt.ArrayLike,
    distances: npt.ArrayLike,
    sensor_height: float,
    method: str = "paper",
    *,
    refine: bool = True,
    height_tolerance_m: float = DEFAULT_HEIGHT_TOLERANCE_M,
    collinearity_tolerance: float = DEFAULT_COLLINEARITY_TOLERANCE,
) -> TrilaterationResult:
    """Position of the robot's sensor from slant ranges to beacons (Sec. III.A).

    Each range is projected onto the horizontal plane at the sensor height:
    ``r_h = sqrt(d^2 - (z_b - h)^2)`` about the beacon's projection ``(x_b, y_b)``.

    Args:
        beacons: ``(n, 3)`` beacon positions ``(x, y, z)`` in {W}, metres. The paper uses
            n = 3.
        distances: ``(n,)`` measured slant ranges in metres from the sensor to each beacon;
            NaN (or inf) marks a missing range, which is ignored.
        sensor_height: height ``h`` of the sensor above the floor, metres.
        method: ``"paper"`` (centroid of the pairwise circle intersections nearest the third
            circle, radical-centre fallback; see the module docstring) or ``"least_squares"``
            (linearised least squares over all valid beacons, then optionally refined).
            With more than three valid beacons the paper method uses the three whose
            horizontal dilution of precision at the least-squares position is smallest.
        refine: for ``"least_squares"`` only: refine the linear solution by a nonlinear fit
            of the slant ranges.
        height_tolerance_m: how far a range may fall below ``|z_b - h|`` and still be taken
            as ``r_h = 0``.
        collinearity_tolerance: relative spread below which beacon projections are collinear.

    Returns:
        A :class:`TrilaterationResult`; status ``"ok"``, ``"too_few_beacons"`` (fewer than
        three valid ranges), ``"collinear_beacons"`` or ``"distance_below_height"``. When
        ok, ``pose`` is ``Pose(x, y, 0.0)`` and ``has_heading`` is ``False``.

    Raises:
        ValueError: on wrong shapes, non-finite beacons or sensor height, negative ranges,
            an unknown method or negative tolerances.
    """
    beacon_array = _beacon_array(beacons, "beacons")
    distance_array = _distance_array(distances, len(beacon_array), "distances")
    height = _finite_float(sensor_height, "sensor_height")
    if method not in TRILATERATION_METHODS:
        raise ValueError(f"method must be one of {TRILATERATION_METHODS}, got {method!r}")
    if not height_tolerance_m >= 0.0:
        raise ValueError(f"height_tolerance_m must be >= 0, got {height_tolerance_m!r}")
    if not collinearity_tolerance >= 0.0:
        raise ValueError(f"collinearity_tolerance must be >= 0, got {collinearity_tolerance!r}")

    scale = unit_scale(beacon_array, distance_array, height)
    if scale != 1.0:
        scaled = trilaterate(
            beacon_array / scale,
            distance_array / scale,
            height / scale,
            method,
            refine=refine,
            height_tolerance_m=height_tolerance_m / scale,
            collinearity_tolerance=collinearity_tolerance,
        )
        if scaled.position is None:
            return scaled
        with np.errstate(over="ignore"):
            unscaled = scale * np.asarray(scaled.position)
        if not np.all(np.isfinite(unscaled)):
            return TrilaterationResult(
                status=OUT_OF_FLOAT_RANGE,
                method=method,
                message="the position lies beyond the float range (about 1.8e308 m)",
            )
        return TrilaterationResult(
            status=OK,
            pose=Pose(float(unscaled[0]), float(unscaled[1]), 0.0),
            position=_frozen(unscaled),
            method=method,
            has_heading=False,
            beacon_indices=scaled.beacon_indices,
            used_radical_centre=scaled.used_radical_centre,
        )

    valid_indices = np.flatnonzero(np.isfinite(distance_array))
    if len(valid_indices) < 3:
        return TrilaterationResult(
            status=STATUS_TOO_FEW_BEACONS,
            method=method,
            message=f"{len(valid_indices)} valid ranges; trilateration needs three",
        )
    used_beacons = beacon_array[valid_indices]
    used_distances = distance_array[valid_indices]
    vertical = used_beacons[:, 2] - height
    radii_sq = used_distances**2 - vertical**2
    short = used_distances < np.abs(vertical) - height_tolerance_m
    if np.any(short):
        worst = int(valid_indices[np.argmax(short)])
        return TrilaterationResult(
            status=STATUS_DISTANCE_BELOW_HEIGHT,
            method=method,
            message=f"range to beacon {worst} is shorter than its height above the sensor",
        )
    radii = np.sqrt(np.maximum(radii_sq, 0.0))
    centres = used_beacons[:, :2]
    if _are_collinear(centres, collinearity_tolerance):
        return TrilaterationResult(
            status=STATUS_COLLINEAR_BEACONS,
            method=method,
            message="beacon projections on the sensor plane are collinear",
        )

    used_radical_centre = False
    if method == "least_squares":
        position = linearised_least_squares(centres, radii)
        if position is not None and refine:
            position = _refine_slant_ranges(position, used_beacons, used_distances, height)
        chosen = tuple(int(i) for i in valid_indices)
    else:
        triple = (0, 1, 2) if len(valid_indices) == 3 else None
        if triple is None:
            triple = _best_triple(used_beacons, radii, height, collinearity_tolerance)
        if triple is None:
            return TrilaterationResult(
                status=STATUS_COLLINEAR_BEACONS,
                method=method,
                message="every triple of beacon projections is collinear",
            )
        index_list = list(triple)
        position, used_radical_centre = paper_centroid(centres[index_list], radii[index_list])
        chosen = tuple(int(valid_indices[i]) for i in triple)

    if position is None or not np.all(np.isfinite(position)):
        return TrilaterationResult(
            status=STATUS_NUMERICAL_FAILURE,
            method=method,
            message="the position could not be computed",
        )
    return TrilaterationResult(
        status=OK,
        pose=Pose(float(position[0]), float(position[1]), 0.0),
        position=_frozen(position),
        method=method,
        has_heading=False,
        beacon_indices=chosen,
        used_radical_centre=used_radical_centre,
    )


@dataclass(frozen=True, eq=False)
class PathFixes:
    """Outcome of :func:`trilaterate_path`: one fix per row of a range table.

    Attributes:
        statuses: ``(n,)`` the :func:`trilaterate` status of each row.
        positions: ``(n, 2)`` estimated ``(x, y)`` in {W}, metres; NaN where not ok.
        used_radical_centre: ``(n,)`` whether the paper method fell back to the radical centre.
    """

    statuses: tuple[str, ...]
    positions: FloatArray
    used_radical_centre: npt.NDArray[np.bool_]

    @property
    def ok(self) -> npt.NDArray[np.bool_]:
        """``(n,)`` whether each row gave a position."""
        return np.isfinite(self.positions[:, 0])


def trilaterate_path(
    beacons: npt.ArrayLike,
    distances: npt.ArrayLike,
    sensor_height: float,
    method: str = "paper",
    *,
    height_tolerance_m: float = DEFAULT_HEIGHT_TOLERANCE_M,
    collinearity_tolerance: float = DEFAULT_COLLINEARITY_TOLERANCE,
) -> PathFixes:
    """:func:`trilaterate` for every row of a range table at once (Sec. III.A).

    The paper method with three beacons runs as arrays over the rows, with the same
    arithmetic as :func:`circle_intersections` and :func:`paper_centroid`; the rows that need
    the radical-centre fallback, and every row of other setups (``"least_squares"``, more
    than three beacons), go through :func:`trilaterate` one by one.

    Args:
        beacons: ``(b, 3)`` beacon positions ``(x, y, z)`` in {W}, metres.
        distances: ``(n, b)`` measured slant ranges, metres; NaN (or inf) marks a missing one.
        sensor_height, method, height_tolerance_m, collinearity_tolerance: as
            :func:`trilaterate`.

    Returns:
        A :class:`PathFixes` whose row ``i`` agrees with ``trilaterate(beacons, distances[i],
        ...)`` in status and position.

    Raises:
        ValueError: as :func:`trilaterate`, and for a table that is not ``(n, b)``.
    """
    beacon_array = _beacon_array(beacons, "beacons")
    table = np.asarray(distances, dtype=np.float64)
    if table.ndim != 2 or table.shape[1] != len(beacon_array):
        raise ValueError(
            f"distances must have shape (n, {len(beacon_array)}) (rows x beacons), "
            f"got {table.shape}"
        )
    if np.any(table < 0.0) and np.any(table[np.isfinite(table)] < 0.0):
        raise ValueError("distances must be non-negative metres (NaN marks a missing range)")
    height = _finite_float(sensor_height, "sensor_height")
    if method not in TRILATERATION_METHODS:
        raise ValueError(f"method must be one of {TRILATERATION_METHODS}, got {method!r}")
    if not height_tolerance_m >= 0.0:
        raise ValueError(f"height_tolerance_m must be >= 0, got {height_tolerance_m!r}")
    if not collinearity_tolerance >= 0.0:
        raise ValueError(f"collinearity_tolerance must be >= 0, got {collinearity_tolerance!r}")
    return _trilaterate_rows(
        beacon_array, table, height, method, height_tolerance_m, collinearity_tolerance
    )


def _trilaterate_rows(
    beacon_array: FloatArray,
    table: FloatArray,
    height: float,
    method: str,
    height_tolerance_m: float,
    collinearity_tolerance: float,
) -> PathFixes:
    """:func:`trilaterate_path` of inputs it has validated: finite ``(b, 3)`` beacons
    (metres), an ``(n, b)`` float64 table of non-negative or missing ranges (metres), a finite
    height (metres), a known method and non-negative tolerances. The block expansion runner,
    whose inputs are validated by its config, calls it directly."""
    n_rows = len(table)
    positions = np.full((n_rows, 2), np.nan)
    statuses = [OK] * n_rows
    fallback = np.zeros(n_rows, dtype=bool)
    options = {
        "height_tolerance_m": height_tolerance_m,
        "collinearity_tolerance": collinearity_tolerance,
    }
    if method != "paper" or len(beacon_array) != 3:
        one_by_one = np.arange(n_rows)
        ok: npt.NDArray[np.bool_] = np.ones(n_rows, dtype=bool)
    else:
        vertical = beacon_array[:, 2] - height
        radii, usable, valid = roh_kernels.usable_radii(table, vertical, height_tolerance_m)
        if not usable.all():
            for row in np.flatnonzero(~usable).tolist():
                statuses[row] = (
                    STATUS_DISTANCE_BELOW_HEIGHT if valid[row] else STATUS_TOO_FEW_BEACONS
                )
        centres = beacon_array[:, :2]
        rows = np.flatnonzero(usable)
        if _centres_are_collinear(centres.tobytes(), collinearity_tolerance):
            for row in rows.tolist():
                statuses[row] = STATUS_COLLINEAR_BEACONS
            return PathFixes(tuple(statuses), positions, fallback)
        centroid, met = _paper_centroids(centres, radii)
        ok = usable
        if met.all():
            positions[rows] = centroid
            one_by_one = rows[:0]
        else:
            missed = ~met
            missed_rows = rows[missed]
            positions[rows[met]] = centroid
            centre = _radical_centres(centres, radii[missed])
            if centre is None:
                one_by_one = missed_rows
            else:
                positions[missed_rows] = centre
                fallback[missed_rows] = True
                one_by_one = rows[:0]
    for row in one_by_one.tolist():
        fix = trilaterate(beacon_array, table[row], height, method, **options)  # type: ignore[arg-type]
        statuses[row] = fix.status
        ok[row] = fix.status == OK
        fallback[row] = fix.used_radical_centre
        if fix.position is not None:
            positions[row] = fix.position
    bad = roh_kernels.unfinished_rows(positions, ok)
    for row in bad.tolist():
        statuses[row] = STATUS_NUMERICAL_FAILURE
    positions[bad] = np.nan
    return PathFixes(tuple(statuses), positions, fallback)


def _radical_centres(centres: FloatArray, radii: FloatArray) -> FloatArray | None:
    """:func:`radical_centre` of one set of three centres for rows of radii ``(m, 3)``.

    The same least-squares problem as :func:`linearised_least_squares`, solved for all rows
    at once (one right-hand side per row); ``None`` when the centres are collinear.
    """
    design, centred_norms = _radical_design(
        np.ascontiguousarray(centres, dtype=np.float64).tobytes()
    )
    radii_sq = radii**2
    # np.mean's own arithmetic (the sum along the row, divided by the count) without its
    # per-call cost.
    row_means = radii_sq.sum(axis=1, keepdims=True) / radii_sq.shape[1]
    rhs = (radii_sq - row_means) - centred_norms
    solution, _, rank, _ = np.linalg.lstsq(design, rhs.T, rcond=None)
    if rank < 2:
        return None
    return np.asarray(solution.T)


@functools.lru_cache(maxsize=64)
def _radical_design(centres: bytes) -> tuple[FloatArray, FloatArray]:
    """The parts of :func:`_radical_centres`' problem that depend only on the centres, given
    as the bytes of a float64 ``(k, 2)`` array (kept per beacon set): the design matrix
    ``-2 (c_i - c_mean)`` ``(k, 2)`` and ``|c_i|^2 - mean(|c|^2)`` ``(k,)``, metres and
    square metres (read-only)."""
    points = np.frombuffer(centres).reshape(-1, 2)
    squared_norms = np.einsum("ij,ij->i", points, points)
    design = -2.0 * (points - points.mean(axis=0))
    centred_norms = squared_norms - squared_norms.mean()
    design.flags.writeable = False
    centred_norms.flags.writeable = False
    return design, centred_norms


_CENTROID_PAIRS = ((0, 1), (1, 2), (0, 2))
"""The circle pairs of :func:`paper_centroid`, in its order."""
_PAIR_CIRCLES: tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], npt.NDArray[np.int64]] = (
    np.array([i for i, _ in _CENTROID_PAIRS], dtype=np.int64),
    np.array([j for _, j in _CENTROID_PAIRS], dtype=np.int64),
    np.array([3 - i - j for i, j in _CENTROID_PAIRS], dtype=np.int64),
)
"""``(first, second, third)`` circle of each pair, as index arrays."""


@functools.lru_cache(maxsize=64)
def _pair_geometry(
    centres: bytes,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray] | None:
    """Per pair of :data:`_CENTROID_PAIRS`: the first and third centres ``(3, 2)``, the centre
    distance and its square ``(3,)`` and the unit vector first -> second ``(3, 2)`` of three
    centres given as the bytes of a float64 ``(3, 2)`` array (kept per beacon set); None when
    two centres coincide."""
    # On Python floats: three pairs are too few for numpy's per-call cost to pay off.
    points = np.frombuffer(centres).reshape(3, 2).tolist()
    first = [points[i] for i, _ in _CENTROID_PAIRS]
    third = [points[3 - i - j] for i, j in _CENTROID_PAIRS]
    offsets = [
        (points[j][0] - points[i][0], points[j][1] - points[i][1]) for i, j in _CENTROID_PAIRS
    ]
    separations = [math.hypot(dx, dy) for dx, dy in offsets]
    if 0.0 in separations:
        return None
    units = [
        (dx / length, dy / length) for (dx, dy), length in zip(offsets, separations, strict=True)
    ]
    return (
        np.array(first),
        np.array(third),
        np.array(separations),
        np.array([value**2 for value in separations]),
        np.array(units),
    )


def _paper_centroids(
    centres: FloatArray, radii: FloatArray
) -> tuple[FloatArray, npt.NDArray[np.bool_]]:
    """:func:`paper_centroid` over rows of radii ``(m, 3)`` for one set of three centres.

    Each element has the arithmetic of :func:`circle_intersections`, row by row in
    :func:`sonar_gym.localization.roh_kernels.paper_centroids`.

    Returns ``(centroids (k, 2), met (m,))``: ``met`` is False where some pair of circles does
    not intersect (those rows need the radical-centre fallback), and the centroids are those
    of the ``k`` rows where ``met`` holds, in row order.
    """
    geometry = _pair_geometry(np.ascontiguousarray(centres, dtype=np.float64).tobytes())
    if geometry is None:
        return np.zeros((0, 2)), np.zeros(len(radii), dtype=bool)
    first_centres, third_centres, separation, separation_sq, units = geometry
    centroids, met = roh_kernels.paper_centroids(
        radii,
        *_PAIR_CIRCLES,
        first_centres,
        third_centres,
        separation,
        separation_sq,
        units,
        _TANGENCY_RELATIVE_TOLERANCE,
    )
    return (centroids if met.all() else centroids[met]), met


# ---------------------------------------------------------------------------------------------
# Auto-calibration (Sec. III.B)
# ---------------------------------------------------------------------------------------------


def _scaled_back(result: CalibrationResult, scale: float) -> CalibrationResult:
    """A calibration computed on lengths divided by ``scale``, in the caller's units."""
    if result.position is not None:
        with np.errstate(over="ignore"):
            position = scale * result.position
        if not np.all(np.isfinite(position)):
            return CalibrationResult(
                status=OUT_OF_FLOAT_RANGE,
                condition=result.condition,
                message="the beacon lies beyond the float range (about 1.8e308 m)",
            )
    return CalibrationResult(
        status=result.status,
        position=None if result.position is None else _frozen(scale * result.position),
        condition=result.condition,
        triangle_area_m2=result.triangle_area_m2 * scale * scale,
        message=result.message,
    )


def _calibration_positions(positions: npt.ArrayLike, sensor_height: float) -> FloatArray:
    array = np.asarray(positions, dtype=np.float64)
    if array.shape not in ((3, 2), (3, 3)):
        raise ValueError(
            f"positions must have shape (3, 2) (x, y at the sensor height) or (3, 3), "
            f"got {array.shape}"
        )
    if not np.all(np.isfinite(array)):
        raise ValueError("positions must be finite")
    if array.shape[1] == 2:
        array = np.column_stack([array, np.full(3, sensor_height)])
    return array


def _cross3(a: FloatArray, b: FloatArray) -> FloatArray:
    """``np.cross`` of two 3-vectors, with its products and differences in its order."""
    a0, a1, a2 = a.tolist()
    b0, b1, b2 = b.tolist()
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def auto_calibrate(
    positions: npt.ArrayLike,
    distances: npt.ArrayLike,
    sensor_height: float = DEFAULT_SENSOR_HEIGHT_M,
    *,
    max_condition: float = DEFAULT_MAX_CALIBRATION_CONDITION,
    intersection_tolerance_m: float = DEFAULT_INTERSECTION_TOLERANCE_M,
) -> CalibrationResult:
    """Position of a new beacon from ranges measured at three robot positions (Sec. III.B).

    The three spheres about the sensor positions ``p_i`` with radii ``d_i`` are intersected
    in closed form. In the frame with origin ``p1``, ``e_x`` towards ``p2``, ``e_y`` in the
    plane of the positions towards ``p3`` and ``e_z = e_x x e_y``, with ``u = |p2 - p1|``,
    ``i = e_x . (p3 - p1)``, ``j = e_y . (p3 - p1)``::

        x = (d1^2 - d2^2 + u^2) / (2 u)
        y = (d1^2 - d3^2 + i^2 + j^2) / (2 j) - i x / j
        z = +- sqrt(d1^2 - x^2 - y^2)

    Of the two mirror solutions the one higher in {W} is returned: for positions on the
    sensor plane (the paper's case) it is the one above the plane, ``z_world > h``.

    Args:
        positions: ``(3, 2)`` sensor positions ``(x, y)`` at height ``sensor_height``, or
            ``(3, 3)`` positions ``(x, y, z)`` (then ``sensor_height`` is not used), metres.
        distances: ``(3,)`` slant ranges to the new beacon, metres; NaN gives
            ``"missing_distance"``.
        sensor_height: sensor height above the floor, metres, for 2D positions.
        max_condition: condition numbers above this count as ``"collinear_positions"``.
        intersection_tolerance_m: when the spheres do not meet, the point ``(x, y, 0)`` of
            their radical line in the plane of the positions lies outside them by the gap
            ``sqrt(x^2 + y^2) - d1``; a gap up to this tolerance (metres) counts as touching
            and the beacon is placed at that point, in the plane of the positions; a larger
            gap gives ``"no_intersection"``.

    Returns:
        A :class:`CalibrationResult` with the status, the position, the condition number and
        the triangle area of the three positions.

    Raises:
        ValueError: on wrong shapes, non-finite positions or height, negative ranges, or
            non-positive tolerances.
    """
    height = _finite_float(sensor_height, "sensor_height")
    points = _calibration_positions(positions, height)
    ranges = _distance_array(distances, 3, "distances")
    if not max_condition > 1.0:
        raise ValueError(f"max_condition must be > 1, got {max_condition!r}")
    if not intersection_tolerance_m >= 0.0:
        raise ValueError(f"intersection_tolerance_m must be >= 0, got {intersection_tolerance_m!r}")
    return _auto_calibrate_checked(points, ranges, max_condition, intersection_tolerance_m)


def _auto_calibrate_checked(
    points: FloatArray, ranges: FloatArray, max_condition: float, intersection_tolerance_m: float
) -> CalibrationResult:
    """:func:`auto_calibrate` of inputs it has validated: finite ``(3, 3)`` positions and
    ``(3,)`` non-negative or missing ranges (metres), ``max_condition > 1`` and a
    non-negative tolerance (metres). The block expansion runner calls it directly."""
    scale = unit_scale(points, ranges)
    if scale != 1.0:
        return _scaled_back(
            auto_calibrate(
                points / scale,
                ranges / scale,
                max_condition=max_condition,
                intersection_tolerance_m=intersection_tolerance_m / scale,
            ),
            scale,
        )

    displacements = points[1:] - points[0]
    singular_values = np.linalg.svd(displacements, compute_uv=False)
    area = 0.5 * vector_norm(_cross3(displacements[0], displacements[1]))
    if singular_values[1] > 0.0:
        condition = float(singular_values[0] / singular_values[1])
    else:
        condition = math.inf
    if not np.all(np.isfinite(ranges)):
        return CalibrationResult(
            status=STATUS_MISSING_DISTANCE,
            condition=condition,
            triangle_area_m2=area,
            message="a range to the new beacon is missing",
        )
    if not condition <= max_condition:
        return CalibrationResult(
            status=STATUS_COLLINEAR_POSITIONS,
            condition=condition,
            triangle_area_m2=area,
            message=f"calibration positions are (nearly) collinear: condition {condition:.3g}",
        )

    d1, d2, d3 = (float(value) for value in ranges)
    separation = vector_norm(displacements[0])
    e_x = displacements[0] / separation
    along_x = float(e_x @ displacements[1])
    across = displacements[1] - along_x * e_x
    along_y = vector_norm(across)
    if not along_y > 0.0:
        return CalibrationResult(
            status=STATUS_COLLINEAR_POSITIONS,
            condition=condition,
            triangle_area_m2=area,
            message="calibration positions are collinear to float precision",
        )
    e_y = across / along_y
    e_z = _cross3(e_x, e_y)
    # Products, not ``**``: under an extreme (user-allowed) condition they overflow to inf
    # instead of raising OverflowError, and the check below reports it.
    x = (d1 * d1 - d2 * d2 + separation * separation) / (2.0 * separation)
    y = (d1 * d1 - d3 * d3 + along_x * along_x + along_y * along_y) / (
        2.0 * along_y
    ) - along_x * x / along_y
    height_sq = d1 * d1 - x * x - y * y
    if not math.isfinite(height_sq):
        return CalibrationResult(
            status=STATUS_COLLINEAR_POSITIONS,
            condition=condition,
            triangle_area_m2=area,
            message="calibration positions are too nearly collinear to compute with",
        )
    if height_sq < 0.0:
        # The radical line of the three spheres pierces the plane of the positions at the
        # local (x, y); it lies outside the spheres by this radial gap.
        miss = math.hypot(x, y) - d1
        if miss > intersection_tolerance_m:
            return CalibrationResult(
                status=STATUS_NO_INTERSECTION,
                condition=condition,
                triangle_area_m2=area,
                message=f"the three spheres miss each other by {miss:.3g} m",
            )
        height_sq = 0.0
    offset = math.sqrt(height_sq)
    foot = points[0] + x * e_x + y * e_y
    upper, lower = foot + offset * e_z, foot - offset * e_z
    beacon = upper if upper[2] >= lower[2] else lower
    return CalibrationResult(
        status=OK, position=_frozen(beacon), condition=condition, triangle_area_m2=area
    )
