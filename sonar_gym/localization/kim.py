"""Kim, Lee & Jeong: voting localization on a certainty grid, with odometry and an EKF.

Kim, Lee & Jeong, *Self localization of mobile robot using sonar sensing and map building*.
This module holds the voting localization of sec. 3.3 and re-exports the rest of the method:

- :mod:`sonar_gym.localization.ekf` (also as ``kim_ekf``): odometry prediction with
  covariance (sec. 3.1) and the EKF correction (sec. 3.2);
- :mod:`sonar_gym.localization.kim_grid`: the occupancy / certainty grid (sec. 2.2) and the
  servo sweeps.

Voting (sec. 3.3). "Apply the end of each vector to an occupied cell; if the vector is
unobstructed, increase the certainty value (or vote) of the cell at the start of the vector.
This procedure is repeated for all occupied cells and range vectors." Here, for a candidate
heading ``psi`` of the robot and a reading whose end point is ``e`` in the robot frame, the
hypothesis "this reading ended at occupied cell ``c``" puts the robot at ``t = c - R(psi) e``
and adds a vote to the cell holding ``t`` when the ray from the sensor to ``c`` is unobstructed.

Choices the paper leaves open, and the ones made here:

- *Unobstructed*: no occupied cell (and no point outside the grid) on the ray between the
  sensor and ``c``, sampled every half cell from ``end_clearance_m`` (one cell by default)
  before ``c`` back to the sensor. The clearance skips ``c`` itself and the neighbouring cells
  of the same wall, which a ray meeting a wall obliquely crosses just before its end cell. The
  test is tabulated once per grid as the free distance behind every occupied cell in
  ``direction_bins`` directions (1 degree by default), so voting is a table look-up.
- *Headings*: the paper does not search heading; here the heading of the robot is searched over
  candidates: given ``heading_candidates``; else the prior heading of ``search_center`` +- the
  heading window (10 degrees) in steps of ``heading_step_rad`` (1 degree); else the full circle
  in that step.
- *Several sweeps* (sec. 3.3: "between two and four sweeps"): each sweep's readings are moved
  into the robot frame of the FIRST sweep through ``Sweep.odometry`` (dead reckoning), so every
  reading votes for the pose of the first sweep. That pose is ``VoteLocalization.pose``; the
  pose of the last sweep, through the same odometry, is ``last_sweep_pose``.
- *Best cell* ("not always as straightforward as simply choosing the cell with the highest
  certainty value"): ``selection="smoothed"`` (default) takes the maximum of the vote map
  smoothed by a 3x3 binomial kernel ``[1 2 1]^T [1 2 1]`` over all candidate headings, so a peak
  spread over neighbouring cells beats an isolated spike; ``selection="max"`` is the raw
  maximum, ties broken by the heading with most tied cells and, within it, the tied cell
  nearest to the centroid of the tied cells. The position is then refined (``refine=
  "vote_mean"``, default) to the mean of the continuous vote positions inside the 3x3 window
  around the chosen cell at the chosen heading, or kept at the cell centre (``"cell_center"``,
  with ``"max"``: the centroid of the tied cells). The heading is the chosen candidate.
- *Where a vector ends in its cell*: ``anchor="cell_center"`` (default, the paper's reading)
  applies the end of the vector to the cell centre. A wall lying on a cell edge then shifts the
  votes of every reading off it by half a cell; ``anchor="obstacle_point"`` (offered beside it)
  applies it to ``OccupancyGrid.obstacle_points_m``, where the obstacle lies inside the cell.
- *Resolution*: the end points are known to a cell only, so votes spread by about half a cell
  along each surface; a heading error ``d`` moves a vote by ``range * d``. With 5 cm cells one
  90-degree sweep resolves the heading to about 1-2 degrees; several sweeps do better.
- *Ambiguity* (optional, ``ambiguity_ratio``): when a rival peak farther than
  ``ambiguity_distance_m`` or ``ambiguity_heading_rad`` from the winner scores at least
  ``ambiguity_ratio`` times the winner's score, the status is ``"ambiguous"``.

Statuses: ``"ok"``; ``"empty_sweep"`` (no reading with an echo); ``"no_votes"`` (the grid has no
occupied cell, or no hypothesis was unobstructed inside the grid and search circle);
``"ambiguous"``.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Literal

import numpy as np
import numpy.typing as npt

from sonar_gym.frozen import unchecked_instance
from sonar_gym.localization.ekf import (
    INTEGRATIONS,
    Integration,
    ekf_update,
    jacobian_state,
    jacobian_wheels,
    motion_model,
    predict,
    proportional_encoder_noise,
)
from sonar_gym.localization.kim_grid import (
    PAPER_CELL_SIZE_M,
    Bounds,
    OccupancyGrid,
    Sweep,
    sweep_end_points,
)
from sonar_gym.localization import kim_kernels
from sonar_gym.localization.result import OK, Localization
from sonar_gym.pose import FloatArray, Pose, wrap_angles

__all__ = [
    "DEFAULT_HEADING_STEP_RAD",
    "DEFAULT_HEADING_WINDOW_RAD",
    "INTEGRATIONS",
    "PAPER_CELL_SIZE_M",
    "TABLE_1_ESTIMATED_POSITIONS_M",
    "TABLE_1_TRUE_POSITIONS_M",
    "Bounds",
    "Integration",
    "OccupancyGrid",
    "Sweep",
    "VoteLocalization",
    "ekf_update",
    "heading_candidates_around",
    "jacobian_state",
    "jacobian_wheels",
    "motion_model",
    "predict",
    "proportional_encoder_noise",
    "sweep_end_points",
    "vote_localize",
    "vote_localize_unchecked",
]

EMPTY_SWEEP = "empty_sweep"
NO_VOTES = "no_votes"
AMBIGUOUS = "ambiguous"

TABLE_1_TRUE_POSITIONS_M: FloatArray = (
    np.array(
        [
            [2.50, 10.00],
            [45.00, 42.50],
            [22.50, 75.00],
            [107.50, 82.50],
            [185.00, 147.50],
            [192.50, 175.00],
            [180.00, 190.00],
        ]
    )
    / 100.0
)
"""Table 1 of sec. 4.1, true positions ``(x_r, y_r)``: printed in cm (the arena is 2 m), here m."""

TABLE_1_ESTIMATED_POSITIONS_M: FloatArray = (
    np.array(
        [
            [3.02, 10.57],
            [46.21, 45.41],
            [23.45, 70.97],
            [105.13, 84.21],
            [186.11, 148.46],
            [194.41, 176.44],
            [183.01, 193.21],
        ]
    )
    / 100.0
)
"""Table 1 of sec. 4.1, the paper's estimates ``(x_e, y_e)`` of the same positions, m."""

DEFAULT_HEADING_STEP_RAD = math.radians(1.0)
"""Spacing of the candidate headings (1 degree)."""

DEFAULT_HEADING_WINDOW_RAD = math.radians(10.0)
"""Half-width of the heading window searched around a prior heading (10 degrees)."""

Selection = Literal["smoothed", "max"]
Refinement = Literal["vote_mean", "cell_center"]
Anchor = Literal["cell_center", "obstacle_point"]
_ANCHORS = ("cell_center", "obstacle_point")
_SELECTIONS = ("smoothed", "max")
_REFINEMENTS = ("vote_mean", "cell_center")
Centre = tuple[float, float]
"""``(x, y)`` of the search circle's centre, {W}, metres."""


@dataclass(frozen=True, eq=False)
class VoteLocalization(Localization):
    """Outcome of :func:`vote_localize`.

    Attributes:
        votes: raw vote count (the certainty value of sec. 2.2 / 3.3) of the chosen cell at the
            chosen heading; 0 when nothing voted.
        vote_map: ``(nx, ny)`` raw votes at the chosen heading on the grid's cell layout
            (indexed ``[ix, iy]``), or None when not requested or nothing was voted.
        heading_rad: the chosen candidate heading of the first sweep's robot frame in {W}
            (rad); None unless ``status == "ok"``.
        last_sweep_pose: the pose of the last sweep, ``pose.compose(sweeps[-1].odometry)``;
            None unless ``status == "ok"``.
    """

    votes: int = 0
    vote_map: npt.NDArray[np.int64] | None = None
    heading_rad: float | None = None
    last_sweep_pose: Pose | None = None


def heading_candidates_around(
    prior_heading_rad: float,
    window_rad: float = DEFAULT_HEADING_WINDOW_RAD,
    step_rad: float = DEFAULT_HEADING_STEP_RAD,
) -> FloatArray:
    """Headings ``prior + k step`` for ``|k step| <= window``, wrapped to (-pi, pi] (rad)."""
    if not math.isfinite(float(prior_heading_rad)):
        raise ValueError(f"prior_heading_rad must be finite, got {prior_heading_rad!r}")
    if not (math.isfinite(float(step_rad)) and step_rad > 0.0):
        raise ValueError(f"heading_step_rad must be a finite angle > 0 rad, got {step_rad!r}")
    if not (math.isfinite(float(window_rad)) and window_rad >= 0.0):
        raise ValueError(f"heading_window_rad must be a finite angle >= 0 rad, got {window_rad!r}")
    return _headings_around(float(prior_heading_rad), float(window_rad), float(step_rad))


def _headings_around(prior_heading_rad: float, window_rad: float, step_rad: float) -> FloatArray:
    """:func:`heading_candidates_around` of checked floats (rad)."""
    count = math.floor(window_rad / step_rad + 1e-9)
    count = min(count, math.ceil(math.pi / step_rad))
    return kim_kernels.heading_grid(prior_heading_rad, step_rad, count)  # type: ignore[no-any-return]


# -- the unobstructed-ray table ---------------------------------------------------------------


class _FreeDistanceTable:
    """Free distance behind each occupied cell, per quantised beam direction.

    ``distance[d, k]`` is how far (m) a ray arriving at the centre of occupied cell ``k`` with
    direction ``2 pi d / n`` can be traced back, from ``end_clearance_m`` before the cell, before
    it meets another occupied cell or leaves the grid. Rows are filled on first use. The table
    keeps the grid's arrays, not the grid, so the per-grid cache below can let the grid go.
    """

    def __init__(self, grid: OccupancyGrid, direction_bins: int, end_clearance_m: float) -> None:
        nx, ny = grid.shape
        # A one-cell border of "blocked" stands for everything off the grid.
        self.blocked_cells = np.ones((nx + 2, ny + 2), dtype=bool)
        self.blocked_cells[1:-1, 1:-1] = grid.occupied
        self.origin_m = grid.origin_m
        self.cell_size_m = grid.cell_size_m
        self.direction_bins = direction_bins
        self.end_clearance_m = end_clearance_m
        # column-major: the x and y columns are contiguous for the per-vote gathers
        self.centers = np.asfortranarray(grid.occupied_centers())
        self.obstacle_points = np.asfortranarray(grid.occupied_obstacle_points())
        step = 0.5 * grid.cell_size_m
        x_min, y_min, x_max, y_max = grid.bounds
        longest = math.hypot(x_max - x_min, y_max - y_min) + 2.0 * step
        self.samples_m = end_clearance_m + step * np.arange(math.ceil(longest / step) + 1)
        # column-major: a vote looks up one cell under neighbouring headings, whose directions
        # are neighbouring rows; this keeps them in one or two cache lines
        self.distance = np.zeros((direction_bins, self.centers.shape[0]), order="F")
        self.filled = np.zeros(direction_bins, dtype=bool)
        self.complete = False

    def anchors(self, anchor: Anchor) -> FloatArray:
        """``(K, 2)`` anchor points (m) of the occupied cells: centres or obstacle points."""
        return self.centers if anchor == "cell_center" else self.obstacle_points

    def columns(self, direction_indices: npt.NDArray[np.intp]) -> FloatArray:
        """The table, with the given direction rows filled."""
        if self.complete or self.filled.take(direction_indices).all():
            return self.distance
        missing = np.unique(direction_indices[~self.filled[direction_indices]])
        if missing.size:
            self.distance[missing] = self._trace(missing)
            self.filled[missing] = True
            self.complete = bool(self.filled.all())
        return self.distance

    def _trace(self, directions: npt.NDArray[np.intp]) -> FloatArray:
        """March back from every cell centre in the given directions, every half cell
        (:func:`~sonar_gym.localization.kim_kernels.free_distances`)."""
        x0, y0 = self.origin_m
        cell_size = self.cell_size_m
        angles = 2.0 * np.pi * directions / self.direction_bins
        return kim_kernels.free_distances(  # type: ignore[no-any-return]
            -np.cos(angles),
            -np.sin(angles),
            (self.centers[:, 0] - x0) / cell_size,
            (self.centers[:, 1] - y0) / cell_size,
            self.samples_m / cell_size,
            self.samples_m,
            self.blocked_cells,
        )


_TABLES: weakref.WeakKeyDictionary[OccupancyGrid, dict[tuple[int, float], _FreeDistanceTable]] = (
    weakref.WeakKeyDictionary()
)


def _free_distance_table(
    grid: OccupancyGrid, direction_bins: int, end_clearance_m: float
) -> _FreeDistanceTable:
    tables = _TABLES.get(grid)
    if tables is None:
        tables = _TABLES[grid] = {}
    key = (direction_bins, end_clearance_m)
    if key not in tables:
        tables[key] = _FreeDistanceTable(grid, direction_bins, end_clearance_m)
    return tables[key]


# -- argument checks ----------------------------------------------------------------------------


def _check_sweeps(sweeps: Sequence[Sweep] | Sweep) -> list[Sweep]:
    if isinstance(sweeps, Sweep):
        return [sweeps]
    checked = list(sweeps)
    if not checked:
        raise ValueError("sweeps must hold at least one Sweep")
    for index, sweep in enumerate(checked):
        if not isinstance(sweep, Sweep):
            raise ValueError(f"sweeps[{index}] must be a Sweep, got {type(sweep).__name__}")
    first = checked[0].odometry
    if max(abs(first.x), abs(first.y), abs(first.theta)) > 1e-12:
        raise ValueError(
            "sweeps[0].odometry must be the identity Pose(0, 0, 0): odometry is measured from the "
            f"first sweep's pose, got {first}"
        )
    return checked


def _check_center(
    search_center: Pose | npt.ArrayLike | None,
) -> tuple[Centre | None, float | None]:
    """``(position, prior heading or None)`` of the search centre."""
    if search_center is None:
        return None, None
    if isinstance(search_center, Pose):
        return (search_center.x, search_center.y), search_center.theta
    values = np.asarray(search_center, dtype=np.float64)
    if values.shape not in ((2,), (3,)) or not np.all(np.isfinite(values)):
        raise ValueError(
            f"search_center must be a Pose or a finite (x, y[, theta]), got {search_center!r}"
        )
    return (float(values[0]), float(values[1])), (float(values[2]) if values.size == 3 else None)


def _resolve_headings(
    heading_candidates: npt.ArrayLike | None,
    prior_heading: float | None,
    heading_step_rad: float,
    heading_window_rad: float,
) -> FloatArray:
    if heading_candidates is not None:
        headings = np.asarray(heading_candidates, dtype=np.float64).reshape(-1)
        if headings.size == 0 or not np.all(np.isfinite(headings)):
            raise ValueError("heading_candidates must be a non-empty array of finite angles (rad)")
        return wrap_angles(headings)
    if prior_heading is not None:
        return heading_candidates_around(prior_heading, heading_window_rad, heading_step_rad)
    if not (math.isfinite(float(heading_step_rad)) and heading_step_rad > 0.0):
        raise ValueError(
            f"heading_step_rad must be a finite angle > 0 rad, got {heading_step_rad!r}"
        )
    count = max(1, math.ceil(2.0 * math.pi / heading_step_rad - 1e-9))
    return wrap_angles(-math.pi + 2.0 * math.pi * np.arange(count) / count)


# -- voting -------------------------------------------------------------------------------------


@dataclass(slots=True)
class _Readings:
    """All valid readings moved into the first sweep's robot frame."""

    end_x: FloatArray  # (J,) end points (m)
    end_y: FloatArray
    beam_rad: FloatArray  # (J,) beam directions (rad)
    range_m: FloatArray  # (J,) ranges (m)

    @property
    def end_xy(self) -> FloatArray:
        """``(J, 2)`` end points (m)."""
        return np.column_stack((self.end_x, self.end_y))


def _gather_readings(sweeps: Sequence[Sweep], max_range_m: float | None) -> _Readings:
    """The readings of every sweep with an echo, as :func:`sweep_end_points` of each sweep at
    its odometry, concatenated (the same arithmetic, element by element, in one pass: compiled
    loops around numpy's ``cos`` and ``sin`` of the beams)."""
    angle_rows: list[FloatArray] = []
    range_rows: list[FloatArray] = []
    counts: list[int] = []
    frames: list[tuple[float, float, float]] = []
    for sweep in sweeps:
        ranges = sweep.ranges
        angle_rows.append(sweep.angles)
        range_rows.append(ranges)
        counts.append(ranges.size)
        # heading and sensor position of the sweep, in the first sweep's frame
        pose = sweep.odometry
        offset_x, offset_y = sweep.sensor_offset
        c, s = math.cos(pose.theta), math.sin(pose.theta)
        frames.append(
            (pose.theta, pose.x + c * offset_x - s * offset_y, pose.y + s * offset_x + c * offset_y)
        )
    # one sweep's own read-only arrays serve as they are: the loops only read them
    angles = angle_rows[0] if len(angle_rows) == 1 else np.concatenate(angle_rows)
    ranges = range_rows[0] if len(range_rows) == 1 else np.concatenate(range_rows)
    sweep_frames = np.array(frames)
    max_range = math.inf if max_range_m is None else float(max_range_m)
    sweep_counts = np.array(counts)
    beam = kim_kernels.echo_beams(angles, ranges, sweep_counts, sweep_frames, max_range)
    rows = kim_kernels.echo_end_points(
        ranges, sweep_counts, sweep_frames, np.cos(beam), np.sin(beam), max_range
    )
    return _Readings(rows[0], rows[1], beam, rows[2])


def _direction_index(
    headings: FloatArray, readings: _Readings, direction_bins: int
) -> npt.NDArray[np.intp]:
    """``(h, J)`` quantised world beam direction of every reading under every heading."""
    return kim_kernels.direction_indices(  # type: ignore[no-any-return]
        headings, readings.beam_rad, direction_bins, direction_bins / (2.0 * np.pi)
    )


def _heading_spread(headings: FloatArray) -> tuple[float, float] | None:
    """The middle candidate heading and the largest angle from it to another candidate
    (radians, padded by 1e-6), or ``None`` when the candidates span half a turn or more and
    no pair can be dropped for its heading (:func:`~sonar_gym.localization.kim_kernels.
    candidate_pairs`)."""
    if headings.size == 0:
        return None
    middle = float(headings[headings.size // 2])
    spread = kim_kernels.heading_offset(headings) + 1e-6
    return None if spread >= np.pi else (middle, spread)


def _pair_test(
    center: Centre | None, radius: float | None, headings: FloatArray
) -> tuple[tuple[float, float, float], tuple[bool, float, float, float, float]]:
    """The search circle ``(centre x, centre y, radius)`` ({W}, metres) and the heading test
    ``(by heading, middle cos, middle sin, spread cos, spread sin)`` of
    :func:`~sonar_gym.localization.kim_kernels.candidate_pairs`; without a search circle an
    infinite one and no heading test, which keep every pair."""
    circle = _search_circle(center, radius)
    if center is None or radius is None:
        return circle, (False, 1.0, 0.0, 1.0, 0.0)
    return circle, _heading_test(headings)


def _heading_test(headings: FloatArray) -> tuple[bool, float, float, float, float]:
    """The heading test of :func:`_pair_test` within a search circle."""
    spread = _heading_spread(headings)
    middle, angle = (0.0, 0.0) if spread is None else spread
    return (
        spread is not None,
        math.cos(middle),
        math.sin(middle),
        math.cos(angle),
        math.sin(angle),
    )


def _candidate_pairs(
    readings: _Readings,
    anchors: FloatArray,
    center: Centre | None,
    radius: float | None,
    headings: FloatArray,
) -> tuple[npt.NDArray[np.intp], npt.NDArray[np.intp]]:
    """``(reading index, anchor index)`` of the pairs that can vote inside the search circle
    under one of the ``headings``, reading-major and anchors ascending (the order of the full
    ``(J, K)`` product, so votes and their sums are unchanged); every pair without a search
    circle. The tests are those of :func:`~sonar_gym.localization.kim_kernels.candidate_pairs`.
    """
    circle, heading_test = _pair_test(center, radius, headings)
    return kim_kernels.candidate_pairs(  # type: ignore[no-any-return]
        readings.end_x, readings.end_y, anchors, *circle, *heading_test
    )


@dataclass(slots=True)
class _VoteWindow:
    """The block of grid cells ``low .. low + shape - 1`` that holds every counted vote.

    Votes are counted in this block only; with a search circle it is the circle's bounding
    box plus two cells (one for the 3x3 smoothing, one for rounding at the circle's edge), so
    the vote volume, its smoothing and the choice of the best cell cost what the circle
    covers, not the whole grid. Cells outside hold no vote and score zero, and the block keeps
    the grid's (ix, iy) order, so every maximum and tie-break is the one of the full grid.
    """

    low: tuple[int, int]
    shape: tuple[int, int]

    def full(self, grid: OccupancyGrid, block: npt.NDArray[np.int64]) -> npt.NDArray[np.int64]:
        """``block`` (``(..., wx, wy)``) placed in a zero array over the whole grid."""
        whole = np.zeros((*block.shape[:-2], *grid.shape), dtype=block.dtype)
        (x, y), (wx, wy) = self.low, self.shape
        whole[..., x : x + wx, y : y + wy] = block
        return whole

    @property
    def cells(self) -> tuple[int, int, int, int]:
        """``(low x, low y, high x, high y)``, inclusive cell indices of the whole grid."""
        (x, y), (wx, wy) = self.low, self.shape
        return x, y, x + wx - 1, y + wy - 1


def _vote_window(grid: OccupancyGrid, center: Centre | None, radius: float | None) -> _VoteWindow:
    """The :class:`_VoteWindow` of a search circle (the whole grid without one)."""
    nx, ny = grid.shape
    if center is None or radius is None:
        return _VoteWindow((0, 0), (nx, ny))
    x0, y0 = grid.origin_m
    size = grid.cell_size_m
    low_x = max(math.floor((center[0] - radius - x0) / size) - 2, 0)
    low_y = max(math.floor((center[1] - radius - y0) / size) - 2, 0)
    high_x = min(math.floor((center[0] + radius - x0) / size) + 2, nx - 1)
    high_y = min(math.floor((center[1] + radius - y0) / size) + 2, ny - 1)
    if high_x < low_x or high_y < low_y:
        return _VoteWindow((0, 0), (0, 0))
    return _VoteWindow((low_x, low_y), (high_x - low_x + 1, high_y - low_y + 1))


def _vote_layout(
    grid: OccupancyGrid, window: _VoteWindow, center: Centre | None, radius: float | None
) -> tuple[tuple[float, float, float], tuple[float, float, float], tuple[int, int, int, int]]:
    """The compiled vote loops' ``(circle, grid_frame, window)``
    (:mod:`~sonar_gym.localization.kim_kernels`): the search circle (an infinite radius
    without one), the grid's origin and cell size, and the window's cells."""
    (x0, y0), size = grid.origin_m, grid.cell_size_m
    return _search_circle(center, radius), (float(x0), float(y0), float(size)), window.cells


def _search_circle(center: Centre | None, radius: float | None) -> tuple[float, float, float]:
    """``(centre x, centre y, radius)`` of the search circle ({W}, metres); without one an
    infinite circle, which every vote lies in."""
    if center is None or radius is None:
        return 0.0, 0.0, math.inf
    return float(center[0]), float(center[1]), float(radius)


def _failure(status: str, message: str) -> VoteLocalization:
    return VoteLocalization(status=status, message=message)


def vote_localize(
    grid: OccupancyGrid,
    sweeps: Sequence[Sweep] | Sweep,
    heading_candidates: npt.ArrayLike | None = None,
    search_center: Pose | npt.ArrayLike | None = None,
    search_radius: float | None = None,
    *,
    heading_step_rad: float = DEFAULT_HEADING_STEP_RAD,
    heading_window_rad: float = DEFAULT_HEADING_WINDOW_RAD,
    max_range_m: float | None = None,
    end_clearance_m: float | None = None,
    direction_bins: int = 360,
    selection: Selection = "smoothed",
    refine: Refinement = "vote_mean",
    anchor: Anchor = "cell_center",
    ambiguity_ratio: float | None = None,
    ambiguity_distance_m: float = 0.15,
    ambiguity_heading_rad: float = math.radians(10.0),
    return_vote_map: bool = True,
) -> VoteLocalization:
    """Voting localization of sec. 3.3 on a known occupancy grid.

    Args:
        grid: the global map with its occupied cells.
        sweeps: one to (typically) four sweeps; ``sweeps[0].odometry`` must be the identity and
            each later sweep's odometry is its dead-reckoned pose in the first sweep's frame.
        heading_candidates: headings (rad, {W}) of the first sweep's robot frame to try. None:
            around the heading of ``search_center`` if it has one, else the full circle.
        search_center: the dead-reckoning estimate, a :class:`Pose` or ``(x, y[, theta])`` in
            {W}; its heading (if any) centres the heading window.
        search_radius: if given, votes count only within this distance (m) of
            ``search_center`` (sec. 3.3: "restricted ... within a circle").
        heading_step_rad: spacing of generated candidate headings (rad).
        heading_window_rad: half-width of the window around a prior heading (rad).
        max_range_m: readings at or beyond this range (m) count as no echo.
        end_clearance_m: length before the end cell over which the ray is not checked for
            obstruction (m); one cell by default.
        direction_bins: number of quantised beam directions of the obstruction table.
        selection: ``"smoothed"`` or ``"max"`` (see the module docstring).
        refine: ``"vote_mean"`` or ``"cell_center"`` (see the module docstring).
        anchor: where a range vector ends in an occupied cell: ``"cell_center"`` (the paper)
            or ``"obstacle_point"`` (``OccupancyGrid.obstacle_points_m``, the obstacle's
            position inside the cell, which removes the half-cell shift of walls lying on
            cell edges).
        ambiguity_ratio: in (0, 1]; enables the ambiguity test. None disables it.
        ambiguity_distance_m: a rival peak must be farther than this (m) ...
        ambiguity_heading_rad: ... or differ in heading by more than this (rad).
        return_vote_map: include the raw vote map of the chosen heading.

    Returns:
        A :class:`VoteLocalization`; ``pose`` is the pose of the first sweep's robot frame.
    """
    if not isinstance(grid, OccupancyGrid):
        raise ValueError(f"grid must be an OccupancyGrid, got {type(grid).__name__}")
    sweep_list = _check_sweeps(sweeps)
    center, prior_heading = _check_center(search_center)
    radius: float | None = None
    if search_radius is not None:
        radius = float(search_radius)
        if not (math.isfinite(radius) and radius > 0.0):
            raise ValueError(
                f"search_radius must be a finite distance > 0 m, got {search_radius!r}"
            )
        if center is None:
            raise ValueError("search_radius needs a search_center")
    if max_range_m is not None and not (float(max_range_m) > 0.0):
        raise ValueError(f"max_range_m must be > 0 m or None, got {max_range_m!r}")
    clearance = grid.cell_size_m if end_clearance_m is None else float(end_clearance_m)
    if not (math.isfinite(clearance) and clearance >= 0.0):
        raise ValueError(
            f"end_clearance_m must be a finite distance >= 0 m, got {end_clearance_m!r}"
        )
    if int(direction_bins) != direction_bins or direction_bins < 8:
        raise ValueError(f"direction_bins must be an integer >= 8, got {direction_bins!r}")
    if selection not in _SELECTIONS:
        raise ValueError(f"selection must be one of {_SELECTIONS}, got {selection!r}")
    if refine not in _REFINEMENTS:
        raise ValueError(f"refine must be one of {_REFINEMENTS}, got {refine!r}")
    if anchor not in _ANCHORS:
        raise ValueError(f"anchor must be one of {_ANCHORS}, got {anchor!r}")
    if ambiguity_ratio is not None and not (0.0 < float(ambiguity_ratio) <= 1.0):
        raise ValueError(f"ambiguity_ratio must lie in (0, 1] or be None, got {ambiguity_ratio!r}")
    if not (ambiguity_distance_m >= 0.0 and ambiguity_heading_rad >= 0.0):
        raise ValueError("ambiguity_distance_m and ambiguity_heading_rad must be >= 0")
    headings = _resolve_headings(
        heading_candidates, prior_heading, heading_step_rad, heading_window_rad
    )
    return _vote(
        grid,
        sweep_list,
        headings,
        center,
        radius,
        max_range_m,
        clearance,
        int(direction_bins),
        selection,
        refine,
        anchor,
        ambiguity_ratio,
        (ambiguity_distance_m, ambiguity_heading_rad),
        return_vote_map,
    )


def vote_localize_unchecked(
    grid: OccupancyGrid,
    sweeps: Sequence[Sweep],
    search_center: Pose,
    search_radius: float,
    *,
    heading_step_rad: float,
    heading_window_rad: float,
    max_range_m: float,
    anchor: Anchor,
) -> VoteLocalization:
    """``vote_localize(grid, sweeps, search_center=..., search_radius=..., heading_step_rad=...,
    heading_window_rad=..., max_range_m=..., anchor=..., return_vote_map=False)`` without the
    argument checks, the other arguments at their defaults.

    For callers that build the arguments from their own checked state (the EKF loop of
    :mod:`~sonar_gym.localization.kim_fix`): finite floats (metres, radians), a step and a
    radius > 0, a window >= 0, a list of :class:`Sweep` whose first odometry is the identity.
    Anything else is the caller's error.
    """
    headings = _headings_around(search_center.theta, heading_window_rad, heading_step_rad)
    return _smoothed_vote(
        grid,
        sweeps,
        headings,
        (search_center.x, search_center.y),
        search_radius,
        max_range_m,
        anchor,
    )


_EKF_LOOP_DIRECTION_BINS = 360
"""``vote_localize``'s default ``direction_bins``, the one of :func:`vote_localize_unchecked`."""


def _smoothed_vote(
    grid: OccupancyGrid,
    sweeps: Sequence[Sweep],
    headings: FloatArray,
    center: Centre,
    radius: float,
    max_range_m: float,
    anchor: Anchor,
) -> VoteLocalization:
    """:func:`_vote` with :func:`vote_localize_unchecked`'s fixed arguments (one cell of end
    clearance, 360 direction bins, ``selection="smoothed"``, ``refine="vote_mean"``, no
    ambiguity test, no vote map): the same steps and the same numbers, without the
    bookkeeping that only the other arguments need (:class:`_Choice`, the vote map)."""
    prepared = _vote_inputs(
        grid,
        sweeps,
        headings,
        center,
        radius,
        max_range_m,
        grid.cell_size_m,
        _EKF_LOOP_DIRECTION_BINS,
        anchor,
    )
    if isinstance(prepared, VoteLocalization):
        return prepared
    votes_of, window = prepared
    volume, peak, heading_index, local_x, local_y, count, mean_x, mean_y = _smoothed_fix(
        votes_of, _heading_test(headings)
    )
    # a vote adds 4 to the score of its own cell: the peak is 0 only when nothing voted
    if peak == 0:
        return _failure(NO_VOTES, _NOTHING_VOTED)
    heading = float(headings[heading_index])
    if count:
        # the mean of the chosen heading's votes in the chosen cells
        x, y = mean_x, mean_y
    else:
        # the centre of the chosen cell, as OccupancyGrid.cell_to_world
        (x0, y0), size = grid.origin_m, grid.cell_size_m
        x = x0 + (local_x + window.low[0] + 0.5) * size
        y = y0 + (local_y + window.low[1] + 0.5) * size
    pose = Pose.unchecked(x, y, heading)
    return _vote_fix(
        pose,
        int(volume[heading_index, local_x, local_y]),
        heading,
        pose.compose(sweeps[-1].odometry),
    )


def _vote_fix(
    pose: Pose, votes: int, heading_rad: float, last_sweep_pose: Pose
) -> VoteLocalization:
    """``VoteLocalization(status=OK, pose=pose, votes=votes, heading_rad=heading_rad,
    last_sweep_pose=last_sweep_pose)``, its fields set as the frozen dataclass sets them,
    without its per-field setters and its check (which a pose with ``"ok"`` passes)."""
    return unchecked_instance(
        VoteLocalization,
        status=OK,
        pose=pose,
        message="",
        votes=votes,
        vote_map=None,
        heading_rad=heading_rad,
        last_sweep_pose=last_sweep_pose,
    )


def _vote(
    grid: OccupancyGrid,
    sweep_list: Sequence[Sweep],
    headings: FloatArray,
    center: Centre | None,
    radius: float | None,
    max_range_m: float | None,
    clearance: float,
    direction_bins: int,
    selection: Selection,
    refine: Refinement,
    anchor: Anchor,
    ambiguity_ratio: float | None,
    ambiguity_reach: tuple[float, float],
    return_vote_map: bool,
) -> VoteLocalization:
    """:func:`vote_localize` of checked arguments: ``clearance`` is ``end_clearance_m``
    resolved, ``ambiguity_reach`` is ``(ambiguity_distance_m, ambiguity_heading_rad)``."""
    prepared = _vote_inputs(
        grid, sweep_list, headings, center, radius, max_range_m, clearance, direction_bins, anchor
    )
    if isinstance(prepared, VoteLocalization):
        return prepared
    votes_of, window = prepared
    # Vote volume over (heading, ix, iy) of the vote window.
    volume: npt.NDArray[np.int64] | None
    if selection == "smoothed":
        volume, choice = _smoothed_choice(grid, votes_of, window, center, radius, headings)
    else:
        volume, choice = _max_choice(grid, votes_of, window, center, radius, headings)
    if volume is None or choice is None:
        return _failure(NO_VOTES, _NOTHING_VOTED)
    low_x, low_y = window.low
    heading = float(headings[choice.heading_index])
    vote_map = window.full(grid, volume[choice.heading_index]) if return_vote_map else None
    votes = int(volume[choice.heading_index, choice.cell[0] - low_x, choice.cell[1] - low_y])

    if ambiguity_ratio is not None:
        rival = _rival_score(grid, choice, window, headings, *ambiguity_reach)
        if rival >= float(ambiguity_ratio) * choice.best_score:
            return VoteLocalization(
                status=AMBIGUOUS,
                message=(
                    f"a rival peak scores {rival} against the best {choice.best_score} "
                    f"(ratio threshold {ambiguity_ratio})"
                ),
                votes=votes,
                vote_map=vote_map,
            )

    x, y = choice.centre
    # the mean of the chosen heading's votes in the chosen cells: np.mean's own arithmetic
    # (one pairwise sum, one division)
    if refine == "vote_mean" and choice.vote_count:
        x, y = choice.vote_mean
    pose = Pose.unchecked(x, y, heading)
    return VoteLocalization(
        status=OK,
        pose=pose,
        votes=votes,
        vote_map=vote_map,
        heading_rad=heading,
        last_sweep_pose=pose.compose(sweep_list[-1].odometry),
    )


def _vote_inputs(
    grid: OccupancyGrid,
    sweep_list: Sequence[Sweep],
    headings: FloatArray,
    center: Centre | None,
    radius: float | None,
    max_range_m: float | None,
    clearance: float,
    direction_bins: int,
    anchor: Anchor,
) -> tuple[_VoteInputs, _VoteWindow] | VoteLocalization:
    """What the vote loops of one fix read, and the vote window; or the failure when the
    sweeps returned no echo, the grid has no occupied cell or the window is empty."""
    readings = _gather_readings(sweep_list, max_range_m)
    if readings.range_m.size == 0:
        return _failure(EMPTY_SWEEP, "no reading of the sweeps returned an echo")
    table_cache = _free_distance_table(grid, direction_bins, clearance)
    anchors = table_cache.anchors(anchor)
    if anchors.shape[0] == 0:
        return _failure(NO_VOTES, "the grid has no occupied cell")
    window = _vote_window(grid, center, radius)
    if window.shape[0] * window.shape[1] == 0:
        return _failure(NO_VOTES, _NOTHING_VOTED)
    direction_index = _direction_index(headings, readings, direction_bins)
    votes_of = _VoteInputs(
        readings,
        anchors,
        direction_index,
        table_cache.columns(direction_index.ravel()),
        np.cos(headings),
        np.sin(headings),
        _vote_layout(grid, window, center, radius),
    )
    return votes_of, window


_NOTHING_VOTED = "no unobstructed range vector voted inside the grid / search circle"


@dataclass(slots=True)
class _VoteInputs:
    """What every vote loop of one fix reads: the readings, the anchors, the quantised beam
    directions ``(h, J)``, the free-distance table, the cosines and sines of the candidate
    headings, and :func:`_vote_layout`."""

    readings: _Readings
    anchors: FloatArray
    direction_index: npt.NDArray[np.intp]
    table: FloatArray
    cos_h: FloatArray
    sin_h: FloatArray
    layout: tuple[tuple[float, float, float], tuple[float, float, float], tuple[int, int, int, int]]


@dataclass
class _Choice:
    """The chosen heading and cells.

    ``window_low``..``window_high`` (inclusive cell indices) bound the cells whose votes make the
    chosen peak; ``cell`` is the cell of the window with most raw votes; ``centre`` the
    position used without refinement; ``vote_count`` and ``vote_mean`` the number and mean
    position ({W}, metres) of the chosen heading's votes in the chosen cells; ``volume`` the
    raw votes over (heading, ix, iy) of the vote window (:class:`_VoteWindow`), scored by
    ``selection``.
    """

    heading_index: int
    cell: tuple[int, int]
    window_low: tuple[int, int]
    window_high: tuple[int, int]
    centre: tuple[float, float]
    vote_count: int
    vote_mean: tuple[float, float]
    volume: npt.NDArray[np.int64]
    selection: Selection

    @cached_property
    def score(self) -> npt.NDArray[np.int64]:
        """The selection score over (heading, ix, iy) of the vote window: the raw votes, or
        their 3x3 binomial smoothing (only the ambiguity test needs it whole)."""
        if self.selection == "max":
            return self.volume
        return kim_kernels.binomial_smooth(self.volume)  # type: ignore[no-any-return]

    @property
    def best_score(self) -> int:
        return int(self.score[self.heading_index].max())


def _smoothed_choice(
    grid: OccupancyGrid,
    votes_of: _VoteInputs,
    window: _VoteWindow,
    center: Centre | None,
    radius: float | None,
    headings: FloatArray,
) -> tuple[npt.NDArray[np.int64], _Choice | None]:
    """The vote volume ``(heading, ix, iy)`` of ``window`` and the maximum of its 3x3 binomial
    smoothing (window = the chosen cell +- 1), or None for the choice when nothing voted: one
    call of :func:`~sonar_gym.localization.kim_kernels.smoothed_fix`."""
    volume, peak, heading_index, local_x, local_y, count, mean_x, mean_y = _smoothed_fix(
        votes_of, _pair_test(center, radius, headings)[1]
    )
    # a vote adds 4 to the score of its own cell: the peak is 0 only when nothing voted
    if peak == 0:
        return volume, None
    nx, ny = grid.shape
    best_x, best_y = local_x + window.low[0], local_y + window.low[1]
    low = (max(best_x - 1, 0), max(best_y - 1, 0))
    high = (min(best_x + 1, nx - 1), min(best_y + 1, ny - 1))
    x0, y0 = grid.origin_m  # the centre of the cell, as OccupancyGrid.cell_to_world
    centre = (x0 + (best_x + 0.5) * grid.cell_size_m, y0 + (best_y + 0.5) * grid.cell_size_m)
    return volume, _Choice(
        heading_index,
        (best_x, best_y),
        low,
        high,
        centre,
        count,
        (mean_x, mean_y),
        volume,
        "smoothed",
    )


def _smoothed_fix(
    votes_of: _VoteInputs, heading_test: tuple[bool, float, float, float, float]
) -> tuple[npt.NDArray[np.int64], int, int, int, int, int, float, float]:
    """:func:`~sonar_gym.localization.kim_kernels.smoothed_fix` of ``votes_of`` with the
    heading test of :func:`_pair_test`: the vote volume, the smoothed peak, its heading
    index and window cell, and the number and mean position of its votes."""
    readings = votes_of.readings
    return kim_kernels.smoothed_fix(  # type: ignore[no-any-return]
        readings.end_x,
        readings.end_y,
        readings.range_m,
        votes_of.anchors,
        votes_of.direction_index,
        votes_of.table,
        votes_of.cos_h,
        votes_of.sin_h,
        heading_test,
        *votes_of.layout,
    )


def _max_choice(
    grid: OccupancyGrid,
    votes_of: _VoteInputs,
    window: _VoteWindow,
    center: Centre | None,
    radius: float | None,
    headings: FloatArray,
) -> tuple[npt.NDArray[np.int64] | None, _Choice | None]:
    """The vote volume ``(heading, ix, iy)`` of ``window`` (None when no pair can vote) and its
    raw maximum, or None for the choice when nothing voted.

    Ties go to the heading with most tied cells, then to the tied cell nearest the centroid of
    the tied cells (the centroid is the unrefined position); window = that cell +- 1.
    """
    readings = votes_of.readings
    pairs = _candidate_pairs(readings, votes_of.anchors, center, radius, headings)
    if pairs[0].size == 0:
        return None, None
    volume = kim_kernels.vote_volume(
        *pairs,
        votes_of.direction_index,
        votes_of.table,
        readings.range_m,
        readings.end_x,
        readings.end_y,
        votes_of.anchors,
        votes_of.cos_h,
        votes_of.sin_h,
        *votes_of.layout,
    )
    if not volume.any():
        return volume, None
    nx, ny = grid.shape
    tied = np.argwhere(volume == volume.max())
    heading_index = int(np.argmax(np.bincount(tied[:, 0], minlength=volume.shape[0])))
    cells = tied[tied[:, 0] == heading_index, 1:] + np.array(window.low)
    centres = grid.cell_to_world(cells)
    centroid = centres.mean(axis=0)
    nearest = cells[int(np.argmin(np.sum((centres - centroid) ** 2, axis=1)))]
    cell = (int(nearest[0]), int(nearest[1]))
    low = (max(cell[0] - 1, 0), max(cell[1] - 1, 0))
    high = (min(cell[0] + 1, nx - 1), min(cell[1] + 1, ny - 1))
    count, mean_x, mean_y = kim_kernels.vote_mean(
        *pairs,
        votes_of.direction_index[heading_index],
        votes_of.table,
        readings.range_m,
        readings.end_x,
        readings.end_y,
        votes_of.anchors,
        float(votes_of.cos_h[heading_index]),
        float(votes_of.sin_h[heading_index]),
        *votes_of.layout,
        (*low, *high),
    )
    return volume, _Choice(
        heading_index,
        cell,
        low,
        high,
        (float(centroid[0]), float(centroid[1])),
        count,
        (mean_x, mean_y),
        volume,
        "max",
    )


def _rival_score(
    grid: OccupancyGrid,
    choice: _Choice,
    window: _VoteWindow,
    headings: FloatArray,
    distance_m: float,
    heading_rad: float,
) -> int:
    """Best score outside the neighbourhood (in position and heading) of the winner."""
    nx, ny = grid.shape
    score = window.full(grid, choice.score)
    cells = np.stack(np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij"), axis=-1)
    offsets = (cells - np.array(choice.cell)) * grid.cell_size_m
    near_position = np.hypot(offsets[..., 0], offsets[..., 1]) <= distance_m
    near_heading = np.abs(wrap_angles(headings - headings[choice.heading_index])) <= heading_rad
    excluded = near_heading[:, None, None] & near_position[None, :, :]
    return int(np.where(excluded, -1, score).max())
