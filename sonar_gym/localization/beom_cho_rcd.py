"""Regions of constant depth (RCDs) of Beom & Cho (1995), section III.A, eqs (3)-(6).

An RCD is the parameter set ``chi = {delta, beta, eta}`` of a run of pan samples at (almost)
one range, with the symmetry measure ``gamma`` of eq. (6). The paper's localizer
(:mod:`sonar_gym.localization.beom_cho`) and the occlusion-aware rebuild
(:mod:`sonar_gym.localization.beom_cho_occlusion`) both start from these. Readings chosen where
the text leaves room are listed in the docstring of :mod:`sonar_gym.localization.beom_cho`.

Units: radians in the robot frame {R} for angles, metres for ranges.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sonar_gym.frozen import unchecked_instance
from sonar_gym.pose import wrap_angle

__all__ = [
    "LARGE_BEACON_NAME",
    "MIN_RCD_SAMPLES",
    "RCD",
    "SMALL_BEACON_NAME",
    "RCDRuns",
    "extract_rcds",
    "make_rcd",
    "rcd_runs",
    "symmetry_measure",
]

SMALL_BEACON_NAME = "small_beacon"
LARGE_BEACON_NAME = "large_beacon"

MIN_RCD_SAMPLES = 2
"""An RCD needs at least two samples (one pair of neighbours closer than ``eps``)."""


def _require_finite(name: str, value: float) -> None:
    if not isinstance(value, (int, float, np.floating, np.integer)) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")


def _require_positive(name: str, value: float) -> None:
    _require_finite(name, value)
    if value <= 0.0:
        raise ValueError(f"{name} must be > 0, got {value!r}")


def _require_non_negative(name: str, value: float) -> None:
    _require_finite(name, value)
    if value < 0.0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")


@dataclass(frozen=True)
class RCD:
    """A region of constant distance: the geometric parameter set ``chi = {delta, beta, eta}``
    of section III.A plus the symmetry measure of eq. (6).

    Attributes:
        delta: range of the RCD in metres, the range at ``beta`` (the centre sample, or the
            mean of the two central samples when the RCD has an even number of samples).
        beta: centre angle ``(beta_s + beta_e) / 2`` in radians in the robot frame {R},
            wrapped to (-pi, pi].
        eta: angular extent ``beta_e - beta_s`` in radians, ``beta_s`` and ``beta_e`` being the
            angles of the first and last samples.
        gamma: symmetry measure of eq. (6), metres.
        start_index, end_index: indices into the scan arrays of the first and last samples;
            on an RCD that wraps across +-180 deg, ``start_index > end_index``. ``-1`` for an
            RCD not taken from a scan (e.g. typed in from Table II).
        indices: every index the RCD spans, in angular order (empty when not from a scan).
        sample_ranges: the ranges of those samples in metres, same order (empty when not from
            a scan). Used by the least-squares refinement; the paper's method needs only
            ``delta``.
        role: ``None`` for an RCD seen in a pan, whose beacon section III.D assigns by
            extent; ``"small_beacon"`` or ``"large_beacon"`` for an RCD rebuilt as that beacon
            by the occlusion-aware extraction (not in the paper), which pairs only in that role.
    """

    delta: float
    beta: float
    eta: float
    gamma: float = 0.0
    start_index: int = -1
    end_index: int = -1
    indices: tuple[int, ...] = ()
    sample_ranges: tuple[float, ...] = ()
    role: str | None = None

    def __post_init__(self) -> None:
        for name in ("delta", "beta", "eta", "gamma"):
            value = float(getattr(self, name))
            if not math.isfinite(value):
                raise ValueError(f"RCD.{name} must be finite, got {value!r}")
            object.__setattr__(self, name, value)
        for name in ("delta", "eta", "gamma"):
            _require_non_negative(f"RCD.{name}", getattr(self, name))
        object.__setattr__(self, "beta", wrap_angle(self.beta))
        object.__setattr__(self, "indices", tuple(int(i) for i in self.indices))
        object.__setattr__(self, "sample_ranges", tuple(float(r) for r in self.sample_ranges))
        if self.role not in (None, SMALL_BEACON_NAME, LARGE_BEACON_NAME):
            raise ValueError(
                f"RCD.role must be None, {SMALL_BEACON_NAME!r} or {LARGE_BEACON_NAME!r}; "
                f"got {self.role!r}"
            )
        if self.sample_ranges and len(self.sample_ranges) != len(self.indices):
            raise ValueError(
                "RCD.sample_ranges must have one range per entry of RCD.indices "
                f"(got {len(self.sample_ranges)} and {len(self.indices)})"
            )

    @classmethod
    def from_degrees(
        cls, delta_m: float, beta_deg: float, eta_deg: float, gamma_m: float = 0.0
    ) -> RCD:
        """Build an RCD from a row as the paper prints it (Table II: m, deg, deg, m)."""
        return cls(
            delta=delta_m,
            beta=math.radians(beta_deg),
            eta=math.radians(eta_deg),
            gamma=gamma_m,
        )


# --------------------------------------------------------------------------------------------
# Section III.A: RCD extraction, eqs (3)-(5); section III.C: symmetry, eq. (6)
# --------------------------------------------------------------------------------------------


def extract_rcds(angles: npt.ArrayLike, ranges: npt.ArrayLike, eps: float = 0.02) -> list[RCD]:
    """All RCDs of a pan, eqs (3)-(5), each with its symmetry measure, eq. (6).

    A sample starts an RCD when it differs from its predecessor by at least ``eps`` and from
    its successor by less (eq. (3)); it ends one in the mirrored case (eq. (4)); inside, both
    neighbours are closer than ``eps`` (eq. (5)). So an RCD is a maximal run of at least
    :data:`MIN_RCD_SAMPLES` (two) consecutive samples whose neighbouring ranges differ by less
    than ``eps``. A single isolated sample is no RCD.

    A NaN range (dropout) breaks an RCD. When the angles cover a full turn (their span plus
    one increment is 2 pi) the sample after the last is the first, and an RCD may wrap across
    +-180 deg (then ``start_index > end_index``); otherwise the ends of the pan break RCDs.
    If every neighbouring pair of a full turn is close, the whole pan is one RCD, not wrapped.

    Args:
        angles: pan angles in radians in the robot frame {R}, one-dimensional, equally spaced
            and strictly ascending.
        ranges: ranges in metres, same length; NaN for dropouts.
        eps: ``epsilon`` of eqs (3)-(5), metres, > 0 (Table I: 0.02 m).

    Returns:
        The RCDs in the order of their first sample in the arrays (a wrapped RCD comes last).
    """
    angles_rad, ranges_m = _validated_scan_arrays(angles, ranges)
    runs = rcd_runs(angles_rad, ranges_m, eps)
    return [make_rcd(angles_rad, ranges_m, runs.indices(k)) for k in range(len(runs.first))]


@dataclass(frozen=True)
class RCDRuns:
    """The sample runs of a pan's RCDs (eqs (3)-(5)), before their parameters are computed.

    Run ``k`` holds the samples ``(first[k] + j) % sample_count`` for ``j < count[k]``, in
    angular order (on a full turn a run may wrap across +-180 deg). Runs are listed in
    :func:`extract_rcds`'s order. ``extent_rad`` and ``delta_m`` are what :func:`make_rcd`
    gives as ``eta`` and ``delta`` for each run (same arithmetic, all runs at once), so a
    filter on them can run before any RCD is built.
    """

    first: np.ndarray  # int64, index of each run's first sample
    count: np.ndarray  # int64, samples per run (>= MIN_RCD_SAMPLES)
    sample_count: int
    extent_rad: np.ndarray  # eta = beta_e - beta_s, radians
    delta_m: np.ndarray  # range at beta, metres

    def indices(self, k: int) -> np.ndarray:
        """The sample indices of run ``k``, in angular order."""
        first, count = int(self.first[k]), int(self.count[k])
        if first + count <= self.sample_count:
            return np.arange(first, first + count)
        return (first + np.arange(count)) % self.sample_count


def rcd_runs(angles_rad: np.ndarray, ranges_m: np.ndarray, eps: float) -> RCDRuns:
    """The runs of :func:`extract_rcds` for arrays that passed its checks (float64, radians,
    metres); see there for the rules of eqs (3)-(5)."""
    _require_positive("eps", eps)
    sample_count = len(angles_rad)
    none = np.zeros(0, dtype=np.int64)
    if sample_count < MIN_RCD_SAMPLES:
        return _runs_with_parameters(angles_rad, ranges_m, none, none)
    increment_rad = (angles_rad[-1] - angles_rad[0]) / (sample_count - 1)

    finite = np.isfinite(ranges_m)
    with np.errstate(invalid="ignore"):
        close_to_next = finite[:-1] & finite[1:] & (np.abs(ranges_m[1:] - ranges_m[:-1]) < eps)
    if not _covers_full_turn(angles_rad, increment_rad):
        starts, stops = _runs_of_links(close_to_next)
        return _runs_with_parameters(angles_rad, ranges_m, starts, stops - starts + 1)

    wrap_link = bool(finite[-1] and finite[0] and abs(ranges_m[0] - ranges_m[-1]) < eps)
    links = np.append(close_to_next, wrap_link)
    if links.all():
        whole = np.array([sample_count], dtype=np.int64)
        return _runs_with_parameters(angles_rad, ranges_m, np.zeros(1, dtype=np.int64), whole)
    shift = int(np.flatnonzero(~links)[0]) + 1  # the walk starts after the first break
    starts, stops = _runs_of_links(np.roll(links, -shift)[:-1])
    first = (starts + shift) % sample_count
    count = stops - starts + 1
    wrapped = (first + count - 1) % sample_count < first
    order = np.lexsort((first, wrapped))  # by start index, the wrapped RCD last
    return _runs_with_parameters(angles_rad, ranges_m, first[order], count[order])


def _runs_with_parameters(
    angles_rad: np.ndarray, ranges_m: np.ndarray, first: np.ndarray, count: np.ndarray
) -> RCDRuns:
    """:class:`RCDRuns` with each run's ``eta`` and ``delta`` computed as :func:`make_rcd` does."""
    n = len(angles_rad)
    last = (first + count - 1) % max(n, 1)
    beta_start = angles_rad[first]
    beta_end = angles_rad[last] + np.where(last < first, 2.0 * math.pi, 0.0)
    middle = ranges_m[(first + count // 2) % max(n, 1)]
    before_middle = ranges_m[(first + count // 2 - 1) % max(n, 1)]
    delta = np.where(count % 2 == 1, middle, 0.5 * (before_middle + middle))
    return RCDRuns(first, count, n, beta_end - beta_start, delta)


def symmetry_measure(
    angles: npt.ArrayLike, ranges: npt.ArrayLike, rcd_indices: Sequence[int] | npt.ArrayLike
) -> float:
    """Eq. (6): ``gamma = (1/M) sum_{i=1..M} |delta(beta + i eta/2M) - delta(beta - i eta/2M)|``.

    ``M = INT(N/2)`` with ``N`` the number of samples of the RCD. With ``eta`` measured between
    the first and last samples, an RCD of odd ``N`` has its samples exactly at
    ``beta +- i eta / (2M)``, so eq. (6) pairs samples symmetric about the centre. For even
    ``N`` those angles fall between samples and the ranges there are interpolated linearly
    (the outermost pair, ``i = M``, is still the first and last sample).

    Args:
        angles: pan angles in radians, as for :func:`extract_rcds`.
        ranges: ranges in metres, same length.
        rcd_indices: indices of the RCD's samples in angular order (may wrap across +-180 deg),
            at least two, with finite ranges.

    Returns:
        ``gamma`` in metres; 0 for a profile symmetric about ``beta``.
    """
    angles_rad, ranges_m = _validated_scan_arrays(angles, ranges)
    indices = np.asarray(rcd_indices, dtype=np.int64).reshape(-1)
    if len(indices) < MIN_RCD_SAMPLES:
        raise ValueError(
            f"rcd_indices must name at least {MIN_RCD_SAMPLES} samples, got {len(indices)}"
        )
    if indices.min() < 0 or indices.max() >= len(angles_rad):
        raise ValueError(f"rcd_indices must lie in [0, {len(angles_rad) - 1}]")
    rcd_ranges = ranges_m[indices]
    if not np.all(np.isfinite(rcd_ranges)):
        raise ValueError("ranges at rcd_indices must be finite (an RCD holds no dropout)")
    rcd_angles = np.unwrap(angles_rad[indices])
    if np.any(np.diff(rcd_angles) <= 0.0):
        raise ValueError("rcd_indices must be in ascending angular order")
    return _symmetry(rcd_angles, rcd_ranges)


def _symmetry(rcd_angles: np.ndarray, rcd_ranges: np.ndarray) -> float:
    """Eq. (6) on an RCD's own samples: unwrapped ascending angles (radians), finite ranges (m)."""
    beta = 0.5 * (rcd_angles[0] + rcd_angles[-1])
    eta = rcd_angles[-1] - rcd_angles[0]
    half_count = len(rcd_ranges) // 2
    offsets = np.arange(1, half_count + 1) * eta / (2 * half_count)
    above = np.interp(beta + offsets, rcd_angles, rcd_ranges)
    below = np.interp(beta - offsets, rcd_angles, rcd_ranges)
    return float(np.abs(above - below).sum() / half_count)  # the mean, as np.mean rounds it


def _runs_of_links(links: npt.NDArray[np.bool_]) -> tuple[np.ndarray, np.ndarray]:
    """First and last sample positions (int64 arrays) of each maximal run of true links.

    ``links[k]`` says whether samples ``k`` and ``k + 1`` are close; a run of links
    ``k0..k1`` makes the RCD of samples ``k0..k1 + 1``.
    """
    padded = np.zeros(len(links) + 2, dtype=np.int8)
    padded[1:-1] = links
    edges = padded[1:] - padded[:-1]
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def make_rcd(angles_rad: np.ndarray, ranges_m: np.ndarray, indices: np.ndarray) -> RCD:
    """The parameter set of the RCD made of ``indices`` (angular order), section III.A.

    ``angles_rad`` and ``ranges_m`` are the whole pan (radians in {R}, metres); ``indices``
    may wrap across +-180 deg on a full turn.
    """
    start, end = int(indices[0]), int(indices[-1])
    beta_start = angles_rad[start]
    beta_end = angles_rad[end] + (2.0 * math.pi if end < start else 0.0)
    count = len(indices)
    if count % 2 == 1:
        delta = float(ranges_m[indices[count // 2]])
    else:
        delta = float(0.5 * (ranges_m[indices[count // 2 - 1]] + ranges_m[indices[count // 2]]))
    rcd_angles = angles_rad[indices]
    if end < start:  # the RCD wraps across +-180 deg
        rcd_angles = np.unwrap(rcd_angles)
    rcd_ranges = ranges_m[indices]
    gamma = _symmetry(rcd_angles, rcd_ranges)
    if not (math.isfinite(delta) and math.isfinite(gamma)):  # a dropout inside: RCD's checks
        return RCD(delta, 0.5 * (beta_start + beta_end), float(beta_end - beta_start), gamma)
    # Built without RCD's checks: every value here is finite and in range by construction.
    return unchecked_instance(
        RCD,
        delta=delta,
        beta=wrap_angle(float(0.5 * (beta_start + beta_end))),
        eta=float(beta_end - beta_start),
        gamma=gamma,
        start_index=start,
        end_index=end,
        indices=tuple(indices.tolist()),
        sample_ranges=tuple(rcd_ranges.tolist()),
        role=None,
    )


def _covers_full_turn(angles_rad: np.ndarray, increment_rad: float) -> bool:
    """Whether the pan is a full turn: span plus one increment equals 2 pi (to 1e-3 step)."""
    span_rad = angles_rad[-1] - angles_rad[0]
    return bool(abs(span_rad + increment_rad - 2.0 * math.pi) <= 1e-3 * increment_rad)


def _validated_scan_arrays(
    angles: npt.ArrayLike, ranges: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    angles_rad = np.asarray(angles, dtype=np.float64)
    ranges_m = np.asarray(ranges, dtype=np.float64)
    if angles_rad.ndim != 1:
        raise ValueError(f"angles must be one-dimensional, got shape {angles_rad.shape}")
    if ranges_m.shape != angles_rad.shape:
        raise ValueError(
            f"ranges must have the shape of angles {angles_rad.shape}, got {ranges_m.shape}"
        )
    if not np.isfinite(angles_rad).all():
        raise ValueError("angles must be finite")
    if len(angles_rad) >= 2:
        steps = angles_rad[1:] - angles_rad[:-1]
        increment = (angles_rad[-1] - angles_rad[0]) / (len(angles_rad) - 1)
        if increment <= 0.0 or (np.abs(steps - increment) > 1e-4 * increment).any():
            raise ValueError("angles must be strictly ascending and equally spaced")
        if angles_rad[-1] - angles_rad[0] >= 2.0 * math.pi:
            raise ValueError("angles must span less than a full turn (2 pi)")
    if ((ranges_m < 0.0) & (ranges_m > -math.inf)).any():  # NaN and -inf are not checked
        raise ValueError("ranges must be non-negative or NaN")
    return angles_rad, ranges_m
