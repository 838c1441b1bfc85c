"""The certainty / occupancy grid of Kim, Lee & Jeong, and the servo sweeps that fill it.

Kim, Lee & Jeong, *Self localization of mobile robot using sonar sensing and map building*,
sec. 2.2: "the grid map consists of a matrix of cells, each containing an occupancy value and
a certainty value. These values are used by the occupancy and localization algorithms
respectively." Sec. 4.1 divides the 2 m arena into 5 cm cells, the default here.

- The occupancy value of a cell is kept as counts, the histogram form of the certainty grid the
  paper cites (Elfes [3], Fig. 3): ``hit_counts`` (range readings that ended in the cell) and
  ``pass_counts`` (readings whose ray crossed it). A cell is ``occupied`` when it has at least
  ``min_hits`` hits and a hit fraction ``hits / (hits + passes)`` of at least
  ``min_hit_fraction`` (0 by default: the paper states no rule, so every hit counts).
- Beside the paper's cells, each cell keeps ``obstacle_points_m``, where inside the cell the
  obstacle lies: the mean of the hit end points (:meth:`OccupancyGrid.from_sweeps`) or the
  point of the mapped outline inside the cell nearest to its centre
  (:meth:`OccupancyGrid.from_segments`). The paper's voting anchors every range vector at the
  cell centre, which shifts a wall lying on a cell edge by half a cell; anchoring at these
  points instead is offered beside it.
- The certainty value is the vote of the localization algorithm of sec. 3.3; it is produced
  per localization, on this grid's cell layout, as ``VoteLocalization.vote_map``
  (:mod:`sonar_gym.localization.kim`).

Layout: cell ``(ix, iy)`` covers ``[x0 + ix c, x0 + (ix+1) c] x [y0 + iy c, y0 + (iy+1) c]`` in
the world frame {W}, with ``(x0, y0) = origin_m`` the lower-left corner and ``c`` the cell size
in metres. Arrays are indexed ``[ix, iy]`` (x along axis 0); plot them with
``imshow(array.T, origin="lower", extent=grid.extent)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import cast

import numpy as np
import numpy.typing as npt

from sonar_gym.frozen import unchecked_instance
from sonar_gym.pose import FloatArray, Pose
from sonar_gym.scenario import Scenario

IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]
Bounds = tuple[float, float, float, float]
"""``(x_min, y_min, x_max, y_max)`` of a region of the world frame, metres."""

PAPER_CELL_SIZE_M = 0.05
"""Cell size of sec. 4.1: the arena is divided into 5 cm cells."""

_GEOMETRY_TOLERANCE = 1e-9
"""Relative tolerance (in cells) under which a shape touching a cell edge marks the cell."""


def occupancy_grid_of(scenario: Scenario, cell_size_m: float = 0.05) -> OccupancyGrid:
    """The known map (sec. 2.2): mapped room walls, walls, box sides and cylinders on a grid.

    The grid covers ``scenario.bounds`` with ``cell_size_m`` cells (5 cm, sec. 4.1).
    """
    segments: list[tuple[tuple[float, float], tuple[float, float]]] = []
    if scenario.room is not None:
        corners = scenario.room.corners
        segments += [(corners[i], corners[(i + 1) % 4]) for i in range(4)]
    segments += [(wall.a, wall.b) for wall in scenario.walls if wall.mapped]
    for box in scenario.boxes:
        if box.mapped:
            corners = box.corners
            segments += [(corners[i], corners[(i + 1) % 4]) for i in range(4)]
    circles = [(c.center[0], c.center[1], c.radius) for c in scenario.cylinders if c.mapped]
    (x_min, y_min), (x_max, y_max) = scenario.bounds
    return OccupancyGrid.from_segments(
        np.array(segments, dtype=np.float64).reshape(-1, 2, 2),
        np.array(circles, dtype=np.float64).reshape(-1, 3),
        (x_min, y_min, x_max, y_max),
        cell_size_m,
    )


__all__ = [
    "occupancy_grid_of",
    "PAPER_CELL_SIZE_M",
    "Bounds",
    "OccupancyGrid",
    "Sweep",
    "sweep_end_points",
]


def _read_only(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class Sweep:
    """One servo sweep of the range sensor (sec. 2.2, sec. 3.3).

    Attributes:
        angles: beam direction of each reading in radians, in the robot frame {R} of this sweep
            (0 = robot forward, counter-clockwise positive).
        ranges: measured range of each reading in metres from the sensor; NaN (or +inf) where
            no echo came back.
        sensor_offset: ``(x, y)`` of the sensor's pan axis in {R}, metres.
        odometry: the robot pose of this sweep expressed in the robot frame of the FIRST sweep
            of the group, from dead reckoning (``Pose(0, 0, 0)`` for the first sweep itself).
            It lets 1 to 4 sweeps taken between short moves be combined (sec. 3.3).
    """

    angles: FloatArray
    ranges: FloatArray
    sensor_offset: tuple[float, float] = (0.0, 0.0)
    odometry: Pose = field(default_factory=lambda: Pose(0.0, 0.0, 0.0))

    def __post_init__(self) -> None:
        if np.ndim(self.angles) != 1:
            raise ValueError(
                f"Sweep.angles must be one-dimensional, got shape {np.shape(self.angles)}"
            )
        if np.ndim(self.ranges) != 1:
            raise ValueError(
                f"Sweep.ranges must be one-dimensional, got shape {np.shape(self.ranges)}"
            )
        angles = np.array(self.angles, dtype=np.float64)
        ranges = np.array(self.ranges, dtype=np.float64)
        if ranges.shape != angles.shape:
            raise ValueError(
                f"Sweep.ranges must have one entry per angle (got {ranges.size} ranges for "
                f"{angles.size} angles)"
            )
        if not np.isfinite(angles).all():
            raise ValueError("Sweep.angles must be finite (radians)")
        if (ranges < 0.0).any():
            raise ValueError("Sweep.ranges must be >= 0 m, or NaN / +inf for no echo")
        offset = np.asarray(self.sensor_offset, dtype=np.float64)
        if offset.shape != (2,) or not np.isfinite(offset).all():
            raise ValueError(
                f"Sweep.sensor_offset must be a finite (x, y) in metres, got {self.sensor_offset!r}"
            )
        if not isinstance(self.odometry, Pose):
            raise ValueError(
                f"Sweep.odometry must be a sonar_gym.pose.Pose, got {type(self.odometry).__name__}"
            )
        object.__setattr__(self, "angles", _read_only(angles))
        object.__setattr__(self, "ranges", _read_only(ranges))
        object.__setattr__(self, "sensor_offset", (float(offset[0]), float(offset[1])))

    @classmethod
    def unchecked(
        cls,
        angles: FloatArray,
        ranges: FloatArray,
        sensor_offset: tuple[float, float],
        odometry: Pose,
    ) -> Sweep:
        """The sweep of ``angles`` and ``ranges`` without the checks of construction.

        For a simulated sweep, valid by construction (1-d float64 arrays of one length, finite
        angles, ranges >= 0 or NaN, a finite float offset, a :class:`Pose`): the same sweep as
        ``Sweep(angles, ranges, sensor_offset, odometry)`` (read-only copies) at a fraction
        of the cost, as :meth:`Pose.unchecked`. Anything else is the caller's error.
        """
        return cls.handed_over(angles.copy(), ranges.copy(), sensor_offset, odometry)

    @classmethod
    def handed_over(
        cls,
        angles: FloatArray,
        ranges: FloatArray,
        sensor_offset: tuple[float, float],
        odometry: Pose,
    ) -> Sweep:
        """:meth:`unchecked` of arrays the caller hands over instead of copies: read-only
        ``angles`` that nothing writes (a sweep grid's) and ``ranges`` that the caller keeps
        no other use of (a fresh sweep's), made read-only in place. The same sweep, two array
        copies cheaper."""
        return unchecked_instance(  # the fields as __post_init__ sets them
            cls,
            angles=_read_only(angles),
            ranges=_read_only(ranges),
            sensor_offset=(float(sensor_offset[0]), float(sensor_offset[1])),
            odometry=odometry,
        )

    @property
    def valid(self) -> BoolArray:
        """Mask of the readings that returned an echo (finite range)."""
        return np.isfinite(self.ranges)


def sweep_end_points(
    sweep: Sweep, pose: Pose, max_range_m: float | None = None
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Sensor positions, end points and beam directions of a sweep's echoes in a parent frame.

    Args:
        sweep: the sweep.
        pose: the pose of the sweep's robot frame {R} in the parent frame (for a map, the world
            pose; for combining sweeps, ``sweep.odometry``).
        max_range_m: readings at or beyond this range count as no echo (None: keep all finite).

    Returns:
        ``(sensor_xy (N, 2), end_xy (N, 2), beam_angle (N,))`` for the N valid readings, in the
        parent frame (m, m, rad).
    """
    keep = sweep.valid
    if max_range_m is not None:
        keep &= sweep.ranges < max_range_m
    ranges = sweep.ranges[keep]
    beam = pose.theta + sweep.angles[keep]
    sensor = pose.transform_point(sweep.sensor_offset)
    sensor_xy = np.broadcast_to(sensor, (ranges.size, 2)).copy()
    end_xy = sensor_xy + ranges[:, None] * np.column_stack((np.cos(beam), np.sin(beam)))
    return sensor_xy, end_xy, beam


def _check_bounds(bounds: Sequence[float]) -> Bounds:
    values = np.asarray(bounds, dtype=np.float64)
    if values.shape != (4,) or not np.all(np.isfinite(values)):
        raise ValueError(
            f"bounds must be finite (x_min, y_min, x_max, y_max) in metres, got {bounds!r}"
        )
    x_min, y_min, x_max, y_max = (float(v) for v in values)
    if not (x_max > x_min and y_max > y_min):
        raise ValueError(f"bounds must have x_max > x_min and y_max > y_min, got {bounds!r}")
    return x_min, y_min, x_max, y_max


def _check_cell_size(cell_size: float) -> float:
    size = float(cell_size)
    if not (math.isfinite(size) and size > 0.0):
        raise ValueError(f"cell_size must be a finite length > 0 m, got {cell_size!r}")
    return size


def _shape_for(bounds: Bounds, cell_size: float) -> tuple[int, int]:
    x_min, y_min, x_max, y_max = bounds
    nx = max(1, math.ceil((x_max - x_min) / cell_size - _GEOMETRY_TOLERANCE))
    ny = max(1, math.ceil((y_max - y_min) / cell_size - _GEOMETRY_TOLERANCE))
    return nx, ny


@dataclass(frozen=True, eq=False)
class OccupancyGrid:
    """Occupancy / certainty grid of sec. 2.2 in the world frame {W}.

    Attributes:
        origin_m: ``(x0, y0)``, world position of the lower-left corner of cell ``(0, 0)`` (m).
        cell_size_m: side of a square cell (m); the paper uses 0.05.
        occupied: boolean ``(nx, ny)`` array indexed ``[ix, iy]``: cells holding an obstacle.
        hit_counts: ``(nx, ny)`` readings that ended in each cell (the occupancy value);
            defaults to ``occupied`` as 0/1.
        pass_counts: ``(nx, ny)`` readings whose ray crossed each cell; defaults to zeros.
        obstacle_points_m: ``(nx, ny, 2)`` world position (m) of the obstacle inside each cell;
            defaults to the cell centres (as for every cell where it is unknown).
    """

    origin_m: tuple[float, float]
    cell_size_m: float
    occupied: BoolArray
    hit_counts: IntArray | None = None
    pass_counts: IntArray | None = None
    obstacle_points_m: FloatArray | None = None

    def __post_init__(self) -> None:
        origin = np.asarray(self.origin_m, dtype=np.float64)
        if origin.shape != (2,) or not np.all(np.isfinite(origin)):
            raise ValueError(f"origin_m must be a finite (x, y) in metres, got {self.origin_m!r}")
        size = _check_cell_size(self.cell_size_m)
        occupied = np.array(self.occupied, dtype=bool)
        if occupied.ndim != 2 or occupied.shape[0] < 1 or occupied.shape[1] < 1:
            raise ValueError(f"occupied must be a non-empty 2-D array, got shape {occupied.shape}")
        counts = {}
        for name, default in (
            ("hit_counts", occupied.astype(np.int64)),
            ("pass_counts", np.zeros(occupied.shape, dtype=np.int64)),
        ):
            value = getattr(self, name)
            array = default if value is None else np.array(value, dtype=np.int64)
            if array.shape != occupied.shape:
                raise ValueError(
                    f"{name} must have the shape of occupied {occupied.shape}, got {array.shape}"
                )
            if np.any(array < 0):
                raise ValueError(f"{name} must be non-negative counts")
            counts[name] = _read_only(array)
        object.__setattr__(self, "origin_m", (float(origin[0]), float(origin[1])))
        object.__setattr__(self, "cell_size_m", size)
        object.__setattr__(self, "occupied", _read_only(occupied))
        object.__setattr__(self, "hit_counts", counts["hit_counts"])
        object.__setattr__(self, "pass_counts", counts["pass_counts"])
        nx, ny = occupied.shape
        centres = (
            origin
            + (np.stack(np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij"), axis=-1) + 0.5)
            * size
        )
        if self.obstacle_points_m is None:
            points = centres
        else:
            points = np.array(self.obstacle_points_m, dtype=np.float64)
            if points.shape != (nx, ny, 2) or not np.all(np.isfinite(points)):
                raise ValueError(
                    f"obstacle_points_m must be a finite ({nx}, {ny}, 2) array, got {points.shape}"
                )
        object.__setattr__(self, "obstacle_points_m", _read_only(points))

    # -- layout -------------------------------------------------------------------------------

    @property
    def shape(self) -> tuple[int, int]:
        """``(nx, ny)``: number of cells along x and y."""
        return self.occupied.shape[0], self.occupied.shape[1]

    @property
    def bounds(self) -> Bounds:
        """``(x_min, y_min, x_max, y_max)`` covered by the cells (m)."""
        x0, y0 = self.origin_m
        nx, ny = self.shape
        return x0, y0, x0 + nx * self.cell_size_m, y0 + ny * self.cell_size_m

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(x_min, x_max, y_min, y_max)``, the order matplotlib's ``imshow`` expects."""
        x_min, y_min, x_max, y_max = self.bounds
        return x_min, x_max, y_min, y_max

    @property
    def hit_fraction(self) -> FloatArray:
        """``hits / (hits + passes)`` per cell, 0 where no reading reached the cell."""
        hits = cast(IntArray, self.hit_counts).astype(np.float64)
        total = hits + cast(IntArray, self.pass_counts)
        return np.divide(hits, total, out=np.zeros_like(hits), where=total > 0)

    def world_to_cell(self, points_m: npt.ArrayLike) -> IntArray:
        """Cell indices ``(..., 2) = [ix, iy]`` of world points ``(..., 2)`` in metres.

        Indices are not clipped: points outside the grid give indices outside
        ``[0, nx) x [0, ny)`` (see :meth:`contains_cell`).
        """
        points = np.asarray(points_m, dtype=np.float64)
        if points.ndim == 0 or points.shape[-1] != 2:
            raise ValueError(f"points_m must have shape (..., 2), got {points.shape}")
        origin = np.asarray(self.origin_m)
        return np.floor((points - origin) / self.cell_size_m).astype(np.int64)

    def cell_to_world(self, cells: npt.ArrayLike) -> FloatArray:
        """World position (m) of the centres of cells ``(..., 2) = [ix, iy]``."""
        indices = np.asarray(cells)
        if indices.ndim == 0 or indices.shape[-1] != 2:
            raise ValueError(f"cells must have shape (..., 2), got {indices.shape}")
        return np.asarray(self.origin_m) + (indices.astype(np.float64) + 0.5) * self.cell_size_m

    def contains_cell(self, cells: npt.ArrayLike) -> BoolArray:
        """Whether cell indices ``(..., 2)`` lie inside the grid."""
        indices = np.asarray(cells)
        nx, ny = self.shape
        return (
            (indices[..., 0] >= 0)
            & (indices[..., 0] < nx)
            & (indices[..., 1] >= 0)
            & (indices[..., 1] < ny)
        )

    def is_occupied_at(self, points_m: npt.ArrayLike) -> BoolArray:
        """Whether world points ``(..., 2)`` fall in occupied cells (False outside the grid)."""
        cells = self.world_to_cell(points_m)
        inside = self.contains_cell(cells)
        nx, ny = self.shape
        clipped_x = np.clip(cells[..., 0], 0, nx - 1)
        clipped_y = np.clip(cells[..., 1], 0, ny - 1)
        return inside & self.occupied[clipped_x, clipped_y]

    def occupied_cells(self) -> IntArray:
        """``(K, 2)`` indices ``[ix, iy]`` of the occupied cells, in row-major order."""
        return np.argwhere(self.occupied).astype(np.int64)

    def occupied_centers(self) -> FloatArray:
        """``(K, 2)`` world positions (m) of the centres of the occupied cells."""
        return self.cell_to_world(self.occupied_cells())

    def occupied_obstacle_points(self) -> FloatArray:
        """``(K, 2)`` obstacle points (m) of the occupied cells, in :meth:`occupied_cells` order."""
        cells = self.occupied_cells()
        points = cast(FloatArray, self.obstacle_points_m)
        return points[cells[:, 0], cells[:, 1]].copy()

    # -- builders -----------------------------------------------------------------------------

    @classmethod
    def empty(cls, bounds: Sequence[float], cell_size: float = PAPER_CELL_SIZE_M) -> OccupancyGrid:
        """A grid with no occupied cell covering ``bounds`` (rounded up to whole cells)."""
        checked = _check_bounds(bounds)
        size = _check_cell_size(cell_size)
        return cls((checked[0], checked[1]), size, np.zeros(_shape_for(checked, size), dtype=bool))

    @classmethod
    def from_segments(
        cls,
        segments: npt.ArrayLike,
        circles: npt.ArrayLike | None,
        bounds: Sequence[float],
        cell_size: float = PAPER_CELL_SIZE_M,
    ) -> OccupancyGrid:
        """Rasterise a known map: wall segments and the outlines of cylinders.

        A cell is occupied when its closed square touches a segment or a circle's
        circumference (a shape lying exactly on a cell edge marks the cells on both sides).
        Interiors of cylinders are left free: the sonar only ever sees the outline.

        Args:
            segments: ``(N, 2, 2)`` array, segment ``i`` from ``segments[i, 0]`` to
                ``segments[i, 1]`` (``[x, y]`` in metres, world frame); N may be 0.
            circles: ``(M, 3)`` array of ``[x, y, radius]`` (m), or None.
            bounds: ``(x_min, y_min, x_max, y_max)`` of the grid (m), rounded up to whole cells.
            cell_size: cell side (m), 0.05 by default (sec. 4.1).
        """
        checked = _check_bounds(bounds)
        size = _check_cell_size(cell_size)
        walls = np.asarray(segments, dtype=np.float64)
        if walls.size == 0:
            walls = walls.reshape(0, 2, 2)
        if walls.ndim != 3 or walls.shape[1:] != (2, 2) or not np.all(np.isfinite(walls)):
            raise ValueError(
                f"segments must be a finite (N, 2, 2) array in metres, got shape {walls.shape}"
            )
        discs = np.zeros((0, 3)) if circles is None else np.asarray(circles, dtype=np.float64)
        if discs.size == 0:
            discs = discs.reshape(0, 3)
        if discs.ndim != 2 or discs.shape[1] != 3 or not np.all(np.isfinite(discs)):
            raise ValueError(
                f"circles must be a finite (M, 3) array of [x, y, r], got shape {discs.shape}"
            )
        if np.any(discs[:, 2] < 0.0):
            raise ValueError("circles radius (column 2) must be >= 0 m")
        grid = cls.empty(checked, size)
        occupied = np.zeros(grid.shape, dtype=bool)
        for start, end in walls:
            _mark_segment(occupied, grid.origin_m, size, start, end)
        for centre_x, centre_y, radius in discs:
            _mark_circle(occupied, grid.origin_m, size, centre_x, centre_y, radius)
        points = np.array(grid.obstacle_points_m)
        cells = np.argwhere(occupied)
        lower_left = np.asarray(grid.origin_m) + cells * size
        points[cells[:, 0], cells[:, 1]] = _nearest_outline_points(lower_left, size, walls, discs)
        return cls(grid.origin_m, size, occupied, obstacle_points_m=points)

    @classmethod
    def from_sweeps(
        cls,
        sweeps: Sequence[Sweep],
        poses: Sequence[Pose],
        bounds: Sequence[float],
        cell_size: float = PAPER_CELL_SIZE_M,
        min_hits: int = 1,
        min_hit_fraction: float = 0.0,
        max_range_m: float | None = None,
    ) -> OccupancyGrid:
        """Map building (sec. 2.2): accumulate sweeps taken at known world poses.

        Each valid reading adds a hit to the cell holding its end point and a pass to every
        other cell its ray crosses on the way (sampled every half cell). ``Sweep.odometry`` is
        not used: ``poses[i]`` is the world pose of the robot during ``sweeps[i]``.

        Args:
            sweeps: the sweeps.
            poses: one world pose of the robot frame {R} per sweep.
            bounds: ``(x_min, y_min, x_max, y_max)`` of the grid (m).
            cell_size: cell side (m), 0.05 by default.
            min_hits: hits a cell needs to be occupied (>= 1).
            min_hit_fraction: hit fraction ``hits / (hits + passes)`` a cell needs, in [0, 1].
            max_range_m: readings at or beyond this range count as no echo.
        """
        if len(sweeps) != len(poses):
            raise ValueError(
                f"poses must hold one Pose per sweep (got {len(poses)} for {len(sweeps)})"
            )
        for index, (sweep, pose) in enumerate(zip(sweeps, poses, strict=True)):
            if not isinstance(sweep, Sweep):
                raise ValueError(f"sweeps[{index}] must be a Sweep, got {type(sweep).__name__}")
            if not isinstance(pose, Pose):
                raise ValueError(f"poses[{index}] must be a Pose, got {type(pose).__name__}")
        if int(min_hits) != min_hits or min_hits < 1:
            raise ValueError(f"min_hits must be an integer >= 1, got {min_hits!r}")
        if not (0.0 <= float(min_hit_fraction) <= 1.0):
            raise ValueError(f"min_hit_fraction must lie in [0, 1], got {min_hit_fraction!r}")
        if max_range_m is not None and not (float(max_range_m) > 0.0):
            raise ValueError(f"max_range_m must be > 0 m or None, got {max_range_m!r}")
        grid = cls.empty(bounds, cell_size)
        nx, ny = grid.shape
        hits = np.zeros(nx * ny, dtype=np.int64)
        passes = np.zeros(nx * ny, dtype=np.int64)
        hit_sums = np.zeros((nx * ny, 2))
        for sweep, pose in zip(sweeps, poses, strict=True):
            sensor_xy, end_xy, _ = sweep_end_points(sweep, pose, max_range_m)
            if end_xy.shape[0] == 0:
                continue
            end_cells = _cells_of_closed_grid(grid, end_xy)
            inside = grid.contains_cell(end_cells)
            end_flat = end_cells[:, 0] * ny + end_cells[:, 1]
            hits += np.bincount(end_flat[inside], minlength=nx * ny)
            for axis in (0, 1):
                hit_sums[:, axis] += np.bincount(
                    end_flat[inside], weights=end_xy[inside, axis], minlength=nx * ny
                )
            passes += _pass_counts(grid, sensor_xy, end_xy, end_flat)
        hit_counts = hits.reshape(nx, ny)
        pass_counts = passes.reshape(nx, ny)
        points = np.array(grid.obstacle_points_m).reshape(nx * ny, 2)
        seen = hits > 0
        points[seen] = hit_sums[seen] / hits[seen, None]
        provisional = cls(grid.origin_m, grid.cell_size_m, hit_counts > 0, hit_counts, pass_counts)
        occupied = (hit_counts >= min_hits) & (provisional.hit_fraction >= float(min_hit_fraction))
        return cls(
            grid.origin_m,
            grid.cell_size_m,
            occupied,
            hit_counts,
            pass_counts,
            points.reshape(nx, ny, 2),
        )


def _cells_of_closed_grid(grid: OccupancyGrid, points: FloatArray) -> IntArray:
    """Cell indices of points, counting points on the grid's outer edges (to rounding) as inside.

    A wall on the boundary of the grid returns echoes at, or a rounding error beyond, the edge.
    """
    cells = grid.world_to_cell(points)
    x_min, y_min, x_max, y_max = grid.bounds
    tolerance = _GEOMETRY_TOLERANCE * grid.cell_size_m
    for axis, (low, high, count) in enumerate(
        ((x_min, x_max, grid.shape[0]), (y_min, y_max, grid.shape[1]))
    ):
        coordinate = points[..., axis]
        index = cells[..., axis]
        index[(index == count) & (coordinate <= high + tolerance)] = count - 1
        index[(index == -1) & (coordinate >= low - tolerance)] = 0
    return cells


def _pass_counts(
    grid: OccupancyGrid, sensor_xy: FloatArray, end_xy: FloatArray, end_flat: IntArray
) -> IntArray:
    """Per-cell count of rays that cross a cell before the cell of their end point."""
    nx, ny = grid.shape
    step = 0.5 * grid.cell_size_m
    lengths = np.linalg.norm(end_xy - sensor_xy, axis=1)
    samples = math.ceil(float(lengths.max(initial=0.0)) / step) + 1
    fractions = np.arange(samples) * step
    along = fractions[None, :] < lengths[:, None]
    directions = np.divide(
        end_xy - sensor_xy, lengths[:, None], out=np.zeros_like(end_xy), where=lengths[:, None] > 0
    )
    points = sensor_xy[:, None, :] + fractions[None, :, None] * directions[:, None, :]
    cells = grid.world_to_cell(points)
    flat = cells[..., 0] * ny + cells[..., 1]
    keep = along & grid.contains_cell(cells) & (flat != end_flat[:, None])
    ray_ids = np.broadcast_to(np.arange(end_xy.shape[0])[:, None], flat.shape)
    unique_pairs = np.unique(ray_ids[keep] * (nx * ny) + flat[keep])
    return np.bincount(unique_pairs % (nx * ny), minlength=nx * ny)


def _nearest_outline_points(
    lower_left: FloatArray, cell_size: float, walls: FloatArray, discs: FloatArray
) -> FloatArray:
    """For each closed cell ``(K, 2)`` lower-left corners, the point of the outlines inside the
    cell nearest to its centre (m); the centre where no outline meets the cell."""
    centres = lower_left + 0.5 * cell_size
    tolerance = _GEOMETRY_TOLERANCE * cell_size
    best = centres.copy()
    best_gap = np.full(centres.shape[0], np.inf)

    def keep_nearer(candidates: FloatArray, valid: npt.NDArray[np.bool_]) -> None:
        gaps = np.where(valid, np.sum((candidates - centres[:, None, :]) ** 2, axis=-1), np.inf)
        choice = np.argmin(gaps, axis=1)
        nearest_gap = gaps[np.arange(gaps.shape[0]), choice]
        better = nearest_gap < best_gap
        best[better] = candidates[better, choice[better]]
        best_gap[better] = nearest_gap[better]

    low = lower_left[:, None, :]
    high = low + cell_size
    if walls.shape[0]:
        start = walls[None, :, 0, :]
        direction = walls[None, :, 1, :] - start
        # Liang-Barsky: the part of each segment inside each closed cell, t in [t_low, t_high].
        t_low = np.zeros((centres.shape[0], walls.shape[0]))
        t_high = np.ones_like(t_low)
        inside = np.ones_like(t_low, dtype=bool)
        for axis in (0, 1):
            d = np.broadcast_to(direction[..., axis], t_low.shape)
            to_low = low[..., axis] - start[..., axis]
            to_high = high[..., axis] - start[..., axis]
            moving = np.abs(d) > 0.0
            safe = np.where(moving, d, 1.0)
            enter = np.where(moving, np.minimum(to_low / safe, to_high / safe), -np.inf)
            leave = np.where(moving, np.maximum(to_low / safe, to_high / safe), np.inf)
            t_low = np.maximum(t_low, enter)
            t_high = np.minimum(t_high, leave)
            inside &= moving | ((to_low <= tolerance) & (to_high >= -tolerance))
        length_sq = np.sum(direction**2, axis=-1)
        along = np.sum((centres[:, None, :] - start) * direction, axis=-1)
        projection = np.divide(along, length_sq, out=np.zeros_like(along), where=length_sq > 0)
        scale = tolerance / np.sqrt(np.maximum(length_sq, cell_size**2))
        valid = inside & (t_low <= t_high + scale)
        fraction = np.clip(projection, t_low, np.maximum(t_low, t_high))
        keep_nearer(start + fraction[..., None] * direction, valid)
    if discs.shape[0]:
        circle_centre = discs[None, :, :2]
        radius = discs[None, :, 2]
        offset = centres[:, None, :] - circle_centre
        distance = np.linalg.norm(offset, axis=-1)
        unit = np.divide(
            offset, distance[..., None], out=np.zeros_like(offset), where=distance[..., None] > 0
        )
        unit[distance == 0] = (1.0, 0.0)
        candidates = [circle_centre + radius[..., None] * unit]
        for axis in (0, 1):
            other = 1 - axis
            for edge in (low[..., axis], high[..., axis]):
                across = np.broadcast_to(edge - circle_centre[..., axis], distance.shape)
                half_chord = np.sqrt(np.maximum(radius**2 - across**2, 0.0))
                reach = np.abs(across) <= radius + tolerance
                for sign in (-1.0, 1.0):
                    point = np.empty((*distance.shape, 2))
                    point[..., axis] = np.where(reach, edge, np.inf)
                    point[..., other] = circle_centre[..., other] + sign * half_chord
                    candidates.append(point)
        stacked = np.stack(candidates, axis=-2)  # (K, M, 9, 2)
        valid = np.all(
            (stacked >= low[:, :, None, :] - tolerance)
            & (stacked <= high[:, :, None, :] + tolerance),
            axis=-1,
        )
        keep_nearer(stacked.reshape(centres.shape[0], -1, 2), valid.reshape(centres.shape[0], -1))
    return best


def _cell_index_range(
    low: float, high: float, origin: float, cell_size: float, count: int
) -> range:
    """Indices of the cells whose closed interval along one axis meets ``[low, high]``."""
    first = math.ceil((low - origin) / cell_size - 1.0 - _GEOMETRY_TOLERANCE)
    last = math.floor((high - origin) / cell_size + _GEOMETRY_TOLERANCE)
    return range(max(first, 0), min(last, count - 1) + 1)


def _mark_segment(
    occupied: BoolArray,
    origin: tuple[float, float],
    cell_size: float,
    start: FloatArray,
    end: FloatArray,
) -> None:
    """Mark the cells whose closed square touches the segment (separating-axis test)."""
    nx, ny = occupied.shape
    x_range = _cell_index_range(
        min(start[0], end[0]), max(start[0], end[0]), origin[0], cell_size, nx
    )
    y_range = _cell_index_range(
        min(start[1], end[1]), max(start[1], end[1]), origin[1], cell_size, ny
    )
    if len(x_range) == 0 or len(y_range) == 0:
        return
    ix = np.arange(x_range.start, x_range.stop)
    iy = np.arange(y_range.start, y_range.stop)
    left = origin[0] + ix[:, None] * cell_size
    bottom = origin[1] + iy[None, :] * cell_size
    direction = end - start
    corner_offsets = ((0.0, 0.0), (cell_size, 0.0), (0.0, cell_size), (cell_size, cell_size))
    sides = np.stack(
        [
            direction[0] * (bottom + dy - start[1]) - direction[1] * (left + dx - start[0])
            for dx, dy in corner_offsets
        ]
    )
    tolerance = _GEOMETRY_TOLERANCE * cell_size * max(float(np.hypot(*direction)), cell_size)
    touches = (sides.min(axis=0) <= tolerance) & (sides.max(axis=0) >= -tolerance)
    occupied[np.ix_(ix, iy)] |= touches


def _mark_circle(
    occupied: BoolArray,
    origin: tuple[float, float],
    cell_size: float,
    centre_x: float,
    centre_y: float,
    radius: float,
) -> None:
    """Mark the cells whose closed square touches the circle's circumference."""
    nx, ny = occupied.shape
    x_range = _cell_index_range(centre_x - radius, centre_x + radius, origin[0], cell_size, nx)
    y_range = _cell_index_range(centre_y - radius, centre_y + radius, origin[1], cell_size, ny)
    if len(x_range) == 0 or len(y_range) == 0:
        return
    ix = np.arange(x_range.start, x_range.stop)
    iy = np.arange(y_range.start, y_range.stop)
    left = origin[0] + ix[:, None] * cell_size
    bottom = origin[1] + iy[None, :] * cell_size
    right, top = left + cell_size, bottom + cell_size
    nearest_dx = np.clip(centre_x, left, right) - centre_x
    nearest_dy = np.clip(centre_y, bottom, top) - centre_y
    nearest = np.hypot(nearest_dx, nearest_dy)
    farthest_dx = np.maximum(np.abs(left - centre_x), np.abs(right - centre_x))
    farthest_dy = np.maximum(np.abs(bottom - centre_y), np.abs(top - centre_y))
    farthest = np.hypot(farthest_dx, farthest_dy)
    tolerance = _GEOMETRY_TOLERANCE * cell_size
    touches = (nearest <= radius + tolerance) & (farthest >= radius - tolerance)
    occupied[np.ix_(ix, iy)] |= touches
