"""Accumulating pings from several sector pans into one pan for localization.

An agent may pan a few sectors at different increments, and calibrate the speed of sound in
between. The memory keeps every ping as a *round-trip time of flight* on a fixed angular grid
in the robot frame {R}, so ranges can be recomputed with whatever speed of sound is best known
when the robot localizes (a calibration after the pans still corrects them).
"""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np

from sonar_gym.pose import FloatArray, wrap_angles
from sonar_gym.sonar.scan import Scan


class ScanMemory:
    """Pings on a circular grid of ``n_slots`` angles (slot k at ``-pi + k * 2 pi / n_slots``).

    Args:
        resolution_rad: the grid spacing in radians; every pan angle must fall on the grid
            (within 1e-6 rad), which holds when increments and sector edges are whole
            multiples of it.
    """

    def __init__(self, resolution_rad: float = math.radians(1.0)) -> None:
        n_slots = round(2.0 * math.pi / resolution_rad)
        if n_slots < 4 or abs(n_slots * resolution_rad - 2.0 * math.pi) > 1e-9:
            raise ValueError(
                "argument 'resolution_rad' must divide a full turn into >= 4 slots; "
                f"got {resolution_rad!r}"
            )
        self.resolution_rad = 2.0 * math.pi / n_slots
        self.n_slots = n_slots
        self.clear()

    def clear(self) -> None:
        """Forget every ping."""
        self.round_trip_tof_s = np.full(self.n_slots, np.nan)
        self.amplitudes = np.zeros(self.n_slots)
        self.scanned = np.zeros(self.n_slots, dtype=bool)
        self.slot_increment = np.zeros(self.n_slots, dtype=np.int64)

    @property
    def slot_angles(self) -> FloatArray:
        """Angle of every slot in {R}, radians, ascending from -pi."""
        return -math.pi + self.resolution_rad * np.arange(self.n_slots, dtype=np.float64)

    @property
    def coverage(self) -> float:
        """Fraction of the grid's slots scanned at least once."""
        return np.count_nonzero(self.scanned) / self.n_slots

    def add(self, scan: Scan, assumed_speed_of_sound_mps: float) -> None:
        """Store a pan; its ranges were converted with ``assumed_speed_of_sound_mps`` (m/s)."""
        if len(scan.angles) == 0:
            return
        angles = np.asarray(scan.angles, dtype=np.float64)
        slots, increment = _grid_slots(self.n_slots, angles.shape, angles.tobytes())
        self.round_trip_tof_s[slots] = 2.0 * scan.ranges / assumed_speed_of_sound_mps
        self.amplitudes[slots] = scan.amplitudes
        self.scanned[slots] = True
        self.slot_increment[slots] = increment

    def ranges(self, speed_of_sound_mps: float) -> FloatArray:
        """Per-slot range in metres with the given speed of sound (NaN: dropout or unscanned)."""
        return self.round_trip_tof_s * speed_of_sound_mps / 2.0

    def as_scans(self, speed_of_sound_mps: float) -> list[Scan]:
        """The stored pings as pans of uniform spacing that RCD extraction can walk.

        Each pan handed out is a *chain*: pings taken at one increment ``g`` on consecutive
        points ``s, s + g, s + 2 g, ...`` of the grid, so its angles are strictly ascending
        and equally spaced whatever pans were mixed: pans of other increments, or of the same
        increment on another offset (odd and even degrees), interleave with a chain without
        breaking it. A lattice ``g`` that divides the grid and is scanned all the way round is
        one full-turn pan from its lowest slot, so that RCDs wrap around +-180 deg (a full pan
        at 1 deg comes back as the pan from -pi). Other chains keep their angles unwrapped
        (they may exceed pi) and are listed in angular order, starting after the widest
        unscanned gap; an unscanned slot on the lattice ends a chain, as it would end an RCD.
        The pans' arrays are slices of arrays made afresh on each call.
        """
        n = self.n_slots
        scanned = np.flatnonzero(self.scanned)
        if len(scanned) == 0:
            return []
        chains = self._chains()
        gaps = np.diff(np.append(scanned, scanned[0] + n))
        walk_start = int(scanned[(int(np.argmax(gaps)) + 1) % len(scanned)])
        chains.sort(key=lambda chain: (int(chain[0]) - walk_start) % n)
        # All chains at once, one array each for angles, ranges and amplitudes; the scans
        # handed out are consecutive slices of them.
        members = np.concatenate(chains) if len(chains) > 1 else chains[0]
        lengths = [len(chain) for chain in chains]
        starts = [0, *itertools.accumulate(lengths[:-1])]
        increments = self.slot_increment[members[starts]].tolist()
        heads = members[starts].tolist()
        for k, (head, length, increment) in enumerate(zip(heads, lengths, increments, strict=True)):
            if head < walk_start and length * increment < n:
                heads[k] = head + n  # the walk reaches it after crossing +-180 deg
        if len(chains) == 1:
            unwrapped = heads[0] + increments[0] * np.arange(lengths[0])
        else:
            position = np.arange(len(members)) - np.repeat(starts, lengths)
            unwrapped = np.repeat(heads, lengths) + np.repeat(increments, lengths) * position
        angles = -math.pi + self.resolution_rad * unwrapped
        ranges = self.ranges(speed_of_sound_mps)[members]
        amplitudes = self.amplitudes[members]
        bounds = [*starts, len(members)]
        return [
            Scan(angles[a:b], ranges[a:b], amplitudes[a:b], 0.0)
            for a, b in zip(bounds[:-1], bounds[1:], strict=True)
        ]

    def _chains(self) -> list[np.ndarray]:
        """Scanned slots grouped into chains ``s, s + g, ...`` (``g``: their pans' increment).

        A slot links to ``s + g`` when that slot was scanned at the same increment; across
        +-180 deg only when ``g`` divides the grid (else the lattice does not close on
        itself). Every slot has at most one predecessor (``s - g``), so the links form paths
        and, for a lattice scanned all the way round, rings; a ring starts at its lowest slot.

        The slots of one increment ``g`` and one residue ``s mod g`` form a lattice; sorted
        along it, chains are its runs of neighbours ``g`` apart, and the run that ends on the
        lattice's last point before +-180 deg continues into the run from its first point
        when ``g`` divides the grid (unless that is one run, a ring). Chains are listed by
        increment, residue and slot.
        """
        n = self.n_slots
        slots = np.flatnonzero(self.scanned)
        if len(slots) == 0:
            return []
        increment = np.maximum(self.slot_increment[slots], 1)
        residue = slots % increment
        order = np.lexsort((slots, residue, increment))
        slots, increment, residue = slots[order], increment[order], residue[order]
        same_lattice = (increment[1:] == increment[:-1]) & (residue[1:] == residue[:-1])
        linked = same_lattice & (slots[1:] - slots[:-1] == increment[:-1])
        run_starts = np.flatnonzero(np.concatenate(([True], ~linked)))
        opens_lattice = np.concatenate(([True], ~same_lattice))[run_starts].tolist()
        closes_lattice = [*opens_lattice[1:], True]
        chains: list[np.ndarray] = []
        lattice_first = 0  # position in chains of the current lattice's first run
        run_bounds = [*run_starts.tolist(), len(slots)]
        for a, b, g, opens, closes in zip(
            run_bounds[:-1],
            run_bounds[1:],
            increment[run_starts].tolist(),
            opens_lattice,
            closes_lattice,
            strict=True,
        ):
            run = slots[a:b]
            if opens:
                lattice_first = len(chains)
            first_run = chains[lattice_first] if not opens else run
            wraps_on = n % g == 0 and int(run[-1]) + g - n == int(first_run[0])
            if closes and not opens and wraps_on:
                chains[lattice_first] = np.concatenate([run, first_run])
            else:
                chains.append(run)
        return chains


@functools.lru_cache(maxsize=1024)
def _grid_slots(n_slots: int, shape: tuple[int, ...], angle_bytes: bytes) -> tuple[np.ndarray, int]:
    """The slots of pan angles on a grid of ``n_slots`` and the pan's increment in slots (the
    smallest gap between distinct slots, ``n_slots`` if none; 1 for one angle).

    The angles are the float64 ``angle_bytes`` of ``shape`` (radians, {R}). Remembered: a
    task offers a few pan grids and pans them again and again. The slots are read-only.

    Raises:
        ValueError: an angle is off the grid by more than 1e-6 of a slot.
    """
    angles_rad = np.frombuffer(angle_bytes, dtype=np.float64).reshape(shape)
    resolution_rad = 2.0 * math.pi / n_slots
    position = (wrap_angles(angles_rad) + math.pi) / resolution_rad
    rounded = np.rint(position)
    if np.any(np.abs(position - rounded) > 1e-6):
        raise ValueError(
            f"pan angles must lie on the memory's grid of {math.degrees(resolution_rad):g} deg"
        )
    slots = rounded.astype(np.int64) % n_slots
    increment = 1
    if len(slots) > 1:  # the smallest gap between distinct slots, n_slots if none
        gaps = np.diff(np.sort(slots))
        gaps = gaps[gaps > 0]
        increment = int(gaps.min()) if len(gaps) else n_slots
    slots.flags.writeable = False
    return slots, increment
