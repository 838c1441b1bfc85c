"""Accumulating pings from several sector pans into one pan for localization.

An agent may pan a few sectors at different increments, and calibrate the speed of sound in
between. The memory keeps every ping as a *round-trip time of flight* on a fixed angular grid
in the robot frame {R}, so ranges can be recomputed with whatever speed of sound is best known
when the robot localizes (a calibration after the pans still corrects them).
"""

from __future__ import annotations

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
                f"argument 'resolution_rad' must divide a full turn into >= 4 slots; got {resolution_rad!r}"
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
        return -math.pi + self.resolution_rad * np.arange(self.n_slots)

    @property
    def coverage(self) -> float:
        """Fraction of the grid's slots scanned at least once."""
        return float(self.scanned.mean())

    def add(self, scan: Scan, assumed_speed_of_sound_mps: float) -> None:
        """Store a pan; its ranges were converted with ``assumed_speed_of_sound_mps`` (m/s)."""
        if len(scan.angles) == 0:
            return
        slots = self._slots(scan.angles)
        increment = 1
        if len(slots) > 1:
            increment = int(np.min(np.diff(np.sort(np.unique(slots))), initial=self.n_slots)) or 1
        self.round_trip_tof_s[slots] = 2.0 * scan.ranges / assumed_speed_of_sound_mps
        self.amplitudes[slots] = scan.amplitudes
        self.scanned[slots] = True
        self.slot_increment[slots] = increment

    def ranges(self, speed_of_sound_mps: float) -> FloatArray:
        """Per-slot range in metres with the given speed of sound (NaN: dropout or unscanned)."""
        return self.round_trip_tof_s * speed_of_sound_mps / 2.0

    def as_scans(self, speed_of_sound_mps: float) -> list[Scan]:
        """The stored pings as pans of uniform spacing that RCD extraction can walk.

        A fully covered grid at one increment is one pan from -pi, so that RCDs wrap around
        +-180 deg. Otherwise the pings are walked in angular order starting after the widest
        unscanned gap, with angles unwrapped (they may exceed pi), and split into blocks of
        consecutive pings taken at one increment; a gap or a change of increment ends a block,
        as it would end an RCD.
        """
        ranges = self.ranges(speed_of_sound_mps)
        scanned = np.flatnonzero(self.scanned)
        if len(scanned) == 0:
            return []
        increments = self.slot_increment[scanned]
        if np.all(increments == increments[0]) and len(scanned) * increments[0] == self.n_slots:
            return [Scan(self.slot_angles[scanned], ranges[scanned], self.amplitudes[scanned], 0.0)]

        gaps = np.diff(np.append(scanned, scanned[0] + self.n_slots))
        order = np.roll(scanned, -((int(np.argmax(gaps)) + 1) % len(scanned)))
        unwrapped = order + self.n_slots * np.cumsum(np.diff(order, prepend=order[0]) < 0)
        step = np.diff(unwrapped)
        increment = self.slot_increment[order]
        same_block = (step == increment[:-1]) & (increment[:-1] == increment[1:])
        breaks = np.flatnonzero(~same_block) + 1
        scans = []
        for block in np.split(np.arange(len(order)), breaks):
            slots = order[block]
            angles = -math.pi + self.resolution_rad * unwrapped[block]
            scans.append(
                Scan(angles.astype(np.float64), ranges[slots], self.amplitudes[slots], 0.0)
            )
        return scans

    def _slots(self, angles_rad: FloatArray) -> np.ndarray:
        position = (wrap_angles(angles_rad) + math.pi) / self.resolution_rad
        slots = np.rint(position)
        if np.any(np.abs(position - slots) > 1e-6):
            raise ValueError(
                "pan angles must lie on the memory's grid of "
                f"{math.degrees(self.resolution_rad):g} deg"
            )
        return slots.astype(np.int64) % self.n_slots
