"""The tables of :meth:`sonar_gym.sonar.acoustics.PistonBeam.for_ka` in their masked-array form
(boolean masks over every sample, ``np.where`` and ``np.column_stack``), which the form on the
samples in front as a prefix replaced, kept as the tests' reference."""

from __future__ import annotations

import numpy as np

from sonar_gym.pose import FloatArray
from sonar_gym.sonar.acoustics import (
    TABLE_STEPS_PER_UNIT,
    _piston_directivity_of,
    _table_grid,
    _validated_leakage,
    first_null_rad,
    leakage_onset_argument,
    side_lobe_envelope,
)


def reference_beam_tables(
    wavenumber_ka: float, side_lobes: bool = True, side_lobe_leakage: float = 0.0
) -> tuple[FloatArray, FloatArray, bool, FloatArray]:
    """``(cells, main_lobe_rising, reaches_back, main_lobe_cells)`` of the beam for ``k a``,
    side lobes and leakage ``S``, as :class:`~sonar_gym.sonar.acoustics.PistonBeam` holds them."""
    leakage = _validated_leakage(side_lobe_leakage)
    front, theta, sin_front = _table_grid()
    x = wavenumber_ka * sin_front  # k a sin(theta) of the samples in front
    values = np.zeros(len(theta))  # behind the transducer the pattern is 0
    beyond_main_lobe = (theta >= first_null_rad(wavenumber_ka)) | ~front
    if side_lobes:
        values[front] = _piston_directivity_of(x) ** 2
    else:
        main_lobe = ~beyond_main_lobe
        values[main_lobe] = _piston_directivity_of(x[main_lobe[front]]) ** 2
    last_monotone = int(np.argmax(beyond_main_lobe)) - 1
    if leakage > 0.0:
        leaking = x >= leakage_onset_argument(leakage)
        floor = leakage * side_lobe_envelope(np.where(leaking, x, 1.0))
        values[front] = np.where(leaking, np.maximum(values[front], floor), values[front])
        if not side_lobes:
            last_monotone = TABLE_STEPS_PER_UNIT  # monotone up to 90 deg
    cells = np.column_stack([values[:-1], np.diff(values)])
    main_lobe_rising = values[last_monotone::-1].copy()
    reaches_back = bool(values[TABLE_STEPS_PER_UNIT] != 0.0)
    last = len(main_lobe_rising) - 1
    numbers = np.arange(last, -2, -1, dtype=np.float64)
    main_lobe_cells = np.column_stack([numbers, cells.take(numbers.astype(np.intp), 0)])
    return cells, main_lobe_rising, reaches_back, main_lobe_cells
