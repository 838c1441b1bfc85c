"""The path errors of Roh et al. (Sec. IV.B): sigma, sigma' and the distance to a polyline.

A localized path is scored against the true one, a curve ``y = f(x)`` given as a polyline:
sigma is the RMS difference in y at the same x, sigma' the mean distance from each
localized point to the true polyline (the per-point "path error" of Figs. 5, 7 and 8).
:class:`TruePath` prepares a true path once for scoring many localized paths against it
(everything that depends only on the true path is computed in its constructor);
:func:`path_errors` is the one-off form. Metres throughout.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonar_gym.localization import roh_kernels
from sonar_gym.pose import FloatArray


def points_array(points: npt.ArrayLike, name: str, min_count: int = 1) -> FloatArray:
    """``points`` as a finite ``(n, 2)`` float array with ``n >= min_count``.

    Raises:
        ValueError: naming ``name``, for another shape or a non-finite value.
    """
    array = np.asarray(points, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 2 or array.shape[0] < min_count:
        raise ValueError(
            f"{name} must have shape (n, 2) of (x, y) in metres with n >= {min_count}, "
            f"got {array.shape}"
        )
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite")
    return array


def _mean(values: FloatArray) -> float:
    """``np.mean`` of a non-empty 1-d float64 array, with its arithmetic (numpy's sum,
    divided by the count) without its per-call cost."""
    return float(values.sum()) / len(values)


class _Segments:
    """The segments of a polyline as component arrays: segment ``k`` runs from vertex ``k``
    to vertex ``k + 1`` (start ``(sx, sy)``, direction ``(dx, dy)``)."""

    def __init__(self, line: FloatArray) -> None:
        starts = line[:-1]
        direction = line[1:] - starts
        self.sx, self.sy = starts[:, 0].copy(), starts[:, 1].copy()
        self.dx, self.dy = direction[:, 0].copy(), direction[:, 1].copy()
        length_sq = self.dx * self.dx + self.dy * self.dy
        self.degenerate = length_sq == 0.0
        self.safe_length_sq = np.where(self.degenerate, 1.0, length_sq)

    def nearest_sq(self, p: FloatArray, members: npt.NDArray[np.intp]) -> FloatArray:
        """Squared distance of each point ``p[i]`` to the nearest of segments ``members[i]``.

        Args:
            p: ``(m, 2)`` points, metres.
            members: ``(m, w)`` segment indices per point.
        """
        dx, dy = self.dx[members], self.dy[members]
        rx = p[:, 0, None] - self.sx[members]
        ry = p[:, 1, None] - self.sy[members]
        t = np.clip((rx * dx + ry * dy) / self.safe_length_sq[members], 0.0, 1.0)
        t[self.degenerate[members]] = 0.0
        gx, gy = rx - t * dx, ry - t * dy
        return np.asarray((gx * gx + gy * gy).min(axis=1))


POLYLINE_BLOCK_SEGMENTS = 8
"""Consecutive polyline segments bounded together by one circle in :func:`distances_to_polyline`."""


class _BlockedPolyline:
    """A polyline's segments in blocks of :data:`POLYLINE_BLOCK_SEGMENTS`, each bounded by a
    circle, for the general nearest-segment search of :func:`distances_to_polyline`."""

    def __init__(self, line: FloatArray) -> None:
        n_segments = len(line) - 1
        n_blocks = -(-n_segments // POLYLINE_BLOCK_SEGMENTS)
        # Segment indices per block; the last block repeats its last segment (harmless for a min).
        self.members = np.minimum(
            np.arange(n_blocks * POLYLINE_BLOCK_SEGMENTS).reshape(n_blocks, -1), n_segments - 1
        )
        block_vertices = np.concatenate(
            [line[self.members], line[self.members[:, -1:] + 1]], axis=1
        )
        self.centres = 0.5 * (block_vertices.min(axis=1) + block_vertices.max(axis=1))
        self.radii = np.sqrt(((block_vertices - self.centres[:, None, :]) ** 2).sum(axis=2)).max(
            axis=1
        )
        self.segments = _Segments(line)

    def distances(self, p: FloatArray) -> FloatArray:
        """``(m,)`` distance of each point of ``p`` ``(m, 2)`` to the polyline, metres."""
        dx, dy = p[:, 0, None] - self.centres[:, 0], p[:, 1, None] - self.centres[:, 1]
        lower = np.sqrt(dx * dx + dy * dy) - self.radii
        members = self.members
        upper = np.sqrt(self.segments.nearest_sq(p, members[np.argmin(lower, axis=1)]))
        # The slack absorbs the rounding of the bounds (far below any distance that matters).
        point_index, block_index = np.nonzero(lower <= (upper + 1e-9 * (1.0 + upper))[:, None])
        nearest_sq = self.segments.nearest_sq(p[point_index], members[block_index])
        # np.nonzero lists the pairs point by point, and every point has its first block.
        first_pair = np.flatnonzero(np.diff(point_index, prepend=-1))
        return np.sqrt(np.minimum.reduceat(nearest_sq, first_pair))


def distances_to_polyline(points: npt.ArrayLike, polyline: npt.ArrayLike) -> FloatArray:
    """Distance (metres) from each point to the nearest segment of a polyline.

    This is the per-point "path error" of Figs. 5, 7 and 8. The segments are taken in blocks
    of :data:`POLYLINE_BLOCK_SEGMENTS`, each bounded by a circle. For each point the block
    whose circle comes nearest is searched first; its distance bounds the answer, so only the
    blocks whose circles come within that distance are searched too. The result is the exact
    minimum over all segments (as :func:`distances_to_polyline_reference`, which searches
    every segment).

    Args:
        points: ``(m, 2)`` points, metres.
        polyline: ``(n, 2)`` vertices in order, n >= 2, metres.

    Returns:
        ``(m,)`` distances.
    """
    p = points_array(points, "points")
    line = points_array(polyline, "polyline", min_count=2)
    return _BlockedPolyline(line).distances(p)


def distances_to_polyline_reference(points: npt.ArrayLike, polyline: npt.ArrayLike) -> FloatArray:
    """:func:`distances_to_polyline` by searching every segment for every point (the
    reference the fast search is tested against), metres."""
    p = points_array(points, "points")
    line = points_array(polyline, "polyline", min_count=2)
    starts, ends = line[:-1], line[1:]
    direction = ends - starts
    length_sq = np.einsum("ij,ij->i", direction, direction)
    safe_length_sq = np.where(length_sq > 0.0, length_sq, 1.0)
    result = np.empty(len(p))
    block = 512
    for first in range(0, len(p), block):
        chunk = p[first : first + block]
        relative = chunk[:, None, :] - starts[None, :, :]
        t = np.clip(np.einsum("mnk,nk->mn", relative, direction) / safe_length_sq, 0.0, 1.0)
        t = np.where(length_sq > 0.0, t, 0.0)
        gap = relative - t[..., None] * direction[None, :, :]
        result[first : first + block] = np.sqrt(np.min(np.einsum("mnk,mnk->mn", gap, gap), axis=1))
    return result


class TruePath:
    """A true path ``y = f(x)`` (x strictly monotonic), prepared for :meth:`errors`.

    Args:
        true: ``(n, 2)`` vertices of the true path, n >= 2, metres, whose x is strictly
            monotonic (increasing or decreasing).

    Raises:
        ValueError: on a wrong shape, non-finite values, or x not strictly monotonic.
    """

    def __init__(self, true: npt.ArrayLike) -> None:
        line = points_array(true, "true", min_count=2)
        steps = np.diff(line[:, 0])
        if not (np.all(steps > 0.0) or np.all(steps < 0.0)):
            raise ValueError("true must be a path y = f(x): its x must be strictly monotonic")
        self.vertices = line
        self._increasing = bool(line[0, 0] < line[-1, 0])
        ordered = line if self._increasing else line[::-1]
        self._xs, self._ys = ordered[:, 0].copy(), ordered[:, 1].copy()
        xs, ys = self._xs, self._ys
        self._low_slope = (ys[1] - ys[0]) / (xs[1] - xs[0])
        self._high_slope = (ys[-1] - ys[-2]) / (xs[-1] - xs[-2])
        self._segments = _Segments(line)
        self._ends = np.array([line[0, 0], line[0, 1], line[-1, 0], line[-1, 1]])

    def y_at(self, x: FloatArray) -> FloatArray:
        """``f(x)``: linear interpolation between vertices; beyond the ends, linear
        extrapolation of the end segments, metres."""
        xs, ys = self._xs, self._ys
        x = np.asarray(x, dtype=np.float64)
        y = np.asarray(np.interp(x, xs, ys))
        # Only the points beyond the ends are extrapolated (the same arithmetic per element).
        below = x < xs[0]
        if below.any():
            y[below] = ys[0] + self._low_slope * (x[below] - xs[0])
        above = x > xs[-1]
        if above.any():
            y[above] = ys[-1] + self._high_slope * (x[above] - xs[-1])
        return y

    def errors(self, estimated: npt.ArrayLike) -> tuple[float, float]:
        """``(sigma, sigma_prime)`` of localized points against this path, metres (see
        :func:`path_errors`).

        Raises:
            ValueError: for ``estimated`` not ``(m, 2)`` finite metres with m >= 1.
        """
        points = points_array(estimated, "estimated")
        y_difference = points[:, 1] - self.y_at(points[:, 0])
        sigma = math.sqrt(_mean(y_difference**2))
        sigma_prime = _mean(self._distances(points, y_difference))
        return sigma, sigma_prime

    def _distances(self, points: FloatArray, y_difference: FloatArray) -> FloatArray:
        """:func:`distances_to_polyline` of ``points`` to this path, metres.

        The vertical gap ``|y - f(x)|`` (inside the path's x range), or the distance to the
        nearer end vertex, bounds each point's distance ``u``; the nearest point of the path
        then lies within ``x +- u``, so only the segments overlapping that x window can hold
        it. The windows are found and searched point by point in
        :func:`sonar_gym.localization.roh_kernels.path_distances`, with the per-segment
        arithmetic of :func:`distances_to_polyline`, so the results agree.
        """
        segments = self._segments
        return np.asarray(
            roh_kernels.path_distances(
                points,
                y_difference,
                self._ends,
                self._xs,
                self._increasing,
                segments.sx,
                segments.sy,
                segments.dx,
                segments.dy,
                segments.safe_length_sq,
                segments.degenerate,
            )
        )


def path_errors(estimated: npt.ArrayLike, true: npt.ArrayLike) -> tuple[float, float]:
    """The path errors ``(sigma, sigma_prime)`` of Sec. IV.B, metres.

    * ``sigma``: the RMS "difference between the y-coordinate of a localized path and that
      of an actual path". The actual path is a curve ``y = f(x)``; for each localized point
      ``(x_e, y_e)`` the difference is ``y_e - f(x_e)``, with ``f`` the true polyline
      interpolated linearly at the same x (extrapolated linearly beyond its ends). It is not
      the difference between points of equal time index. It grows where the path is steep:
      a normal offset ``e`` shows as ``e * sqrt(1 + f'(x)^2)`` in y.
    * ``sigma_prime``: "an average distance from every single data point in a localized path
      to an actual path": the mean over localized points of the Euclidean distance to the
      true polyline (nearest point on any of its segments).

    To score many localized paths against one true path, build :class:`TruePath` once.

    Args:
        estimated: ``(m, 2)`` localized points, metres (only successful fixes; no NaN).
        true: ``(n, 2)`` vertices of the true path, n >= 2, whose x is strictly monotonic
            (increasing or decreasing) so that it is a function ``y = f(x)``.

    Returns:
        ``(sigma, sigma_prime)`` in metres.

    Raises:
        ValueError: on wrong shapes, non-finite values, or a true path whose x is not
            strictly monotonic.
    """
    points = points_array(estimated, "estimated")
    return TruePath(true).errors(points)
