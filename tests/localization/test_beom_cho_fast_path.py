"""The run-based RCD extraction and the candidates-first localization match the plain chain.

``extract_rcds`` and ``localize_scans`` find RCD runs for a whole pan at once and build only
the RCDs that can pass the extent and range filters; these tests hold them to a direct
transcription of eqs (3)-(5) (every RCD built, then filtered) on random pans.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.localization.beom_cho import (
    BeomChoParameters,
    _plausible_rcds_of_pans,
    _ranges_in_window,
    filter_beacon_candidates,
    localize_rcds,
    localize_scans,
)
from sonar_gym.localization.beom_cho_rcd import RCD, extract_rcds, make_rcd, rcd_runs
from sonar_gym.scenario import load_scenario
from sonar_gym.sonar.scan import Scan


def _reference_extract(angles: np.ndarray, ranges: np.ndarray, eps: float) -> list[RCD]:
    """Eqs (3)-(5) walked sample by sample: maximal runs of neighbours closer than ``eps``."""
    n = len(angles)
    if n < 2:
        return []
    increment = (angles[-1] - angles[0]) / (n - 1)
    full_turn = abs(angles[-1] - angles[0] + increment - 2.0 * math.pi) <= 1e-3 * increment

    def close(i: int, j: int) -> bool:
        a, b = ranges[i], ranges[j]
        return bool(np.isfinite(a) and np.isfinite(b) and abs(b - a) < eps)

    links = [close(i, i + 1) for i in range(n - 1)]
    if full_turn:
        links.append(close(n - 1, 0))
        if all(links):
            return [make_rcd(angles, ranges, np.arange(n))]
        start = links.index(False) + 1
    else:
        start = 0
    runs: list[list[int]] = []
    current: list[int] = []
    for step in range(len(links)):
        position = (start + step) % n
        if links[position] and (full_turn or position < n - 1):
            current = current or [position]
            current.append((position + 1) % n)
        elif current:
            runs.append(current)
            current = []
    if current:
        runs.append(current)
    rcds = [make_rcd(angles, ranges, np.array(run, dtype=np.int64)) for run in runs]
    return sorted(rcds, key=lambda rcd: (rcd.start_index > rcd.end_index, rcd.start_index))


@st.composite
def _pans(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray]:
    """Pans of plateaus (beacon-like runs), noise and dropouts; some full turns."""
    increment_deg = draw(st.sampled_from([1, 2, 5]))
    full_turn = draw(st.booleans())
    n = 360 // increment_deg if full_turn else draw(st.integers(0, 360 // increment_deg - 1))
    start_deg = draw(st.integers(-180, 179))
    angles = np.radians(start_deg + increment_deg * np.arange(n, dtype=np.float64))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    ranges = np.empty(n)
    position = 0
    while position < n:
        length = min(int(rng.integers(1, 30)), n - position)
        level = rng.uniform(0.2, 4.5)
        jitter = rng.choice([0.0, 0.002, 0.03])
        ranges[position : position + length] = level + rng.normal(0.0, jitter + 1e-9, length)
        position += length
    ranges[rng.random(n) < draw(st.sampled_from([0.0, 0.05, 0.3]))] = np.nan
    return angles, ranges


@settings(max_examples=300, deadline=None)
@given(pan=_pans(), eps=st.sampled_from([0.005, 0.02, 0.1]))
def test_extract_rcds_matches_a_sample_by_sample_walk(
    pan: tuple[np.ndarray, np.ndarray], eps: float
) -> None:
    angles, ranges = pan
    assert extract_rcds(angles, ranges, eps) == _reference_extract(angles, ranges, eps)


@settings(max_examples=300, deadline=None)
@given(pan=_pans())
def test_run_extents_and_deltas_are_those_of_the_rcds(pan: tuple[np.ndarray, np.ndarray]) -> None:
    angles, ranges = pan
    runs = rcd_runs(angles, ranges, 0.02)
    rcds = extract_rcds(angles, ranges, 0.02)
    assert len(runs.first) == len(rcds)
    assert runs.extent_rad.tolist() == [rcd.eta for rcd in rcds]
    assert runs.delta_m.tolist() == [rcd.delta for rcd in rcds]
    for k, rcd in enumerate(rcds):
        assert tuple(runs.indices(k).tolist()) == rcd.indices


LAB = load_scenario("beom_cho_lab")


def _reference_localize(scans: list[Scan], params: BeomChoParameters):  # type: ignore[no-untyped-def]
    """Every RCD of every pan built, then the paper's localizer (sensor pose, {W})."""
    rcds = []
    for scan in scans:
        ranges = np.array(scan.ranges, dtype=np.float64)
        with np.errstate(invalid="ignore"):
            ranges[(ranges < params.r_min_m) | (ranges > params.r_max_m)] = np.nan
        rcds += extract_rcds(scan.angles, ranges, params.eps_m)
    small, large = LAB.beacon("small_beacon"), LAB.beacon("large_beacon")
    return localize_rcds(
        rcds, small.center, small.radius, large.center, large.radius, params=params
    )


@pytest.mark.parametrize("seed", range(40))
def test_localize_scans_finds_what_the_whole_chain_finds(seed: int) -> None:
    rng = np.random.default_rng(seed)
    scans = []
    for _ in range(int(rng.integers(1, 4))):
        increment = int(rng.choice([1, 2, 5]))
        width = int(rng.choice([30, 90, 180, 360]))
        start = int(rng.integers(-180, 180)) // increment * increment
        angles = np.radians(start + increment * np.arange(width // increment, dtype=np.float64))
        ranges = np.full(len(angles), float(rng.uniform(1.0, 3.0)))
        for _ in range(int(rng.integers(0, 4))):  # beacon-like plateaus of 18-26 deg
            at = int(rng.integers(0, len(angles)))
            ranges[at : at + int(rng.integers(18, 27)) // increment + 1] = rng.uniform(0.5, 3.5)
        ranges += rng.normal(0.0, 0.004, len(angles))
        ranges[rng.random(len(angles)) < 0.05] = np.nan
        scans.append(Scan(angles, ranges, np.ones(len(angles)), 0.0))
    params = BeomChoParameters()
    fast = localize_scans(scans, LAB, params)
    reference = _reference_localize(scans, params)
    assert fast.status == reference.status
    assert fast.message == reference.message
    assert fast.candidates == reference.candidates
    assert fast.pair_error_m == reference.pair_error_m
    assert fast.small_rcd == reference.small_rcd and fast.large_rcd == reference.large_rcd
    assert filter_beacon_candidates(fast.candidates, params) == fast.candidates


@settings(max_examples=200, deadline=None)
@given(pans=st.lists(_pans(), min_size=1, max_size=6))
def test_pans_taken_together_give_the_rcds_of_each_pan(
    pans: list[tuple[np.ndarray, np.ndarray]],
) -> None:
    params = BeomChoParameters()
    scans = [Scan(angles, ranges, np.ones(len(angles)), 0.0) for angles, ranges in pans]
    windowed = [pan for pan in _ranges_in_window(scans, params) if len(pan[0]) >= 2]
    count, plausible = _plausible_rcds_of_pans(windowed, params)
    every_rcd = [rcd for angles, ranges in windowed for rcd in extract_rcds(angles, ranges)]
    assert count == len(every_rcd)
    assert filter_beacon_candidates(plausible, params) == filter_beacon_candidates(
        every_rcd, params
    )
    assert plausible == [rcd for rcd in every_rcd if _passes_extent_and_range(rcd, params)]


def _passes_extent_and_range(rcd: RCD, params: BeomChoParameters) -> bool:
    slack = 1e-9
    return (
        params.eta_min_rad - slack <= rcd.eta <= params.eta_max_rad + slack
        and params.r_min_m <= rcd.delta <= params.r_max_m
    )


@pytest.mark.parametrize(
    ("bad_angles", "message"),
    [
        (np.radians([0.0, 1.0, 3.0, 4.0]), "equally spaced"),
        (np.radians([0.0, -1.0, -2.0, -3.0]), "ascending"),
        (np.array([0.0, np.nan, 0.1, 0.2]), "finite"),
    ],
)
def test_a_bad_pan_among_good_ones_raises_as_it_does_alone(
    bad_angles: np.ndarray, message: str
) -> None:
    good = Scan(np.radians(np.arange(40.0)), np.full(40, 2.0), np.ones(40), 0.0)
    bad = Scan(bad_angles, np.full(len(bad_angles), 2.0), np.ones(len(bad_angles)), 0.0)
    with pytest.raises(ValueError, match=message) as together:
        localize_scans([good, bad, good], LAB)
    with pytest.raises(ValueError) as alone:
        extract_rcds(bad.angles, bad.ranges)
    assert str(together.value) == str(alone.value)


def test_an_rcd_never_runs_on_from_one_pan_into_the_next() -> None:
    """Two sector pans at one range: an RCD each (the second a beacon-sized 20 deg)."""
    first = (np.radians(np.arange(-60.0, -30.0)), np.full(30, 2.0))
    second = (np.radians(np.arange(-29.0, -8.0)), np.full(21, 2.0))
    count, plausible = _plausible_rcds_of_pans([first, second], BeomChoParameters())
    assert count == 2
    assert [(rcd.start_index, rcd.end_index) for rcd in plausible] == [(0, 20)]
