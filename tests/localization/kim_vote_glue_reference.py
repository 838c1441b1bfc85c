"""Kim's vote glue as it was first written, kept as the tests' reference: the readings gathered
with one concatenation per field (:func:`gather_readings_reference`), and the unchecked vote
through the general ``_vote`` (:func:`vote_localize_unchecked_reference`)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from sonar_gym.localization import kim_kernels
from sonar_gym.localization.kim import (
    Anchor,
    OccupancyGrid,
    Sweep,
    VoteLocalization,
    _headings_around,
    _Readings,
    _vote,
)
from sonar_gym.pose import Pose


def gather_readings_reference(sweeps: Sequence[Sweep], max_range_m: float | None) -> _Readings:
    """The readings of every sweep with an echo, as :func:`sweep_end_points` of each sweep at
    its odometry, concatenated (the same arithmetic, element by element, in one pass: compiled
    loops around numpy's ``cos`` and ``sin`` of the beams)."""
    angles = np.concatenate([sweep.angles for sweep in sweeps])
    ranges = np.concatenate([sweep.ranges for sweep in sweeps])
    counts = np.array([sweep.ranges.size for sweep in sweeps])
    # heading and sensor position of each sweep, in the first sweep's frame
    frames = []
    for sweep in sweeps:
        pose = sweep.odometry
        offset_x, offset_y = sweep.sensor_offset
        c, s = math.cos(pose.theta), math.sin(pose.theta)
        frames.append(
            (pose.theta, pose.x + c * offset_x - s * offset_y, pose.y + s * offset_x + c * offset_y)
        )
    sweep_frames = np.array(frames)
    max_range = math.inf if max_range_m is None else float(max_range_m)
    beam = kim_kernels.echo_beams(angles, ranges, counts, sweep_frames, max_range)
    rows = kim_kernels.echo_end_points(
        ranges, counts, sweep_frames, np.cos(beam), np.sin(beam), max_range
    )
    return _Readings(rows[0], rows[1], beam, rows[2])


def vote_localize_unchecked_reference(
    grid: OccupancyGrid,
    sweeps: Sequence[Sweep],
    search_center: Pose,
    search_radius: float,
    *,
    heading_step_rad: float,
    heading_window_rad: float,
    max_range_m: float,
    anchor: Anchor,
) -> VoteLocalization:
    """``vote_localize(grid, sweeps, search_center=..., search_radius=..., heading_step_rad=...,
    heading_window_rad=..., max_range_m=..., anchor=..., return_vote_map=False)`` without the
    argument checks, the other arguments at their defaults.

    For callers that build the arguments from their own checked state (the EKF loop of
    :mod:`~sonar_gym.localization.kim_fix`): finite floats (metres, radians), a step and a
    radius > 0, a window >= 0, a list of :class:`Sweep` whose first odometry is the identity.
    Anything else is the caller's error.
    """
    headings = _headings_around(search_center.theta, heading_window_rad, heading_step_rad)
    return _vote(
        grid,
        sweeps,
        headings,
        (search_center.x, search_center.y),
        search_radius,
        max_range_m,
        grid.cell_size_m,
        360,
        "smoothed",
        "vote_mean",
        anchor,
        None,
        (0.15, math.radians(10.0)),
        False,
    )
