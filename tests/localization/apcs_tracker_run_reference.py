""":meth:`sonar_gym.localization.apcs_online.APCSTracker.run_unchecked` as it was written when
every closed group, dropped or not, was built with its verdict and handed to
:meth:`~sonar_gym.localization.apcs_online.APCSTracker.handle_groups` (which only counts a
dropped one): the form the tracker's loop replaced, kept as the tests' reference, with the
tracker's way of storing the readings of that time (its rows as separate flat lists, its pending
ERPs those of :func:`tests.localization.apcs_row_kernels_reference.pending_rows`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import numpy.typing as npt

from sonar_gym.localization.apcs_online import (
    SIDE_NAMES,
    APCSTracker,
    RunResult,
    _sensor_positions,
)
from sonar_gym.odometry import checked_variance_per_m, predict_run_unchecked
from sonar_gym.pose import FloatArray, Pose
from tests.localization.apcs_row_kernels_reference import pending_rows

_PendingRows = tuple[list[float], list[float], list[float], list[bool]]
"""A side's rows from a reading on, as flat lists: sensor ``x0, y0, x1, ...`` (metres), ERP
``x0, y0, x1, ...`` (metres), reflection directions (radians), whether the reading gives an
ERP."""


def _store_readings(
    self: APCSTracker,
    unstored: dict[str, int],
    pending: Mapping[str, _PendingRows],
    headings: list[float],
    range_lists: Mapping[str, list[float]],
    first_sample: int,
) -> None:
    """Store each side's latest reading (``unstored``: side -> its sample) in its stream
    (:meth:`WallStream._remember`), from the plain-float rows of a pass of
    :meth:`run_unchecked` that starts at sample ``first_sample``; ``unstored`` is emptied."""
    for side, m in unstored.items():
        sensor_coordinates = pending[side][0]
        row = m - first_sample
        self.streams[side]._remember(
            sensor_coordinates[2 * row],
            sensor_coordinates[2 * row + 1],
            headings[row],
            range_lists[side][m],
        )
    unstored.clear()


def run_unchecked_reference(
    self: APCSTracker,
    encoder_left_m: FloatArray,
    encoder_right_m: FloatArray,
    sample_commands: npt.NDArray[np.int64],
    readings: Mapping[str, FloatArray],
    sensor_offset_m: float,
    stops: Sequence[int],
) -> RunResult:
    """:meth:`run` on checked arguments: finite float64 ``(K,)`` encoder increments
    (metres), ``(M,)`` int64 increasing command indices in ``[0, K)``, per side in
    :data:`SIDE_NAMES` float64 ``(M,)`` ranges ``>= 0`` metres (NaN = dropout)."""
    left, right, samples, ranges = encoder_left_m, encoder_right_m, sample_commands, readings
    sides = tuple(side for side in SIDE_NAMES if side in ranges)
    # The estimate, covariance and wheel base were checked on construction and stay so.
    variance_per_m = checked_variance_per_m(self.variance_per_m)
    poses, covariances = predict_run_unchecked(
        self.estimate, self.covariance, left, right, self.wheel_base_m, variance_per_m
    )
    result = RunResult(estimated_path=poses[1:].copy(), consumed=len(left))
    limit = len(left)
    # Events in time order: (sample, side). Pending ERPs are valid until a correction.
    events = [(m, side) for m in range(len(samples)) for side in sides]
    sample_list: list[int] = samples.tolist()
    range_lists = {side: ranges[side].tolist() for side in sides}
    event = 0
    while event < len(events) and sample_list[events[event][0]] < limit:
        first_sample = events[event][0]
        pending: dict[str, _PendingRows] = {}
        rows = poses[samples[first_sample:] + 1]
        for side in sides:
            sensor_xy = _sensor_positions(rows, side, sensor_offset_m)
            points, phis, valid = pending_rows(
                self.streams[side], sensor_xy, rows[:, 2], ranges[side][first_sample:]
            )
            # Flat lists of floats (x0, y0, x1, ...): no list per row to allocate.
            pending[side] = (
                sensor_xy.ravel().tolist(),
                points.ravel().tolist(),
                phis.tolist(),
                valid.tolist(),
            )
        headings = rows[:, 2].tolist()
        # WallStream.accept on plain floats. Each side's latest reading (its sample) is
        # stored in its stream only where the stored reading is read: before a verified
        # wall is handled (a correction moves the streams) and when this pass ends.
        unstored: dict[str, int] = {}
        corrected = False
        while event < len(events) and not corrected and sample_list[events[event][0]] < limit:
            m, side = events[event]
            event += 1
            unstored[side] = m
            _, erp_coordinates, erp_phis, erp_valid = pending[side]
            row = m - first_sample
            if not erp_valid[row]:
                continue
            point_x, point_y = erp_coordinates[2 * row], erp_coordinates[2 * row + 1]
            result.erps.append((point_x, point_y, side))
            groups = self.streams[side]._accept_erp(point_x, point_y, erp_phis[row])
            if groups:
                command = sample_list[m]
                # Only a verified wall reads the estimate (most closed groups are dropped);
                # the end of the run sets it in any case.
                if any(group.fit.wall is not None for group in groups):
                    _store_readings(self, unstored, pending, headings, range_lists, first_sample)
                    self.estimate = Pose.unchecked(*poses[command + 1].tolist())
                    self.covariance = covariances[command + 1]
                corrected = self.handle_groups(side, groups, command, result)
        _store_readings(self, unstored, pending, headings, range_lists, first_sample)
        if corrected:
            command = sample_list[events[event - 1][0]]
            later_stops = [stop for stop in stops if stop > command]
            if later_stops:
                limit = min(limit, later_stops[0])
            tail_poses, tail_covariances = predict_run_unchecked(
                self.estimate,
                self.covariance,
                left[command + 1 :],
                right[command + 1 :],
                self.wheel_base_m,
                variance_per_m,
            )
            poses = np.vstack([poses[: command + 1], tail_poses])
            covariances = np.concatenate([covariances[: command + 1], tail_covariances])
            result.estimated_path[command + 1 :] = tail_poses[1:]
    if limit < len(left):
        result.consumed = limit
        result.estimated_path = result.estimated_path[:limit]
    if limit:
        self.estimate = Pose.unchecked(*poses[limit].tolist())
        self.covariance = covariances[limit].copy()
    return result
