"""Two pieces of the APCS stream's glue as they were written: the chosen roots of eq. (4)
(:func:`tests.localization.apcs_row_kernels_reference.chosen_roots_once`) with the sine and
cosine of each pair's first and second reading taken apart, and the sensor positions of
:func:`sonar_gym.localization.apcs_online._sensor_positions` through ``np.column_stack``: the
forms the modules replaced, kept as the tests' reference."""

from __future__ import annotations

import math

import numpy as np

from sonar_gym.localization.apcs_walls import IntArray
from sonar_gym.pose import FloatArray
from tests.localization.apcs_row_kernels_reference import chosen_roots, pair_geometry


def chosen_roots_sliced(
    positions: FloatArray,
    directions: FloatArray,
    ranges: FloatArray,
    valid_range_m: tuple[float, float],
) -> tuple[FloatArray, IntArray]:
    """``(phi, pairs)`` of ``_newest_points`` on checked inputs (``N >= 2``), with the ranges
    outside ``valid_range_m`` taken as dropouts: the loops of
    :mod:`~tests.localization.apcs_row_kernels_reference` with numpy's trigonometry between
    them."""
    low, high = valid_range_m
    first, second = directions[:-1], directions[1:]
    sin_alpha, cos_alpha, cosine, solvable, beam_y, beam_x = pair_geometry(
        positions, ranges, low, high, np.sin(first), np.sin(second), np.cos(first), np.cos(second)
    )
    return chosen_roots(  # type: ignore[no-any-return]
        np.arctan2(sin_alpha, cos_alpha),  # alpha of eqs (5)-(6)
        np.arccos(cosine),  # the offset of the roots of eq. (4)
        np.arctan2(beam_y, beam_x),  # the pair's mean beam axis
        solvable,
    )


def sensor_positions_stacked(poses: FloatArray, side: str, offset_m: float) -> FloatArray:
    """``(n, 2)`` positions of ``side``'s sensor for rows ``[x, y, theta]`` of ``poses``."""
    if offset_m == 0.0:
        return poses[:, :2].copy()
    sign = 1.0 if side == "left" else -1.0
    angle = poses[:, 2] + sign * math.pi / 2.0
    return poses[:, :2] + offset_m * np.column_stack([np.cos(angle), np.sin(angle)])
