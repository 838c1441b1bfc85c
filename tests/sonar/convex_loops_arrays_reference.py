"""Which side of each segment is solid, all loops at once as arrays with the per-loop verdicts
on Python lists: the form :func:`sonar_gym.sonar.echo_tables.convex_loops` replaced by a
compiled loop, kept as the tests' reference."""

from __future__ import annotations

import numpy as np

from sonar_gym.pose import FloatArray
from sonar_gym.sonar.echo_tables import LOOP_TOLERANCE_M, _pairwise_distances


def reference_array_convex_loops(
    starts: FloatArray, ends: FloatArray, centres: FloatArray
) -> tuple[FloatArray, np.ndarray]:
    """Per segment: the side of its solid and whether it belongs to an enclosure.

    Segments chained end to start into a closed convex polygon are either an *enclosure* (the
    polygon contains every end point and centre of the geometry: a room, solid outside) or an
    obstacle (a box, solid inside). ``solid_side`` is +1 when the solid lies on the segment's
    left, -1 on its right, and 0 for segments of open chains (free walls), which reflect on
    both sides.
    """
    n = len(starts)
    joins = _pairwise_distances(ends, starts) < LOOP_TOLERANCE_M  # [i, j]: end i meets start j
    successor = [-1] * n
    if n:  # (argmax refuses an empty axis)
        successor = np.where(joins.sum(axis=1) == 1, joins.argmax(axis=1), -1).tolist()
    loops = reference_closed_chains(successor)
    if not loops:
        return np.zeros(n), np.zeros(n, dtype=bool)
    # All loops at once, row by row the arithmetic of one loop: its members in loop order; the
    # few per-loop verdicts on Python lists.
    members = [segment for loop in loops for segment in loop]
    firsts = [0] * len(loops)  # the row of each loop's first member
    next_rows: list[int] = []  # each member's row of the next member of its loop
    for k, loop in enumerate(loops):
        firsts[k] = len(next_rows)
        next_rows += range(firsts[k] + 1, firsts[k] + len(loop))
        next_rows.append(firsts[k])
    d = ends[members] - starts[members]
    d_next = d[next_rows]
    turns = d[:, 0] * d_next[:, 1] - d[:, 1] * d_next[:, 0]
    points = np.concatenate([starts, ends, centres])
    offsets = points[None, :, :] - starts[members][:, None, :]
    crosses = d[:, None, 0] * offsets[..., 1] - d[:, None, 1] * offsets[..., 0]
    turn_list = turns.tolist()
    # The sign of each loop's first turn: which side of its segments the loop's interior lies.
    interior_left = [float(np.sign(turn_list[first])) for first in firsts]
    member_sides = [side for loop, side in zip(loops, interior_left, strict=True) for _ in loop]
    sides = np.array(member_sides)[:, None] * crosses
    inside_rows = np.all(sides >= -LOOP_TOLERANCE_M, axis=1).tolist()
    solid_side = [0.0] * n
    encloses = [False] * n
    for loop, side, first in zip(loops, interior_left, firsts, strict=True):
        rows = slice(first, first + len(loop))
        loop_turns = turn_list[rows]
        if not (all(t > 1e-12 for t in loop_turns) or all(t < -1e-12 for t in loop_turns)):
            continue  # not convex: reflects on both sides
        enclosure = all(inside_rows[rows])
        for segment in loop:
            solid_side[segment] = -side if enclosure else side
            encloses[segment] = enclosure
    return np.array(solid_side, dtype=np.float64), np.array(encloses, dtype=bool)


def reference_closed_chains(successor: list[int]) -> list[list[int]]:
    """The chains along ``successor`` (each segment's next, or -1) that close into a loop of
    at least three segments, walked from each segment in turn that no earlier walk reached."""
    loops: list[list[int]] = []
    seen = [False] * len(successor)
    for first in range(len(successor)):
        if seen[first]:
            continue
        loop = [first]
        while successor[loop[-1]] >= 0 and successor[loop[-1]] not in loop:
            loop.append(successor[loop[-1]])
        for segment in loop:
            seen[segment] = True
        if len(loop) >= 3 and successor[loop[-1]] == first:
            loops.append(loop)
    return loops
