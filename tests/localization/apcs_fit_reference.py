""":func:`sonar_gym.localization.apcs_walls.fit_group_points` as it was written with numpy
arrays throughout (``np.linalg.eigh``, array end points): the form its float glue replaced,
kept as the tests' reference.

:func:`fit_group_points_numpy_glue` is the float-glue form as it was before the centroid moved
into a compiled loop and ``eigh`` was called as its LAPACK ufunc.
:func:`fit_group_points_two_sums` is the form with the compiled centroid as it was before the
cosines and the sines were summed in one reduction and the scatter divided in place.
"""

from __future__ import annotations

import numpy as np

from sonar_gym.localization import apcs_kernels
from sonar_gym.localization.apcs_walls import (
    DEFAULT_PARAMETERS,
    GROUP_OK,
    GROUP_TOO_MUCH_VARIANCE,
    GROUP_ZERO_LENGTH,
    ZERO_LENGTH_M,
    APCSParameters,
    DetectedWall,
    WallFit,
)
from sonar_gym.pose import FloatArray


def fit_group_points_arrays(
    members: FloatArray,
    directions: FloatArray | None,
    indices: tuple[int, ...],
    params: APCSParameters = DEFAULT_PARAMETERS,
) -> WallFit:
    """The verdict on one checked group of ERPs (Yamamoto et al. sec. 4.2.2-4.2.3, Fig. 6),
    every step on numpy arrays."""
    centroid = np.add.reduce(members, axis=0) / len(members)
    centred = members - centroid
    scatter = centred.T @ centred / len(indices)
    eigenvalues, eigenvectors = np.linalg.eigh(scatter)
    along = eigenvectors[:, 1]
    residual_variance = float(max(eigenvalues[0], 0.0))
    if residual_variance >= params.variance_threshold_m2:
        return WallFit(GROUP_TOO_MUCH_VARIANCE, indices, residual_variance)

    occupied_side = np.array([-along[1], along[0]])
    if directions is not None:
        towards_wall = np.array([np.cos(directions).sum(), np.sin(directions).sum()])
        flip = float(occupied_side @ towards_wall) < 0.0
    else:
        flip = float((centred[-1] - centred[0]) @ along) < 0.0
    if flip:
        along = -along

    positions_along = centred @ along
    extent_start, extent_end = float(positions_along.min()), float(positions_along.max())
    if extent_end - extent_start <= ZERO_LENGTH_M:
        return WallFit(GROUP_ZERO_LENGTH, indices, residual_variance)
    start = centroid + extent_start * along
    end = centroid + extent_end * along
    wall = DetectedWall(tuple(start.tolist()), tuple(end.tolist()), indices, residual_variance)
    return WallFit(GROUP_OK, indices, residual_variance, wall)


def fit_group_points_numpy_glue(
    members: FloatArray,
    directions: FloatArray | None,
    indices: tuple[int, ...],
    params: APCSParameters = DEFAULT_PARAMETERS,
) -> WallFit:
    """:func:`~sonar_gym.localization.apcs_walls.fit_wall_group` of a group given as its own
    points, on checked inputs, as it was written with numpy's centroid, ``np.linalg.eigh`` and
    float glue.

    Args:
        members: ``(n, 2)`` the group's ERPs, finite, metres in {W}, with
            ``n >= params.min_group_size``.
        directions: ``(n,)`` their reflection directions, radians in (-pi, pi], or ``None``
            for plain points.
        indices: the group's positions in the ERP sequence (kept in the verdict).
    """
    centroid = np.add.reduce(members, axis=0) / len(members)  # members.mean(axis=0), as it sums
    centred = members - centroid
    scatter = centred.T @ centred / len(indices)
    values, eigenvectors = np.linalg.eigh(scatter)
    eigenvalues: list[float] = values.tolist()  # ascending
    residual_variance = max(eigenvalues[0], 0.0)
    if residual_variance >= params.variance_threshold_m2:
        return WallFit(GROUP_TOO_MUCH_VARIANCE, indices, residual_variance)

    along = eigenvectors[:, 1]
    along_x, along_y = along.tolist()
    occupied_side = np.array([-along_y, along_x])  # left of `along`
    if directions is not None:
        # np.add.reduce is what ndarray.sum calls, without its Python wrapper
        towards_wall = np.array(
            [np.add.reduce(np.cos(directions)), np.add.reduce(np.sin(directions))]
        )
        flip = float(occupied_side @ towards_wall) < 0.0
    else:
        flip = float((centred[-1] - centred[0]) @ along) < 0.0
    if flip:
        along = -along
        along_x, along_y = -along_x, -along_y

    positions_along = (centred @ along).tolist()
    extent_start, extent_end = min(positions_along), max(positions_along)
    if extent_end - extent_start <= ZERO_LENGTH_M:
        return WallFit(GROUP_ZERO_LENGTH, indices, residual_variance)
    centroid_x, centroid_y = centroid.tolist()
    start = (centroid_x + extent_start * along_x, centroid_y + extent_start * along_y)  # T_s
    end = (centroid_x + extent_end * along_x, centroid_y + extent_end * along_y)  # T_e
    # floats from the fit, a tuple of ints: what the constructor's conversions would give
    wall = DetectedWall.unchecked(start, end, indices, residual_variance)
    return WallFit(GROUP_OK, indices, residual_variance, wall)


def fit_group_points_two_sums(
    members: FloatArray,
    directions: FloatArray | None,
    indices: tuple[int, ...],
    params: APCSParameters = DEFAULT_PARAMETERS,
) -> WallFit:
    """:func:`fit_wall_group` of a group given as its own points, on checked inputs.

    Args:
        members: ``(n, 2)`` the group's ERPs, finite, metres in {W}, with
            ``n >= params.min_group_size``.
        directions: ``(n,)`` their reflection directions, radians in (-pi, pi], or ``None``
            for plain points.
        indices: the group's positions in the ERP sequence (kept in the verdict).
    """
    # members.mean(axis=0), as it sums, and the ERPs relative to it, in one compiled loop
    centred, centroid_x, centroid_y = apcs_kernels.centred_group(members)
    scatter = centred.T @ centred / len(indices)
    values, eigenvectors = np.linalg.eigh(scatter)
    eigenvalues: list[float] = values.tolist()  # ascending
    residual_variance = max(eigenvalues[0], 0.0)
    if residual_variance >= params.variance_threshold_m2:
        return WallFit(GROUP_TOO_MUCH_VARIANCE, indices, residual_variance)

    along = eigenvectors[:, 1]
    along_x, along_y = along.tolist()
    occupied_side = np.array([-along_y, along_x])  # left of `along`
    if directions is not None:
        # np.add.reduce is what ndarray.sum calls, without its Python wrapper
        towards_wall = np.array(
            [np.add.reduce(np.cos(directions)), np.add.reduce(np.sin(directions))]
        )
        flip = float(occupied_side @ towards_wall) < 0.0
    else:
        flip = float((centred[-1] - centred[0]) @ along) < 0.0
    if flip:
        along = -along
        along_x, along_y = -along_x, -along_y

    positions_along = (centred @ along).tolist()
    extent_start, extent_end = min(positions_along), max(positions_along)
    if extent_end - extent_start <= ZERO_LENGTH_M:
        return WallFit(GROUP_ZERO_LENGTH, indices, residual_variance)
    start = (centroid_x + extent_start * along_x, centroid_y + extent_start * along_y)  # T_s
    end = (centroid_x + extent_end * along_x, centroid_y + extent_end * along_y)  # T_e
    # floats from the fit, a tuple of ints: what the constructor's conversions would give
    wall = DetectedWall.unchecked(start, end, indices, residual_variance)
    return WallFit(GROUP_OK, indices, residual_variance, wall)
