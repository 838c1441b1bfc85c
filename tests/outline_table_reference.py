"""The table of a world's static outlines as
:meth:`sonar_gym.path_clearance.StaticShapeTable.of_outlines` built it with numpy before it
became a compiled loop: the form kept as the tests' reference."""

from __future__ import annotations

import numpy as np

from sonar_gym.path_clearance import CIRCLE, SEGMENT, StaticShapeTable
from sonar_gym.pose import FloatArray


def reference_of_outlines(
    segment_starts: FloatArray, segment_ends: FloatArray, circles: FloatArray
) -> StaticShapeTable:
    """The table :meth:`of` gives for segments of radius 0 from ``segment_starts`` to
    ``segment_ends`` (``(S, 2)`` each) followed by circles ``(C, 3)`` ``[x, y, radius]``,
    made on a space's static body (at the origin, angle 0) and added to its space; built
    from the numbers pymunk was given instead of read back from its shapes.

    pymunk maps a point to {W} as ``1 x + 0 y + 0``: the same number, but for ``-0.0``,
    which becomes ``0.0``. The bounding boxes and circle centres are of mapped points; a
    segment's end points are kept as given.
    """
    a = segment_starts + 0.0  # as mapped to {W} by the static body
    b = segment_ends + 0.0
    centres, radii = circles[:, :2] + 0.0, circles[:, 2:3]
    bounds = np.concatenate(
        [
            np.concatenate([np.minimum(a, b), np.maximum(a, b)], axis=1),
            np.concatenate([centres - radii, centres + radii], axis=1),
        ]
    )
    n_segments, n_circles = len(a), len(centres)
    kinds = np.concatenate(
        [
            np.full(n_segments, SEGMENT, dtype=np.int64),
            np.full(n_circles, CIRCLE, dtype=np.int64),
        ]
    )
    rows = np.zeros((n_segments + n_circles, 5))
    rows[:n_segments, :2] = segment_starts
    rows[:n_segments, 2:4] = segment_ends
    rows[n_segments:, :2] = centres
    rows[n_segments:, 2:3] = radii
    for array in (bounds, kinds, rows):
        array.setflags(write=False)
    return StaticShapeTable(bounds, kinds, rows)
