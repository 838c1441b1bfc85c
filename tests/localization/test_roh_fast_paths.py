"""The array paths of Roh et al.'s method against their one-sample-at-a-time references:
trilateration over a range table, the three-point extraction over a path, the polyline
distance and the whole block expansion run."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization.result import OK
from sonar_gym.localization.roh_trilateration import _CENTROID_PAIRS, _TANGENCY_RELATIVE_TOLERANCE
from sonar_gym.localization.roh import (
    DEFAULT_SENSOR_HEIGHT_M,
    PAPER_THREE_AREAS,
    PAPER_TWO_AREAS,
    TABLE_I_BEACONS_M,
    BlockExpansion,
    BlockExpansionConfig,
    ThreePointExtractor,
    auto_calibrate,
    distances_to_polyline,
    parabolic_path,
    path_errors,
    trilaterate,
    trilaterate_path,
)
from sonar_gym.localization.roh_block_expansion import distances_to_polyline_reference

HEIGHT_M = DEFAULT_SENSOR_HEIGHT_M
AREA_1 = np.array([TABLE_I_BEACONS_M[name] for name in ("A", "B", "C")])


def noisy_table(beacons: np.ndarray, path: np.ndarray, noise_m: float, seed: int) -> np.ndarray:
    """Slant ranges along a path with Gaussian noise, a few dropouts and a few short ranges."""
    rng = np.random.default_rng(seed)
    horizontal = path[:, None, :] - beacons[None, :, :2]
    table = np.sqrt((horizontal**2).sum(axis=2) + (beacons[:, 2] - HEIGHT_M) ** 2)
    table = table + rng.normal(0.0, noise_m, table.shape)
    rows = rng.choice(len(path), 12, replace=False)
    table[rows[:6], rng.integers(0, beacons.shape[0], 6)] = np.nan
    table[rows[6:], 0] = 0.05  # shorter than the beacon's height above the sensor
    return np.abs(table)


@pytest.mark.parametrize(
    ("method", "beacon_names", "noise_m"),
    [
        ("paper", "ABC", 0.002),
        ("paper", "ABC", 0.3),  # many pairs of circles miss: the radical-centre fallback
        ("least_squares", "ABC", 0.01),
        ("paper", "ABCD", 0.01),  # four beacons: the best triple, row by row
    ],
)
def test_trilaterate_path_agrees_with_trilaterate_row_by_row(method, beacon_names, noise_m):
    beacons = np.array([TABLE_I_BEACONS_M[name] for name in beacon_names])
    path = parabolic_path(x_end_m=1.3)[::3]
    table = noisy_table(beacons, path, noise_m, seed=4)
    fixes = trilaterate_path(beacons, table, HEIGHT_M, method)
    fallbacks = 0
    for row, ranges in enumerate(table):
        fix = trilaterate(beacons, ranges, HEIGHT_M, method)
        assert fixes.statuses[row] == fix.status
        assert fixes.used_radical_centre[row] == fix.used_radical_centre
        fallbacks += fix.used_radical_centre
        if fix.ok:
            np.testing.assert_allclose(fixes.positions[row], fix.position, rtol=0, atol=1e-12)
        else:
            assert np.all(np.isnan(fixes.positions[row]))
    # With four beacons one dropout still leaves three ranges.
    failing = {"too_few_beacons"} if len(beacon_names) == 3 else set()
    assert set(fixes.statuses) >= {OK, "distance_below_height"} | failing
    if noise_m > 0.1 and method == "paper" and len(beacon_names) == 3:
        assert fallbacks > 10


def test_trilaterate_path_reports_collinear_beacons_and_bad_tables() -> None:
    collinear = np.array([[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [2.0, 0.0, 2.0]])
    fixes = trilaterate_path(collinear, np.full((4, 3), 2.0), HEIGHT_M)
    assert fixes.statuses == ("collinear_beacons",) * 4
    assert not fixes.ok.any()
    with pytest.raises(ValueError, match="distances"):
        trilaterate_path(AREA_1, np.ones((5, 2)), HEIGHT_M)
    with pytest.raises(ValueError, match="distances"):
        trilaterate_path(AREA_1, -np.ones((5, 3)), HEIGHT_M)


@pytest.mark.parametrize(
    "distances",
    [(0.45, 0.25, 0.05), (0.3, 0.4, 0.7), (0.2, 0.2, 0.2), (0.0, 0.5, 0.1), (0.6, 0.3, 0.31)],
)
def test_update_path_saves_what_update_saves_sample_by_sample(distances) -> None:
    rng = np.random.default_rng(8)
    path = parabolic_path(x_end_m=0.55) + rng.normal(0.0, 0.003, (1, 2))
    path = path + rng.normal(0.0, 0.002, path.shape)
    a, b = TABLE_I_BEACONS_M["B"], TABLE_I_BEACONS_M["C"]
    one_by_one = ThreePointExtractor(a, b, distances)
    stop = len(path)
    for index, position in enumerate(path):
        one_by_one.update(position, index)
        if one_by_one.done:
            stop = index + 1
            break
    batch = ThreePointExtractor(a, b, distances)
    used = batch.update_path(path, np.arange(len(path)))
    expected, got = one_by_one.result(), batch.result()
    assert used == stop
    assert got.status == expected.status
    assert got.indices == expected.indices
    np.testing.assert_allclose(got.fractions, expected.fractions, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.points, expected.points, rtol=0, atol=1e-12)


def test_update_path_continues_where_an_earlier_call_stopped() -> None:
    path = parabolic_path(x_end_m=1.3)
    a, b = TABLE_I_BEACONS_M["B"], TABLE_I_BEACONS_M["C"]
    whole = ThreePointExtractor(a, b, (0.45, 0.25, 0.05))
    whole.update_path(path, np.arange(len(path)))
    pieces = ThreePointExtractor(a, b, (0.45, 0.25, 0.05))
    for first in range(0, len(path), 37):
        piece = path[first : first + 37]
        pieces.update_path(piece, np.arange(first, first + len(piece)))
    assert pieces.result().indices == whole.result().indices
    assert len(whole.result().indices) == 3


@pytest.mark.parametrize("seed", range(6))
def test_polyline_distance_is_the_minimum_over_every_segment(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 400))
    line = np.cumsum(rng.normal(0.0, rng.uniform(0.001, 0.5), (n, 2)), axis=0)
    if n > 3:
        line[2] = line[1]  # a zero-length segment
    points = line[rng.integers(0, n, 200)] + rng.normal(0.0, rng.choice([1e-3, 0.1, 3.0]), (200, 2))
    np.testing.assert_allclose(
        distances_to_polyline(points, line),
        distances_to_polyline_reference(points, line),
        rtol=1e-12,
        atol=1e-15,
    )


def reference_run(config: BlockExpansionConfig, path: np.ndarray, table: np.ndarray):
    """Sec. II walked one fix at a time: trilaterate, extract, calibrate, switch past the line."""
    names = config.beacon_names
    known = {name: np.array(config.beacons_m[name]) for name in config.areas[0]}
    area, fixes, areas, switches, calibrated = 0, [], [], [], {}
    extractor, points, ranges, calibration = None, [], [], None
    for index, row in enumerate(table):
        if extractor is None and area < len(config.areas) - 1:
            boundary, new = config.boundaries[area], config.new_beacons[area]
            extractor = ThreePointExtractor(
                known[boundary[0]], known[boundary[1]], config.calibration_distances_m[area]
            )
            opposite = next(n for n in config.areas[area] if n not in boundary)
            origin = known[boundary[0]][:2]
            direction = known[boundary[1]][:2] - origin

            def side(xy, origin=origin, direction=direction):
                offset = xy - origin
                return np.sign(direction[0] * offset[1] - direction[1] * offset[0])

            inner = side(known[opposite][:2])
            points, ranges, calibration = [], [], None
        area_names = config.areas[area]
        fix = trilaterate(
            np.array([known[n] for n in area_names]),
            row[[names.index(n) for n in area_names]],
            config.sensor_height_m,
            config.trilateration_method,
        )
        fixes.append(fix)
        areas.append(area)
        if not fix.ok or extractor is None:
            continue
        if calibration is None:
            for _ in range(extractor.update(fix.position, index)):
                points.append(fix.position)
                ranges.append(row[names.index(new)])
            if extractor.done:
                calibration = auto_calibrate(np.array(points), np.array(ranges), HEIGHT_M)
        if calibration is not None and calibration.ok:
            s = side(fix.position)
            if s != 0 and s != inner:
                known[new] = calibration.position
                calibrated[new] = calibration.position
                switches.append(index + 1)
                area, extractor = area + 1, None
    return fixes, np.array(areas), switches, calibrated


@pytest.mark.parametrize(
    ("areas", "distances", "method"),
    [
        (PAPER_TWO_AREAS, ((0.45, 0.25, 0.05),), "paper"),
        (PAPER_TWO_AREAS, ((0.3, 0.4, 0.7),), "paper"),
        (PAPER_TWO_AREAS, ((0.02, 0.02, 0.02),), "paper"),
        (PAPER_THREE_AREAS, ((0.45, 0.25, 0.05), (0.3, 0.4, 0.7)), "paper"),
        (PAPER_THREE_AREAS, ((0.6, 0.35, 0.1), (0.5, 0.3, 0.05)), "least_squares"),
    ],
)
@pytest.mark.parametrize("seed", [0, 1])
def test_the_array_run_is_the_fix_by_fix_run(areas, distances, method, seed: int) -> None:
    config = BlockExpansionConfig(
        areas=areas,
        calibration_distances_m=distances,
        trilateration_method=method,
        range_noise_std_m=0.002,
    )
    path = parabolic_path(x_end_m=1.3 if len(areas) == 2 else 0.55)
    runner = BlockExpansion(config)
    table = runner.measure_ranges(path, np.random.default_rng(seed))
    table[np.random.default_rng(seed).integers(0, len(path), 8), 0] = np.nan
    result = runner.run(path, distance_table=table)
    fixes, area_indices, switches, calibrated = reference_run(config, path, table)
    np.testing.assert_array_equal(result.area_indices, area_indices)
    assert result.statuses == tuple(fix.status for fix in fixes)
    expected_xy = np.array([fix.position for fix in fixes if fix.ok])
    np.testing.assert_allclose(result.estimated_xy, expected_xy, rtol=0, atol=1e-12)
    assert [c.switch_index for c in result.calibrations if c.switch_index is not None] == switches
    assert sorted(result.calibrated_beacons_m) >= sorted(calibrated)
    for name, position in calibrated.items():
        np.testing.assert_allclose(result.calibrated_beacons_m[name], position, atol=1e-12)
    for kept, fix in zip(result.localizations, fixes, strict=True):
        assert (kept.status, kept.message, kept.used_radical_centre) == (
            fix.status,
            fix.message,
            fix.used_radical_centre,
        )


@pytest.mark.parametrize("seed", range(8))
def test_path_errors_sigma_prime_is_the_mean_distance_over_every_segment(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 600))
    x = np.linspace(-2.0, 3.0, n) + rng.uniform(-1e-3, 1e-3, n) * (n > 2)
    x = np.sort(x) if seed % 2 else np.sort(x)[::-1]
    path = np.column_stack([x, np.cumsum(rng.normal(0.0, rng.uniform(0.001, 0.5), n))])
    noise = [1e-4, 1e-2, 0.3, 5.0][seed % 4]
    points = path[rng.integers(0, n, 300)] + rng.normal(0.0, noise, (300, 2))
    _, sigma_prime = path_errors(points, path)
    reference = float(np.mean(distances_to_polyline_reference(points, path)))
    assert sigma_prime == pytest.approx(reference, rel=1e-12, abs=1e-15)


# The array form of the paper centroids that the compiled loop replaced: the reference the
# loop is checked against, bit for bit.
def array_paper_centroids(centres: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`paper_centroid` over rows of radii ``(m, 3)`` for one set of three centres.

    The three circle pairs are computed side by side (arrays ``(m, 3)``, one column per
    pair), each element with the arithmetic of :func:`circle_intersections`.

    Returns ``(centroids (k, 2), met (m,))``: ``met`` is False where some pair of circles does
    not intersect (those rows need the radical-centre fallback), and the centroids are those
    of the ``k`` rows where ``met`` holds, in row order.
    """
    first_of, second_of = [i for i, _ in _CENTROID_PAIRS], [j for _, j in _CENTROID_PAIRS]
    third_of = [3 - i - j for i, j in _CENTROID_PAIRS]
    ca, cb, ck = centres[first_of], centres[second_of], centres[third_of]
    offset = cb - ca
    separations = [math.hypot(dx, dy) for dx, dy in offset.tolist()]
    if 0.0 in separations:
        return np.zeros((0, 2)), np.zeros(len(radii), dtype=bool)
    separation = np.array(separations)
    separation_sq = np.array([value**2 for value in separations])
    ra, rb = radii[:, first_of], radii[:, second_of]
    ra_sq, rb_sq = ra * ra, rb * rb
    along = (ra_sq - rb_sq + separation_sq) / (2.0 * separation)
    half_chord_sq = ra_sq - along * along
    tolerance = _TANGENCY_RELATIVE_TOLERANCE * np.maximum(np.maximum(ra_sq, rb_sq), separation_sq)
    met = (half_chord_sq >= -tolerance).all(axis=1)
    rk = radii[:, third_of]
    if not met.all():  # the rest only for the rows that keep their centroid
        along, half_chord_sq, tolerance = along[met], half_chord_sq[met], tolerance[met]
        rk = rk[met]
    # x and y as separate (k, 3) arrays: the same arithmetic per element as (k, 3, 2) arrays,
    # without numpy's slow inner loops of length 2
    unit_x, unit_y = offset[:, 0] / separation, offset[:, 1] / separation
    normal_x, normal_y = -unit_y, unit_x
    foot_x, foot_y = ca[:, 0] + along * unit_x, ca[:, 1] + along * unit_y
    half_chord = np.where(half_chord_sq <= tolerance, 0.0, np.sqrt(np.abs(half_chord_sq)))
    chord_x, chord_y = half_chord * normal_x, half_chord * normal_y
    first_x, first_y = foot_x + chord_x, foot_y + chord_y
    second_x, second_y = foot_x - chord_x, foot_y - chord_y
    take_second = array_second_misses_less(
        first_x - ck[:, 0], first_y - ck[:, 1], second_x - ck[:, 0], second_y - ck[:, 1], rk
    )
    centroids = np.empty((len(rk), 2))
    for column, (first_c, second_c) in enumerate(((first_x, second_x), (first_y, second_y))):
        kept = np.where(take_second, second_c, first_c)
        # the mean over the three pairs, summed in pair order as np.mean over that axis sums
        centroids[:, column] = ((kept[:, 0] + kept[:, 1]) + kept[:, 2]) / 3
    return centroids, met


def array_second_misses_less(
    first_x: np.ndarray,
    first_y: np.ndarray,
    second_x: np.ndarray,
    second_y: np.ndarray,
    radius: np.ndarray,
) -> np.ndarray:
    """``|hypot(second) - radius| < |hypot(first) - radius|``, elementwise (metres).

    Which intersection point lies nearer the third circle (:func:`paper_centroid`). The
    comparison is made on ``sqrt(x^2 + y^2)``, within a few ulps of ``hypot`` and several
    times cheaper; where the two misses are too close for that to decide, or a square leaves
    the float range, ``hypot`` itself decides, so the result is the ``hypot`` comparison's.
    """
    with np.errstate(over="ignore", invalid="ignore"):  # such elements are decided by hypot
        first = np.sqrt(first_x * first_x + first_y * first_y)
        second = np.sqrt(second_x * second_x + second_y * second_y)
        miss_first, miss_second = np.abs(first - radius), np.abs(second - radius)
        take_second = miss_second < miss_first
        margin = 1e-12 * (first + second + radius) + 1e-150
        unsure = ~(np.abs(miss_second - miss_first) > margin)
    if unsure.any():
        exact_first = np.abs(np.hypot(first_x[unsure], first_y[unsure]) - radius[unsure])
        exact_second = np.abs(np.hypot(second_x[unsure], second_y[unsure]) - radius[unsure])
        take_second[unsure] = exact_second < exact_first
    return take_second


@pytest.mark.parametrize("noise_m", [1e-3, 0.05, 0.5])
def test_the_compiled_paper_centroids_are_the_array_forms_bit_for_bit(noise_m: float) -> None:
    from sonar_gym.localization.roh_trilateration import _paper_centroids

    rng = np.random.default_rng(12)
    met_rows = missed_rows = 0
    for _ in range(200):
        centres = rng.uniform(-3.0, 3.0, (3, 2))
        truth = rng.uniform(-3.0, 3.0, 2)
        exact = np.hypot(*(truth - centres).T)
        radii = np.abs(exact + rng.normal(0.0, noise_m, (int(rng.integers(1, 60)), 3)))
        compiled, compiled_met = _paper_centroids(centres, radii)
        array, array_met = array_paper_centroids(centres, radii)
        np.testing.assert_array_equal(compiled_met, array_met)
        assert compiled.view(np.int64).tolist() == array.view(np.int64).tolist()
        met_rows += int(array_met.sum())
        missed_rows += int((~array_met).sum())
    assert met_rows > 0 and missed_rows > 0


@pytest.mark.parametrize("scale", [1.0, 1e-170, 1e170])
def test_the_nearer_intersection_is_chosen_as_hypot_would_choose_it(scale: float) -> None:
    from sonar_gym.localization.roh_kernels import _second_is_nearer

    rng = np.random.default_rng(8)
    first_x, first_y = rng.normal(size=(2, 4000)) * scale
    second_x, second_y = -first_x, first_y.copy()  # exact ties ...
    second_x[1000:2000] *= 1.0 + 1e-15 * rng.normal(size=1000)  # ... near ties ...
    second_x[2000:] = rng.normal(size=2000) * scale  # ... and clear cases
    radius = rng.uniform(0.0, 3.0, 4000) * scale
    radius[:500] = np.hypot(first_x[:500], first_y[:500])  # the first point on the circle
    expected = np.abs(np.hypot(second_x, second_y) - radius) < np.abs(
        np.hypot(first_x, first_y) - radius
    )
    chosen = np.array(
        [
            _second_is_nearer(*values)
            for values in zip(first_x, first_y, second_x, second_y, radius, strict=True)
        ]
    )
    np.testing.assert_array_equal(chosen, expected)
    assert expected[1000:].any() and not expected[1000:].all()
    np.testing.assert_array_equal(
        array_second_misses_less(first_x, first_y, second_x, second_y, radius), expected
    )


def test_the_cross_product_of_the_calibration_frame_is_numpys() -> None:
    from sonar_gym.localization.roh_trilateration import _cross3

    rng = np.random.default_rng(9)
    for a, b in rng.normal(size=(500, 2, 3)) * 10.0 ** rng.integers(-6, 6, (500, 1, 1)):
        np.testing.assert_array_equal(_cross3(a, b), np.cross(a, b))


def test_the_extractors_point_distance_is_distance_to_segment() -> None:
    from sonar_gym.localization.roh_block_expansion import distance_to_segment

    rng = np.random.default_rng(10)
    for _ in range(50):
        a, b = rng.uniform(-3, 3, (2, 2))
        extractor = ThreePointExtractor(a, b, (0.45, 0.25, 0.05))
        for point in rng.uniform(-4, 4, (40, 2)):
            assert extractor._point_distance(point) == float(distance_to_segment(point, a, b))


@pytest.mark.parametrize("increasing", [False, True])
@pytest.mark.parametrize("n_outliers", [1, 3, 200])
def test_true_path_distances_of_outliers_are_the_general_search(
    n_outliers: int, increasing: bool
) -> None:
    from sonar_gym.localization.roh_path_errors import TruePath

    rng = np.random.default_rng(n_outliers)
    path = parabolic_path(x_end_m=1.3)
    if increasing:
        path = path[::-1].copy()
    points = path[rng.integers(0, len(path), 400)] + rng.normal(0.0, 0.01, (400, 2))
    points[rng.choice(400, n_outliers, replace=False)] += rng.normal(0.0, 1.0, (n_outliers, 2))
    true_path = TruePath(path)
    y_difference = points[:, 1] - true_path.y_at(points[:, 0])
    np.testing.assert_array_equal(
        true_path._distances(points, y_difference), distances_to_polyline(points, path)
    )


def test_the_compiled_usable_radii_are_the_array_forms_bit_for_bit() -> None:
    from sonar_gym.localization.roh_kernels import usable_radii

    rng = np.random.default_rng(21)
    vertical = AREA_1[:, 2] - HEIGHT_M
    table = noisy_table(AREA_1, parabolic_path(x_end_m=1.3), 0.05, seed=9)
    table[::17, 1] = np.inf
    table[::23, 2] = -np.inf
    table[::29] = np.abs(vertical) - 0.01  # exactly at the height tolerance: usable, r = 0
    table[::31, 0] = rng.uniform(0.0, 2.0, len(table[::31]))
    radii, usable, valid = usable_radii(table, vertical, 0.01)
    expected_valid = np.isfinite(table).all(axis=1)
    with np.errstate(invalid="ignore"):
        short = (table < np.abs(vertical) - 0.01).any(axis=1) & expected_valid
    expected_usable = expected_valid & ~short
    expected_radii = np.sqrt(np.maximum(table[expected_usable] ** 2 - vertical**2, 0.0))
    np.testing.assert_array_equal(valid, expected_valid)
    np.testing.assert_array_equal(usable, expected_usable)
    assert radii.view(np.int64).tolist() == expected_radii.view(np.int64).tolist()
    assert 0 < usable.sum() < valid.sum() < len(table)


def test_the_unfinished_rows_are_the_ok_rows_with_a_non_finite_coordinate() -> None:
    from sonar_gym.localization.roh_kernels import unfinished_rows

    positions = np.zeros((6, 2))
    positions[1, 0] = np.nan
    positions[2, 1] = np.inf
    positions[3, 0] = -np.inf
    positions[4] = np.nan
    ok = np.array([True, True, True, False, True, True])
    assert unfinished_rows(positions, ok).tolist() == [1, 2, 4]
    assert unfinished_rows(positions[:0], ok[:0]).tolist() == []


def test_true_path_y_is_interpolated_inside_and_extrapolated_beyond_the_ends() -> None:
    from sonar_gym.localization.roh_path_errors import TruePath

    path = parabolic_path(x_end_m=1.3)
    true_path = TruePath(path)
    x = np.random.default_rng(5).uniform(0.5, 3.5, 500)
    xs, ys = path[::-1, 0], path[::-1, 1]
    below = ys[0] + (ys[1] - ys[0]) / (xs[1] - xs[0]) * (x - xs[0])
    above = ys[-1] + (ys[-1] - ys[-2]) / (xs[-1] - xs[-2]) * (x - xs[-1])
    expected = np.where(x < xs[0], below, np.where(x > xs[-1], above, np.interp(x, xs, ys)))
    assert (x < xs[0]).any() and (x > xs[-1]).any()
    assert true_path.y_at(x).view(np.int64).tolist() == expected.view(np.int64).tolist()
    assert true_path.y_at(float(x[0])).shape == ()


def test_the_first_side_change_is_where_the_sign_of_the_excess_first_differs() -> None:
    from sonar_gym.localization.roh_kernels import first_side_change

    rng = np.random.default_rng(3)
    distances = rng.uniform(0.0, 1.0, 300)
    distances[::37] = 0.5  # on the target: sign 0, which differs from both sides
    distances[250] = np.nan
    for start in range(0, 300, 7):
        for reference in (-1.0, 1.0):
            changes = np.flatnonzero(np.sign(distances[start:] - 0.5) != reference)
            expected = start + int(changes[0]) if len(changes) else len(distances)
            assert first_side_change(distances, start, 0.5, reference) == expected
    assert first_side_change(np.full(5, 0.7), 0, 0.5, 1.0) == 5


def test_a_boundary_of_two_beacons_above_one_point_is_refused_by_extractor_and_runner() -> None:
    with pytest.raises(ValueError, match="boundary_a and boundary_b must be distinct points"):
        ThreePointExtractor((1.0, 2.0, 1.4), (1.0, 2.0, 0.9), (0.45, 0.25, 0.05))
    beacons = dict(TABLE_I_BEACONS_M)
    beacons["C"] = (beacons["B"][0], beacons["B"][1], 1.2)  # C right above B's projection
    config = BlockExpansionConfig(beacons_m=beacons)
    with pytest.raises(ValueError, match="boundary_a and boundary_b must be distinct points"):
        BlockExpansion(config).run(parabolic_path(x_end_m=1.3))


def test_unit_scale_of_few_values_is_that_of_the_array_scan() -> None:
    from sonar_gym.localization.roh_trilateration import unit_scale

    def array_scan(*arrays: np.ndarray) -> float:
        largest = 0.0
        for values in arrays:
            magnitudes = np.abs(np.asarray(values, dtype=np.float64))
            finite = magnitudes[np.isfinite(magnitudes)]
            if finite.size:
                largest = max(largest, float(finite.max()))
        return largest

    rng = np.random.default_rng(6)
    for _ in range(300):
        values = rng.normal(size=int(rng.integers(1, 12))) * 10.0 ** rng.integers(-300, 300)
        values[rng.random(values.size) < 0.2] = rng.choice([np.nan, np.inf, -np.inf, 0.0])
        other = rng.normal(size=(3, 3)) * 10.0 ** rng.integers(-250, 250)
        large = rng.normal(size=40) * 10.0 ** rng.integers(-250, 250)
        assert unit_scale(values, other) == unit_scale(large[:0], values, other.tolist())
        largest = array_scan(values, other)
        expected = unit_scale(np.array([largest] * 20))  # above _FEW_VALUES: the array scan
        assert unit_scale(values, other) == expected


def test_the_shared_vector_norm_is_numpys_norm_bit_for_bit() -> None:
    from sonar_gym.pose import vector_norm

    rng = np.random.default_rng(14)
    vectors = rng.normal(size=(5000, 3)) * 10.0 ** rng.integers(-5, 5, (5000, 1))
    assert all(vector_norm(vector) == float(np.linalg.norm(vector)) for vector in vectors)


def test_the_extractors_sign_is_numpys_sign() -> None:
    from sonar_gym.localization.roh_block_expansion import _sign

    for value in (2.5, -1e-300, 0.0, -0.0, math.inf, -math.inf, math.nan, 5e-324):
        expected = float(np.sign(value))
        assert _sign(value) == expected or (math.isnan(expected) and math.isnan(_sign(value)))


def test_the_path_error_mean_is_numpys_mean_bit_for_bit() -> None:
    from sonar_gym.localization.roh_path_errors import _mean

    rng = np.random.default_rng(17)
    for size in [*range(1, 40), 127, 128, 129, 255, 513, 1000, 4097]:
        values = rng.lognormal(-4.0, 2.0, size)
        assert _mean(values) == float(np.mean(values))


def test_the_radical_centres_of_a_table_are_the_array_forms_bit_for_bit() -> None:
    from sonar_gym.localization.roh_trilateration import _radical_centres

    rng = np.random.default_rng(23)
    for _ in range(100):
        centres = rng.uniform(-3.0, 3.0, (3, 2))
        radii = rng.uniform(0.0, 4.0, (int(rng.integers(1, 40)), 3))
        squared_norms = np.einsum("ij,ij->i", centres, centres)
        design = -2.0 * (centres - centres.mean(axis=0))
        rhs = (radii**2 - np.mean(radii**2, axis=1, keepdims=True)) - (
            squared_norms - squared_norms.mean()
        )
        expected = np.linalg.lstsq(design, rhs.T, rcond=None)[0].T
        centre = _radical_centres(centres, radii)
        assert centre is not None
        assert centre.view(np.int64).tolist() == expected.view(np.int64).tolist()


@pytest.mark.parametrize("tolerance", [0.0, 1e-6, 1e-3, 0.3, 2.0])
def test_the_collinearity_shortcut_agrees_with_the_svd(tolerance: float) -> None:
    from sonar_gym.localization.roh_trilateration import _are_collinear, _clearly_spread

    def by_svd(points: np.ndarray) -> bool:
        singular_values = np.linalg.svd(points - points.mean(axis=0), compute_uv=False)
        return bool(
            singular_values[0] == 0.0 or singular_values[1] <= tolerance * singular_values[0]
        )

    rng = np.random.default_rng(31)
    shortcuts = 0
    for _ in range(3000):
        start, direction = rng.uniform(-5.0, 5.0, 2), rng.normal(size=2)
        along = rng.uniform(-2.0, 2.0, 3)
        across = rng.normal(size=3) * 10.0 ** rng.uniform(-12.0, 1.0)
        normal = np.array([-direction[1], direction[0]])
        points = start + along[:, None] * direction + across[:, None] * normal
        points *= 10.0 ** rng.integers(-3, 4)
        shortcuts += _clearly_spread(points, tolerance)
        assert _are_collinear(points, tolerance) == by_svd(points)
    # A ratio of singular values is at most 1: above a quarter the svd always decides.
    assert (shortcuts > 100) == (tolerance < 0.25)
    assert not _clearly_spread(np.zeros((3, 2)), tolerance)
