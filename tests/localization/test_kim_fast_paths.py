"""The compiled loops of Kim, Lee & Jeong's voting (sec. 3.3) against the array forms they
replaced: the same pairs, the same vote volume and the same vote positions, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pytest

from sonar_gym.localization import kim, kim_kernels
from sonar_gym.localization.kim import OccupancyGrid
from sonar_gym.pose import FloatArray, Pose
from tests.localization.test_kim import (
    MOVES,
    noisy_sweeps,
)

Pairs = tuple[npt.NDArray[np.intp], npt.NDArray[np.intp]]
Votes = tuple[
    npt.NDArray[np.intp], FloatArray, FloatArray, npt.NDArray[np.int64], npt.NDArray[np.int64]
]


def reference_pairs(
    readings: kim._Readings,
    anchors: FloatArray,
    center: FloatArray | None,
    radius: float | None,
    headings: FloatArray,
) -> Pairs:
    """The array form: the circle test over the ``(J, K)`` product, then the heading test."""
    n_readings, n_anchors = readings.range_m.size, anchors.shape[0]
    if center is None or radius is None:
        pair_j, pair_k = np.divmod(np.arange(n_readings * n_anchors), n_anchors)
        return pair_j, pair_k
    anchor_distance = np.hypot(anchors[:, 0] - center[0], anchors[:, 1] - center[1])
    reach = np.hypot(readings.end_x, readings.end_y)
    slack = radius * (1.0 + 1e-9) + 1e-12
    flat = np.flatnonzero(np.abs(anchor_distance - reach[:, None]) <= slack)
    pair_j = flat // n_anchors
    pair_k = flat - pair_j * n_anchors
    if headings.size == 0 or pair_j.size == 0:
        return pair_j, pair_k
    middle = float(headings[headings.size // 2])
    spread = float(np.abs(np.remainder(headings - middle + np.pi, 2.0 * np.pi) - np.pi).max())
    spread += 1e-6
    if spread >= np.pi:
        return pair_j, pair_k
    cos_m, sin_m = math.cos(middle), math.sin(middle)
    to_anchor_x, to_anchor_y = anchors[:, 0] - center[0], anchors[:, 1] - center[1]
    back_x = (cos_m * to_anchor_x + sin_m * to_anchor_y).take(pair_k)
    back_y = (cos_m * to_anchor_y - sin_m * to_anchor_x).take(pair_k)
    end_x, end_y = readings.end_x.take(pair_j), readings.end_y.take(pair_j)
    dot = back_x * end_x + back_y * end_y
    cross = np.abs(back_x * end_y - back_y * end_x)
    squared_d = (to_anchor_x * to_anchor_x + to_anchor_y * to_anchor_y).take(pair_k)
    squared_e = (readings.end_x * readings.end_x + readings.end_y * readings.end_y).take(pair_j)
    padded = radius * (1.0 + 1e-9) + 1e-12
    needed = 0.5 * (squared_d + squared_e - padded * padded) - 1e-12
    cos_s, sin_s = math.cos(spread), math.sin(spread)
    within_spread = dot >= cos_s * np.sqrt(squared_d * squared_e) - 1e-12
    kept = np.flatnonzero(within_spread | (dot * cos_s + cross * sin_s >= needed))
    return pair_j.take(kept), pair_k.take(kept)


def reference_votes(
    arena_grid: OccupancyGrid,
    readings: kim._Readings,
    anchors: FloatArray,
    table: FloatArray,
    headings: FloatArray,
    direction_index: npt.NDArray[np.intp],
    pairs: Pairs,
    window: tuple[int, int, int, int],
    center: FloatArray | None,
    radius: float | None,
) -> tuple[
    npt.NDArray[np.intp], FloatArray, FloatArray, npt.NDArray[np.int64], npt.NDArray[np.int64]
]:
    """The array form: every vote of every heading, heading by heading in pair order, kept
    when inside the circle and the window: ``(heading index, t_x, t_y, cell_x, cell_y)``."""
    pair_j, pair_k = pairs
    n_anchors = table.shape[1]
    flat = (direction_index * n_anchors).take(pair_j, axis=1) + pair_k
    hits = np.flatnonzero(table.take(flat) > readings.range_m.take(pair_j))
    cos_h, sin_h = np.cos(headings)[:, None], np.sin(headings)[:, None]
    rotated_x = (cos_h * readings.end_x - sin_h * readings.end_y).take(pair_j, axis=1)
    rotated_y = (sin_h * readings.end_x + cos_h * readings.end_y).take(pair_j, axis=1)
    t_x = (anchors[:, 0].take(pair_k) - rotated_x).take(hits)
    t_y = (anchors[:, 1].take(pair_k) - rotated_y).take(hits)
    heading_i = hits // pair_j.size
    if center is not None and radius is not None:
        inside = np.flatnonzero((t_x - center[0]) ** 2 + (t_y - center[1]) ** 2 <= radius * radius)
        heading_i, t_x, t_y = heading_i.take(inside), t_x.take(inside), t_y.take(inside)
    x0, y0 = arena_grid.origin_m
    cell_x = np.floor((t_x - x0) / arena_grid.cell_size_m).astype(np.int64)
    cell_y = np.floor((t_y - y0) / arena_grid.cell_size_m).astype(np.int64)
    low_x, low_y, high_x, high_y = window
    kept = np.flatnonzero(
        (cell_x >= low_x) & (cell_x <= high_x) & (cell_y >= low_y) & (cell_y <= high_y)
    )
    return (
        heading_i.take(kept),
        t_x.take(kept),
        t_y.take(kept),
        cell_x.take(kept),
        cell_y.take(kept),
    )


@pytest.mark.parametrize("anchor", ["cell_center", "obstacle_point"])
@pytest.mark.parametrize("radius", [None, 0.1, 0.3, 0.6])
@pytest.mark.parametrize("window_deg", [2.0, 10.0, 100.0, 180.0])
@pytest.mark.parametrize("count", [1, 3])
@pytest.mark.parametrize(
    "truth", [Pose(0.93, 0.71, 0.4), Pose(0.2, 0.25, -3.1)], ids=["middle", "near_corner"]
)
def test_compiled_votes_are_the_array_forms_votes(
    arena_grid: OccupancyGrid,
    anchor: str,
    radius: float | None,
    window_deg: float,
    count: int,
    truth: Pose,
) -> None:
    rng = np.random.default_rng(int(window_deg) + 7 * count)
    sweeps = noisy_sweeps(truth, MOVES[:count], rng, dropout_fraction=0.1)
    prior = Pose(truth.x + 0.04, truth.y - 0.03, truth.theta + math.radians(2.0))
    center = None if radius is None else prior.position
    headings = kim.heading_candidates_around(
        prior.theta, math.radians(window_deg), math.radians(1.0)
    )
    readings = kim._gather_readings(sweeps, None)
    table_cache = kim._free_distance_table(arena_grid, 360, arena_grid.cell_size_m)
    anchors = table_cache.anchors(anchor)  # type: ignore[arg-type]

    pairs = kim._candidate_pairs(readings, anchors, center, radius, headings)
    expected_pairs = reference_pairs(readings, anchors, center, radius, headings)
    assert np.array_equal(pairs[0], expected_pairs[0])
    assert np.array_equal(pairs[1], expected_pairs[1])
    assert pairs[0].size > 0

    window = kim._vote_window(arena_grid, center, radius)
    direction_index = kim._direction_index(headings, readings, 360)
    table = table_cache.columns(direction_index.ravel())
    cos_h, sin_h = np.cos(headings), np.sin(headings)
    layout = kim._vote_layout(arena_grid, window, center, radius)
    volume = kim_kernels.vote_volume(
        *pairs, direction_index, table, readings.range_m, readings.end_x, readings.end_y,
        anchors, cos_h, sin_h, *layout,
    )  # fmt: skip

    heading_i, t_x, t_y, cell_x, cell_y = reference_votes(
        arena_grid, readings, anchors, table, headings, direction_index, pairs, window.cells,
        center, radius,
    )  # fmt: skip
    low_x, low_y = window.low
    wx, wy = window.shape
    flat = heading_i * (wx * wy) + (cell_x - low_x) * wy + (cell_y - low_y)
    expected_volume = np.bincount(flat, minlength=headings.size * wx * wy).reshape(-1, wx, wy)
    assert np.array_equal(volume, expected_volume)
    assert volume.sum() > 0

    chosen = int(np.argmax(volume.reshape(headings.size, -1).max(axis=1)))
    best = np.unravel_index(int(np.argmax(volume[chosen])), (wx, wy))
    cells = (
        low_x + int(best[0]) - 1,
        low_y + int(best[1]) - 1,
        low_x + int(best[0]) + 1,
        low_y + int(best[1]) + 1,
    )
    votes_x, votes_y = kim_kernels.votes_in_cells(
        *pairs, direction_index[chosen], table, readings.range_m, readings.end_x,
        readings.end_y, anchors, float(cos_h[chosen]), float(sin_h[chosen]), *layout, cells,
    )  # fmt: skip
    of_heading = heading_i == chosen
    in_cells = (cell_x >= cells[0]) & (cell_x <= cells[2])
    in_cells &= (cell_y >= cells[1]) & (cell_y <= cells[3])
    assert np.array_equal(votes_x, t_x[of_heading & in_cells])
    assert np.array_equal(votes_y, t_y[of_heading & in_cells])
    assert votes_x.size > 0


def test_heading_spread_of_half_a_turn_or_more_keeps_the_circle_test_only() -> None:
    headings = kim.heading_candidates_around(0.3, math.radians(180.0), math.radians(1.0))
    assert kim._heading_spread(headings) is None
    narrow = kim.heading_candidates_around(0.3, math.radians(10.0), math.radians(1.0))
    spread = kim._heading_spread(narrow)
    assert spread is not None
    middle, angle = spread
    assert middle == pytest.approx(0.3, abs=1e-12)
    assert angle == pytest.approx(math.radians(10.0) + 1e-6, abs=1e-9)
    assert kim._heading_spread(np.array([])) is None


def test_binomial_smoothing_of_an_empty_and_a_one_cell_layer() -> None:
    assert kim_kernels.binomial_smooth(np.zeros((2, 0, 3), dtype=np.int64)).shape == (2, 0, 3)
    one = kim_kernels.binomial_smooth(np.full((1, 1, 1), 3, dtype=np.int64))
    assert one.tolist() == [[[12]]]


def _one_vote(radius: float) -> int:
    """Votes of one reading ``e = (0.5, 0)`` at heading 0 ending at anchor ``(1, 1)``: the
    robot at ``t = (0.5, 1)``, exactly ``0.25`` m from the search centre ``(0.25, 1)``."""
    volume = kim_kernels.vote_volume(
        np.array([0]), np.array([0]), np.zeros((1, 1), dtype=np.int64), np.array([[10.0]]),
        np.array([0.5]), np.array([0.5]), np.array([0.0]), np.array([[1.0, 1.0]]),
        np.array([1.0]), np.array([0.0]), (0.25, 1.0, radius), (0.0, 0.0, 0.1), (0, 0, 20, 20),
    )  # fmt: skip
    assert volume.shape == (1, 21, 21)
    assert volume.sum() == volume[0, 5, 10]
    return int(volume.sum())


def test_a_vote_on_the_search_circle_counts() -> None:
    assert _one_vote(0.25) == 1
    assert _one_vote(math.nextafter(0.25, 0.0)) == 0
    assert _one_vote(math.inf) == 1


def test_a_pair_at_the_padded_circle_test_bound_is_kept() -> None:
    """``| |a - c| - |e| | <= slack`` keeps a pair exactly at the bound (the array form's test)."""
    for radius in (0.25, 0.3, 0.125, 0.2):
        slack = radius * (1.0 + 1e-9) + 1e-12
        distance = 0.5 + slack
        if distance - 0.5 == slack:
            break
    else:
        pytest.fail("no radius gives an exact bound")
    anchors = np.array([[distance, 0.0], [math.nextafter(distance, 2.0), 0.0]])
    pair_j, pair_k = kim_kernels.candidate_pairs(
        np.array([0.5]), np.array([0.0]), anchors, 0.0, 0.0, radius, False, 1.0, 0.0, 1.0, 0.0
    )
    assert pair_j.tolist() == [0]
    assert pair_k.tolist() == [0]


def test_a_ray_free_exactly_to_its_range_is_obstructed() -> None:
    """``free_distance > range`` votes; a free distance equal to the range does not."""
    for free, expected in ((0.5, 0), (math.nextafter(0.5, 1.0), 1)):
        volume = kim_kernels.vote_volume(
            np.array([0, 0]), np.array([0, 1]), np.zeros((1, 1), dtype=np.int64),
            np.array([[free, 0.0]]), np.array([0.5]), np.array([0.5]), np.array([0.0]),
            np.array([[1.0, 1.0], [1.2, 1.0]]), np.array([1.0]), np.array([0.0]),
            (0.25, 1.0, math.inf), (0.0, 0.0, 0.1), (0, 0, 20, 20),
        )  # fmt: skip
        assert volume.sum() == volume[0, 5, 10] == expected
