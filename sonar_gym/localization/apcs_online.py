"""The on-line half of APCS: the Fig. 2 loop of Yamamoto et al. run while the robot moves.

While the robot drives, APCS keeps a dead-reckoning estimate with its covariance, turns every
new side-sonar reading into an estimated reflection point (ERP, eqs 1-6) paired with the
previous reading of the same sensor, groups consecutive ERPs (sec. 4.2.2), verifies each closed
group as a flat wall (sec. 4.2.2-4.2.3), matches it to the map (sec. 4.3) and, on a unique
match, corrects the estimate by maximum likelihood (eqs 7-14). After a correction the stored
readings and ERPs move with the estimate's frame.

- :class:`WallStream`: the ERPs and ERP groups of one side sonar.
- :class:`APCSTracker`: the whole loop over a run of motion commands and the readings taken
  along it, consuming the run's readings as arrays and re-doing only what a correction changes.
- :func:`rejection_reason`, :func:`fit_measurement_variances`, :func:`nearest_facing_walls`:
  the pieces the tracker, the env's observation and the reproduction share.

Everything here takes plain arrays and dataclasses; nothing reads a world.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from sonar_gym.frozen import unchecked_instance
from sonar_gym.localization import apcs_kernels
from sonar_gym.localization.apcs import (
    AMBIGUOUS,
    DEFAULT_PARAMETERS,
    GROUP_TOO_FEW_POINTS,
    APCSParameters,
    CorrectionResult,
    DetectedWall,
    MatchResult,
    WallFit,
    WallVector,
    correct_with_checked_wall,
)
from sonar_gym.localization.apcs_correction import symmetrized, validated_covariance
from sonar_gym.localization.apcs_walls import (
    WallMap,
    fit_group_points,
    newest_reflection_table,
    reflection_rows_of_table,
)
from sonar_gym.localization.result import OK
from sonar_gym.odometry import checked_variance_per_m, predict_run_unchecked
from sonar_gym.pose import FloatArray, Pose
from sonar_gym.validation import checked_array, checked_positive

SIDE_NAMES = ("left", "right")
"""The side sonars: ``left`` looks along the heading + pi/2, ``right`` along heading - pi/2."""
BEAM_OFFSET_RAD = {"left": math.pi / 2.0, "right": -math.pi / 2.0}
"""Beam axis of each side sonar relative to the robot heading, radians."""
MEASUREMENT_VARIANCES = ("fixed", "fit")
CORRECTION_METHODS = ("paper", "linear")


def _check_ranges(ranges: FloatArray, name: str) -> None:
    if np.any(ranges < 0.0):
        raise ValueError(
            f"argument {name!r} must hold ranges >= 0 metres (NaN for a dropout); got {ranges!r}"
        )


def _check_side(side: object) -> str:
    if side not in SIDE_NAMES:
        raise ValueError(f"argument 'side' must be one of {list(SIDE_NAMES)}; got {side!r}")
    return str(side)


# --------------------------------------------------------------------------------------------
# Matching verdicts and measurement variances
# --------------------------------------------------------------------------------------------


def rejection_reason(match: MatchResult) -> str | None:
    """Why a detected wall was not used: the paper's first failed condition (sec. 4.3).

    ``None`` for a unique match, ``"ambiguous"`` when more than one map wall matched, else
    the reason of the map wall that came closest to matching (most conditions passed, in the
    paper's order orientation, inclusion, distance; ties by the smaller ``d1^2 + d2^2``).
    """
    if match.matched:
        return None
    if match.status == AMBIGUOUS:
        return AMBIGUOUS
    # the closest check's reason alone, without building the check (only an empty map has none)
    checks = match.checks
    return "empty_map" if len(checks) == 0 else checks.closest_reason


@dataclass(frozen=True)
class ClosedGroup:
    """A closed group of ERPs and its verdict.

    Attributes:
        fit: the size, line and variance verdict
            (:func:`~sonar_gym.localization.apcs.fit_wall_group`).
        points: ``(n, 2)`` the group's ERPs, metres, in the frame of the estimate.
    """

    fit: WallFit
    points: FloatArray


def fit_measurement_variances(
    group: ClosedGroup,
    pose: Pose,
    fixed: tuple[float, float],
    mode: str = "fixed",
) -> tuple[float, float]:
    """``(sigma_r, sigma_xi)`` of eqs (13)-(14) for a detected wall (m^2, rad^2).

    The paper gives no values. ``mode="fixed"`` returns ``fixed``; ``"fit"`` takes the wall
    fit's own least-squares variances: the residual variance (unbiased, ``n - 2`` degrees of
    freedom) over the spread of the ERPs along the line for the bearing, and the variance of
    the line's offset at the foot of ``pose`` on it for the range; floors of 1e-6 m^2 and
    (0.05 deg)^2 keep them positive. A group without a wall gets ``fixed``.
    """
    if mode not in MEASUREMENT_VARIANCES:
        raise ValueError(
            f"argument 'mode' must be one of {list(MEASUREMENT_VARIANCES)}; got {mode!r}"
        )
    if mode == "fixed" or group.fit.wall is None:
        return fixed
    points = group.points
    n = len(points)
    along = group.fit.wall.vector.unit_direction
    centroid = points.mean(axis=0)
    spread = float(np.sum(((points - centroid) @ along) ** 2))
    residual = group.fit.residual_variance_m2 * n / max(n - 2, 1)
    bearing_variance = residual / max(spread, 1e-12)
    lever = float((pose.position - centroid) @ along)
    range_variance = residual / n + bearing_variance * lever * lever
    return max(range_variance, 1e-6), max(bearing_variance, math.radians(0.05) ** 2)


def nearest_facing_walls(
    walls: Sequence[WallVector], origins: npt.ArrayLike, direction: npt.ArrayLike
) -> tuple[np.ndarray, FloatArray]:
    """For each origin, the nearest wall the ray ``origin + t direction`` meets face on.

    A wall counts when the ray crosses its segment at ``t > 0`` coming from its free side.

    Args:
        walls: the map's wall vectors.
        origins: ``(n, 2)`` ray origins, metres in {W}.
        direction: unit direction of the rays in {W}.

    Returns:
        ``(ids, distances)``: the index of the wall in ``walls`` (-1 where none) and ``t``
        (metres; inf where none), each ``(n,)``.
    """
    origins = checked_array(origins, "origins", (None, 2))
    direction = checked_array(direction, "direction", (2,))
    if not walls:
        return np.full(len(origins), -1), np.full(len(origins), math.inf)
    starts = np.array([wall.start for wall in walls])
    units = np.array([wall.unit_direction for wall in walls])
    lengths = np.array([wall.length for wall in walls])
    normals = np.column_stack([units[:, 1], -units[:, 0]])  # free side, WallVector.normal
    facing = normals @ direction  # (walls,)
    signed = np.einsum("nwk,wk->nw", origins[:, None, :] - starts[None, :, :], normals)
    with np.errstate(divide="ignore", invalid="ignore"):
        distance = np.where(facing < -1e-9, signed / -np.where(facing < -1e-9, facing, -1.0), -1.0)
    hits = origins[:, None, :] + distance[:, :, None] * direction
    along = np.einsum("nwk,wk->nw", hits - starts[None, :, :], units) / lengths
    valid = (distance > 0.0) & (along >= -1e-9) & (along <= 1.0 + 1e-9)
    distance = np.where(valid, distance, math.inf)
    ids = np.argmin(distance, axis=1)
    best = distance[np.arange(len(origins)), ids]
    return np.where(np.isfinite(best), ids, -1), best


# --------------------------------------------------------------------------------------------
# One side sonar's ERPs and groups
# --------------------------------------------------------------------------------------------


def _frame_move(before: Pose, after: Pose) -> tuple[float, FloatArray, FloatArray, FloatArray]:
    """The rigid move of the estimate's frame in a correction from ``before`` to ``after``:
    ``(turn, rotation, origin_before, origin_after)``, the turn in radians, its ``(2, 2)``
    rotation and the two positions (metres, {W}); a point ``p`` moves to
    ``origin_after + rotation @ (p - origin_before)``."""
    turn = after.theta - before.theta
    cos_turn, sin_turn = math.cos(turn), math.sin(turn)
    rotation = np.array([[cos_turn, -sin_turn], [sin_turn, cos_turn]])
    return turn, rotation, np.array((before.x, before.y)), np.array((after.x, after.y))


_RawGroup = tuple[list[tuple[float, float]], list[float]]
"""A closed group before its verdict: its ERPs ``(x, y)`` (metres, in the frame of the
estimate) and their reflection directions (radians), in the order taken."""


class WallStream:
    """On-line ERPs and ERP groups of one side sonar (sec. 4.2.1-4.2.2), reading by reading.

    Each reading pairs with the previous one to give one ERP (the newer reading's, as
    :func:`~sonar_gym.localization.apcs.estimated_reflection_points` with
    ``points_per_pair="newest"``); ERPs join the open group while consecutive ERPs stay within
    the grouping distance. A group is closed at a discontinuity, as soon as it holds
    ``max_group_size`` ERPs, or when the stream is flushed, and then verified with
    :func:`~sonar_gym.localization.apcs.fit_wall_group`. The groups are those
    :func:`~sonar_gym.localization.apcs.group_erps` finds on the whole sequence.

    :meth:`add` takes one reading; :meth:`pending_erps` computes the ERPs of a run of readings
    at once without storing them, and :meth:`accept` stores one reading with its ERP.

    Args:
        side: ``"left"`` or ``"right"``: the beam axis is the heading plus or minus pi/2.
        params: APCS thresholds.
    """

    def __init__(self, side: str, params: APCSParameters = DEFAULT_PARAMETERS) -> None:
        self.side = _check_side(side)
        self.params = params
        self._beam_offset_rad = BEAM_OFFSET_RAD[self.side]
        self._previous: tuple[tuple[float, float], float, float] | None = None
        self._group_points: list[tuple[float, float]] = []
        self._group_directions: list[float] = []

    @property
    def open_group_size(self) -> int:
        """Number of ERPs in the group being built."""
        return len(self._group_points)

    def pending_erps(
        self, sensor_xy: npt.ArrayLike, headings_rad: npt.ArrayLike, ranges_m: npt.ArrayLike
    ) -> tuple[FloatArray, FloatArray, np.ndarray]:
        """The ERPs that readings ``0..n-1`` would give, each paired with its predecessor.

        The first reading pairs with the stream's last stored reading. Nothing is stored.

        Args:
            sensor_xy: ``(n, 2)`` sensor positions, metres, in the frame of the estimate.
            headings_rad: ``(n,)`` robot headings of the estimate, radians.
            ranges_m: ``(n,)`` measured ranges, metres; NaN for a dropout.

        Returns:
            ``(points, directions, valid)``: ``(n, 2)`` ERPs (metres), ``(n,)`` reflection
            directions (radians) and ``(n,)`` whether the reading gives an ERP (rows where not
            are zero).
        """
        positions = checked_array(sensor_xy, "sensor_xy", (None, 2))
        headings = checked_array(headings_rad, "headings_rad", (len(positions),))
        ranges = np.asarray(ranges_m, dtype=np.float64)
        if ranges.shape != (len(positions),):
            raise ValueError(
                f"argument 'ranges_m' must have shape ({len(positions)},); got {ranges.shape}"
            )
        _check_ranges(ranges, "ranges_m")
        return self._pending(positions, headings, ranges)

    def _pending(
        self, positions: FloatArray, headings: FloatArray, ranges: FloatArray
    ) -> tuple[FloatArray, FloatArray, np.ndarray]:
        """:meth:`pending_erps` on checked arrays."""
        return reflection_rows_of_table(self._pending_table(positions, headings, ranges))

    def _pending_rows(
        self, positions: FloatArray, headings: FloatArray, ranges: FloatArray
    ) -> list[float]:
        """:meth:`_pending` with the readings' sensor positions, as the flat list of the rows of
        :meth:`_pending_table` (six floats a reading)."""
        return self._pending_table(positions, headings, ranges).ravel().tolist()  # type: ignore[no-any-return]

    def _pending_table(
        self, positions: FloatArray, headings: FloatArray, ranges: FloatArray
    ) -> FloatArray:
        """The pending ERPs of the readings after the stored one, as the rows of
        :func:`~sonar_gym.localization.apcs_walls.newest_reflection_table` (columns
        :data:`~sonar_gym.localization.apcs_kernels.ERP_COLUMNS`), one per new reading."""
        has_previous, previous = self._previous_reading()
        readings = apcs_kernels.reading_table(
            positions, headings, ranges, self._beam_offset_rad, has_previous, previous
        )
        return newest_reflection_table(readings, self.params.sensing_range_m, int(has_previous))

    def _previous_reading(self) -> tuple[bool, tuple[float, float, float, float]]:
        """Whether a reading is stored, and its ``(x, y, direction, range)`` (metres, radians;
        zeros without one)."""
        if self._previous is None:
            return False, (0.0, 0.0, 0.0, 0.0)
        (previous_x, previous_y), previous_direction, previous_range = self._previous
        return True, (previous_x, previous_y, previous_direction, previous_range)

    def accept(
        self,
        sensor_xy: Sequence[float],
        heading_rad: float,
        range_m: float,
        erp: tuple[Sequence[float], float] | None,
    ) -> list[ClosedGroup]:
        """Store one reading and its ERP ``(point, direction)`` (from :meth:`pending_erps`).

        Returns:
            The verdicts of the groups this reading closed.
        """
        sensor_x, sensor_y = sensor_xy
        self._remember(float(sensor_x), float(sensor_y), float(heading_rad), float(range_m))
        if erp is None:
            return []
        (point_x, point_y), phi = erp
        return list(self._accept_erp(float(point_x), float(point_y), float(phi)))

    def _remember(
        self, sensor_x: float, sensor_y: float, heading_rad: float, range_m: float
    ) -> None:
        """Store the latest reading (plain floats: sensor position and robot heading in the
        frame of the estimate, metres and radians; range in metres), which the next
        :meth:`pending_erps` pairs with."""
        self._previous = ((sensor_x, sensor_y), heading_rad + self._beam_offset_rad, range_m)

    def _accept_erp(self, point_x: float, point_y: float, phi: float) -> tuple[ClosedGroup, ...]:
        """Add one ERP (plain floats, metres and radians) to the open group; returns the
        verdicts of the groups it closed. The reading itself is stored by the caller."""
        return tuple(self._verdict(group) for group in self._grouped(point_x, point_y, phi))

    def _grouped(self, point_x: float, point_y: float, phi: float) -> tuple[_RawGroup, ...]:
        """Add one ERP (plain floats, metres and radians) to the open group; returns the groups
        it closed as their ERPs and reflection directions, before any verdict."""
        # Plain floats: this runs once per reading, where numpy's per-call cost dominates.
        group_points = self._group_points
        closed: tuple[_RawGroup, ...] = ()
        if group_points:
            last_x, last_y = group_points[-1]
            step_x, step_y = point_x - last_x, point_y - last_y
            if step_x * step_x + step_y * step_y > self.params.grouping_distance_squared_m2:
                closed = (self._take_group(),)
                group_points = self._group_points
        group_points.append((point_x, point_y))
        self._group_directions.append(phi)
        if len(group_points) >= self.params.max_group_size:
            closed = (*closed, self._take_group())
        return closed

    def add(
        self, sensor_xy: npt.ArrayLike, heading_rad: float, range_m: float
    ) -> tuple[FloatArray | None, list[ClosedGroup]]:
        """Add one reading taken at ``sensor_xy`` ({W} estimate, metres) with the robot heading.

        Args:
            sensor_xy: sensor position, metres, in the frame of the pose estimate.
            heading_rad: robot heading of the estimate, radians.
            range_m: the measured range, metres; NaN for a dropout.

        Returns:
            The new ERP (or ``None``) and the verdicts of the groups this reading closed.
        """
        position = checked_array(sensor_xy, "sensor_xy", (2,))
        points, phis, valid = self.pending_erps(position[None, :], [heading_rad], [range_m])
        erp_point = points[0].copy() if valid[0] else None
        erp = None if erp_point is None else (erp_point.tolist(), float(phis[0]))
        closed = self.accept(position.tolist(), float(heading_rad), float(range_m), erp)
        return erp_point, closed

    def flush(self) -> list[ClosedGroup]:
        """End the stream (the sensor stops): close the open group and forget the last reading."""
        self._previous = None
        return [self._close()] if self._group_points else []

    def move_frame(self, before: Pose, after: Pose) -> None:
        """Re-express the stored positions after a pose correction from ``before`` to ``after``.

        The readings and ERPs of the stream live in the frame of the pose estimate; a
        correction moves that frame rigidly, and the stored points move with it.
        """
        self._move(*_frame_move(before, after))

    def _move(
        self,
        turn: float,
        rotation: FloatArray,
        origin_before: FloatArray,
        origin_after: FloatArray,
    ) -> None:
        """:meth:`move_frame` by the parts :func:`_frame_move` gives."""
        previous = self._previous
        # The group's ERPs, then the stored reading's position: one row each.
        points = self._group_points if previous is None else [*self._group_points, previous[0]]
        if points:
            offsets = np.array(points) - origin_before
            # np.matvec makes, row by row, the BLAS call of ``rotation @ offset`` (the same bits)
            moved = (origin_after + np.matvec(rotation, offsets)).tolist()
            if previous is not None:
                position_x, position_y = moved.pop()
                self._previous = ((position_x, position_y), previous[1] + turn, previous[2])
            self._group_points = [(x, y) for x, y in moved]
        self._group_directions = [direction + turn for direction in self._group_directions]

    def _close(self) -> ClosedGroup:
        return self._verdict(self._take_group())

    def _take_group(self) -> _RawGroup:
        """The open group's ERPs and reflection directions; the stream starts a new group."""
        group = (self._group_points, self._group_directions)
        self._group_points, self._group_directions = [], []
        return group

    def _verdict(self, group: _RawGroup) -> ClosedGroup:
        """A closed group with its verdict (:func:`fit_group_points`, after the size test)."""
        group_points, directions = group
        points = np.array(group_points)
        indices = tuple(range(len(points)))
        if len(points) < self.params.min_group_size:  # fit_wall_group's first verdict
            return ClosedGroup(WallFit(GROUP_TOO_FEW_POINTS, indices), points)
        fit = fit_group_points(
            points, apcs_kernels.wrapped_angles(np.array(directions)), indices, self.params
        )
        return ClosedGroup(fit, points)

    def _wall_verdict(self, group: _RawGroup) -> ClosedGroup | None:
        """:meth:`_verdict` of a closed group if it holds a verified wall, else ``None``
        (without building the verdict of a group too small to fit)."""
        if len(group[0]) < self.params.min_group_size:
            return None
        closed = self._verdict(group)
        return closed if closed.fit.wall is not None else None


# --------------------------------------------------------------------------------------------
# The Fig. 2 loop
# --------------------------------------------------------------------------------------------

# A side's rows from a reading on, as one flat list of floats (WallStream._pending_rows):
# per reading, the columns of apcs_kernels.ERP_COLUMNS.
_ROW_WIDTH = len(apcs_kernels.ERP_COLUMNS)
_SENSOR_X, _SENSOR_Y, _ERP_X, _ERP_Y, _DIRECTION, _VALID = range(_ROW_WIDTH)


@dataclass(frozen=True)
class WallHandling:
    """One detected wall and what APCS did with it (Fig. 2).

    Attributes:
        side: ``"left"`` or ``"right"``.
        group: the closed ERP group with its wall.
        match: the matching against the map (sec. 4.3).
        reason: ``None`` when matched, else why not (:func:`rejection_reason`).
        correction: the correction result (status ``"ok"`` when the pose was corrected).
        pose_before, pose_after: the estimate before and after (equal without a correction).
        command_index: the command after which the reading that closed the group was taken
            (-1 for a flush before any command of the run).
    """

    side: str
    group: ClosedGroup
    match: MatchResult
    reason: str | None
    correction: CorrectionResult
    pose_before: Pose
    pose_after: Pose
    command_index: int

    @classmethod
    def unchecked(
        cls,
        side: str,
        group: ClosedGroup,
        match: MatchResult,
        reason: str | None,
        correction: CorrectionResult,
        pose_before: Pose,
        pose_after: Pose,
        command_index: int,
    ) -> WallHandling:
        """``WallHandling(side, group, ...)``, its fields set as its ``__init__`` sets them
        (frozen: straight into ``__dict__``) at a fraction of the cost."""
        return unchecked_instance(
            cls,
            side=side,
            group=group,
            match=match,
            reason=reason,
            correction=correction,
            pose_before=pose_before,
            pose_after=pose_after,
            command_index=command_index,
        )


@dataclass
class RunResult:
    """What :meth:`APCSTracker.run` did over a run of commands.

    Attributes:
        estimated_path: ``(K, 3)`` the estimate after each command (before a correction made
            at that command's reading).
        erps: ``(x, y, side)`` of every ERP, in the frame of the estimate when computed.
        walls: every verified wall, in order.
        dropped: per side, closed groups that failed the size or variance test.
        consumed: how many of the run's commands were dead-reckoned and sensed.
    """

    estimated_path: FloatArray
    consumed: int = 0
    erps: list[tuple[float, float, str]] = field(default_factory=list)
    walls: list[WallHandling] = field(default_factory=list)
    dropped: dict[str, int] = field(default_factory=lambda: {"left": 0, "right": 0})


class APCSTracker:
    """The APCS estimate, its covariance and the two side streams, updated as the robot moves.

    Args:
        wall_map: the map's oriented wall vectors (sec. 4.1); a
            :class:`~sonar_gym.localization.apcs_walls.WallMap` is used as it is (it is
            read-only, so trackers can share one), any other sequence is made one.
        estimate, covariance: the initial estimate ({W}) and its 3x3 covariance.
        wheel_base_m: the wheel base the dead reckoning assumes, metres.
        variance_per_m: each wheel's variance per metre rolled, m^2/m (``odometry.predict_run``).
        range_variance_m2, bearing_variance_rad2: the fixed ``sigma_r`` and ``sigma_xi``.
        measurement_variances: ``"fixed"`` or ``"fit"`` (:func:`fit_measurement_variances`).
        correction_method: ``"paper"`` (eqs 11-14) or ``"linear"``.
        params: APCS thresholds (sec. 6).
    """

    def __init__(
        self,
        wall_map: Sequence[WallVector],
        estimate: Pose,
        covariance: npt.ArrayLike,
        *,
        wheel_base_m: float,
        variance_per_m: float,
        range_variance_m2: float,
        bearing_variance_rad2: float,
        measurement_variances: str = "fixed",
        correction_method: str = "paper",
        params: APCSParameters = DEFAULT_PARAMETERS,
    ) -> None:
        if measurement_variances not in MEASUREMENT_VARIANCES:
            raise ValueError(
                "argument 'measurement_variances' must be one of "
                f"{list(MEASUREMENT_VARIANCES)}; got {measurement_variances!r}"
            )
        if correction_method not in CORRECTION_METHODS:
            raise ValueError(
                f"argument 'correction_method' must be one of {list(CORRECTION_METHODS)}; "
                f"got {correction_method!r}"
            )
        self.wall_map = wall_map if isinstance(wall_map, WallMap) else WallMap(tuple(wall_map))
        self.estimate = estimate
        self.covariance = checked_array(covariance, "covariance", (3, 3)).copy()
        # Checked once here: dead reckoning and the Joseph-form corrections keep it so.
        validated_covariance(self.covariance)
        self.wheel_base_m = checked_positive(wheel_base_m, "wheel_base_m")
        self.variance_per_m = float(variance_per_m)
        self.fixed_variances = (
            checked_positive(range_variance_m2, "range_variance_m2"),
            checked_positive(bearing_variance_rad2, "bearing_variance_rad2"),
        )
        self._set_up(measurement_variances, correction_method, params)

    @classmethod
    def unchecked(
        cls,
        wall_map: WallMap,
        estimate: Pose,
        covariance: FloatArray,
        *,
        wheel_base_m: float,
        variance_per_m: float,
        range_variance_m2: float,
        bearing_variance_rad2: float,
        measurement_variances: str = "fixed",
        correction_method: str = "paper",
        params: APCSParameters = DEFAULT_PARAMETERS,
    ) -> APCSTracker:
        """The tracker the constructor makes of arguments it accepts, without the checks.

        For a caller whose arguments are valid by construction: a
        :class:`~sonar_gym.localization.apcs_walls.WallMap`, a finite float64 ``(3, 3)``
        covariance within the constructor's symmetry tolerance and positive definite (it is
        copied), a finite positive wheel base (metres) and variances (m^2, rad^2), and
        ``measurement_variances``, ``correction_method`` among the constructor's choices.
        """
        tracker = cls.__new__(cls)
        tracker.wall_map = wall_map
        tracker.estimate = estimate
        tracker.covariance = np.array(covariance, dtype=np.float64)
        tracker.wheel_base_m = float(wheel_base_m)
        tracker.variance_per_m = float(variance_per_m)
        tracker.fixed_variances = (float(range_variance_m2), float(bearing_variance_rad2))
        tracker._set_up(measurement_variances, correction_method, params)
        return tracker

    def _set_up(
        self, measurement_variances: str, correction_method: str, params: APCSParameters
    ) -> None:
        """The settings and the two empty side streams, the last step of construction."""
        self.measurement_variances = measurement_variances
        self.correction_method = correction_method
        self.params = params
        self.streams = {side: WallStream(side, params) for side in SIDE_NAMES}

    def run(
        self,
        encoder_left_m: npt.ArrayLike,
        encoder_right_m: npt.ArrayLike,
        sample_commands: npt.ArrayLike = (),
        readings: Mapping[str, npt.ArrayLike] | None = None,
        sensor_offset_m: float = 0.0,
        stops: Sequence[int] = (),
    ) -> RunResult:
        """Dead-reckon over a run of commands and run Fig. 2 on the readings taken along it.

        Args:
            encoder_left_m, encoder_right_m: ``(K,)`` encoder increments of each command, metres.
            sample_commands: ``(M,)`` increasing indices of the commands after which the side
                sonars took a reading.
            readings: per active side, ``(M,)`` ranges in metres (NaN = dropout); at each
                reading instant ``left`` is handled before ``right``.
            sensor_offset_m: distance of each sensor from the robot centre along {R}'s y axis.
            stops: increasing command counts at which the run may stop: after a correction
                the run goes on to the next of them and stops there (the commands after it
                were planned from the estimate before the correction).

        Returns:
            The estimated path, the ERPs and the walls handled, and how many commands were
            consumed. ``estimate`` and ``covariance`` are those after the last consumed command.
        """
        left = checked_array(encoder_left_m, "encoder_left_m", (None,))
        right = checked_array(encoder_right_m, "encoder_right_m", (len(left),))
        samples = np.asarray(sample_commands, dtype=np.int64).reshape(-1)
        if samples.size and (
            samples[0] < 0 or samples[-1] >= len(left) or np.any(np.diff(samples) <= 0)
        ):
            raise ValueError(
                "argument 'sample_commands' must hold increasing command indices in "
                f"[0, {len(left)}); got {samples!r}"
            )
        ranges: dict[str, FloatArray] = {}
        for side, values in (readings or {}).items():
            _check_side(side)
            array = np.asarray(values, dtype=np.float64)
            if array.shape != samples.shape:
                raise ValueError(
                    f"argument 'readings[{side!r}]' must have shape {samples.shape}; "
                    f"got {array.shape}"
                )
            _check_ranges(array, f"readings[{side!r}]")
            ranges[side] = array
        return self.run_unchecked(left, right, samples, ranges, sensor_offset_m, stops)

    def run_unchecked(
        self,
        encoder_left_m: FloatArray,
        encoder_right_m: FloatArray,
        sample_commands: npt.NDArray[np.int64],
        readings: Mapping[str, FloatArray],
        sensor_offset_m: float,
        stops: Sequence[int],
    ) -> RunResult:
        """:meth:`run` on checked arguments: finite float64 ``(K,)`` encoder increments
        (metres), ``(M,)`` int64 increasing command indices in ``[0, K)``, per side in
        :data:`SIDE_NAMES` float64 ``(M,)`` ranges ``>= 0`` metres (NaN = dropout)."""
        left, right, samples, ranges = encoder_left_m, encoder_right_m, sample_commands, readings
        sides = tuple(side for side in SIDE_NAMES if side in ranges)
        # The estimate, covariance and wheel base were checked on construction and stay so.
        variance_per_m = checked_variance_per_m(self.variance_per_m)
        poses, covariances = predict_run_unchecked(
            self.estimate, self.covariance, left, right, self.wheel_base_m, variance_per_m
        )
        result = RunResult(estimated_path=poses[1:].copy(), consumed=len(left))
        limit = len(left)
        # Events in time order: (sample, side). Pending ERPs are valid until a correction.
        events = [(m, side) for m in range(len(samples)) for side in sides]
        sample_list: list[int] = samples.tolist()
        range_lists = {side: ranges[side].tolist() for side in sides}
        event = 0
        while event < len(events) and sample_list[events[event][0]] < limit:
            first_sample = events[event][0]
            reachable = bisect.bisect_left(sample_list, limit)  # a correction stops at `limit`
            rows = poses[samples[first_sample:reachable] + 1]
            # Flat lists of floats, six a reading: no list per row to allocate.
            pending: dict[str, list[float]] = {
                side: self.streams[side]._pending_rows(
                    _sensor_positions(rows, side, sensor_offset_m),
                    rows[:, 2],
                    ranges[side][first_sample:reachable],
                )
                for side in sides
            }
            headings = rows[:, 2].tolist()
            # WallStream.accept on plain floats. Each side's latest reading (its sample) is
            # stored in its stream only where the stored reading is read: before a verified
            # wall is handled (a correction moves the streams) and when this pass ends.
            unstored: dict[str, int] = {}
            corrected = False
            while event < len(events) and not corrected and sample_list[events[event][0]] < limit:
                m, side = events[event]
                event += 1
                unstored[side] = m
                erp_rows = pending[side]
                at = _ROW_WIDTH * (m - first_sample)
                if erp_rows[at + _VALID] == 0.0:
                    continue
                point_x, point_y = erp_rows[at + _ERP_X], erp_rows[at + _ERP_Y]
                result.erps.append((point_x, point_y, side))
                closed = self.streams[side]._grouped(point_x, point_y, erp_rows[at + _DIRECTION])
                if closed:
                    walls = self._verified_walls(side, closed, result)
                    # Only a verified wall reads the estimate (most closed groups are dropped);
                    # the end of the run sets it in any case.
                    if walls:
                        command = sample_list[m]
                        self._store_readings(unstored, pending, headings, range_lists, first_sample)
                        self.estimate = Pose.unchecked(*poses[command + 1].tolist())
                        self.covariance = covariances[command + 1]
                        corrected = self.handle_groups(side, walls, command, result)
            self._store_readings(unstored, pending, headings, range_lists, first_sample)
            if corrected:
                command = sample_list[events[event - 1][0]]
                later_stops = [stop for stop in stops if stop > command]
                if later_stops:
                    limit = min(limit, later_stops[0])
                # dead reckoning from the corrected estimate, up to where the run now stops
                tail_poses, tail_covariances = predict_run_unchecked(
                    self.estimate,
                    self.covariance,
                    left[command + 1 : limit],
                    right[command + 1 : limit],
                    self.wheel_base_m,
                    variance_per_m,
                )
                poses = np.vstack([poses[: command + 1], tail_poses])
                covariances = np.concatenate([covariances[: command + 1], tail_covariances])
                result.estimated_path[command + 1 : limit] = tail_poses[1:]
        if limit < len(left):
            result.consumed = limit
            result.estimated_path = result.estimated_path[:limit]
        if limit:
            self.estimate = Pose.unchecked(*poses[limit].tolist())
            self.covariance = covariances[limit].copy()
        return result

    def _verified_walls(
        self, side: str, closed: Sequence[_RawGroup], result: RunResult
    ) -> list[ClosedGroup]:
        """The groups of ``closed`` (from ``side``'s stream) that hold a verified wall, in
        order; the others are counted in ``result.dropped``, as :meth:`handle_groups` counts
        them (it only counts a dropped group, so its verdict object is not built)."""
        stream = self.streams[side]
        min_group_size = self.params.min_group_size
        walls = []
        for group in closed:
            # most closed groups are too small to fit: dropped without a call
            too_small = len(group[0]) < min_group_size
            verdict = None if too_small else stream._wall_verdict(group)
            if verdict is None:
                result.dropped[side] += 1
            else:
                walls.append(verdict)
        return walls

    def _store_readings(
        self,
        unstored: dict[str, int],
        pending: Mapping[str, list[float]],
        headings: list[float],
        range_lists: Mapping[str, list[float]],
        first_sample: int,
    ) -> None:
        """Store each side's latest reading (``unstored``: side -> its sample) in its stream
        (:meth:`WallStream._remember`), from the plain-float rows of a pass of
        :meth:`run_unchecked` that starts at sample ``first_sample``; ``unstored`` is emptied."""
        for side, m in unstored.items():
            erp_rows = pending[side]
            row = m - first_sample
            at = _ROW_WIDTH * row
            self.streams[side]._remember(
                erp_rows[at + _SENSOR_X],
                erp_rows[at + _SENSOR_Y],
                headings[row],
                range_lists[side][m],
            )
        unstored.clear()

    def flush(self, side: str, result: RunResult | None = None) -> RunResult:
        """Stop ``side``'s sonar: close its open group and handle it (Fig. 2)."""
        result = RunResult(np.zeros((0, 3))) if result is None else result
        self.handle_groups(_check_side(side), self.streams[side].flush(), -1, result)
        return result

    def handle_groups(
        self, side: str, groups: Sequence[ClosedGroup], command_index: int, result: RunResult
    ) -> bool:
        """Match every verified wall and correct the estimate on a unique match (Fig. 2).

        Returns:
            Whether the estimate was corrected.
        """
        corrected = False
        for group in groups:
            fit = group.fit
            if fit.wall is None:
                result.dropped[side] += 1
                continue
            before = self.estimate
            sigma_r, sigma_xi = fit_measurement_variances(
                group, before, self.fixed_variances, self.measurement_variances
            )
            prior = symmetrized(self.covariance)
            prior.setflags(write=False)
            match, correction = correct_with_checked_wall(
                before,
                prior,
                fit.wall,
                self.wall_map,
                sigma_r,
                sigma_xi,
                self.params,
                method=self.correction_method,  # type: ignore[arg-type]
            )
            after = self._apply(correction)
            corrected = corrected or after is not before
            result.walls.append(
                WallHandling.unchecked(
                    side,
                    group,
                    match,
                    rejection_reason(match),
                    correction,
                    before,
                    after,
                    command_index,
                )
            )
        return corrected

    def _apply(self, correction: CorrectionResult) -> Pose:
        before = self.estimate
        if correction.status != OK or correction.pose is None:
            return before
        after = correction.pose
        self.estimate = after
        self.covariance = np.array(correction.covariance, dtype=np.float64)
        move = _frame_move(before, after)  # one move for both streams
        for stream in self.streams.values():
            stream._move(*move)
        return after


def _sensor_positions(poses: FloatArray, side: str, offset_m: float) -> FloatArray:
    """``(n, 2)`` positions of ``side``'s sensor for rows ``[x, y, theta]`` of ``poses``."""
    if offset_m == 0.0:
        return poses[:, :2].copy()
    sign = 1.0 if side == "left" else -1.0
    angle = poses[:, 2] + sign * math.pi / 2.0
    beam = np.empty((len(poses), 2))  # np.column_stack's table, without its Python overhead
    beam[:, 0] = np.cos(angle)
    beam[:, 1] = np.sin(angle)
    return poses[:, :2] + offset_m * beam


__all__ = [
    "BEAM_OFFSET_RAD",
    "SIDE_NAMES",
    "APCSTracker",
    "ClosedGroup",
    "DetectedWall",
    "RunResult",
    "WallHandling",
    "WallStream",
    "fit_measurement_variances",
    "nearest_facing_walls",
    "rejection_reason",
]
