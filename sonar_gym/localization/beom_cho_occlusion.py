"""Occlusion-aware RCDs for Beom & Cho (1995): beacons whose RCD a nearer echo cut.

Not in the paper.

A first-echo sonar reports the earliest echo above threshold. When a wall, a corner or the other
beacon is heard at a shorter range while the beam still covers a beacon, that echo replaces the
beacon's on one side of its RCD. The paper's extraction (eqs (3)-(5)) then yields an RCD that is
too narrow for the 18-26 deg window of section III.B, with its centre ``beta`` pulled toward the
side that was not cut; or, when the two ranges differ by less than ``eps`` sample to sample, one
long RCD that runs from the beacon into the other object. Either way eq. (7) finds no pair.

This module rebuilds such beacons from what the pan still shows:

1. **Pieces.** Each RCD of the paper's extraction is split where a sample is nearer than the
   piece so far by at least ``eps / 2`` (a different object: the threshold delay only ever
   lengthens ranges, at a beacon RCD's edges) or farther than the piece's median by at least
   ``eps`` (a slow drift of small steps into another object).
2. **Ends.** An end of a piece is *occluded* when the sample beyond it is nearer than every
   sample of the piece by at least ``eps / 2``; *free* when that sample is a dropout or farther;
   *unknown* at the end of a partial pan.
3. **Hypotheses.** A piece with one occluded and one free end, whose visible extent is between
   ``min_visible_extent_rad`` and a beacon's expected extent, stands for either beacon: for
   each, an RCD with ``eta`` the beacon's expected angular extent (Table II: 22 deg for the
   small beacon, 24 deg for the large), ``beta`` the free end moved inward by half of it, and
   ``delta`` the median range of the piece (a cylinder's RCD has one range, that of the point
   on the line of centres). The symmetry measure of eq. (6) cannot be taken on a cut profile;
   such an RCD carries ``gamma = 0``. It carries its ``role`` too, and pairs only in that role:
   eq. (7) hardly tells the beacons apart (only their radii enter it), and a rebuilt extent
   says nothing about which beacon it was.

Because a rebuilt RCD may be either beacon, the retry asks by default that every pair within
eq. (7)'s tolerance agree on the place (``BeomChoParameters.rebuilt_agreement_m``, 0.1 m).

Pieces with no occluded end are ordinary RCDs (with eq. (6) on their own samples); pieces with
two occluded ends, or one occluded and one unknown, are dropped. The result feeds the paper's
filters, eq. (7) and eqs (8)-(15) unchanged (:func:`sonar_gym.localization.beom_cho.localize_scans`
with ``BeomChoParameters(extraction="occlusion_aware")`` tries it only when the paper's own
RCDs give no pair).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from enum import Enum

import numpy as np
import numpy.typing as npt

from sonar_gym.localization.beom_cho_rcd import (
    LARGE_BEACON_NAME,
    RCD,
    SMALL_BEACON_NAME,
    extract_rcds,
    make_rcd,
)
from sonar_gym.pose import wrap_angle

__all__ = ["EndState", "occlusion_aware_rcds", "split_at_other_objects"]


class EndState(Enum):
    """What lies beyond one end of an RCD piece."""

    FREE = "free"
    OCCLUDED = "occluded"
    UNKNOWN = "unknown"


def split_at_other_objects(
    indices: Sequence[int], ranges_m: npt.NDArray[np.float64], eps: float
) -> list[list[int]]:
    """Split one RCD (its sample indices in angular order) where another object takes over.

    A sample starts a new piece when it is nearer than every sample of the current piece by at
    least ``eps / 2``, or farther than the piece's median by at least ``eps``.

    Args:
        indices: the RCD's sample indices, in angular order.
        ranges_m: the pan's ranges in metres (finite at ``indices``).
        eps: ``epsilon`` of eqs (3)-(5), metres.
    """
    pieces: list[list[int]] = [[int(indices[0])]]
    for index in indices[1:]:
        piece_ranges = ranges_m[pieces[-1]]
        sample = ranges_m[index]
        if sample <= piece_ranges.min() - eps / 2.0 or sample >= np.median(piece_ranges) + eps:
            pieces.append([int(index)])
        else:
            pieces[-1].append(int(index))
    return pieces


def occlusion_aware_rcds(
    angles: npt.ArrayLike,
    ranges: npt.ArrayLike,
    eps: float,
    expected_extents_rad: tuple[float, float],
    min_visible_extent_rad: float,
) -> list[RCD]:
    """The RCDs of a pan with beacons cut by nearer echoes rebuilt (see the module docstring).

    Args:
        angles: pan angles in radians in the robot frame {R}, equally spaced, ascending.
        ranges: ranges in metres, NaN for dropouts.
        eps: ``epsilon`` of eqs (3)-(5), metres (Table I: 0.02 m).
        expected_extents_rad: the angular extents ``eta`` of the small and the large beacon's
            full RCDs, radians (Table II: 22 and 24 deg).
        min_visible_extent_rad: the smallest visible extent of a cut piece that is rebuilt,
            radians.

    Returns:
        Ordinary RCDs of the uncut pieces, then two rebuilt RCDs (small, large) per cut piece.
    """
    angles_rad = np.asarray(angles, dtype=np.float64)
    ranges_m = np.asarray(ranges, dtype=np.float64)
    count = len(angles_rad)
    if count < 2:
        return []
    increment_rad = (angles_rad[-1] - angles_rad[0]) / (count - 1)
    full_turn = (
        abs(angles_rad[-1] - angles_rad[0] + increment_rad - 2.0 * math.pi) <= 1e-3 * increment_rad
    )

    def beyond(index: int, step: int) -> float | None:
        """The range beyond ``index`` (NaN = dropout), or None past the end of a partial pan."""
        neighbour = index + step
        if full_turn:
            return float(ranges_m[neighbour % count])
        if 0 <= neighbour < count:
            return float(ranges_m[neighbour])
        return None

    def end_state(piece_ranges: npt.NDArray[np.float64], outside: float | None) -> EndState:
        if outside is None:
            return EndState.UNKNOWN
        if math.isfinite(outside) and outside <= piece_ranges.min() - eps / 2.0:
            return EndState.OCCLUDED
        return EndState.FREE

    rebuilt: list[RCD] = []
    kept: list[RCD] = []
    for rcd in extract_rcds(angles_rad, ranges_m, eps):
        for piece in split_at_other_objects(rcd.indices, ranges_m, eps):
            if len(piece) < 2:
                continue
            piece_ranges = ranges_m[piece]
            start = end_state(piece_ranges, beyond(piece[0], -1))
            end = end_state(piece_ranges, beyond(piece[-1], +1))
            if EndState.OCCLUDED not in (start, end):
                kept.append(make_rcd(angles_rad, ranges_m, np.asarray(piece)))
                continue
            if {start, end} != {EndState.OCCLUDED, EndState.FREE}:
                continue
            visible_rad = (len(piece) - 1) * increment_rad
            first_angle = angles_rad[piece[0]]
            last_angle = first_angle + visible_rad
            delta = float(np.median(piece_ranges))
            for role, extent_rad in zip(
                (SMALL_BEACON_NAME, LARGE_BEACON_NAME), expected_extents_rad, strict=True
            ):
                if not min_visible_extent_rad <= visible_rad <= extent_rad + 1e-9:
                    continue
                if start is EndState.FREE:
                    beta = first_angle + extent_rad / 2.0
                else:
                    beta = last_angle - extent_rad / 2.0
                rebuilt.append(
                    RCD(delta=delta, beta=wrap_angle(beta), eta=extent_rad, gamma=0.0, role=role)
                )
    return kept + rebuilt
