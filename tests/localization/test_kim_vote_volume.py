"""Kim's vote volume (sec. 3.3) against a pair-by-pair count written out here.

The compiled loop finds each reading's table rows and turned end point once per run of its
pairs; these inputs give readings several pairs each, pairs of one reading in more than one
run, and readings with no pair, so a wrong run boundary moves votes.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization import kim_kernels

CIRCLE = (0.2, -0.1, 2.5)  # centre x, centre y, radius (m)
GRID_FRAME = (-4.0, -4.0, 0.1)  # origin x, origin y, cell size (m)
WINDOW = (5, 8, 70, 66)  # low x, low y, high x, high y (cells)


def reference_volume(
    pair_j: np.ndarray,
    pair_k: np.ndarray,
    direction_index: np.ndarray,
    free_distance: np.ndarray,
    range_m: np.ndarray,
    end_x: np.ndarray,
    end_y: np.ndarray,
    anchors: np.ndarray,
    cos_h: np.ndarray,
    sin_h: np.ndarray,
) -> np.ndarray:
    """The definition: each pair under each heading, one vote at a time."""
    low_x, low_y, high_x, high_y = WINDOW
    origin_x, origin_y, size = GRID_FRAME
    volume = np.zeros((len(cos_h), high_x - low_x + 1, high_y - low_y + 1), dtype=np.int64)
    for j, k in zip(pair_j.tolist(), pair_k.tolist(), strict=True):
        for heading, (c, s) in enumerate(zip(cos_h.tolist(), sin_h.tolist(), strict=True)):
            if not free_distance[direction_index[heading, j], k] > range_m[j]:
                continue
            t_x = anchors[k, 0] - (c * end_x[j] - s * end_y[j])
            t_y = anchors[k, 1] - (s * end_x[j] + c * end_y[j])
            off_x, off_y = t_x - CIRCLE[0], t_y - CIRCLE[1]
            if not off_x * off_x + off_y * off_y <= CIRCLE[2] * CIRCLE[2]:
                continue
            cell_x = math.floor((t_x - origin_x) / size)
            cell_y = math.floor((t_y - origin_y) / size)
            if low_x <= cell_x <= high_x and low_y <= cell_y <= high_y:
                volume[heading, cell_x - low_x, cell_y - low_y] += 1
    return volume


@pytest.mark.parametrize("seed", range(6))
def test_vote_volume_counts_every_pair_as_the_definition(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n_readings, n_anchors, n_headings, bins = 14, 40, 7, 36
    anchors = rng.uniform(-2.0, 2.0, (n_anchors, 2))
    end_x, end_y = rng.uniform(-2.0, 2.0, n_readings), rng.uniform(-2.0, 2.0, n_readings)
    range_m = np.hypot(end_x, end_y)
    free_distance = rng.uniform(0.0, 3.5, (bins, n_anchors))
    direction_index = rng.integers(0, bins, (n_headings, n_readings))
    headings = rng.uniform(-math.pi, math.pi, n_headings)
    # Reading-major pairs, some readings without any, then a second run of one reading.
    pair_j, pair_k = [], []
    for j in range(n_readings):
        if j % 5 == 3:
            continue
        anchors_of_j = np.sort(rng.choice(n_anchors, int(rng.integers(1, 12)), replace=False))
        pair_j += [j] * len(anchors_of_j)
        pair_k += anchors_of_j.tolist()
    pair_j += [2, 2, 2]
    pair_k += [0, 1, 2]
    arguments = (
        np.array(pair_j, dtype=np.int64),
        np.array(pair_k, dtype=np.int64),
        direction_index,
        free_distance,
        range_m,
        end_x,
        end_y,
        anchors,
        np.cos(headings),
        np.sin(headings),
    )
    expected = reference_volume(*arguments)
    assert expected.sum() > 20  # votes were counted, under several headings
    got = kim_kernels.vote_volume(*arguments, CIRCLE, GRID_FRAME, WINDOW)
    np.testing.assert_array_equal(got, expected)
