"""The last step of :func:`sonar_gym.sonar.echoes.echo_candidates` in its array form, which
:func:`sonar_gym.sonar.kernels.nearest_first` replaced, kept as the tests' reference."""

from __future__ import annotations

import numpy as np

from sonar_gym.pose import FloatArray


def nearest_first_reference(
    keep: np.ndarray,
    clear: np.ndarray,
    kept: FloatArray,
    ranges: FloatArray,
    amplitudes: FloatArray,
) -> tuple[np.ndarray, FloatArray, FloatArray, FloatArray]:
    """``(indices, unit directions, path lengths, amplitudes)`` of ``keep[clear]``, nearest
    first by a stable argsort of their ranges."""
    keep, kept = keep[clear], kept[clear]
    order = ranges.take(keep).argsort(kind="stable")
    keep = keep[order]
    path_lengths = ranges.take(keep)
    directions = kept[order, :2] / path_lengths[:, None]
    return keep, directions, path_lengths, amplitudes.take(keep)
