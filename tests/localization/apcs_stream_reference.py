"""The readings of :meth:`sonar_gym.localization.apcs_online.WallStream.pending_erps` as numpy
arrays: the form :func:`sonar_gym.localization.apcs_kernels.reading_table` replaced (its ERPs
through :mod:`tests.localization.apcs_row_kernels_reference`), kept as the tests' reference."""

from __future__ import annotations

import numpy as np

from sonar_gym.localization.apcs_online import BEAM_OFFSET_RAD, WallStream
from sonar_gym.pose import FloatArray
from tests.localization.apcs_row_kernels_reference import newest_reflection_rows


def pending_erps_arrays(
    stream: WallStream, positions: FloatArray, headings: FloatArray, ranges: FloatArray
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """``stream``'s pending ERPs of checked readings (Yamamoto et al. sec. 4.2.1): its stored
    reading put before them with ``np.vstack`` and ``np.concatenate``."""
    directions = headings + BEAM_OFFSET_RAD[stream.side]
    if stream._previous is not None:
        previous_xy, previous_direction, previous_range = stream._previous
        positions = np.vstack([previous_xy, positions])
        directions = np.concatenate([[previous_direction], directions])
        ranges = np.concatenate([[previous_range], ranges])
        skipped = 1
    else:
        skipped = 0
    return newest_reflection_rows(
        positions, directions, ranges, stream.params.sensing_range_m, skipped
    )
