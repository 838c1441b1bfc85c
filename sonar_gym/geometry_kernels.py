"""The compiled loop of the box corners' wall test (:func:`sonar_gym.geometry._box_corner_arms`).

A box corner within a tolerance of a wall stands on it; its arms then follow the wall. The
decisions rest on two dot products, which numpy takes with BLAS. This loop takes them with its
own arithmetic, so it may round them otherwise by a few units in the last place; it decides
only where every quantity compared clears its threshold by a margin far above any such
difference, and marks the other corners *undecided*, for the caller to test as numpy does. So
every decision, and hence every arm (a copy of a box side's direction, or its negative), is the
one numpy's arithmetic gives.
"""

from __future__ import annotations

import numpy as np
from numba import types

from sonar_gym.compiled import INDICES, NUMBERS, TABLE, compiled
from sonar_gym.pose import FloatArray

DECISION_MARGIN = 1e-12
"""Relative margin: a distance (metres) decides when it clears its threshold by this times
``1 + |point| + |wall start| + wall length`` (max-norms), a cosine when it clears 0.99 by this.
Rounding the two-term dot products otherwise moves them by under 1e-14 of that scale."""

ALONG_COSINE = 0.99
"""A corner's next side whose direction's cosine with the wall exceeds this (in magnitude) runs
along the wall."""


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.float64, 3, "C"), types.Array(types.boolean, 1, "C"))),
    TABLE,  # points
    TABLE,  # to_next
    TABLE,  # to_previous
    TABLE,  # wall starts
    TABLE,  # wall spans
    NUMBERS,  # wall lengths
    INDICES,  # pair point index
    INDICES,  # pair wall index
    types.float64,  # tolerance_m
)
def corner_arms(
    points: FloatArray,
    to_next: FloatArray,
    to_previous: FloatArray,
    starts: FloatArray,
    spans: FloatArray,
    lengths: FloatArray,
    point_index: np.ndarray,
    segment: np.ndarray,
    tolerance_m: float,
) -> tuple[FloatArray, np.ndarray]:
    """``(P, 2, 2)`` arms of the ``(P, 2)`` corners and ``(P,)`` whether each is undecided.

    For every pair ``(point_index[k], segment[k])`` the wall passes the corner when the
    corner's position along it, ``t`` (metres from its start), is in ``[-tolerance_m, length
    + tolerance_m]`` and the corner is within ``tolerance_m`` of the foot at ``t``. A corner
    on no wall keeps ``(to_next, to_next)``; on walls, the lowest passing wall gives
    ``(to_previous, -to_next)`` when the next side runs along it, else ``(to_next,
    -to_previous)``. A corner any of whose pairs is too close to a threshold is undecided
    (its arms are then meaningless).
    """
    n_points = points.shape[0]
    n_segments = starts.shape[0]
    lowest = np.full(n_points, n_segments, dtype=np.int64)
    undecided = np.zeros(n_points, dtype=np.bool_)
    for k in range(segment.shape[0]):
        p, i = point_index[k], segment[k]
        px, py = points[p, 0], points[p, 1]
        ax, ay = starts[i, 0], starts[i, 1]
        sx, sy = spans[i, 0], spans[i, 1]
        length = lengths[i]
        margin = DECISION_MARGIN * (1.0 + max(abs(px), abs(py)) + max(abs(ax), abs(ay)) + length)
        t = ((px - ax) * sx + (py - ay) * sy) / length
        if t < -tolerance_m - margin or t > length + tolerance_m + margin:
            continue  # clearly outside the wall's reach
        if not (-tolerance_m + margin < t < length + tolerance_m - margin):
            undecided[p] = True  # too close to call (or NaN)
            continue
        ox = px - (ax + sx * t / length)
        oy = py - (ay + sy * t / length)
        distance = np.sqrt(ox * ox + oy * oy)
        if distance > tolerance_m + margin:
            continue
        if not distance < tolerance_m - margin:
            undecided[p] = True
            continue
        lowest[p] = min(lowest[p], i)
    arms = np.empty((n_points, 2, 2))
    for p in range(n_points):
        arms[p, 0, 0], arms[p, 0, 1] = to_next[p, 0], to_next[p, 1]
        arms[p, 1, 0], arms[p, 1, 1] = to_next[p, 0], to_next[p, 1]
        i = lowest[p]
        if undecided[p] or i == n_segments:
            continue
        wx, wy = spans[i, 0] / lengths[i], spans[i, 1] / lengths[i]
        cosine = abs(wx * to_next[p, 0] + wy * to_next[p, 1])
        if abs(cosine - ALONG_COSINE) <= DECISION_MARGIN or cosine != cosine:
            undecided[p] = True
            continue
        if cosine > ALONG_COSINE:  # the next side runs along the wall: the previous one leaves
            arms[p, 0, 0], arms[p, 0, 1] = to_previous[p, 0], to_previous[p, 1]
            arms[p, 1, 0], arms[p, 1, 1] = -to_next[p, 0], -to_next[p, 1]
        else:
            arms[p, 1, 0], arms[p, 1, 1] = -to_previous[p, 0], -to_previous[p, 1]
    return arms, undecided
