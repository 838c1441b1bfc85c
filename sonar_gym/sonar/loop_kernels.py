"""The compiled loop of :func:`sonar_gym.sonar.echo_tables.convex_loops` (numba): which side of
each segment is solid, from which segment's end meets which one's start.

The array form spent most of its time in numpy's per-call overhead on a few dozen segments.
This loop does its arithmetic element by element in the same order (differences, the two
products of each cross product and their difference, the sign of the first turn times each
cross product), all IEEE-754 steps that numba rounds as numpy does (no fused multiply-add without
``fastmath``: :mod:`sonar_gym.compiled`), so every comparison, and hence the result, is the same.
"""

from __future__ import annotations

import numpy as np
from numba import types

from sonar_gym.compiled import TABLE, compiled
from sonar_gym.pose import FloatArray

_JOINS = types.Array(types.boolean, 2, "A", readonly=True)
_LOOP = types.Array(types.int64, 1, "A", readonly=True)

TURN_TOLERANCE = 1e-12
"""A loop is convex when every turn (cross product of consecutive sides, m^2) exceeds this, or
every one is below its negative."""


def _settle_loop(
    starts: FloatArray,
    ends: FloatArray,
    centres: FloatArray,
    loop: np.ndarray,
    loop_tolerance_m: float,
    solid_side: FloatArray,
    encloses: np.ndarray,
) -> None:
    """Write the solid side and enclosure flag of one closed loop's segments, if it is convex."""
    size = loop.shape[0]
    first_turn = 0.0
    all_left, all_right = True, True
    for k in range(size):
        i, following = loop[k], loop[(k + 1) % size]
        dx, dy = ends[i, 0] - starts[i, 0], ends[i, 1] - starts[i, 1]
        nx, ny = (
            ends[following, 0] - starts[following, 0],
            ends[following, 1] - starts[following, 1],
        )
        turn = dx * ny - dy * nx
        if k == 0:
            first_turn = turn
        all_left = all_left and turn > TURN_TOLERANCE
        all_right = all_right and turn < -TURN_TOLERANCE
    if not (all_left or all_right):
        return  # not convex: reflects on both sides
    side = np.sign(first_turn)
    enclosure = True
    for k in range(size):
        i = loop[k]
        ax, ay = starts[i, 0], starts[i, 1]
        dx, dy = ends[i, 0] - ax, ends[i, 1] - ay
        for points in (starts, ends, centres):
            for p in range(points.shape[0]):
                cross = dx * (points[p, 1] - ay) - dy * (points[p, 0] - ax)
                if not side * cross >= -loop_tolerance_m:
                    enclosure = False
                    break
            if not enclosure:
                break
        if not enclosure:
            break
    for k in range(size):
        solid_side[loop[k]] = -side if enclosure else side
        encloses[loop[k]] = enclosure


settle_loop = compiled(
    types.none,
    TABLE,
    TABLE,
    TABLE,
    _LOOP,
    types.float64,
    types.Array(types.float64, 1, "C"),
    types.Array(types.boolean, 1, "C"),
    inline=True,
)(_settle_loop)
"""Compiled :func:`_settle_loop`, called by :func:`solid_sides` once per closed loop."""


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.float64, 1, "C"), types.Array(types.boolean, 1, "C"))),
    TABLE,  # starts
    TABLE,  # ends
    TABLE,  # centres
    _JOINS,  # joins[i, j]: end i meets start j
    types.float64,  # loop_tolerance_m
)
def solid_sides(
    starts: FloatArray,
    ends: FloatArray,
    centres: FloatArray,
    joins: np.ndarray,
    loop_tolerance_m: float,
) -> tuple[FloatArray, np.ndarray]:
    """``(S,)`` solid side (+1 left, -1 right, 0 none) and whether each segment encloses.

    A segment's successor is the one segment whose start its end meets (none when it meets
    several). Walked from each segment in turn that no earlier walk reached, a chain that comes
    back to its first segment after at least three is a loop; a convex loop is an enclosure
    when every end point and centre lies on its interior side (within ``loop_tolerance_m``),
    solid outside, else an obstacle, solid inside.
    """
    n = starts.shape[0]
    solid_side = np.zeros(n)
    encloses = np.zeros(n, dtype=np.bool_)
    successor = np.full(n, -1, dtype=np.int64)
    for i in range(n):
        count, first_join = 0, -1
        for j in range(n):
            if joins[i, j]:
                if count == 0:
                    first_join = j
                count += 1
        if count == 1:
            successor[i] = first_join
    seen = np.zeros(n, dtype=np.bool_)
    walk = np.full(n, -1, dtype=np.int64)  # the first segment of the walk that reached each
    loop = np.empty(n, dtype=np.int64)
    for first in range(n):
        if seen[first]:
            continue
        size = 0
        current = first
        while True:
            loop[size] = current
            size += 1
            walk[current] = first
            seen[current] = True
            following = successor[current]
            if following < 0 or walk[following] == first:
                break
            current = following
        if size >= 3 and successor[loop[size - 1]] == first:
            settle_loop(starts, ends, centres, loop[:size], loop_tolerance_m, solid_side, encloses)
    return solid_side, encloses


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.boolean, 2, "C"), types.boolean)),
    TABLE,  # from_points
    TABLE,  # to_points
    types.float64,  # tolerance_m
)
def closer_than(
    from_points: FloatArray, to_points: FloatArray, tolerance_m: float
) -> tuple[np.ndarray, bool]:
    """``[i, j]``: whether ``hypot`` of ``to_points[j] - from_points[i]`` is below
    ``tolerance_m`` (metres), and whether any pair was left undecided (its answer then False).

    A pair decides without ``hypot``: one coordinate difference at least ``tolerance_m`` (or
    NaN) puts the length (``hypot``, within an ulp) at or above it (no); both under half of it
    put the length under ``0.71 tolerance_m`` (yes). A pair in between is left to the caller.
    """
    n_from, n_to = from_points.shape[0], to_points.shape[0]
    closer = np.zeros((n_from, n_to), dtype=np.bool_)
    undecided = False
    half = 0.5 * tolerance_m
    for i in range(n_from):
        for j in range(n_to):
            dx = abs(to_points[j, 0] - from_points[i, 0])
            dy = abs(to_points[j, 1] - from_points[i, 1])
            if dx < half and dy < half:
                closer[i, j] = True
            elif not (dx >= tolerance_m or dy >= tolerance_m or dx != dx or dy != dy):
                undecided = True
    return closer, undecided
