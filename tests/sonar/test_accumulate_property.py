"""ScanMemory under any sequence of pans: what it hands out is always valid RCD input.

The pans are the ones BeaconScan can take (whole-degree start, an increment from the set the
env accepts, up to a full turn) on the memory's 1-deg grid, with ranges that form plateaus
(RCDs) and dropouts, so overlapping pans of different widths, offsets and increments mix.
"""

from __future__ import annotations

import functools
import math
import operator
from typing import Any

import gymnasium as gym
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import sonar_gym  # noqa: F401  (registers the envs)
from sonar_gym.localization.beom_cho import extract_rcds
from sonar_gym.pose import wrap_angles
from sonar_gym.sonar.accumulate import ScanMemory
from sonar_gym.sonar.scan import Scan

SPEED_MPS = 343.2
ENV_INCREMENTS_DEG = (1, 2, 3, 5, 6, 10)


WIDTHS_DEG = (30, 60, 90, 180, 360)
"""BeaconScan's default sector widths (any other multiple of the increment is drawn too)."""


@st.composite
def pan_sequences(draw: st.DrawFn) -> list[tuple[int, int, int, int]]:
    """1-6 pans ``(start_deg, increment_deg, n_pings, seed)`` on the 1-deg grid; half the
    sequences keep one increment throughout, as an agent with a single increment would."""
    shared = draw(st.one_of(st.none(), st.sampled_from(ENV_INCREMENTS_DEG)))
    sequence = []
    for _ in range(draw(st.integers(min_value=1, max_value=6))):
        increment = shared or draw(st.sampled_from(ENV_INCREMENTS_DEG))
        width = draw(
            st.one_of(
                st.sampled_from(WIDTHS_DEG),
                st.integers(min_value=1, max_value=360 // increment).map(
                    functools.partial(operator.mul, increment)
                ),
            )
        )
        start = draw(st.integers(min_value=-180, max_value=179))
        seed = draw(st.integers(min_value=0, max_value=2**16))
        sequence.append((start, increment, max(1, width // increment), seed))
    return sequence


def _scan(start_deg: int, increment_deg: int, n_pings: int, seed: int) -> Scan:
    """A pan with plateau ranges (10-deg sectors of one range each) and 10 % dropouts."""
    rng = np.random.default_rng(seed)
    degrees = start_deg + increment_deg * np.arange(n_pings)
    plateau = 0.5 + 3.0 * rng.random(36)
    ranges = plateau[(degrees // 10) % 36] + rng.normal(0.0, 0.002, n_pings)
    ranges[rng.random(n_pings) < 0.1] = np.nan
    amplitudes = np.where(np.isfinite(ranges), 0.1, 0.0)
    return Scan(np.radians(degrees.astype(np.float64)), ranges, amplitudes, 0.0)


@settings(max_examples=300, deadline=None)
@given(pan_sequences())
def test_any_pan_sequence_gives_scans_rcd_extraction_accepts(
    sequence: list[tuple[int, int, int, int]],
) -> None:
    memory = ScanMemory(math.radians(1.0))
    for pan in sequence:
        memory.add(_scan(*pan), SPEED_MPS)
    scans = memory.as_scans(SPEED_MPS)

    slots_handed_out = []
    for scan in scans:
        assert len(scan.angles) >= 1
        assert np.all(np.isfinite(scan.angles))
        for rcd in extract_rcds(scan.angles, scan.ranges):  # raises on invalid input
            assert all(math.isfinite(v) for v in (rcd.delta, rcd.beta, rcd.eta, rcd.gamma))
            assert rcd.delta > 0.0
        slots = np.rint((wrap_angles(scan.angles) + math.pi) / memory.resolution_rad)
        slots = slots.astype(np.int64) % memory.n_slots
        np.testing.assert_array_equal(scan.ranges, memory.ranges(SPEED_MPS)[slots])
        slots_handed_out.extend(slots.tolist())
    # Every stored ping is handed out exactly once, and nothing else.
    assert sorted(slots_handed_out) == np.flatnonzero(memory.scanned).tolist()


def test_pans_of_different_widths_at_one_increment_localize_without_error() -> None:
    env: Any = gym.make("SonarGym/BeaconScan-v0").unwrapped
    env.reset(seed=0)
    for centre, width in ((0, 180), (130, 90), (230, 90)):
        env.step(env.encode_action("pan", centre_deg=centre, width_deg=width, increment_deg=2))
    _, _, terminated, _, info = env.step(env.encode_action("localize"))
    assert terminated
    assert info["status"] != "truncated"


def test_interleaved_two_degree_pans_keep_each_pans_pings_together() -> None:
    memory = ScanMemory(math.radians(1.0))
    memory.add(_scan(-90, 2, 90, seed=1), SPEED_MPS)  # even degrees -90 .. 88
    memory.add(_scan(-45, 2, 45, seed=2), SPEED_MPS)  # odd degrees -45 .. 43
    lengths = sorted(len(scan.angles) for scan in memory.as_scans(SPEED_MPS))
    # The odd pan is whole, and the even pan is whole around it: no ping left on its own.
    assert lengths == [45, 90]


def test_full_one_degree_pan_comes_back_as_one_pan_from_minus_pi() -> None:
    memory = ScanMemory(math.radians(1.0))
    scan = _scan(-180, 1, 360, seed=3)
    memory.add(scan, SPEED_MPS)
    (whole,) = memory.as_scans(SPEED_MPS)
    np.testing.assert_allclose(whole.angles, scan.angles, atol=1e-12)
    np.testing.assert_allclose(whole.ranges, scan.ranges, rtol=1e-12)


def _reference_chains(memory: ScanMemory) -> list[list[int]]:
    """The chains walked slot by slot from each head (then each ring's lowest slot)."""
    n = memory.n_slots
    increment = np.maximum(memory.slot_increment, 1)
    after = np.arange(n) + increment
    successor = after % n
    linked = (
        memory.scanned
        & memory.scanned[successor]
        & (memory.slot_increment[successor] == memory.slot_increment)
        & ((after < n) | (n % increment == 0))
    )
    has_predecessor = np.zeros(n, dtype=bool)
    has_predecessor[successor[linked]] = True
    visited = np.zeros(n, dtype=bool)
    chains = []
    heads = np.flatnonzero(memory.scanned & ~has_predecessor).tolist()
    rings = np.flatnonzero(memory.scanned & has_predecessor).tolist()
    for head in (*heads, *rings):
        if visited[head]:
            continue
        chain = [head]
        visited[head] = True
        slot = head
        while linked[slot] and not visited[successor[slot]]:
            slot = int(successor[slot])
            visited[slot] = True
            chain.append(slot)
        chains.append(chain)
    return chains


@settings(max_examples=400, deadline=None)
@given(pan_sequences(), st.sampled_from([1, 2, 8]), st.sampled_from([None, 7, 11]))
def test_chains_are_those_of_a_slot_by_slot_walk(
    sequence: list[tuple[int, int, int, int]], resolution_deg: int, odd_increment: int | None
) -> None:
    """On grids of 360, 180 and 45 slots; ``odd_increment`` (which leaves a remainder on the
    1-deg grid, as do odd multiples of two slots on the 45-slot one) replaces 10 deg."""
    memory = ScanMemory(math.radians(resolution_deg))
    for start_deg, increment_deg, n_pings, seed in sequence:
        if odd_increment is not None and increment_deg == 10:
            increment_deg = odd_increment
        start = -180 + (start_deg + 180) // resolution_deg * resolution_deg  # on the grid
        increment = increment_deg * resolution_deg
        pings = max(1, min(n_pings, 360 // increment))
        memory.add(_scan(start, increment, pings, seed), SPEED_MPS)
    fast = sorted(chain.tolist() for chain in memory._chains())
    assert fast == sorted(_reference_chains(memory))


def test_a_lattice_scanned_across_the_back_is_one_chain_and_a_full_one_a_ring() -> None:
    memory = ScanMemory(math.radians(1.0))
    memory.add(_scan(170, 2, 10, seed=4), SPEED_MPS)  # 170 .. 188 deg: crosses +-180
    memory.add(_scan(-169, 1, 3, seed=5), SPEED_MPS)  # -169 .. -167 deg at 1 deg
    assert sorted(c.tolist() for c in memory._chains()) == sorted(_reference_chains(memory))
    assert [350, 352, 354, 356, 358, 0, 2, 4, 6, 8] in _reference_chains(memory)
    ring = ScanMemory(math.radians(1.0))
    ring.add(_scan(-179, 5, 72, seed=6), SPEED_MPS)
    (chain,) = ring._chains()
    assert chain.tolist() == list(range(1, 360, 5))


def _slots_computed_afresh(angles_rad: np.ndarray, n_slots: int) -> tuple[np.ndarray, int]:
    """The slots and increment of a pan, as ScanMemory.add computed them on every call."""
    resolution_rad = 2.0 * math.pi / n_slots
    position = (wrap_angles(angles_rad) + math.pi) / resolution_rad
    slots = np.rint(position).astype(np.int64) % n_slots
    increment = 1
    if len(slots) > 1:
        gaps = np.diff(np.sort(slots))
        gaps = gaps[gaps > 0]
        increment = int(gaps.min()) if len(gaps) else n_slots
    return slots, increment


def test_remembered_pan_slots_are_those_computed_afresh() -> None:
    from sonar_gym.sonar.accumulate import _grid_slots

    rng = np.random.default_rng(3)
    for n_slots in (360, 720, 120):
        resolution = 2.0 * math.pi / n_slots
        for _ in range(200):
            start = int(rng.integers(-n_slots, n_slots))
            step = int(rng.choice([*range(1, 12), n_slots]))  # n_slots: one slot again and again
            count = int(rng.integers(1, max(n_slots // step, 3) + 2))
            angles = resolution * (start + step * np.arange(count))
            for _ in range(2):  # the second call is remembered
                slots, increment = _grid_slots(n_slots, angles.shape, angles.tobytes())
                want_slots, want_increment = _slots_computed_afresh(angles, n_slots)
                assert slots.tobytes() == want_slots.tobytes() and increment == want_increment
        for _ in range(2):  # off the grid: refused every time, never remembered
            with np.testing.assert_raises(ValueError):
                ScanMemory(resolution).add(
                    Scan(np.array([0.5 * resolution]), np.array([1.0]), np.array([1.0]), 0.0),
                    SPEED_MPS,
                )
