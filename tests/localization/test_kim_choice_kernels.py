"""The compiled heading candidates, the smoothed peak and the vote mean of Kim, Lee & Jeong's
voting (sec. 3.3) against the array forms they replaced, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization import kim, kim_kernels
from sonar_gym.localization.kim import OccupancyGrid
from sonar_gym.pose import FloatArray, Pose, wrap_angles
from tests.localization.test_kim import (
    MOVES,
    noisy_sweeps,
)


def reference_heading_grid(prior_rad: float, step_rad: float, count: int) -> FloatArray:
    return wrap_angles(prior_rad + step_rad * np.arange(-count, count + 1))


def reference_heading_offset(headings: FloatArray) -> float:
    middle = float(headings[headings.size // 2])
    return float(np.abs(np.remainder(headings - middle + np.pi, 2.0 * np.pi) - np.pi).max())


@pytest.mark.parametrize("prior", [0.0, 0.3, -3.1, 3.1, math.pi, -math.pi, 2.5 * math.pi])
@pytest.mark.parametrize("step_deg", [0.5, 1.0, 7.0, 180.0])
@pytest.mark.parametrize("count", [0, 1, 10, 400])
def test_heading_grid_and_offset_are_the_array_forms(
    prior: float, step_deg: float, count: int
) -> None:
    step = math.radians(step_deg)
    headings = kim_kernels.heading_grid(prior, step, count)
    expected = reference_heading_grid(prior, step, count)
    assert headings.tobytes() == expected.tobytes()
    offset = kim_kernels.heading_offset(headings)
    assert np.float64(offset).tobytes() == np.float64(reference_heading_offset(expected)).tobytes()


def test_heading_offset_of_no_heading_is_zero() -> None:
    assert kim_kernels.heading_offset(np.array([])) == 0.0


def reference_peak(volume: np.ndarray) -> tuple[np.ndarray, int, int, int]:
    score = kim_kernels.binomial_smooth(volume)
    heading, rest = divmod(int(np.argmax(score)), score.shape[1] * score.shape[2])
    x, y = divmod(rest, score.shape[2])
    return score, heading, x, y


def _assert_peak_is_the_array_forms(volume: np.ndarray) -> None:
    score, heading, x, y = kim_kernels.smoothed_maximum(volume)
    expected_score, *expected_peak = reference_peak(volume)
    assert [heading, x, y] == expected_peak
    assert score == expected_score[heading, x, y]


def test_smoothed_maximum_takes_the_first_of_tied_maxima() -> None:
    rng = np.random.default_rng(5)
    for shape in ((1, 1, 1), (3, 1, 5), (4, 6, 1), (5, 7, 9), (30, 14, 17)):
        _assert_peak_is_the_array_forms(np.zeros(shape, dtype=np.int64))  # all tied
        _assert_peak_is_the_array_forms(np.ones(shape, dtype=np.int64))
        for _ in range(20):  # few distinct counts: many ties
            _assert_peak_is_the_array_forms(rng.integers(0, 3, shape))
            _assert_peak_is_the_array_forms(rng.integers(0, 3, shape) * (rng.random(shape) < 0.05))
    tied = np.zeros((3, 5, 5), dtype=np.int64)
    tied[1, 1, 1] = tied[2, 1, 1] = tied[1, 3, 3] = 1  # equal peaks in two headings
    _assert_peak_is_the_array_forms(tied)
    assert kim_kernels.smoothed_maximum(tied)[1:] == (1, 1, 1)


def test_smoothed_maximum_of_an_empty_volume() -> None:
    assert kim_kernels.smoothed_maximum(np.zeros((2, 0, 3), dtype=np.int64)) == (0, 0, 0, 0)
    assert kim_kernels.smoothed_maximum(np.zeros((0, 4, 3), dtype=np.int64)) == (0, 0, 0, 0)


@pytest.mark.parametrize("count", [1, 3])
@pytest.mark.parametrize("radius", [None, 0.3])
@pytest.mark.parametrize("cells_half_width", [0, 1, 100])
def test_vote_mean_is_the_array_forms_mean(
    arena_grid: OccupancyGrid, count: int, radius: float | None, cells_half_width: int
) -> None:
    truth = Pose(0.93, 0.71, 0.4)
    sweeps = noisy_sweeps(truth, MOVES[:count], np.random.default_rng(count), 0.01, 0.1)
    center = None if radius is None else np.array([truth.x + 0.04, truth.y - 0.03])
    headings = kim.heading_candidates_around(truth.theta, math.radians(5.0), math.radians(1.0))
    readings = kim._gather_readings(sweeps, None)
    table_cache = kim._free_distance_table(arena_grid, 360, arena_grid.cell_size_m)
    anchors = table_cache.anchors("cell_center")
    pairs = kim._candidate_pairs(readings, anchors, center, radius, headings)
    window = kim._vote_window(arena_grid, center, radius)
    direction_index = kim._direction_index(headings, readings, 360)
    table = table_cache.columns(direction_index.ravel())
    layout = kim._vote_layout(arena_grid, window, center, radius)
    best_x, best_y = arena_grid.world_to_cell(truth.position)
    cells = (
        best_x - cells_half_width,
        best_y - cells_half_width,
        best_x + cells_half_width,
        best_y + cells_half_width,
    )
    for heading in range(headings.size):
        arguments = (
            *pairs, direction_index[heading], table, readings.range_m, readings.end_x,
            readings.end_y, anchors, math.cos(headings[heading]), math.sin(headings[heading]),
            *layout, cells,
        )  # fmt: skip
        votes_x, votes_y = kim_kernels.votes_in_cells(*arguments)
        found, mean_x, mean_y = kim_kernels.vote_mean(*arguments)
        assert found == votes_x.size
        if found:
            assert np.float64(mean_x).tobytes() == (votes_x.sum() / found).tobytes()
            assert np.float64(mean_y).tobytes() == (votes_y.sum() / found).tobytes()
        else:
            assert (mean_x, mean_y) == (0.0, 0.0)
