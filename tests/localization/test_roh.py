"""Tests of Roh et al.'s block expansion: trilateration, auto-calibration, three-point
extraction, path errors and the area-to-area runner, against closed forms and Tables I-V."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from sonar_gym.localization.roh import (
    DEFAULT_SENSOR_HEIGHT_M,
    PAPER_THREE_AREAS,
    PAPER_TWO_AREAS,
    TABLE_I_BEACONS_M,
    TABLE_I_BEACONS_MM,
    TABLE_II_III_D_MM,
    TABLE_II_SIGMA_MM,
    TABLE_III_SIGMA_PRIME_MM,
    TABLE_IV_SIGMA_MM,
    TABLE_IV_V_D_MM,
    TABLE_V_SIGMA_PRIME_MM,
    BlockExpansion,
    BlockExpansionConfig,
    auto_calibrate,
    circle_intersections,
    extract_three_points,
    paper_centroid,
    parabolic_path,
    path_errors,
    radical_axis,
    radical_centre,
    trilaterate,
)

HEIGHT_M = DEFAULT_SENSOR_HEIGHT_M
AREA_1 = np.array([TABLE_I_BEACONS_M[name] for name in ("A", "B", "C")])
SCALE_M = 4.0  # size of the Table I layout; "relative" tolerances are taken against it


def slant_ranges(beacons: np.ndarray, xy: np.ndarray, height: float = HEIGHT_M) -> np.ndarray:
    """Exact slant ranges from a sensor at (x, y, height) to each beacon, metres."""
    sensor = np.array([xy[0], xy[1], height])
    return np.linalg.norm(beacons - sensor, axis=1)


def cross2(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """z-component of the cross product of 2D vectors (row-wise for arrays)."""
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def distance_to_line(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    direction = b - a
    offset = point - a
    return abs(direction[0] * offset[1] - direction[1] * offset[0]) / np.linalg.norm(direction)


def two_area_path() -> np.ndarray:
    """The default parabola from Area 1 to the far end of Area 2 (boundary BD)."""
    return parabolic_path(x_end_m=1.2)


# ---------------------------------------------------------------------------------------------
# Table I
# ---------------------------------------------------------------------------------------------


def test_table_i_beacons_are_the_printed_millimetres_in_metres() -> None:
    assert TABLE_I_BEACONS_MM["A"] == (3467.0, 101.0, 825.0)
    assert TABLE_I_BEACONS_MM["C"] == (2459.0, 1870.0, 1457.0)
    assert TABLE_I_BEACONS_MM["E"] == (351.0, 132.0, 835.0)
    assert sorted(TABLE_I_BEACONS_M) == ["A", "B", "C", "D", "E"]
    assert TABLE_I_BEACONS_M["B"] == pytest.approx((1.551, 0.139, 1.441))
    assert TABLE_I_BEACONS_M["D"] == pytest.approx((0.921, 2.065, 1.341))


def test_paper_areas_partition_the_parallelogram_without_overlap() -> None:
    """Areas 1 and 2 lie on opposite sides of BC, Areas 2 and 3 on opposite sides of BD."""

    def side(p: str, a: str, b: str) -> float:
        pa, pb, pp = (np.array(TABLE_I_BEACONS_M[n][:2]) for n in (a, b, p))
        return float(np.sign(cross2(pb - pa, pp - pa)))

    assert PAPER_THREE_AREAS[:2] == PAPER_TWO_AREAS
    assert side("A", "B", "C") * side("D", "B", "C") == -1.0
    assert side("C", "B", "D") * side("E", "B", "D") == -1.0


# ---------------------------------------------------------------------------------------------
# Trilateration (Sec. III.A)
# ---------------------------------------------------------------------------------------------

barycentric = st.floats(min_value=-0.25, max_value=1.25, allow_nan=False)


@settings(max_examples=150, deadline=None)
@given(u=barycentric, v=barycentric, method=st.sampled_from(["paper", "least_squares"]))
def test_trilateration_is_exact_on_noise_free_ranges(u: float, v: float, method: str) -> None:
    a, b, c = AREA_1[:, :2]
    truth = a + u * (b - a) + v * (c - a)
    # On an edge line two circles are tangent and their meeting point is only known to
    # sqrt(machine epsilon); keep 1 cm off the three lines of centres.
    assume(min(distance_to_line(truth, p, q) for p, q in ((a, b), (b, c), (a, c))) > 0.01)
    result = trilaterate(AREA_1, slant_ranges(AREA_1, truth), HEIGHT_M, method=method)
    assert result.status == "ok"
    assert result.method == method
    np.testing.assert_allclose(result.position, truth, rtol=0.0, atol=1e-9 * SCALE_M)
    assert (result.pose.x, result.pose.y) == (result.position[0], result.position[1])


def test_trilateration_on_a_line_of_centres_is_still_accurate_to_sqrt_epsilon() -> None:
    a, b = AREA_1[0, :2], AREA_1[1, :2]
    truth = 0.5 * (a + b)
    result = trilaterate(AREA_1, slant_ranges(AREA_1, truth), HEIGHT_M)
    assert result.ok
    np.testing.assert_allclose(result.position, truth, atol=1e-6)


def test_trilateration_reports_no_heading() -> None:
    result = trilaterate(AREA_1, slant_ranges(AREA_1, np.array([2.5, 0.7])), HEIGHT_M)
    assert result.ok and result.has_heading is False and result.pose.theta == 0.0


def test_literal_radical_axis_reading_gives_a_degenerate_triangle() -> None:
    """Sec. III.A: the three "lines of intersection" meet in one point even with noise,
    so their "triangle" has no area; the paper reading's triangle does, and its centroid
    differs from the radical centre while both stay near the truth."""
    rng = np.random.default_rng(3)
    truth = np.array([2.5, 0.7])
    ranges = slant_ranges(AREA_1, truth) + rng.normal(0.0, 0.01, 3)
    centres = AREA_1[:, :2]
    radii = np.sqrt(ranges**2 - (AREA_1[:, 2] - HEIGHT_M) ** 2)

    axes = [
        radical_axis(centres[i], radii[i], centres[j], radii[j])
        for i, j in ((0, 1), (1, 2), (0, 2))
    ]
    corners = []
    for first, second in ((0, 1), (1, 2), (0, 2)):
        normals = np.array([axes[first][0], axes[second][0]])
        offsets = np.array([axes[first][1], axes[second][1]])
        corners.append(np.linalg.solve(normals, offsets))
    corners = np.array(corners)
    literal_area = 0.5 * abs(cross2(corners[1] - corners[0], corners[2] - corners[0]))
    assert literal_area < 1e-12
    centre = radical_centre(centres, radii)
    np.testing.assert_allclose(corners, np.tile(centre, (3, 1)), atol=1e-9)

    kept = []
    for i, j in ((0, 1), (1, 2), (0, 2)):
        k = 3 - i - j
        points = circle_intersections(centres[i], radii[i], centres[j], radii[j])
        miss = np.abs(np.linalg.norm(points - centres[k], axis=1) - radii[k])
        kept.append(points[np.argmin(miss)])
    kept = np.array(kept)
    paper_area = 0.5 * abs(cross2(kept[1] - kept[0], kept[2] - kept[0]))
    assert paper_area > 1e-5

    estimate, used_fallback = paper_centroid(centres, radii)
    assert not used_fallback
    np.testing.assert_allclose(estimate, kept.mean(axis=0), atol=1e-12)
    assert np.linalg.norm(estimate - centre) > 1e-5  # rounding is ~1e-15
    assert np.linalg.norm(estimate - truth) < 0.05
    assert np.linalg.norm(centre - truth) < 0.05


def test_paper_method_falls_back_to_the_radical_centre_when_two_circles_miss() -> None:
    centres = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 2.0]])
    radii = np.array([0.9, 0.9, 1.8])  # circles 0 and 1 are 0.2 m apart
    estimate, used_fallback = paper_centroid(centres, radii)
    assert used_fallback
    np.testing.assert_allclose(estimate, radical_centre(centres, radii), atol=1e-12)
    # By symmetry and r0 = r1 the radical centre lies on x = 1.
    assert estimate[0] == pytest.approx(1.0, abs=1e-12)


def test_radical_centre_solves_the_three_circle_equations_pairwise() -> None:
    centres = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 4.0]])
    radii = np.array([1.0, 2.0, 3.0])
    centre = radical_centre(centres, radii)
    powers = np.sum((centre - centres) ** 2, axis=1) - radii**2
    np.testing.assert_allclose(powers, powers[0], atol=1e-12)


def test_least_squares_uses_all_beacons_and_paper_picks_a_well_conditioned_triple() -> None:
    beacons = np.array([[0.0, 0.0, 1.2], [1.0, 0.0, 1.3], [2.0, 0.002, 1.1], [1.0, 1.5, 1.4]])
    truth = np.array([1.1, 0.6])
    ranges = slant_ranges(beacons, truth)
    by_least_squares = trilaterate(beacons, ranges, HEIGHT_M, method="least_squares")
    by_paper = trilaterate(beacons, ranges, HEIGHT_M, method="paper")
    assert by_least_squares.beacon_indices == (0, 1, 2, 3)
    assert len(by_paper.beacon_indices) == 3 and 3 in by_paper.beacon_indices
    for result in (by_least_squares, by_paper):
        np.testing.assert_allclose(result.position, truth, atol=1e-9 * SCALE_M)


def test_all_five_table_i_beacons_locate_exactly() -> None:
    beacons = np.array(list(TABLE_I_BEACONS_M.values()))
    truth = np.array([1.7, 1.1])
    for method in ("paper", "least_squares"):
        result = trilaterate(beacons, slant_ranges(beacons, truth), HEIGHT_M, method=method)
        np.testing.assert_allclose(result.position, truth, atol=1e-9 * SCALE_M)


def test_missing_ranges_are_skipped_and_too_few_give_a_status() -> None:
    beacons = np.array(list(TABLE_I_BEACONS_M.values()))[:4]
    truth = np.array([2.0, 1.0])
    ranges = slant_ranges(beacons, truth)
    ranges[1] = np.nan
    result = trilaterate(beacons, ranges, HEIGHT_M)
    assert result.ok and result.beacon_indices == (0, 2, 3)
    np.testing.assert_allclose(result.position, truth, atol=1e-9 * SCALE_M)
    ranges[2] = np.nan
    failed = trilaterate(beacons, ranges, HEIGHT_M)
    assert failed.status == "too_few_beacons" and failed.pose is None and failed.position is None
    two = trilaterate(AREA_1[:2], slant_ranges(AREA_1[:2], truth), HEIGHT_M)
    assert two.status == "too_few_beacons"


def test_collinear_beacons_give_a_status() -> None:
    beacons = np.array([[0.0, 0.0, 1.0], [1.0, 1.0, 1.2], [2.0, 2.0, 1.4]])
    result = trilaterate(beacons, slant_ranges(beacons, np.array([0.0, 1.0])), HEIGHT_M)
    assert result.status == "collinear_beacons" and result.position is None


def test_a_range_shorter_than_the_beacon_height_gives_a_status() -> None:
    ranges = slant_ranges(AREA_1, np.array([2.5, 0.7]))
    ranges[0] = 0.5 * (AREA_1[0, 2] - HEIGHT_M)
    result = trilaterate(AREA_1, ranges, HEIGHT_M)
    assert result.status == "distance_below_height" and result.position is None


def test_a_range_just_under_the_beacon_height_means_right_below_it() -> None:
    ranges = slant_ranges(AREA_1, AREA_1[0, :2])
    ranges[0] -= 0.002  # within the default 0.01 m tolerance
    result = trilaterate(AREA_1, ranges, HEIGHT_M, method="least_squares")
    assert result.ok
    np.testing.assert_allclose(result.position, AREA_1[0, :2], atol=0.02)


@pytest.mark.parametrize(
    ("beacons", "distances", "method", "name"),
    [
        (np.zeros((3, 2)), np.ones(3), "paper", "beacons"),
        (AREA_1, np.ones(4), "paper", "distances"),
        (AREA_1, np.array([1.0, -1.0, 1.0]), "paper", "distances"),
        (AREA_1, np.ones(3), "centroid", "method"),
    ],
)
def test_trilateration_rejects_bad_arguments_by_name(
    beacons: np.ndarray, distances: np.ndarray, method: str, name: str
) -> None:
    with pytest.raises(ValueError, match=name):
        trilaterate(beacons, distances, HEIGHT_M, method=method)


# ---------------------------------------------------------------------------------------------
# Auto-calibration (Sec. III.B)
# ---------------------------------------------------------------------------------------------

coordinate = st.floats(min_value=-2.0, max_value=2.0, allow_nan=False)


@settings(max_examples=150, deadline=None)
@given(
    corners=st.lists(st.tuples(coordinate, coordinate), min_size=3, max_size=3),
    beacon=st.tuples(coordinate, coordinate, st.floats(min_value=0.2, max_value=2.0)),
)
def test_auto_calibration_is_exact_on_noise_free_ranges(
    corners: list[tuple[float, float]], beacon: tuple[float, float, float]
) -> None:
    positions = np.array(corners)
    truth = np.array([beacon[0], beacon[1], HEIGHT_M + beacon[2]])
    displacements = positions[1:] - positions[0]
    singular = np.linalg.svd(displacements, compute_uv=False)
    assume(singular[1] > 0.05 and singular[0] / singular[1] < 100.0)
    sensors = np.column_stack([positions, np.full(3, HEIGHT_M)])
    ranges = np.linalg.norm(sensors - truth, axis=1)
    result = auto_calibrate(positions, ranges, HEIGHT_M)
    assert result.status == "ok"
    assert result.position[2] > HEIGHT_M
    np.testing.assert_allclose(result.position, truth, atol=1e-9 * SCALE_M)
    assert result.condition == pytest.approx(singular[0] / singular[1])
    assert result.triangle_area_m2 == pytest.approx(
        0.5 * abs(cross2(displacements[0], displacements[1]))
    )


def test_auto_calibration_of_table_i_beacon_d_from_three_area_1_positions() -> None:
    beacon_d = np.array(TABLE_I_BEACONS_M["D"])
    positions = np.array([[2.6, 0.5], [2.3, 0.9], [2.0, 0.6]])
    ranges = (
        slant_ranges(beacon_d[None, :], positions[0])[0],
        *(slant_ranges(beacon_d[None, :], p)[0] for p in positions[1:]),
    )
    result = auto_calibrate(positions, np.array(ranges), HEIGHT_M)
    np.testing.assert_allclose(result.position, beacon_d, atol=1e-9 * SCALE_M)


def test_auto_calibration_accepts_3d_positions_and_picks_the_higher_solution() -> None:
    positions = np.array([[0.0, 0.0, 0.2], [1.0, 0.0, 0.4], [0.0, 1.0, 0.3]])
    truth = np.array([0.4, 0.3, 1.5])
    result = auto_calibrate(positions, np.linalg.norm(positions - truth, axis=1))
    np.testing.assert_allclose(result.position, truth, atol=1e-9 * SCALE_M)


def test_the_other_sphere_intersection_is_the_mirror_below_the_sensor_plane() -> None:
    positions = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    below = np.array([0.4, 0.3, HEIGHT_M - 0.8])
    sensors = np.column_stack([positions, np.full(3, HEIGHT_M)])
    result = auto_calibrate(positions, np.linalg.norm(sensors - below, axis=1), HEIGHT_M)
    np.testing.assert_allclose(result.position, [0.4, 0.3, HEIGHT_M + 0.8], atol=1e-12)


@pytest.mark.parametrize(
    "positions",
    [
        np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]),
        np.array([[0.0, 0.0], [1.0, 1e-6], [2.0, 0.0]]),
        np.array([[1.0, 1.0], [1.0, 1.0], [1.0, 1.0]]),
    ],
    ids=["collinear", "nearly_collinear", "coincident"],
)
def test_collinear_calibration_positions_give_a_status_not_nan(positions: np.ndarray) -> None:
    result = auto_calibrate(positions, np.array([1.5, 1.4, 1.6]), HEIGHT_M)
    assert result.status == "collinear_positions"
    assert result.position is None
    assert result.condition > 1e4 and not math.isnan(result.condition)
    assert not math.isnan(result.triangle_area_m2)


def test_spheres_that_do_not_meet_give_no_intersection() -> None:
    positions = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    result = auto_calibrate(positions, np.array([0.5, 0.5, 0.5]), HEIGHT_M)
    assert result.status == "no_intersection" and result.position is None


def test_spheres_touching_within_tolerance_are_clamped_to_the_plane() -> None:
    positions = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    on_plane = np.array([0.3, 0.4])
    ranges = np.linalg.norm(positions - on_plane, axis=1) - 1e-4
    assert auto_calibrate(positions, ranges, HEIGHT_M).status == "no_intersection"
    clamped = auto_calibrate(positions, ranges, HEIGHT_M, intersection_tolerance_m=1e-3)
    assert clamped.ok
    np.testing.assert_allclose(clamped.position, [0.3, 0.4, HEIGHT_M], atol=1e-3)
    strict = auto_calibrate(positions, ranges, HEIGHT_M, intersection_tolerance_m=5e-5)
    assert strict.status == "no_intersection"


def test_a_missing_calibration_range_gives_a_status() -> None:
    positions = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    result = auto_calibrate(positions, np.array([1.5, np.nan, 1.6]), HEIGHT_M)
    assert result.status == "missing_distance" and result.position is None


@pytest.mark.parametrize(
    ("positions", "distances", "name"),
    [
        (np.zeros((2, 2)), np.ones(3), "positions"),
        (np.zeros((3, 4)), np.ones(3), "positions"),
        (np.eye(3)[:, :2], np.ones(2), "distances"),
    ],
)
def test_auto_calibration_rejects_bad_shapes_by_name(
    positions: np.ndarray, distances: np.ndarray, name: str
) -> None:
    with pytest.raises(ValueError, match=name):
        auto_calibrate(positions, distances, HEIGHT_M)


# ---------------------------------------------------------------------------------------------
# Three-point extraction (Sec. III.C)
# ---------------------------------------------------------------------------------------------

BOUNDARY_A = np.array([0.0, 0.0])
BOUNDARY_B = np.array([2.0, 0.0])


def straight_path(start_y: float, end_y: float, step: float, x: float = 1.0) -> np.ndarray:
    count = int(round((start_y - end_y) / step)) + 1
    return np.column_stack([np.full(count, x), start_y - step * np.arange(count)])


def test_extraction_saves_the_first_samples_past_each_distance_and_interpolates() -> None:
    path = straight_path(1.003, -0.5, 0.01)
    result = extract_three_points(path, BOUNDARY_A, BOUNDARY_B, [0.45, 0.25, 0.05])
    assert result.status == "ok"
    expected_indices = [math.ceil((1.003 - d) / 0.01) for d in (0.45, 0.25, 0.05)]
    assert list(result.indices) == expected_indices
    np.testing.assert_allclose(result.sample_points, path[expected_indices])
    np.testing.assert_allclose(result.points, [[1.0, 0.45], [1.0, 0.25], [1.0, 0.05]], atol=1e-12)
    for fraction, index, d in zip(
        result.fractions, result.indices, (0.45, 0.25, 0.05), strict=True
    ):
        assert fraction == pytest.approx((path[index - 1, 1] - d) / 0.01, abs=1e-9)


def test_extraction_on_an_oblique_path_matches_the_analytic_crossings() -> None:
    direction = np.array([0.6, -0.8])
    start = np.array([0.3, 0.9])
    path = start + np.outer(np.arange(0.0, 1.5, 0.0137), direction)
    result = extract_three_points(path, BOUNDARY_A, BOUNDARY_B, [0.45, 0.25, 0.05])
    expected = [start + ((0.9 - d) / 0.8) * direction for d in (0.45, 0.25, 0.05)]
    np.testing.assert_allclose(result.points, expected, atol=1e-12)


def test_a_larger_distance_after_a_smaller_one_is_met_beyond_the_boundary() -> None:
    """D is unsigned: "bigger than d for the first time" happens on the far side."""
    path = straight_path(1.003, -0.5, 0.01)
    result = extract_three_points(path, BOUNDARY_A, BOUNDARY_B, [0.3, 0.1, 0.2])
    np.testing.assert_allclose(result.points, [[1.0, 0.3], [1.0, 0.1], [1.0, -0.2]], atol=1e-12)


def test_extraction_reports_not_reached_with_the_points_found() -> None:
    path = straight_path(1.003, 0.2, 0.01)
    result = extract_three_points(path, BOUNDARY_A, BOUNDARY_B, [0.45, 0.25, 0.05])
    assert result.status == "not_reached"
    assert len(result.indices) == 2 and result.points.shape == (2, 2)
    assert not np.isnan(result.points).any()


def test_extraction_uses_the_projection_of_3d_boundary_beacons() -> None:
    path = straight_path(1.003, -0.5, 0.01)
    result = extract_three_points(
        path, np.array([0.0, 0.0, 1.4]), np.array([2.0, 0.0, 0.8]), [0.45, 0.25, 0.05]
    )
    np.testing.assert_allclose(result.points[:, 1], [0.45, 0.25, 0.05], atol=1e-12)


@pytest.mark.parametrize(
    ("path", "distances", "name"),
    [
        (np.zeros((5, 3)), [0.45, 0.25, 0.05], "path"),
        (np.zeros((5, 2)), [0.45, 0.25], "distances"),
        (np.zeros((5, 2)), [0.45, -0.25, 0.05], "distances"),
    ],
)
def test_extraction_rejects_bad_arguments_by_name(
    path: np.ndarray, distances: list[float], name: str
) -> None:
    with pytest.raises(ValueError, match=name):
        extract_three_points(path, BOUNDARY_A, BOUNDARY_B, distances)


# ---------------------------------------------------------------------------------------------
# Path errors (Sec. IV.B)
# ---------------------------------------------------------------------------------------------


def test_a_parallel_horizontal_path_has_sigma_and_sigma_prime_equal_to_the_offset() -> None:
    true = np.column_stack([np.linspace(0.0, 3.0, 7), np.full(7, 1.0)])
    estimated = np.column_stack([np.linspace(0.1, 2.9, 40), np.full(40, 1.03)])
    sigma, sigma_prime = path_errors(estimated, true)
    assert sigma == pytest.approx(0.03, abs=1e-12)
    assert sigma_prime == pytest.approx(0.03, abs=1e-12)


def test_on_a_sloped_path_sigma_is_the_y_offset_and_sigma_prime_the_normal_offset() -> None:
    slope, offset = 0.5, 0.02
    x = np.linspace(3.0, 0.0, 11)  # x may decrease along the path
    true = np.column_stack([x, 1.0 + slope * x])
    xe = np.linspace(2.8, 0.3, 50)
    estimated = np.column_stack([xe, 1.0 + slope * xe + offset])
    sigma, sigma_prime = path_errors(estimated, true)
    assert sigma == pytest.approx(offset, abs=1e-12)
    assert sigma_prime == pytest.approx(offset / math.sqrt(1.0 + slope**2), abs=1e-12)


def test_sigma_is_the_rms_and_sigma_prime_the_mean() -> None:
    true = np.array([[0.0, 0.0], [4.0, 0.0]])
    estimated = np.array([[1.0, 0.03], [2.0, -0.04], [3.0, 0.0]])
    sigma, sigma_prime = path_errors(estimated, true)
    assert sigma == pytest.approx(math.sqrt((0.03**2 + 0.04**2) / 3.0), abs=1e-15)
    assert sigma_prime == pytest.approx(0.07 / 3.0, abs=1e-15)


def test_sigma_prime_is_the_distance_to_the_nearest_segment_of_the_polyline() -> None:
    true = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 0.0]])
    estimated = np.array([[0.4, 0.6], [1.0, 1.2], [0.0, -0.1]])  # foot inside, vertex, end
    _, sigma_prime = path_errors(estimated, true)
    assert sigma_prime == pytest.approx((0.1 * math.sqrt(2.0) + 0.2 + 0.1) / 3.0, abs=1e-12)


def test_path_errors_reject_a_true_path_that_is_not_a_function_of_x() -> None:
    true = np.array([[0.0, 0.0], [1.0, 1.0], [0.5, 2.0]])
    with pytest.raises(ValueError, match="true"):
        path_errors(np.array([[0.5, 0.5]]), true)
    with pytest.raises(ValueError, match="estimated"):
        path_errors(np.array([[np.nan, 0.5]]), np.array([[0.0, 0.0], [1.0, 0.0]]))


# ---------------------------------------------------------------------------------------------
# Block expansion (Sec. II, IV)
# ---------------------------------------------------------------------------------------------


def test_noise_free_two_areas_recover_the_path_and_beacon_d_exactly() -> None:
    path = two_area_path()
    run = BlockExpansion(BlockExpansionConfig.paper((450.0, 250.0, 50.0))).run(path)
    assert run.status == "ok"
    assert len(run.estimated_xy) == len(path)
    np.testing.assert_allclose(run.estimated_xy, path, atol=1e-9 * SCALE_M)
    assert run.calibration_errors_m["D"] < 1e-9 * SCALE_M
    np.testing.assert_allclose(run.calibrated_beacons_m["D"], TABLE_I_BEACONS_M["D"], atol=1e-9)
    sigma, sigma_prime = run.path_errors(path)
    assert sigma < 1e-9 and sigma_prime < 1e-9

    calibration = run.calibrations[0]
    assert calibration.boundary == ("B", "C") and calibration.new_beacon == "D"
    b, c = (np.array(TABLE_I_BEACONS_M[n][:2]) for n in ("B", "C"))
    saved = calibration.calibration_points_xy
    for point, d in zip(saved, (0.45, 0.25, 0.05), strict=True):
        assert distance_to_line(point, b, c) <= d  # first samples past each d
    switch = calibration.switch_index
    assert np.all(run.area_indices[:switch] == 0) and np.all(run.area_indices[switch:] == 1)
    side = np.sign(cross2(c - b, path - b))
    assert side[switch - 1] != side[0] and side[switch - 2] == side[0]  # first fix past BC


@pytest.mark.parametrize("d_mm", TABLE_IV_V_D_MM[1:], ids=["row2", "row3"])
def test_noise_free_three_areas_recover_beacons_d_and_e_exactly(d_mm: tuple[float, ...]) -> None:
    path = parabolic_path()
    run = BlockExpansion(BlockExpansionConfig.paper(d_mm)).run(path)
    assert run.status == "ok"
    assert set(run.calibration_errors_m) == {"D", "E"}
    assert max(run.calibration_errors_m.values()) < 1e-9 * SCALE_M
    np.testing.assert_allclose(run.estimated_xy, path, atol=1e-9 * SCALE_M)
    assert run.calibrations[1].boundary == ("B", "D")
    assert set(run.area_indices.tolist()) == {0, 1, 2}


def test_table_iv_row_1_repeated_distances_are_reported_not_reached() -> None:
    """d4 = d5 = d6 = 200 mm: on a path that crosses the 0.2 m line of BD only twice (before
    and after BD) the third crossing never happens."""
    run = BlockExpansion(BlockExpansionConfig.paper(TABLE_IV_V_D_MM[0])).run(parabolic_path())
    assert run.calibrations[0].status == "ok"
    assert run.calibrations[1].status == "not_reached"
    assert run.status == "calibration_failed"
    assert len(run.calibrations[1].three_points.indices) == 2
    assert not np.isnan(run.estimated_xy).any()


def run_noisy(
    d_mm: tuple[float, ...], path: np.ndarray, noise_m: float, seeds: range
) -> list[tuple[float, float]]:
    """(sigma, sigma') of the runs whose calibrations all succeeded."""
    errors = []
    for seed in seeds:
        config = BlockExpansionConfig.paper(d_mm, range_noise_std_m=noise_m)
        run = BlockExpansion(config).run(path, rng=np.random.default_rng(seed))
        assert run.status in ("ok", "calibration_failed")
        assert np.all(np.isfinite(run.estimated_xy))
        if run.ok:
            errors.append(run.path_errors(path))
    return errors


def test_a_few_mm_of_range_noise_keeps_sigma_prime_within_tens_of_mm() -> None:
    errors = run_noisy((450.0, 250.0, 50.0), two_area_path(), 0.002, range(8))
    assert len(errors) >= 4
    sigma_prime = np.median([e[1] for e in errors])
    assert 0.002 < sigma_prime < 0.1


@pytest.mark.parametrize(
    ("d_mm", "paper_sigma_mm", "paper_sigma_prime_mm"),
    list(zip(TABLE_II_III_D_MM, TABLE_II_SIGMA_MM, TABLE_III_SIGMA_PRIME_MM, strict=True)),
    ids=[f"{int(d[1])}-{int(d[2])}" for d in TABLE_II_III_D_MM],
)
def test_two_area_errors_are_of_the_order_of_tables_ii_and_iii(
    d_mm: tuple[float, ...], paper_sigma_mm: float, paper_sigma_prime_mm: float
) -> None:
    errors = np.array(run_noisy(d_mm, two_area_path(), 0.001, range(6))) * 1000.0
    assert len(errors) >= 1
    sigma_mm, sigma_prime_mm = np.median(errors, axis=0)
    assert paper_sigma_mm / 10.0 < sigma_mm < paper_sigma_mm * 10.0
    assert paper_sigma_prime_mm / 10.0 < sigma_prime_mm < paper_sigma_prime_mm * 10.0
    assert sigma_mm >= sigma_prime_mm  # RMS of y differences vs mean normal distance


@pytest.mark.parametrize(
    ("d_mm", "paper_sigma_mm", "paper_sigma_prime_mm"),
    list(zip(TABLE_IV_V_D_MM, TABLE_IV_SIGMA_MM, TABLE_V_SIGMA_PRIME_MM, strict=True))[1:],
    ids=["row2", "row3"],
)
def test_three_area_errors_are_of_the_order_of_tables_iv_and_v(
    d_mm: tuple[float, ...], paper_sigma_mm: float, paper_sigma_prime_mm: float
) -> None:
    errors = np.array(run_noisy(d_mm, parabolic_path(), 0.001, range(12))) * 1000.0
    assert len(errors) >= 1
    sigma_mm, sigma_prime_mm = np.median(errors, axis=0)
    assert paper_sigma_mm / 10.0 < sigma_mm < paper_sigma_mm * 10.0
    assert paper_sigma_prime_mm / 10.0 < sigma_prime_mm < paper_sigma_prime_mm * 10.0


def test_same_seed_gives_the_same_run() -> None:
    config = BlockExpansionConfig.paper(range_noise_std_m=0.002)
    path = two_area_path()
    first = BlockExpansion(config).run(path, rng=np.random.default_rng(7))
    second = BlockExpansion(config).run(path, rng=np.random.default_rng(7))
    np.testing.assert_array_equal(first.estimated_xy, second.estimated_xy)


def test_least_squares_trilateration_in_the_runner_is_also_exact_without_noise() -> None:
    config = BlockExpansionConfig.paper(trilateration_method="least_squares")
    path = two_area_path()[::4]
    run = BlockExpansion(config).run(path)
    assert run.ok
    np.testing.assert_allclose(run.estimated_xy, path, atol=1e-9 * SCALE_M)


def test_a_failed_calibration_is_reported_and_the_robot_keeps_its_beacons() -> None:
    config = BlockExpansionConfig.paper()
    runner = BlockExpansion(config)
    path = two_area_path()
    table = runner.measure_ranges(path)
    table[:, config.beacon_names.index("D")] = np.nan  # beacon D never heard
    run = runner.run(path, distance_table=table)
    assert run.status == "calibration_failed"
    assert run.calibrations[0].status == "missing_distance"
    assert run.calibrated_beacons_m == {} and run.calibration_errors_m == {}
    assert np.all(run.area_indices == 0)
    np.testing.assert_allclose(run.estimated_xy, path, atol=1e-9 * SCALE_M)


def test_a_path_that_stops_short_of_the_boundary_reports_not_reached() -> None:
    path = parabolic_path(x_end_m=2.35)
    run = BlockExpansion(BlockExpansionConfig.paper()).run(path)
    assert run.status == "calibration_failed"
    assert run.calibrations[0].status == "not_reached"


def test_dropouts_from_the_ranging_sensor_give_statuses_never_nan() -> None:
    path = two_area_path()[:200]
    config = BlockExpansionConfig.paper()
    beacon_c = np.array(TABLE_I_BEACONS_M["C"])

    def flaky(xy: np.ndarray, beacon_xyz: np.ndarray) -> float:
        if np.array_equal(beacon_xyz, beacon_c) and xy[0] > 2.6:
            return math.nan
        return float(np.linalg.norm(np.array([xy[0], xy[1], HEIGHT_M]) - beacon_xyz))

    run = BlockExpansion(config).run(path, measure=flaky)
    statuses = run.statuses
    dropped = path[:, 0] > 2.6
    assert all(statuses[i] == "too_few_beacons" for i in np.flatnonzero(dropped))
    assert all(statuses[i] == "ok" for i in np.flatnonzero(~dropped))
    np.testing.assert_array_equal(run.estimated_indices, np.flatnonzero(~dropped))
    assert not np.isnan(run.estimated_xy).any()


def test_runner_rejects_bad_arguments_by_name() -> None:
    runner = BlockExpansion(BlockExpansionConfig.paper(range_noise_std_m=0.002))
    path = two_area_path()
    with pytest.raises(ValueError, match="rng"):
        runner.run(path)
    with pytest.raises(ValueError, match="path"):
        runner.run(path[:, :1], rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match="distance_table"):
        runner.run(path, distance_table=np.ones((3, 5)))


def test_config_rejects_areas_that_do_not_chain() -> None:
    with pytest.raises(ValueError, match="areas"):
        BlockExpansionConfig(
            areas=(("A", "B", "C"), ("A", "D", "E")), calibration_distances_m=((0.45, 0.25, 0.05),)
        )
    with pytest.raises(ValueError, match="calibration_distances_m"):
        BlockExpansionConfig(areas=PAPER_THREE_AREAS, calibration_distances_m=((0.45, 0.25, 0.05),))
    with pytest.raises(ValueError, match="areas"):
        BlockExpansionConfig(areas=(("A", "B", "Z"),), calibration_distances_m=())
