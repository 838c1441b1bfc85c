"""Beom & Cho (1995): pose from one rotating sonar and two passive cylindrical beacons.

The chain of the paper, section by section:

* section II.A, eq. (1): range from round-trip time of flight, and the speed-of-sound
  self-calibration against a reflector at the known distance ``d_c = 0.515 m``;
* section III.A, eqs (3)-(5): regions of constant distance (RCDs) in a pan;
* section III.B: the angular-extent filter ``18.0 deg <= eta <= 26.0 deg``;
* section III.C, eq. (6): the symmetry measure ``gamma`` and the filter ``gamma < gamma_T``;
* section III.D, eq. (7): the pair of RCDs whose implied beacon distance is nearest the known
  one (within 0.04 m), with the large/small assignment by angular extent;
* section IV, eqs (8)-(15): the two-circle intersection, the root chosen by the sign rule, and
  the heading.

Readings chosen where the text leaves room (each is restated where it is implemented):

* An RCD is a maximal run of at least two consecutive finite samples whose neighbouring ranges
  differ by less than ``eps`` (eqs (3)-(5)); a NaN (dropout) or the end of a partial pan breaks
  a run; a full turn wraps across +-180 deg.
* ``eta = beta_e - beta_s`` with ``beta_s``, ``beta_e`` the angles of the first and last samples
  of the RCD, no increment added (the paper's own definition). An RCD of ``N`` samples at
  increment ``dphi`` has ``eta = (N - 1) dphi``; Table II's 22.0 and 24.0 deg are 23 and 25
  samples at 1 deg, whose centre sample sits exactly at ``beta``.
* ``delta`` is the range at ``beta`` ("the range value along the angle beta"): the centre
  sample when ``N`` is odd, the mean of the two central samples when ``N`` is even. The centre
  is the sample least bent by the threshold delay that lengthens ranges at an RCD's edges.
* Eq. (11) as printed, ``x_R = y_R tan(psi) + L``, has a sign slip: subtracting eq. (9) from
  eq. (8) gives the radical axis ``x_R = L - y_R tan(psi)``, and eqs (10) and (12) are the
  quadratic obtained with this minus sign. The printed plus sign yields points that lie on
  neither circle (8.9 mm off the small-beacon circle for Table II), so the minus sign is used.
* Eq. (10)'s ``+-``: the root whose ``delta-phi`` (eqs (13)-(14)) has the sign of
  ``delta-beta = beta_S - beta_L`` (both wrapped to (-pi, pi]); the ``tan^-1`` of eqs (13)-(15)
  is the four-quadrant ``atan2``.
* ``D < 0`` (eq. (12)) gives the status ``"no_intersection"``, never a NaN.

Poses: :func:`localize_rcds` returns the pose of the sensor frame {P} on the pan axis (where
ranges are measured from) with the heading of the robot frame {R} (pan angles are relative to
the robot's x-axis); :func:`localize_scan` moves that to the robot centre using the sensor
offset of the scenario.

Beside the paper's solution, ``method="least_squares"`` refines it with a weighted
Gauss-Newton fit over both beacons' ranges and bearings
(:mod:`sonar_gym.localization.beom_cho_refine`).
"""

from __future__ import annotations

import itertools
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from sonar_gym.localization.beom_cho_occlusion import occlusion_aware_rcds
from sonar_gym.localization.beom_cho_rcd import (
    LARGE_BEACON_NAME,
    MIN_RCD_SAMPLES,
    RCD,
    SMALL_BEACON_NAME,
    _require_finite,
    _require_non_negative,
    _require_positive,
    _runs_of_links,
    _runs_with_parameters,
    _validated_scan_arrays,
    extract_rcds,
    make_rcd,
    rcd_runs,
    symmetry_measure,
)
from sonar_gym.localization.beom_cho_refine import central_range_estimate, refine_two_beacon_pose
from sonar_gym.localization.result import OK, OUT_OF_FLOAT_RANGE, Localization
from sonar_gym.pose import Pose, angle_difference, wrap_angle
from sonar_gym.sonar.scan import Scan

__all__ = [
    "LARGE_BEACON_NAME",
    "METHODS",
    "MIN_RCD_SAMPLES",
    "RCD",
    "SMALL_BEACON_NAME",
    "BeaconLike",
    "BeaconLocalization",
    "BeomChoParameters",
    "RobotLike",
    "ScenarioLike",
    "TwoCircleSolution",
    "ASSIGNMENTS",
    "EXTRACTIONS",
    "assign_large_and_small",
    "assigned_pair_distance_error",
    "extract_rcds",
    "filter_beacon_candidates",
    "heading_from_large_beacon",
    "localize_rcds",
    "localize_scan",
    "localize_scans",
    "make_rcd",
    "pair_distance_error",
    "range_from_tof",
    "solve_two_circles",
    "speed_of_sound_from_reflector",
    "symmetry_measure",
]

METHODS = ("paper", "least_squares")
"""Values of the ``method`` argument: the paper's closed form, or its least-squares refinement."""
ASSIGNMENTS = ("extent", "best_fit")
"""Values of :attr:`BeomChoParameters.assignment`: the paper's rule, or both tried."""
EXTRACTIONS = ("paper", "occlusion_aware")
"""Values of :attr:`BeomChoParameters.extraction`: the paper's RCDs only, or a second try with
beacons rebuilt from RCDs that nearer echoes cut
(:mod:`sonar_gym.localization.beom_cho_occlusion`)."""

REFLECTOR_DISTANCE_M = 0.515
"""``d_c`` of section II.A: distance from the rotating sonar to the calibration reflector."""

_EXTENT_TOLERANCE_RAD = 1e-9
"""Slack on the angular-extent bounds and on "equal extents", so that an extent of exactly
18 or 26 increments survives the rounding of angle differences."""

_UNSCALED_EXPONENT = 100
"""Eqs (8)-(14) run on the lengths as given while they all lie within ``2**+-100`` m (their
squares, and the ``1/cos psi`` factors, stay far from overflow and underflow); beyond, the
lengths are scaled by a power of two first."""

_PAPER_FORMULA_MIN_COS_PSI = 0.05
"""Eqs (10)-(12) divide by ``x_L - x_S`` and lose about ``2 log10|tan psi|`` significant digits;
when ``|x_L - x_S| < 0.05 d_0`` (the line of centres within 2.9 deg of the y-axis) the same two
intersection points are computed with the rotation-invariant construction instead."""


# --------------------------------------------------------------------------------------------
# Argument checks
# --------------------------------------------------------------------------------------------


def _point(name: str, value: tuple[float, float] | npt.ArrayLike) -> tuple[float, float]:
    if (
        type(value) is tuple
        and len(value) == 2
        and type(value[0]) is float
        and type(value[1]) is float
        and math.isfinite(value[0])
        and math.isfinite(value[1])
    ):
        return value  # a scenario's own (x, y), as every localization passes it
    array = np.asarray(value, dtype=np.float64)
    if array.shape != (2,) or not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be a finite (x, y) pair in metres, got {value!r}")
    return float(array[0]), float(array[1])


# --------------------------------------------------------------------------------------------
# Parameters and the RCD feature
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BeomChoParameters:
    """Parameters of the method; defaults are the paper's (Table I and section III).

    Attributes:
        eps_m: ``epsilon`` of eqs (3)-(5), metres: neighbouring ranges closer than this belong
            to one RCD (Table I: 0.02 m).
        eta_min_rad, eta_max_rad: angular-extent window of section III.B, radians
            (18.0 deg and 26.0 deg), bounds included.
        gamma_threshold_m: ``gamma_T`` of section III.C, metres; an RCD passes when
            ``gamma < gamma_T`` (Table I: 0.005).
        distance_tolerance_m: largest accepted ``Delta d_0`` of eq. (7), metres (0.04 m).
        r_min_m, r_max_m: sensing range of the sensor, metres (Table I: 0.3 m and 4.0 m).
            Readings outside it are dropouts, and an RCD whose ``delta`` lies outside it is not
            a beacon candidate.
        range_sigma_m: standard deviation of one range sample, metres; weights the
            least-squares refinement only.
        bearing_sigma_rad: standard deviation of an RCD's centre angle ``beta``, radians;
            weights the least-squares refinement only.
        assignment: which RCD of a pair is the large beacon. ``"extent"`` is the paper's rule
            (section III.D: the larger ``eta``; on a tie the larger ``delta``). ``"best_fit"``
            (not in the paper) tries both assignments in eq. (7) and keeps the one with the
            smaller error. It helps a sensor whose extents do not tell the beacons apart
            (an ideal piston at a fixed threshold, where range changes the extent as much as
            diameter does); with a sensor like the Polaroid preset, whose extents grow with
            diameter and not with range (Fig. 4), it swaps the beacons more often than the
            paper's rule does.
        extraction: ``"paper"`` (eqs (3)-(5) only) or ``"occlusion_aware"`` (not in the paper):
            when the paper's RCDs give no pair, try again with RCDs split where another object
            takes over and beacons rebuilt from RCDs a nearer echo cut short
            (:mod:`sonar_gym.localization.beom_cho_occlusion`).
        expected_extents_rad: angular extents of the small and the large beacon's full RCDs,
            radians (Table II: 22 and 24 deg); used by ``"occlusion_aware"`` only.
        min_visible_extent_rad: the smallest visible part of a cut RCD that is rebuilt,
            radians (5 deg: five samples at the paper's 1 deg increment); ``"occlusion_aware"``
            only.
        rebuilt_agreement_m: with ``"occlusion_aware"``, the retry gives a pose only if every
            beacon pair within eq. (7)'s tolerance puts the sensor within this many metres of
            the best one (a rebuilt RCD does not tell which beacon it was, so swapped pairs
            often pass eq. (7) too); ``None`` keeps the best pair regardless. On 1000 lab
            poses at 20 deg C, 0.1 m takes the retry's gain from +9.2 to +6.5 points of success
            and the poses it adds off by more than 10 cm from 1.3 % to 0.5 % of all poses.
    """

    eps_m: float = 0.02
    eta_min_rad: float = math.radians(18.0)
    eta_max_rad: float = math.radians(26.0)
    gamma_threshold_m: float = 0.005
    distance_tolerance_m: float = 0.04
    r_min_m: float = 0.3
    r_max_m: float = 4.0
    range_sigma_m: float = 0.003
    bearing_sigma_rad: float = math.radians(0.5)
    assignment: str = "extent"
    extraction: str = "paper"
    expected_extents_rad: tuple[float, float] = (math.radians(22.0), math.radians(24.0))
    min_visible_extent_rad: float = math.radians(5.0)
    rebuilt_agreement_m: float | None = 0.1

    def __post_init__(self) -> None:
        if self.assignment not in ASSIGNMENTS:
            raise ValueError(
                f"BeomChoParameters.assignment must be one of {ASSIGNMENTS}; "
                f"got {self.assignment!r}"
            )
        if self.extraction not in EXTRACTIONS:
            raise ValueError(
                f"BeomChoParameters.extraction must be one of {EXTRACTIONS}; "
                f"got {self.extraction!r}"
            )
        extents = self.expected_extents_rad
        if (
            not isinstance(extents, tuple)
            or len(extents) != 2
            or not all(isinstance(e, (int, float)) and 0.0 < e < math.pi for e in extents)
        ):
            raise ValueError(
                "BeomChoParameters.expected_extents_rad must be (small, large) extents in "
                f"(0, pi) radians; got {extents!r}"
            )
        for name in (
            "eps_m",
            "eta_max_rad",
            "gamma_threshold_m",
            "distance_tolerance_m",
            "r_max_m",
            "range_sigma_m",
            "bearing_sigma_rad",
        ):
            _require_positive(f"BeomChoParameters.{name}", getattr(self, name))
        if self.rebuilt_agreement_m is not None:
            _require_positive("BeomChoParameters.rebuilt_agreement_m", self.rebuilt_agreement_m)
        for name in ("eta_min_rad", "r_min_m", "min_visible_extent_rad"):
            _require_non_negative(f"BeomChoParameters.{name}", getattr(self, name))
        if self.eta_min_rad > self.eta_max_rad:
            raise ValueError(
                "BeomChoParameters.eta_min_rad must not exceed eta_max_rad "
                f"(got {self.eta_min_rad!r} > {self.eta_max_rad!r})"
            )
        if self.r_min_m >= self.r_max_m:
            raise ValueError(
                "BeomChoParameters.r_min_m must be below r_max_m "
                f"(got {self.r_min_m!r} >= {self.r_max_m!r})"
            )


# --------------------------------------------------------------------------------------------
# Section II.A: time of flight and speed-of-sound self-calibration
# --------------------------------------------------------------------------------------------


def range_from_tof(tof_s: float, speed_of_sound_mps: float) -> float:
    """Eq. (1): range ``delta = v_s t_0 / 2`` in metres from the round-trip time of flight.

    Args:
        tof_s: round-trip time of flight ``t_0``, seconds, > 0.
        speed_of_sound_mps: ``v_s``, metres per second, > 0.
    """
    _require_positive("tof_s", tof_s)
    _require_positive("speed_of_sound_mps", speed_of_sound_mps)
    return float(speed_of_sound_mps) * float(tof_s) / 2.0


def speed_of_sound_from_reflector(
    round_trip_tof_s: float, reflector_distance_m: float = REFLECTOR_DISTANCE_M
) -> float:
    """Section II.A self-calibration: ``v_s = 2 d_c / t_0`` (eq. (1) solved for ``v_s``), m/s.

    The sonar, tilted to 53.1 deg, pings the reflector on the robot's front face at the known
    distance ``d_c``; the measured round-trip time gives the current speed of sound without a
    temperature or humidity sensor.

    Args:
        round_trip_tof_s: measured round-trip time of flight to the reflector, seconds, > 0.
        reflector_distance_m: ``d_c``, metres, > 0 (the paper's 0.515 m by default).
    """
    _require_positive("round_trip_tof_s", round_trip_tof_s)
    _require_positive("reflector_distance_m", reflector_distance_m)
    return 2.0 * float(reflector_distance_m) / float(round_trip_tof_s)


# --------------------------------------------------------------------------------------------
# Sections III.B-III.D: filters and pair selection, eq. (7)
# --------------------------------------------------------------------------------------------


def filter_beacon_candidates(
    rcds: Sequence[RCD], params: BeomChoParameters = BeomChoParameters()
) -> tuple[RCD, ...]:
    """The RCDs that may be beacons: angular extent in ``[eta_min, eta_max]`` (section III.B),
    ``gamma < gamma_T`` (section III.C, eq. (6)) and ``r_min <= delta <= r_max`` (Table I)."""
    return tuple(
        rcd
        for rcd in rcds
        if _extent_and_range_pass(rcd.eta, rcd.delta, params)
        and rcd.gamma < params.gamma_threshold_m
    )


def _extent_and_range_pass(eta_rad: Any, delta_m: Any, params: BeomChoParameters) -> Any:
    """The filters of :func:`filter_beacon_candidates` but symmetry: on floats a bool, on
    arrays (one entry per RCD) a boolean array."""
    return (
        (params.eta_min_rad - _EXTENT_TOLERANCE_RAD <= eta_rad)
        & (eta_rad <= params.eta_max_rad + _EXTENT_TOLERANCE_RAD)
        & (params.r_min_m <= delta_m)
        & (delta_m <= params.r_max_m)
    )


def _plausible_rcds_of_pans(
    pans: Sequence[tuple[np.ndarray, np.ndarray]], params: BeomChoParameters
) -> tuple[int, list[RCD]]:
    """:func:`_plausible_rcds` summed over ``pans`` (each ``(angles, ranges)``, in their order).

    Pans that are not a full turn share one pass over their concatenated samples (with the
    links between pans cut), as an agent's sector pans leave many short chains in the scan
    memory; a full turn, whose RCDs may wrap, gets a pass of its own. Any pan that fails
    :func:`extract_rcds`'s checks sends the whole set through the pan-by-pan path, which
    raises the same error as before.
    """
    if not pans:
        return 0, []
    checked = None if len(pans) == 1 else _pans_checked_at_once(pans)
    if checked is None:
        total, rcds = 0, []
        for angles, ranges_m in pans:
            count, pan_rcds = _plausible_rcds(angles, ranges_m, params)
            total += count
            rcds += pan_rcds
        return total, rcds
    angles_rad, ranges_m, offsets, full_turn = checked
    _require_positive("eps", params.eps_m)
    per_pan: list[list[RCD]] = [[] for _ in pans]
    total = 0
    finite = np.isfinite(ranges_m)
    with np.errstate(invalid="ignore"):
        links = finite[:-1] & finite[1:] & (np.abs(ranges_m[1:] - ranges_m[:-1]) < params.eps_m)
    links[offsets[1:-1] - 1] = False  # the last sample of a pan and the first of the next
    for k in np.flatnonzero(full_turn).tolist():
        links[offsets[k] : offsets[k + 1] - 1] = False
        pan_angles, pan_ranges = pans[k]
        count, per_pan[k] = _plausible_rcds(pan_angles, pan_ranges, params)
        total += count
    starts, stops = _runs_of_links(links)
    runs = _runs_with_parameters(angles_rad, ranges_m, starts, stops - starts + 1)
    total += len(starts)
    plausible = np.flatnonzero(_extent_and_range_pass(runs.extent_rad, runs.delta_m, params))
    pan_of_run = np.searchsorted(offsets, starts[plausible], side="right") - 1
    for run, k in zip(plausible.tolist(), pan_of_run.tolist(), strict=True):
        first = int(starts[run]) - int(offsets[k])
        pan_angles, pan_ranges = pans[k]
        indices = np.arange(first, first + int(runs.count[run]))
        per_pan[k].append(make_rcd(pan_angles, pan_ranges, indices))
    return total, [rcd for pan_rcds in per_pan for rcd in pan_rcds]


def _pans_checked_at_once(
    pans: Sequence[tuple[np.ndarray, np.ndarray]],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """The concatenated angles and ranges of ``pans`` (float64 arrays of two samples or
    more), the offset of each pan in them (and the total length last) and which pans are full
    turns, when every pan passes :func:`extract_rcds`'s checks (the same comparisons, made on
    all pans at once); ``None`` when any pan does not, or is not such an array."""
    for angles, ranges_m in pans:
        if not (
            type(angles) is np.ndarray
            and type(ranges_m) is np.ndarray
            and angles.dtype == np.float64
            and ranges_m.dtype == np.float64
            and angles.ndim == 1
            and ranges_m.shape == angles.shape
            and len(angles) >= MIN_RCD_SAMPLES
        ):
            return None
    lengths = np.array([len(angles) for angles, _ in pans], dtype=np.int64)
    offsets = np.concatenate(([0], np.cumsum(lengths)))
    angles_rad = np.concatenate([angles for angles, _ in pans])
    ranges_m = np.concatenate([ranges for _, ranges in pans])
    firsts, lasts = offsets[:-1], offsets[1:] - 1
    span_rad = angles_rad[lasts] - angles_rad[firsts]
    increment_rad = span_rad / (lengths - 1)
    step_increment = np.repeat(increment_rad, lengths)[:-1]
    within_pan = np.ones(len(angles_rad) - 1, dtype=bool)
    within_pan[lasts[:-1]] = False
    steps = angles_rad[1:] - angles_rad[:-1]
    if (
        not np.isfinite(angles_rad).all()
        or (increment_rad <= 0.0).any()
        or (within_pan & (np.abs(steps - step_increment) > 1e-4 * step_increment)).any()
        or (span_rad >= 2.0 * math.pi).any()
        or ((ranges_m < 0.0) & (ranges_m > -math.inf)).any()
    ):
        return None
    full_turn = np.abs(span_rad + increment_rad - 2.0 * math.pi) <= 1e-3 * increment_rad
    return angles_rad, ranges_m, offsets, full_turn


def _plausible_rcds(
    angles: np.ndarray, ranges_m: np.ndarray, params: BeomChoParameters
) -> tuple[int, list[RCD]]:
    """How many RCDs :func:`extract_rcds` finds in a pan, and those of them that pass the
    extent and range filters (in its order). Only these are built, as most RCDs of a pan
    (short runs on walls and corners) fail the extent filter."""
    angles_rad, ranges_m = _validated_scan_arrays(angles, ranges_m)
    runs = rcd_runs(angles_rad, ranges_m, params.eps_m)
    plausible = np.flatnonzero(_extent_and_range_pass(runs.extent_rad, runs.delta_m, params))
    return len(runs.first), [
        make_rcd(angles_rad, ranges_m, runs.indices(k)) for k in plausible.tolist()
    ]


def assign_large_and_small(rcd_a: RCD, rcd_b: RCD) -> tuple[RCD, RCD]:
    """Section III.D: ``(small, large)`` for a pair of RCDs.

    The RCD of larger angular extent ``eta`` is the large beacon's; on equal extents (to
    1e-9 rad) the one of larger range ``delta``. If both are equal too, ``rcd_b`` is taken
    as the large one.
    """
    if abs(rcd_a.eta - rcd_b.eta) > _EXTENT_TOLERANCE_RAD:
        return (rcd_b, rcd_a) if rcd_a.eta > rcd_b.eta else (rcd_a, rcd_b)
    return (rcd_b, rcd_a) if rcd_a.delta > rcd_b.delta else (rcd_a, rcd_b)


def _role_assignment(rcd_a: RCD, rcd_b: RCD) -> list[tuple[RCD, RCD]]:
    """``[(small, large)]`` for a pair in which an RCD has a fixed role; ``[]`` if they clash."""
    for small, large in ((rcd_a, rcd_b), (rcd_b, rcd_a)):
        if small.role in (None, SMALL_BEACON_NAME) and large.role in (None, LARGE_BEACON_NAME):
            return [(small, large)]
    return []


def pair_distance_error(
    rcd_a: RCD,
    rcd_b: RCD,
    small_radius: float,
    large_radius: float,
    beacon_distance: float,
) -> float:
    """Eq. (7): ``|d_0 - sqrt(d_S^2 + d_L^2 - 2 d_L d_S cos(phi_S - phi_L))|``, metres.

    The pair is assigned with :func:`assign_large_and_small`; ``d_S = delta_S + r_S`` and
    ``d_L = delta_L + r_L`` are the distances to the beacon centres and ``phi = beta``.

    On the rounded Table II this gives 2.049 m for RCDs (1, 4) and 0.253 m for (2, 4), where
    the paper prints 2.049 m and 0.257 m, and 0.005 m for (1, 2), where it prints 0.031 m
    (0.032 m is what (1, 2) gives with the radii left out); the choice of (1, 2) is the same.

    Args:
        rcd_a, rcd_b: the two RCDs, in any order.
        small_radius, large_radius: beacon radii ``r_S``, ``r_L``, metres, > 0.
        beacon_distance: known distance ``d_0`` between the beacon centres, metres, > 0.
    """
    _require_positive("small_radius", small_radius)
    _require_positive("large_radius", large_radius)
    _require_positive("beacon_distance", beacon_distance)
    small, large = assign_large_and_small(rcd_a, rcd_b)
    return assigned_pair_distance_error(small, large, small_radius, large_radius, beacon_distance)


def assigned_pair_distance_error(
    small: RCD, large: RCD, small_radius: float, large_radius: float, beacon_distance: float
) -> float:
    """Eq. (7) for a pair whose small and large beacon are already assigned, metres."""
    small_distance = small.delta + small_radius
    large_distance = large.delta + large_radius
    squared = (
        small_distance**2
        + large_distance**2
        - 2.0 * large_distance * small_distance * math.cos(small.beta - large.beta)
    )
    return abs(beacon_distance - math.sqrt(max(squared, 0.0)))


# --------------------------------------------------------------------------------------------
# Section IV: two-circle solution, eqs (8)-(14), and heading, eq. (15)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TwoCircleSolution:
    """Outcome of eqs (8)-(14).

    Attributes:
        status: ``"ok"``, ``"no_intersection"`` (``D < 0``) or ``"out_of_float_range"``
            (the circles meet, but a meeting point lies beyond the largest float, 1.8e308 m).
        position: the intersection chosen by the sign rule, ``(x, y)`` metres in {W};
            ``None`` unless ok.
        other_position: the mirror intersection the sign rule rejected; ``None`` unless ok.
        discriminant: ``D`` of eq. (12), m^2. When the line of centres is nearly parallel to
            the y-axis and the rotation-invariant construction is used instead, this is the
            squared half-chord ``h^2``, which has the sign of ``D`` (``D = h^2 (1 + tan^2 psi)``).
        used_paper_formula: whether eqs (10)-(12) were used (False on the fallback).
    """

    status: str
    position: tuple[float, float] | None
    other_position: tuple[float, float] | None
    discriminant: float
    used_paper_formula: bool


def solve_two_circles(
    small_center: tuple[float, float] | npt.ArrayLike,
    small_distance: float,
    large_center: tuple[float, float] | npt.ArrayLike,
    large_distance: float,
    bearing_difference: float,
) -> TwoCircleSolution:
    """Eqs (8)-(14): the sensor position as an intersection of two circles.

    Eqs (8)-(9) are the circles of radius ``d_L`` about ``(x_L, y_L)`` and ``d_S`` about
    ``(x_S, y_S)``. With ``tan psi = (y_L - y_S)/(x_L - x_S)`` and
    ``L = (d_S^2 - d_L^2 + x_L^2 - x_S^2 + y_L^2 - y_S^2) / (2 (x_L - x_S))``:
    ``y_R = (-(x_L tan psi - L tan psi - y_L) +- sqrt(D)) / (1 + tan^2 psi)`` (eq. (10)),
    ``x_R = L - y_R tan psi`` (eq. (11), with the sign the subtraction of eq. (9) from
    eq. (8) gives; the text prints ``+``), and ``D`` of eq. (12).

    The root is chosen by the sign rule: ``delta-phi = phi_S - phi_L`` of eqs (13)-(14),
    wrapped to (-pi, pi], must have the sign of the measured ``delta-beta``. The two roots
    are mirror images across the line of centres, so their ``delta-phi`` are opposite; when
    the sign does not decide (``delta-beta`` or ``delta-phi`` zero or pi) the root with
    ``delta-phi`` nearer ``delta-beta`` is taken.

    When ``|x_L - x_S| < 0.05 d_0`` eqs (10)-(12) are ill-conditioned (they divide by
    ``x_L - x_S``) and the same intersections are computed rotation-invariantly: the foot
    ``a = (d_L^2 - d_S^2 + d_0^2) / (2 d_0)`` along the line of centres from the large beacon
    and the half-chord ``h = sqrt(d_L^2 - a^2)`` across it.

    Args:
        small_center, large_center: beacon centres ``(x, y)``, metres, in {W}; distinct.
        small_distance, large_distance: ``d_S = delta_S + r_S`` and ``d_L = delta_L + r_L``,
            metres, > 0.
        bearing_difference: ``delta-beta = beta_S - beta_L``, radians.

    Every finite input (centres, distances > 0, any bearing) gives a solution with a status
    and no NaN, at any magnitude: inputs beyond ``2**+-100`` m are solved scaled by a power of
    two. Non-finite input raises ``ValueError`` naming the argument.
    """
    small_xy = _point("small_center", small_center)
    large_xy = _point("large_center", large_center)
    _require_positive("small_distance", small_distance)
    _require_positive("large_distance", large_distance)
    _require_finite("bearing_difference", bearing_difference)
    if small_xy == large_xy:
        raise ValueError("small_center and large_center must be distinct points")
    lengths = (*small_xy, *large_xy, float(small_distance), float(large_distance))
    exponent = math.frexp(max(abs(v) for v in lengths))[1]
    if -_UNSCALED_EXPONENT <= exponent <= _UNSCALED_EXPONENT:
        return _solve_guarded(small_xy, large_xy, *lengths[4:], bearing_difference)
    # Scaling by a power of two is exact: the same solution, computed where no square
    # overflows or underflows, then scaled back.
    x_s, y_s, x_l, y_l, d_s, d_l = (math.ldexp(v, -exponent) for v in lengths)
    scaled = _solve_guarded((x_s, y_s), (x_l, y_l), d_s, d_l, bearing_difference)
    # D is in m^2: beyond the float range it saturates at the largest float, keeping its sign.
    discriminant = max(
        -sys.float_info.max,
        min(_ldexp_saturated(scaled.discriminant, 2 * exponent), sys.float_info.max),
    )
    if scaled.position is None or scaled.other_position is None:
        return replace(scaled, discriminant=discriminant)
    chosen, other = (
        (_ldexp_saturated(x, exponent), _ldexp_saturated(y, exponent))
        for x, y in (scaled.position, scaled.other_position)
    )
    if not all(math.isfinite(v) for v in (*chosen, *other)):
        return TwoCircleSolution(
            OUT_OF_FLOAT_RANGE, None, None, discriminant, scaled.used_paper_formula
        )
    return replace(scaled, position=chosen, other_position=other, discriminant=discriminant)


def _solve_guarded(
    small_xy: tuple[float, float],
    large_xy: tuple[float, float],
    d_s: float,
    d_l: float,
    bearing_difference: float,
) -> TwoCircleSolution:
    """Eqs (8)-(14); where they overflow (ranges vastly longer than the beacon distance), the
    factored construction of :func:`_solve_factored`, which cannot."""
    try:
        solution = _solve_two_circles(small_xy, large_xy, d_s, d_l, bearing_difference)
    except (OverflowError, ZeroDivisionError):
        return _solve_factored(small_xy, large_xy, d_s, d_l, bearing_difference)
    values = [solution.discriminant, *(solution.position or ()), *(solution.other_position or ())]
    if all(math.isfinite(v) for v in values):
        return solution
    return _solve_factored(small_xy, large_xy, d_s, d_l, bearing_difference)


def _solve_factored(
    small_xy: tuple[float, float],
    large_xy: tuple[float, float],
    d_s: float,
    d_l: float,
    bearing_difference: float,
) -> TwoCircleSolution:
    """The two intersections with every square factored, for lengths of magnitude <= 1.

    Foot of the chord along the line of centres from the large beacon:
    ``a = ((d_L - d_S)(d_L + d_S) / d_0 + d_0) / 2``; squared half-chord
    ``h^2 = (d_L - a)(d_L + a)``. An ``a`` beyond the float range means ``|d_L - d_S|`` far
    exceeds ``d_0``: no intersection (``h^2 = -inf``, reported as the most negative float).
    """
    beacon_distance = math.dist(small_xy, large_xy)
    if beacon_distance == 0.0:  # the centres merged in the scaling: no single intersection
        return TwoCircleSolution("no_intersection", None, None, -sys.float_info.max, False)
    along = ((d_l - d_s) * (d_l + d_s) / beacon_distance + beacon_distance) / 2.0
    half_chord_sq = (d_l - along) * (d_l + along)
    if not half_chord_sq >= 0.0:
        return TwoCircleSolution(
            "no_intersection", None, None, max(half_chord_sq, -sys.float_info.max), False
        )
    half_chord = math.sqrt(half_chord_sq)
    unit = (
        (small_xy[0] - large_xy[0]) / beacon_distance,
        (small_xy[1] - large_xy[1]) / beacon_distance,
    )
    foot = (large_xy[0] + along * unit[0], large_xy[1] + along * unit[1])
    first, second = (
        (foot[0] - sign * half_chord * unit[1], foot[1] + sign * half_chord * unit[0])
        for sign in (1.0, -1.0)
    )
    chosen, other = _apply_sign_rule(first, second, small_xy, large_xy, bearing_difference)
    return TwoCircleSolution(OK, chosen, other, min(half_chord_sq, sys.float_info.max), False)


def _ldexp_saturated(value: float, exponent: int) -> float:
    """``value * 2**exponent``, infinite (with the sign of ``value``) beyond the float range."""
    try:
        return math.ldexp(value, exponent)
    except OverflowError:
        return math.copysign(math.inf, value)


def _solve_two_circles(
    small_xy: tuple[float, float],
    large_xy: tuple[float, float],
    d_s: float,
    d_l: float,
    bearing_difference: float,
) -> TwoCircleSolution:
    """Eqs (8)-(14) on validated lengths whose magnitudes lie within ``2**+-100`` m."""
    beacon_distance = math.dist(small_xy, large_xy)
    x_s, y_s = small_xy
    x_l, y_l = large_xy
    if abs(x_l - x_s) >= _PAPER_FORMULA_MIN_COS_PSI * beacon_distance:
        tan_psi = (y_l - y_s) / (x_l - x_s)
        offset_l = (d_s**2 - d_l**2 + x_l**2 - x_s**2 + y_l**2 - y_s**2) / (2.0 * (x_l - x_s))
        half_b = x_l * tan_psi - offset_l * tan_psi - y_l
        discriminant = half_b**2 - (tan_psi**2 + 1.0) * ((x_l - offset_l) ** 2 + y_l**2 - d_l**2)
        if discriminant < 0.0:
            return TwoCircleSolution("no_intersection", None, None, discriminant, True)
        root = math.sqrt(discriminant)
        candidates = []
        for sign in (1.0, -1.0):
            y_r = (-half_b + sign * root) / (1.0 + tan_psi**2)
            candidates.append((offset_l - y_r * tan_psi, y_r))
        used_paper_formula = True
    else:
        unit = ((x_s - x_l) / beacon_distance, (y_s - y_l) / beacon_distance)
        along = (d_l**2 - d_s**2 + beacon_distance**2) / (2.0 * beacon_distance)
        discriminant = d_l**2 - along**2
        if discriminant < 0.0:
            return TwoCircleSolution("no_intersection", None, None, discriminant, False)
        half_chord = math.sqrt(discriminant)
        foot = (x_l + along * unit[0], y_l + along * unit[1])
        candidates = [
            (foot[0] - sign * half_chord * unit[1], foot[1] + sign * half_chord * unit[0])
            for sign in (1.0, -1.0)
        ]
        used_paper_formula = False

    first, second = candidates
    chosen, other = _apply_sign_rule(first, second, small_xy, large_xy, bearing_difference)
    return TwoCircleSolution(OK, chosen, other, discriminant, used_paper_formula)


def _apply_sign_rule(
    first: tuple[float, float],
    second: tuple[float, float],
    small_xy: tuple[float, float],
    large_xy: tuple[float, float],
    bearing_difference: float,
) -> tuple[tuple[float, float], tuple[float, float]]:
    """``(chosen, other)``: the root whose ``delta-phi`` (eqs (13)-(14)) has the sign of the
    measured ``delta-beta``, or, when the sign does not decide, lies nearer it."""
    measured = wrap_angle(bearing_difference)
    delta_phi_first = _bearing_difference_at(first, small_xy, large_xy)
    delta_phi_second = _bearing_difference_at(second, small_xy, large_xy)
    first_sign_ok = delta_phi_first * measured > 0.0
    second_sign_ok = delta_phi_second * measured > 0.0
    if first_sign_ok != second_sign_ok:
        choose_first = first_sign_ok
    else:
        choose_first = abs(angle_difference(delta_phi_first, measured)) <= abs(
            angle_difference(delta_phi_second, measured)
        )
    return (first, second) if choose_first else (second, first)


def heading_from_large_beacon(
    sensor_position: tuple[float, float] | npt.ArrayLike,
    large_center: tuple[float, float] | npt.ArrayLike,
    large_bearing: float,
) -> float:
    """Eq. (15): ``theta = atan2(y_L - y_R, x_L - x_R) - phi_L``, radians in (-pi, pi].

    ``phi_L`` is the bearing (``beta``) of the large beacon's RCD in the robot frame.
    """
    x_r, y_r = _point("sensor_position", sensor_position)
    x_l, y_l = _point("large_center", large_center)
    _require_finite("large_bearing", large_bearing)
    return wrap_angle(math.atan2(y_l - y_r, x_l - x_r) - large_bearing)


def _bearing_difference_at(
    position: tuple[float, float], small_xy: tuple[float, float], large_xy: tuple[float, float]
) -> float:
    """``delta-phi = phi_S - phi_L`` of eqs (13)-(14) seen from ``position``, wrapped."""
    phi_s = math.atan2(small_xy[1] - position[1], small_xy[0] - position[0])
    phi_l = math.atan2(large_xy[1] - position[1], large_xy[0] - position[0])
    return angle_difference(phi_s, phi_l)


# --------------------------------------------------------------------------------------------
# The whole method
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BeaconLocalization(Localization):
    """A :class:`Localization` with what the Beom & Cho chain found on the way.

    Attributes:
        small_rcd, large_rcd: the chosen pair (section III.D), ``None`` when none was found.
        pair_error_m: ``Delta d_0`` of eq. (7) for the chosen pair, metres; on
            ``"no_pair"`` the smallest error over all pairs (``None`` with fewer than two
            candidates).
        candidates: the RCDs that passed the angular-extent, symmetry and range filters.
        discriminant: ``D`` of eq. (12), m^2 (see :class:`TwoCircleSolution`); ``None``
            before eqs (8)-(12) were reached.
    """

    small_rcd: RCD | None = None
    large_rcd: RCD | None = None
    pair_error_m: float | None = None
    candidates: tuple[RCD, ...] = ()
    discriminant: float | None = None


def localize_rcds(
    rcds: Sequence[RCD],
    small_center: tuple[float, float] | npt.ArrayLike,
    small_radius: float,
    large_center: tuple[float, float] | npt.ArrayLike,
    large_radius: float,
    distance_tolerance: float | None = None,
    params: BeomChoParameters = BeomChoParameters(),
    method: str = "paper",
    prior: Pose | None = None,
    prior_gate_m: float = 0.5,
    agreement_m: float | None = None,
) -> BeaconLocalization:
    """Sections III.B-IV: the sensor pose from a pan's RCDs and the two known beacons.

    Steps: the angular-extent, symmetry and range filters (:func:`filter_beacon_candidates`);
    over all pairs of candidates, eq. (7) with the known ``d_0 = |c_S - c_L|``, keeping the
    pair of smallest error if it is within the tolerance; eqs (8)-(14) for the position and
    eq. (15) for the heading. With ``method="least_squares"`` that solution is refined by
    :func:`sonar_gym.localization.beom_cho_refine.refine_two_beacon_pose` over both beacons'
    ranges (the mean of each RCD's central samples when they are known) and bearings.

    Args:
        rcds: RCDs of one pan (:func:`extract_rcds`), unfiltered.
        small_center, large_center: beacon centres ``(x, y)``, metres, in {W}; distinct.
        small_radius, large_radius: beacon radii, metres, > 0 (paper: 0.0191 m and 0.07 m).
        distance_tolerance: allowed ``Delta d_0``, metres, > 0; ``None`` takes
            ``params.distance_tolerance_m`` (0.04 m).
        params: filter thresholds and noise levels.
        method: ``"paper"`` or ``"least_squares"``.
        prior: an optional estimate of the sensor pose (odometry), {W}. Not in the paper:
            when given, pairs are tried in order of their eq. (7) error and the first whose
            solution lies within ``prior_gate_m`` of the prior is kept, so a coincidental
            pair of walls or corners cannot win against the beacons.
        prior_gate_m: the gate radius around ``prior``, metres, > 0.
        agreement_m: not in the paper: when given (metres, > 0), every pair within the
            tolerance must put the sensor within this distance of the best pair's position;
            otherwise the pan is ``"ambiguous_pair"`` (no pose) rather than a coin toss
            between places.

    Returns:
        Status ``"ok"`` with the pose of the sensor frame {P} (position of the pan axis in
        {W}, heading of the robot's x-axis), or ``"no_candidates"`` (no RCD passed the
        filters), ``"no_pair"`` (no pair within the tolerance, or a single candidate),
        ``"ambiguous_pair"`` (see ``agreement_m``) or ``"no_intersection"`` (``D < 0``).
    """
    return _localize_rcds(
        rcds,
        len(rcds),
        small_center,
        small_radius,
        large_center,
        large_radius,
        distance_tolerance,
        params,
        method,
        prior,
        prior_gate_m,
        agreement_m,
    )


def _localize_rcds(
    rcds: Sequence[RCD],
    rcd_count: int,
    small_center: tuple[float, float] | npt.ArrayLike,
    small_radius: float,
    large_center: tuple[float, float] | npt.ArrayLike,
    large_radius: float,
    distance_tolerance: float | None,
    params: BeomChoParameters,
    method: str,
    prior: Pose | None,
    prior_gate_m: float,
    agreement_m: float | None,
) -> BeaconLocalization:
    """:func:`localize_rcds` on ``rcds``, which may leave out RCDs that fail the extent or
    range filter; ``rcd_count`` is how many RCDs the pans held in all (for the message)."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    small_xy = _point("small_center", small_center)
    large_xy = _point("large_center", large_center)
    _require_positive("small_radius", small_radius)
    _require_positive("large_radius", large_radius)
    tolerance_m = params.distance_tolerance_m if distance_tolerance is None else distance_tolerance
    _require_positive("distance_tolerance", tolerance_m)
    for position, rcd in enumerate(rcds):
        if not isinstance(rcd, RCD):
            message = f"rcds[{position}] must be an RCD, got {type(rcd).__name__}"
            raise ValueError(message)  # noqa: TRY004 (bad arguments raise ValueError here)
    beacon_distance = math.dist(small_xy, large_xy)
    if beacon_distance <= 0.0:
        raise ValueError("small_center and large_center must be distinct points")

    candidates = filter_beacon_candidates(rcds, params)
    if not candidates:
        return BeaconLocalization(
            "no_candidates",
            message=f"none of {rcd_count} RCDs passed the extent, symmetry and range filters",
        )

    pairs = _ranked_pairs(candidates, params, small_radius, large_radius, beacon_distance)
    if not pairs or pairs[0][0] > tolerance_m:
        return BeaconLocalization(
            "no_pair",
            message=(
                "a single candidate RCD"
                if not pairs
                else f"smallest beacon-distance error {pairs[0][0]:.4f} m exceeds {tolerance_m} m"
            ),
            pair_error_m=None if not pairs else pairs[0][0],
            candidates=candidates,
        )
    if prior is not None:
        _require_positive("prior_gate_m", prior_gate_m)
        gated = _first_pair_near_prior(
            [pair for pair in pairs if pair[0] <= tolerance_m],
            small_xy,
            small_radius,
            large_xy,
            large_radius,
            prior,
            prior_gate_m,
        )
        if gated is None:
            return BeaconLocalization(
                "no_pair_near_prior",
                message=(
                    "no beacon pair within tolerance puts the robot within "
                    f"{prior_gate_m} m of the prior"
                ),
                pair_error_m=pairs[0][0],
                candidates=candidates,
            )
        pairs = [gated]
    pair_error, small_rcd, large_rcd = pairs[0]

    solution = _solve_pair(small_xy, small_radius, large_xy, large_radius, small_rcd, large_rcd)
    if agreement_m is not None and solution.position is not None:
        _require_positive("agreement_m", agreement_m)
        if not _pairs_agree(
            [pair for pair in pairs[1:] if pair[0] <= tolerance_m],
            solution.position,
            small_xy,
            small_radius,
            large_xy,
            large_radius,
            agreement_m,
        ):
            return BeaconLocalization(
                "ambiguous_pair",
                message=f"beacon pairs within tolerance disagree by more than {agreement_m} m",
                pair_error_m=pair_error,
                candidates=candidates,
            )
    found: dict[str, Any] = {
        "small_rcd": small_rcd,
        "large_rcd": large_rcd,
        "pair_error_m": pair_error,
        "candidates": candidates,
        "discriminant": solution.discriminant,
    }
    if solution.position is None:
        reason = (
            f"the beacon circles do not intersect (D = {solution.discriminant:.3g} m^2)"
            if solution.status == "no_intersection"
            else "the beacon circles meet beyond the float range"
        )
        return BeaconLocalization(solution.status, message=reason, **found)
    heading = heading_from_large_beacon(solution.position, large_xy, large_rcd.beta)
    sensor_pose = Pose(solution.position[0], solution.position[1], heading)

    if method == "least_squares":
        small_range, small_sigma = central_range_estimate(
            small_rcd.delta, small_rcd.sample_ranges, params.range_sigma_m
        )
        large_range, large_sigma = central_range_estimate(
            large_rcd.delta, large_rcd.sample_ranges, params.range_sigma_m
        )
        sensor_pose = refine_two_beacon_pose(
            sensor_pose,
            centers=(small_xy, large_xy),
            center_distances_m=(small_range + small_radius, large_range + large_radius),
            range_sigmas_m=(small_sigma, large_sigma),
            bearings_rad=(small_rcd.beta, large_rcd.beta),
            bearing_sigma_rad=params.bearing_sigma_rad,
        )
    return BeaconLocalization(
        OK,
        sensor_pose,
        small_rcd=small_rcd,
        large_rcd=large_rcd,
        pair_error_m=pair_error,
        candidates=candidates,
        discriminant=solution.discriminant,
    )


def _ranked_pairs(
    candidates: Sequence[RCD],
    params: BeomChoParameters,
    small_radius: float,
    large_radius: float,
    beacon_distance: float,
) -> list[tuple[float, RCD, RCD]]:
    """Every assigned pair ``(Delta d_0, small, large)`` of candidates, smallest eq. (7) error
    first."""
    pairs: list[tuple[float, RCD, RCD]] = []
    for rcd_a, rcd_b in itertools.combinations(candidates, 2):
        if rcd_a.role is not None or rcd_b.role is not None:
            assignments = _role_assignment(rcd_a, rcd_b)
        elif params.assignment == "extent":
            assignments = [assign_large_and_small(rcd_a, rcd_b)]
        else:
            assignments = [(rcd_a, rcd_b), (rcd_b, rcd_a)]
        for small, large in assignments:
            error = assigned_pair_distance_error(
                small, large, small_radius, large_radius, beacon_distance
            )
            pairs.append((error, small, large))
    pairs.sort(key=lambda pair: pair[0])
    return pairs


def _solve_pair(
    small_xy: tuple[float, float],
    small_radius: float,
    large_xy: tuple[float, float],
    large_radius: float,
    small_rcd: RCD,
    large_rcd: RCD,
) -> TwoCircleSolution:
    """Eqs (8)-(14) for an assigned pair of RCDs."""
    return solve_two_circles(
        small_xy,
        small_rcd.delta + small_radius,
        large_xy,
        large_rcd.delta + large_radius,
        angle_difference(small_rcd.beta, large_rcd.beta),
    )


def _pairs_agree(
    pairs: Sequence[tuple[float, RCD, RCD]],
    position: tuple[float, float],
    small_xy: tuple[float, float],
    small_radius: float,
    large_xy: tuple[float, float],
    large_radius: float,
    agreement_m: float,
) -> bool:
    """Whether every pair that solves puts the sensor within ``agreement_m`` of ``position``."""
    for pair in pairs:
        solution = _solve_pair(small_xy, small_radius, large_xy, large_radius, pair[1], pair[2])
        if solution.position is not None and math.dist(solution.position, position) > agreement_m:
            return False
    return True


def _first_pair_near_prior(
    pairs: Sequence[tuple[float, RCD, RCD]],
    small_xy: tuple[float, float],
    small_radius: float,
    large_xy: tuple[float, float],
    large_radius: float,
    prior: Pose,
    gate_m: float,
) -> tuple[float, RCD, RCD] | None:
    """The first pair (in the given order) whose eqs (8)-(14) solution lies near ``prior``."""
    for pair in pairs:
        solution = _solve_pair(small_xy, small_radius, large_xy, large_radius, pair[1], pair[2])
        if (
            solution.position is not None
            and math.dist(solution.position, (prior.x, prior.y)) <= gate_m
        ):
            return pair
    return None


class BeaconLike(Protocol):
    """What :func:`localize_scan` reads of a beacon: centre (x, y) in metres in {W}, radius in m."""

    @property
    def center(self) -> tuple[float, float]: ...

    @property
    def radius(self) -> float: ...


class RobotLike(Protocol):
    """What :func:`localize_scan` reads of the robot: the pan axis (x, y) in metres in {R}."""

    @property
    def sensor_offset(self) -> tuple[float, float]: ...


class ScenarioLike(Protocol):
    """What :func:`localize_scan` reads of a scenario (:mod:`sonar_gym.scenario`)."""

    @property
    def robot(self) -> RobotLike: ...

    def beacon(self, name: str) -> BeaconLike: ...


def _ranges_in_window(
    scans: Sequence[Scan], params: BeomChoParameters
) -> list[tuple[np.ndarray, np.ndarray]]:
    """``(angles, ranges)`` of each scan, ranges outside ``[r_min, r_max]`` made dropouts."""
    pans = []
    with np.errstate(invalid="ignore"):
        for scan in scans:
            ranges_m = np.array(scan.ranges, dtype=np.float64)
            ranges_m[(ranges_m < params.r_min_m) | (ranges_m > params.r_max_m)] = np.nan
            pans.append((np.asarray(scan.angles, dtype=np.float64), ranges_m))
    return pans


def _short_pans_are_valid(scans: Sequence[Scan], params: BeomChoParameters) -> bool:
    """Whether scans of at most one ping pass :func:`extract_rcds`'s checks once their ranges
    are windowed: one-dimensional, ranges shaped like angles, finite angles, ranges
    non-negative or NaN."""
    if any(np.ndim(s.angles) != 1 or np.shape(s.ranges) != np.shape(s.angles) for s in scans):
        return False
    angles = np.concatenate([np.asarray(s.angles, dtype=np.float64) for s in scans])
    ranges = np.concatenate([np.asarray(s.ranges, dtype=np.float64) for s in scans])
    with np.errstate(invalid="ignore"):
        ranges[(ranges < params.r_min_m) | (ranges > params.r_max_m)] = np.nan
    return bool(np.isfinite(angles).all() and not ((ranges < 0.0) & (ranges > -math.inf)).any())


def localize_scan(
    scan: Scan,
    scenario: ScenarioLike,
    params: BeomChoParameters = BeomChoParameters(),
    method: str = "paper",
) -> BeaconLocalization:
    """The whole chain on one pan: the robot-centre pose in {W}.

    Readings outside ``[r_min, r_max]`` become dropouts; RCDs are extracted with
    ``params.eps_m`` (eqs (3)-(6)); :func:`localize_rcds` gives the pose of the pan axis; the
    robot centre is ``p_sensor - R(theta) sensor_offset``.

    Args:
        scan: the pan; ``scan.angles`` in radians in {R}, ``scan.ranges`` in metres from the pan
            axis, NaN for dropouts.
        scenario: provides ``beacon("small_beacon")`` and ``beacon("large_beacon")`` (each with
            ``center`` (x, y) in metres in {W} and ``radius`` in metres) and
            ``robot.sensor_offset`` (x, y) in metres in {R}.
        params: as for :func:`localize_rcds`.
        method: ``"paper"`` or ``"least_squares"``.
    """
    return localize_scans([scan], scenario, params, method)


def localize_scans(
    scans: Sequence[Scan],
    scenario: ScenarioLike,
    params: BeomChoParameters = BeomChoParameters(),
    method: str = "paper",
    prior: Pose | None = None,
    prior_gate_m: float = 0.5,
) -> BeaconLocalization:
    """:func:`localize_scan` over several pans from one robot pose (e.g. sector pans).

    Each pan must be equally spaced on its own (sectors at different increments are separate
    pans); RCDs are extracted from each and pooled before the filters and pair selection.
    Angles may be unwrapped past pi (a sector across the robot's back); RCD bearings are
    wrapped to (-pi, pi] before they are used. ``prior`` (the robot-centre pose from
    odometry, {W}) and ``prior_gate_m`` gate the pair choice as in :func:`localize_rcds`;
    without a prior, and with ``params.extraction="paper"``, this is the paper's method. With
    ``"occlusion_aware"``, a pan whose RCDs give no pair is tried once more with
    :func:`sonar_gym.localization.beom_cho_occlusion.occlusion_aware_rcds` (a pose, or
    ``"ambiguous_pair"`` when its pairs disagree on the place; otherwise the paper's status
    stands); the paper's answer stands whenever it finds a pair.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    # A pan of fewer than two pings holds no RCD; such pans are only checked, all at once.
    pans = _ranges_in_window([s for s in scans if len(s.angles) >= MIN_RCD_SAMPLES], params)
    short = [s for s in scans if len(s.angles) < MIN_RCD_SAMPLES]
    if short and not _short_pans_are_valid(short, params):
        for angles, ranges_m in _ranges_in_window(short, params):
            extract_rcds(angles, ranges_m, eps=params.eps_m)  # raises, naming the problem
    rcd_count, plausible = _plausible_rcds_of_pans(pans, params)
    small = scenario.beacon(SMALL_BEACON_NAME)
    large = scenario.beacon(LARGE_BEACON_NAME)

    def localize(
        candidate_rcds: list[RCD], count: int, agreement_m: float | None = None
    ) -> BeaconLocalization:
        return _localize_rcds(
            candidate_rcds,
            count,
            small.center,
            small.radius,
            large.center,
            large.radius,
            None,
            params,
            method,
            None if prior is None else prior.compose(Pose(*scenario.robot.sensor_offset, 0.0)),
            prior_gate_m,
            agreement_m,
        )

    result = localize(plausible, rcd_count)
    if params.extraction == "occlusion_aware" and result.status in ("no_candidates", "no_pair"):
        rebuilt = [
            rcd
            for angles, ranges_m in pans
            for rcd in occlusion_aware_rcds(
                angles,
                ranges_m,
                params.eps_m,
                params.expected_extents_rad,
                params.min_visible_extent_rad,
            )
        ]
        second_try = localize(rebuilt, len(rebuilt), params.rebuilt_agreement_m)
        if second_try.ok or second_try.status == "ambiguous_pair":
            result = second_try
    if result.pose is None:
        return result
    offset_x, offset_y = _point("scenario.robot.sensor_offset", scenario.robot.sensor_offset)
    sensor_pose = result.pose
    cos_t, sin_t = math.cos(sensor_pose.theta), math.sin(sensor_pose.theta)
    robot_pose = Pose(
        sensor_pose.x - (cos_t * offset_x - sin_t * offset_y),
        sensor_pose.y - (sin_t * offset_x + cos_t * offset_y),
        sensor_pose.theta,
    )
    return BeaconLocalization(
        OK,
        robot_pose,
        result.message,
        small_rcd=result.small_rcd,
        large_rcd=result.large_rcd,
        pair_error_m=result.pair_error_m,
        candidates=result.candidates,
        discriminant=result.discriminant,
    )
