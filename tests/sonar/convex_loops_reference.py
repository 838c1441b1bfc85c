"""Which side of each segment is solid, with numpy's scalar indexing and ``np.roll``: the form
:func:`sonar_gym.sonar.echo_tables.convex_loops` replaced, kept as the tests' reference."""

from __future__ import annotations

import numpy as np

from sonar_gym.pose import FloatArray
from sonar_gym.sonar.echo_tables import LOOP_TOLERANCE_M, _pairwise_distances


def reference_convex_loops(
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
    successor = np.full(n, -1)
    if len(starts):  # (argmax refuses an empty axis)
        successor = np.where(joins.sum(axis=1) == 1, joins.argmax(axis=1), -1)
    points = np.concatenate([starts, ends, centres])
    solid_side = np.zeros(n)
    encloses = np.zeros(n, dtype=bool)
    seen = np.zeros(n, dtype=bool)
    for first in range(n):
        if seen[first]:
            continue
        loop = [first]
        while successor[loop[-1]] >= 0 and successor[loop[-1]] not in loop:
            loop.append(int(successor[loop[-1]]))
        seen[loop] = True
        if len(loop) < 3 or successor[loop[-1]] != first:
            continue
        d = ends[loop] - starts[loop]
        turns = d[:, 0] * np.roll(d[:, 1], -1) - d[:, 1] * np.roll(d[:, 0], -1)
        if not (np.all(turns > 1e-12) or np.all(turns < -1e-12)):
            continue
        interior_left = np.sign(turns[0])
        offsets = points[None, :, :] - starts[loop][:, None, :]
        sides = interior_left * (d[:, None, 0] * offsets[..., 1] - d[:, None, 1] * offsets[..., 0])
        enclosure = bool(np.all(sides >= -LOOP_TOLERANCE_M))
        solid_side[loop] = -interior_left if enclosure else interior_left
        encloses[loop] = enclosure
    return solid_side, encloses
