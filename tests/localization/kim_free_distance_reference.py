"""The free-distance trace of Kim's unobstructed-ray table (sec. 3.3) as
``kim._FreeDistanceTable._trace`` first wrote it (blocks of samples over all pending rays in
numpy), kept as the tests' reference."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from sonar_gym.localization import kim
from sonar_gym.pose import FloatArray


def reference_trace(table: kim._FreeDistanceTable, directions: npt.NDArray[np.intp]) -> FloatArray:
    """March back from every cell centre in the given directions, a block of samples at a
    time, keeping only the rays not yet blocked: ``(directions, cells)`` metres."""
    nx, ny = table.blocked_cells.shape[0] - 2, table.blocked_cells.shape[1] - 2
    x0, y0 = table.origin_m
    cell_size = table.cell_size_m
    angles = 2.0 * np.pi * directions / table.direction_bins
    back_x = np.repeat(-np.cos(angles), table.centers.shape[0])
    back_y = np.repeat(-np.sin(angles), table.centers.shape[0])
    start_x = np.tile((table.centers[:, 0] - x0) / cell_size, directions.size)
    start_y = np.tile((table.centers[:, 1] - y0) / cell_size, directions.size)
    samples = table.samples_m / cell_size
    distance = np.full(back_x.size, table.samples_m[-1])
    pending = np.arange(back_x.size)
    block = 8
    for first in range(0, samples.size, block):
        steps = samples[first : first + block]
        cell_x = np.floor(start_x[pending, None] + steps[None, :] * back_x[pending, None])
        cell_y = np.floor(start_y[pending, None] + steps[None, :] * back_y[pending, None])
        cell_x = np.clip(cell_x, -1, nx).astype(np.intp) + 1
        cell_y = np.clip(cell_y, -1, ny).astype(np.intp) + 1
        blocked = table.blocked_cells[cell_x, cell_y]
        hit = blocked.any(axis=1)
        distance[pending[hit]] = table.samples_m[first + np.argmax(blocked[hit], axis=1)]
        pending = pending[~hit]
        if pending.size == 0:
            break
    return distance.reshape(directions.size, table.centers.shape[0])
