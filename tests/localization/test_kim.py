"""Kim, Lee & Jeong: odometry covariance, EKF, certainty grid and voting localization."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.localization.kim import (
    TABLE_1_ESTIMATED_POSITIONS_M,
    TABLE_1_TRUE_POSITIONS_M,
    OccupancyGrid,
    Sweep,
    VoteLocalization,
    ekf_update,
    heading_candidates_around,
    jacobian_state,
    jacobian_wheels,
    motion_model,
    predict,
    proportional_encoder_noise,
    vote_localize,
)
from sonar_gym.localization.kim_fix import fix_covariance, gated_ekf_update
from sonar_gym.pose import Pose, angle_difference, wrap_angle

CELL = 0.05
IDENTITY = Pose(0.0, 0.0, 0.0)

# -- a 2 m x 2 m arena: walls, one box, two cylinders ------------------------------------------


def _box(x0: float, y0: float, x1: float, y1: float) -> list[list[tuple[float, float]]]:
    return [
        [(x0, y0), (x1, y0)],
        [(x1, y0), (x1, y1)],
        [(x1, y1), (x0, y1)],
        [(x0, y1), (x0, y0)],
    ]


ARENA_SEGMENTS = np.array(_box(0.0, 0.0, 2.0, 2.0) + _box(0.45, 1.25, 0.8, 1.55))
ARENA_CIRCLES = np.array([[1.45, 0.55, 0.10], [0.50, 0.45, 0.06]])
ARENA_BOUNDS = (0.0, 0.0, 2.0, 2.0)
SECTOR = np.radians(np.arange(-45.0, 46.0, 1.0))  # 91 readings over the paper's +-45 deg


def _ray_cast(origin: np.ndarray, angle: float, max_range: float = 3.0) -> float:
    """Exact first intersection of a ray with the arena's segments and circles (m), NaN if none."""
    ox, oy = float(origin[0]), float(origin[1])
    dx, dy = math.cos(angle), math.sin(angle)
    best = math.inf
    for (ax, ay), (bx, by) in ARENA_SEGMENTS:
        ex, ey = bx - ax, by - ay
        denominator = dx * ey - dy * ex
        if abs(denominator) < 1e-15:
            continue
        t = ((ax - ox) * ey - (ay - oy) * ex) / denominator
        u = ((ax - ox) * dy - (ay - oy) * dx) / denominator
        if t > 1e-12 and -1e-12 <= u <= 1.0 + 1e-12:
            best = min(best, t)
    for cx, cy, radius in ARENA_CIRCLES:
        fx, fy = ox - cx, oy - cy
        b = fx * dx + fy * dy
        discriminant = b * b - (fx * fx + fy * fy - radius * radius)
        if discriminant < 0.0:
            continue
        for t in (-b - math.sqrt(discriminant), -b + math.sqrt(discriminant)):
            if t > 1e-12:
                best = min(best, t)
                break
    return best if best < max_range else math.nan


def _sweep(
    first_pose: Pose,
    odometry: Pose = IDENTITY,
    offset: tuple[float, float] = (0.04, 0.0),
    angles: np.ndarray = SECTOR,
) -> Sweep:
    """Noise-free sweep taken at ``first_pose`` composed with ``odometry``."""
    pose = first_pose.compose(odometry)
    sensor = pose.transform_point(offset)
    ranges = np.array([_ray_cast(sensor, pose.theta + angle) for angle in angles])
    return Sweep(angles, ranges, offset, odometry)


def noisy_sweeps(
    truth: Pose,
    moves: list[Pose],
    rng: np.random.Generator,
    range_std_m: float = 0.01,
    dropout_fraction: float = 0.0,
) -> list[Sweep]:
    """One sweep per odometry move from ``truth``, ranges with Gaussian noise of
    ``range_std_m`` metres (folded at zero) and, with ``dropout_fraction``, that share of
    readings lost (NaN)."""
    sweeps = []
    for move in moves:
        exact = _sweep(truth, move)
        noisy = np.abs(exact.ranges + rng.normal(0.0, range_std_m, exact.ranges.size))
        if dropout_fraction:
            noisy[rng.random(noisy.size) < dropout_fraction] = np.nan
        sweeps.append(Sweep(exact.angles, noisy, exact.sensor_offset, move))
    return sweeps


def _position_error(estimate: Pose, truth: Pose) -> float:
    return math.hypot(estimate.x - truth.x, estimate.y - truth.y)


def _heading_error(estimate: Pose, truth: Pose) -> float:
    return abs(angle_difference(estimate.theta, truth.theta))


# -- odometry prediction (sec. 3.1) ------------------------------------------------------------

poses = st.builds(
    Pose,
    st.floats(-5.0, 5.0),
    st.floats(-5.0, 5.0),
    st.floats(-math.pi, math.pi),
)
increments = st.floats(-0.3, 0.3)
wheel_bases = st.floats(0.05, 1.0)


def test_zero_motion_keeps_pose_and_adds_only_process_noise() -> None:
    pose = Pose(0.3, -1.2, 2.0)
    covariance = np.array([[0.02, 0.005, 0.001], [0.005, 0.03, -0.002], [0.001, -0.002, 0.01]])
    process = np.diag([1e-4, 2e-4, 3e-4])
    encoder = proportional_encoder_noise(0.0, 0.0, variance_per_metre_m=0.01)
    new_pose, new_covariance = predict(pose, covariance, 0.0, 0.0, 0.2, process, encoder)
    assert new_pose == pose
    np.testing.assert_allclose(new_covariance, covariance + process, rtol=0, atol=1e-15)


def test_zero_motion_with_constant_wheel_noise_adds_f_v_f_transpose() -> None:
    theta, base, variance = 0.7, 0.25, 1e-4
    pose = Pose(0.0, 0.0, theta)
    _, covariance = predict(pose, np.zeros((3, 3)), 0.0, 0.0, base, encoder_noise=variance)
    c, s = math.cos(theta), math.sin(theta)
    # F = [[c/2, c/2], [s/2, s/2], [1/l, -1/l]], V = variance * I.
    expected = variance * np.array(
        [
            [c * c / 2, c * s / 2, 0.0],
            [c * s / 2, s * s / 2, 0.0],
            [0.0, 0.0, 2.0 / base**2],
        ]
    )
    np.testing.assert_allclose(covariance, expected, rtol=1e-12, atol=1e-18)


def test_straight_motion_moves_by_the_mean_increment_along_the_heading() -> None:
    pose = Pose(1.0, 2.0, math.radians(30.0))
    moved = motion_model(pose, 0.25, 0.25, 0.3)
    assert moved.x == pytest.approx(1.0 + 0.25 * math.cos(math.radians(30.0)), abs=1e-12)
    assert moved.y == pytest.approx(2.0 + 0.25 * math.sin(math.radians(30.0)), abs=1e-12)
    assert moved.theta == pytest.approx(pose.theta, abs=1e-15)
    # Unequal wheels: the paper's step moves by the mean along the starting heading.
    turned = motion_model(pose, 0.2, 0.4, 0.3)
    assert turned.x == pytest.approx(1.0 + 0.3 * math.cos(math.radians(30.0)), abs=1e-12)
    assert turned.y == pytest.approx(2.0 + 0.3 * math.sin(math.radians(30.0)), abs=1e-12)


def test_pure_rotation_turns_by_the_increment_difference_over_the_wheel_base() -> None:
    pose = Pose(-0.4, 0.9, 3.0)
    turned = motion_model(pose, -0.05, 0.05, 0.3)
    assert (turned.x, turned.y) == (pose.x, pose.y)
    assert angle_difference(turned.theta, pose.theta) == pytest.approx(0.1 / 0.3, abs=1e-12)


def test_heading_wraps_past_pi() -> None:
    turned = motion_model(Pose(0.0, 0.0, math.pi - 0.1), -0.03, 0.03, 0.3)
    assert turned.theta == pytest.approx(-math.pi + 0.1, abs=1e-12)


def test_wheel_jacobian_divides_by_the_wheel_base_not_by_one() -> None:
    base, variance = 0.25, 1e-4
    jacobian = jacobian_wheels(Pose(0.0, 0.0, 0.3), -0.02, 0.02, base)
    np.testing.assert_allclose(jacobian[2], [1.0 / base, -1.0 / base], rtol=1e-15)
    # Pure rotation from a certain pose: var(theta) = (var_r + var_l) / l^2 = 32 variance,
    # where the printed T/1 would give 2 variance.
    _, covariance = predict(
        Pose(0.0, 0.0, 0.3), np.zeros((3, 3)), -0.02, 0.02, base, encoder_noise=[variance, variance]
    )
    assert covariance[2, 2] == pytest.approx(2.0 * variance / base**2, rel=1e-12)
    assert covariance[2, 2] == pytest.approx(32.0 * variance, rel=1e-12)


def test_midpoint_integration_is_closer_to_the_exact_arc_than_the_paper_step() -> None:
    base, d_left, d_right = 0.3, 0.10, 0.20
    start = Pose(0.0, 0.0, 0.0)
    turn = (d_right - d_left) / base
    radius = 0.5 * (d_left + d_right) / turn
    exact = np.array([radius * math.sin(turn), radius * (1.0 - math.cos(turn))])
    paper = motion_model(start, d_left, d_right, base).position
    midpoint = motion_model(start, d_left, d_right, base, integration="midpoint").position
    assert np.linalg.norm(midpoint - exact) < 0.2 * np.linalg.norm(paper - exact)


def _numerical_jacobians(
    pose: Pose, d_left: float, d_right: float, base: float, integration: str
) -> tuple[np.ndarray, np.ndarray]:
    """Central differences of the motion model wrt ``[x, y, theta]`` and ``[d_right, d_left]``."""
    step = 1e-6

    def f(state: np.ndarray, wheels: np.ndarray) -> np.ndarray:
        start = Pose(state[0], state[1], state[2])
        return motion_model(start, wheels[1], wheels[0], base, integration).as_array()

    def derivative(plus: np.ndarray, minus: np.ndarray) -> np.ndarray:
        difference = plus - minus
        difference[2] = wrap_angle(difference[2])
        return difference / (2.0 * step)

    state = pose.as_array()
    wheels = np.array([d_right, d_left])
    state_jacobian = np.column_stack(
        [derivative(f(state + step * e, wheels), f(state - step * e, wheels)) for e in np.eye(3)]
    )
    wheel_jacobian = np.column_stack(
        [derivative(f(state, wheels + step * e), f(state, wheels - step * e)) for e in np.eye(2)]
    )
    return state_jacobian, wheel_jacobian


@settings(max_examples=60, deadline=None)
@given(poses, increments, increments, wheel_bases, st.sampled_from(["paper", "midpoint"]))
def test_jacobians_match_finite_differences(
    pose: Pose, d_left: float, d_right: float, base: float, integration: str
) -> None:
    numeric_state, numeric_wheels = _numerical_jacobians(pose, d_left, d_right, base, integration)
    np.testing.assert_allclose(
        jacobian_state(pose, d_left, d_right, base, integration), numeric_state, atol=1e-6
    )
    np.testing.assert_allclose(
        jacobian_wheels(pose, d_left, d_right, base, integration), numeric_wheels, atol=1e-6
    )


@st.composite
def covariances(draw: st.DrawFn, size: int) -> np.ndarray:
    entries = draw(st.lists(st.floats(-0.5, 0.5), min_size=size * size, max_size=size * size))
    root = np.array(entries).reshape(size, size)
    return root @ root.T


@settings(max_examples=80, deadline=None)
@given(poses, covariances(3), increments, increments, wheel_bases, covariances(3), covariances(2))
def test_predicted_covariance_stays_symmetric_positive_semidefinite(
    pose: Pose,
    covariance: np.ndarray,
    d_left: float,
    d_right: float,
    base: float,
    process: np.ndarray,
    encoder: np.ndarray,
) -> None:
    for _ in range(5):
        pose, covariance = predict(pose, covariance, d_left, d_right, base, process, encoder)
    np.testing.assert_array_equal(covariance, covariance.T)
    scale = max(1.0, float(np.abs(covariance).max()))
    assert np.linalg.eigvalsh(covariance).min() >= -1e-9 * scale


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"wheel_base_m": 0.0}, "wheel_base_m"),
        ({"wheel_base_m": -0.2}, "wheel_base_m"),
        ({"d_left_m": math.nan}, "d_left_m"),
        ({"covariance": np.eye(2)}, "covariance"),
        ({"process_noise": np.eye(4)}, "process_noise"),
        ({"encoder_noise": np.ones((3, 3))}, "encoder_noise"),
        ({"encoder_noise": [-1.0, 0.0]}, "encoder_noise"),
        ({"integration": "rk4"}, "integration"),
    ],
)
def test_predict_rejects_bad_arguments_by_name(kwargs: dict, name: str) -> None:
    arguments = {
        "pose": Pose(0.0, 0.0, 0.0),
        "covariance": np.eye(3) * 0.01,
        "d_left_m": 0.1,
        "d_right_m": 0.1,
        "wheel_base_m": 0.2,
    }
    arguments.update(kwargs)
    with pytest.raises(ValueError, match=name):
        predict(**arguments)


# -- EKF correction (sec. 3.2) -----------------------------------------------------------------


def test_equal_covariances_give_the_midpoint_and_half_the_covariance() -> None:
    covariance = np.diag([0.04, 0.09, 0.01])
    pose, updated = ekf_update(Pose(1.0, 2.0, 0.1), covariance, Pose(1.2, 1.6, 0.3), covariance)
    assert (pose.x, pose.y, pose.theta) == pytest.approx((1.1, 1.8, 0.2), abs=1e-12)
    np.testing.assert_allclose(updated, covariance / 2.0, atol=1e-15)


def test_gain_inverts_the_innovation_covariance() -> None:
    prior, measured = Pose(0.0, 0.0, 0.0), Pose(1.0, 1.0, 0.1)
    covariance = np.diag([0.04, 0.09, 0.01])
    noise = np.diag([0.01, 0.01, 0.04])
    pose, updated = ekf_update(prior, covariance, measured, noise)
    gain = np.diag(covariance) / (np.diag(covariance) + np.diag(noise))  # 0.8, 0.9, 0.2
    assert (pose.x, pose.y, pose.theta) == pytest.approx((0.8, 0.9, 0.02), abs=1e-12)
    np.testing.assert_allclose(np.diag(updated), (1 - gain) * np.diag(covariance), atol=1e-15)
    # The printed K = P (P + G), without the inverse, would move x by 0.04 * 0.05 = 0.002.
    literal_gain_x = (covariance @ (covariance + noise))[0, 0]
    literal_x = prior.x + literal_gain_x * (measured.x - prior.x)
    assert literal_x == pytest.approx(0.002)
    assert abs(pose.x - literal_x) > 0.5


def test_heading_innovation_wraps_across_pi() -> None:
    covariance = np.diag([0.01, 0.01, 0.01])
    pose, _ = ekf_update(
        Pose(0.0, 0.0, math.radians(179.0)),
        covariance,
        Pose(0.0, 0.0, math.radians(-179.0)),
        covariance,
    )
    assert abs(angle_difference(pose.theta, math.pi)) < 1e-12
    pose, _ = ekf_update(
        Pose(0.0, 0.0, math.radians(179.0)),
        covariance,
        Pose(0.0, 0.0, math.radians(-177.0)),
        covariance * 3.0,
    )
    # Gain 1/4 on a +4 deg innovation: 179 + 1 = 180 deg, never through 0.
    assert abs(angle_difference(pose.theta, math.pi)) < 1e-12


def test_position_fix_with_correlated_prior_also_corrects_the_heading() -> None:
    covariance = np.array([[0.04, 0.0, 0.01], [0.0, 0.04, 0.0], [0.01, 0.0, 0.01]])
    noise = np.diag([0.04, 0.04])
    pose, updated = ekf_update(Pose(0.0, 0.0, 0.0), covariance, Pose(0.2, 0.0, 3.0), noise)
    # Innovation [0.2, 0], S = diag(0.08, 0.08): K[:, 0] = [0.5, 0, 0.125].
    assert (pose.x, pose.y, pose.theta) == pytest.approx((0.1, 0.0, 0.025), abs=1e-12)
    np.testing.assert_array_equal(updated, updated.T)


def test_joseph_form_matches_the_paper_form_for_the_optimal_gain() -> None:
    covariance = np.array([[0.05, 0.01, 0.002], [0.01, 0.03, -0.001], [0.002, -0.001, 0.02]])
    noise = np.array([[0.02, 0.004, 0.0], [0.004, 0.03, 0.001], [0.0, 0.001, 0.01]])
    plain = ekf_update(Pose(0, 0, 0), covariance, Pose(0.1, -0.1, 0.2), noise)
    joseph = ekf_update(Pose(0, 0, 0), covariance, Pose(0.1, -0.1, 0.2), noise, joseph_form=True)
    assert plain[0] == joseph[0]
    np.testing.assert_allclose(plain[1], joseph[1], atol=1e-15)


def test_certain_prior_and_certain_fix_keep_the_prior_without_nan() -> None:
    pose, covariance = ekf_update(
        Pose(1.0, 1.0, 0.0), np.zeros((3, 3)), Pose(2.0, 2.0, 1.0), np.zeros((3, 3))
    )
    assert pose == Pose(1.0, 1.0, 0.0)
    assert np.all(np.isfinite(covariance))


@settings(max_examples=80, deadline=None)
@given(poses, covariances(3), poses, covariances(3), st.booleans())
def test_ekf_update_never_grows_the_covariance(
    pose: Pose, covariance: np.ndarray, measured: Pose, noise: np.ndarray, joseph: bool
) -> None:
    prior = covariance + 1e-6 * np.eye(3)
    _, posterior = ekf_update(pose, prior, measured, noise + 1e-6 * np.eye(3), joseph_form=joseph)
    np.testing.assert_array_equal(posterior, posterior.T)
    scale = float(np.abs(prior).max())
    # P+ = P - P (P + G)^-1 P: the reduction is positive semi-definite, and so is P+.
    assert np.linalg.eigvalsh(prior - posterior).min() >= -1e-9 * scale
    assert np.linalg.eigvalsh(posterior).min() >= -1e-9 * scale


def test_ekf_update_rejects_a_bad_measurement_covariance() -> None:
    with pytest.raises(ValueError, match="measurement_covariance"):
        ekf_update(Pose(0, 0, 0), np.eye(3), Pose(0, 0, 0), np.eye(4))
    with pytest.raises(ValueError, match="measurement_covariance"):
        ekf_update(Pose(0, 0, 0), np.eye(3), Pose(0, 0, 0), -np.eye(3))


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(-2.0, 2.0), min_size=3, max_size=3),
    st.lists(st.floats(1e-4, 0.05), min_size=3, max_size=3),
    st.floats(-0.5, 0.5),
)
def test_gated_update_is_the_ekf_update_inside_the_gate_and_none_outside(
    offset: list[float], variances: list[float], correlation: float
) -> None:
    """The env's gated update skips ekf_update's checks, not its arithmetic: the same bits
    when the innovation passes the gate, no update when it does not."""
    estimate = Pose(1.0, -0.5, 3.0)
    root = np.diag(np.sqrt(variances))
    root[1, 0] = correlation * root[0, 0]
    prior = root @ root.T
    noise = fix_covariance(0.05, 0.02)
    fix = Pose(estimate.x + offset[0], estimate.y + offset[1], estimate.theta + offset[2])
    expected_pose, expected_covariance = ekf_update(estimate, prior, fix, noise)
    ungated = gated_ekf_update(estimate, prior, fix, noise, None)
    assert ungated is not None
    assert ungated[0].as_array().tobytes() == expected_pose.as_array().tobytes()
    assert ungated[1].tobytes() == expected_covariance.tobytes()
    innovation = np.array([offset[0], offset[1], angle_difference(fix.theta, estimate.theta)])
    distance = float(innovation @ np.linalg.inv(prior + noise) @ innovation)
    gated = gated_ekf_update(estimate, prior, fix, noise, 9.0)
    assert (gated is not None) == (distance <= 9.0) or abs(distance - 9.0) < 1e-9


# -- grid (sec. 2.2) ---------------------------------------------------------------------------


def test_grid_has_five_centimetre_cells_by_default() -> None:
    grid = OccupancyGrid.from_segments(np.zeros((0, 2, 2)), None, ARENA_BOUNDS)
    assert grid.cell_size_m == 0.05
    assert grid.shape == (40, 40)
    assert grid.bounds == (0.0, 0.0, 2.0, 2.0)


def test_rasterised_horizontal_segment_marks_its_row_of_cells() -> None:
    grid = OccupancyGrid.from_segments(
        np.array([[[0.12, 0.37], [0.33, 0.37]]]), None, (0.0, 0.0, 1.0, 1.0)
    )
    assert {tuple(cell) for cell in grid.occupied_cells()} == {(ix, 7) for ix in range(2, 7)}


def test_segment_on_a_cell_edge_marks_the_cells_on_both_sides() -> None:
    grid = OccupancyGrid.from_segments(
        np.array([[[0.1, 0.2], [0.1, 0.4]]]), None, (0.0, 0.0, 1.0, 1.0)
    )
    expected = {(ix, iy) for ix in (1, 2) for iy in range(3, 9)}
    assert {tuple(cell) for cell in grid.occupied_cells()} == expected


def _closed_square_meets_segment(
    left: float, bottom: float, size: float, start: np.ndarray, end: np.ndarray
) -> bool:
    """Liang-Barsky clip of the segment against the closed square."""
    t_low, t_high = 0.0, 1.0
    direction = end - start
    for p, q in (
        (-direction[0], start[0] - left),
        (direction[0], left + size - start[0]),
        (-direction[1], start[1] - bottom),
        (direction[1], bottom + size - start[1]),
    ):
        if p == 0.0:
            if q < 0.0:
                return False
            continue
        t = q / p
        if p < 0.0:
            t_low = max(t_low, t)
        else:
            t_high = min(t_high, t)
    return t_low <= t_high


def test_rasterised_diagonal_segment_matches_a_cell_by_cell_clip() -> None:
    start, end = np.array([0.113, 0.061]), np.array([0.871, 0.547])
    grid = OccupancyGrid.from_segments(np.array([[start, end]]), None, (0.0, 0.0, 1.0, 1.0))
    expected = {
        (ix, iy)
        for ix in range(20)
        for iy in range(20)
        if _closed_square_meets_segment(ix * CELL, iy * CELL, CELL, start, end)
    }
    assert {tuple(cell) for cell in grid.occupied_cells()} == expected
    assert len(expected) > 20


def test_rasterised_circle_marks_its_outline_and_leaves_the_inside_free() -> None:
    centre, radius = np.array([0.512, 0.487]), 0.173
    grid = OccupancyGrid.from_segments(
        np.zeros((0, 2, 2)), np.array([[*centre, radius]]), (0.0, 0.0, 1.0, 1.0)
    )
    angles = np.linspace(0.0, 2.0 * np.pi, 200_000, endpoint=False)
    outline = centre + radius * np.column_stack((np.cos(angles), np.sin(angles)))
    expected = {tuple(cell) for cell in np.floor(outline / CELL).astype(int)}
    assert {tuple(cell) for cell in grid.occupied_cells()} == expected
    assert not grid.occupied[10, 9]  # the cell holding the centre


def test_obstacle_points_lie_on_the_mapped_outline(arena_grid: OccupancyGrid) -> None:
    points = arena_grid.occupied_obstacle_points()
    # Every obstacle point lies on a wall, the box or a cylinder outline, inside its cell.
    on_walls = (
        np.isclose(points[:, 0], 0.0)
        | np.isclose(points[:, 0], 2.0)
        | np.isclose(points[:, 1], 0.0)
        | np.isclose(points[:, 1], 2.0)
    )
    in_box = (
        (np.isclose(points[:, 0], 0.45) | np.isclose(points[:, 0], 0.8))
        & (points[:, 1] >= 1.25)
        & (points[:, 1] <= 1.55)
    ) | (
        (np.isclose(points[:, 1], 1.25) | np.isclose(points[:, 1], 1.55))
        & (points[:, 0] >= 0.45)
        & (points[:, 0] <= 0.8)
    )
    on_circle = np.zeros(points.shape[0], dtype=bool)
    for cx, cy, radius in ARENA_CIRCLES:
        on_circle |= np.isclose(np.hypot(points[:, 0] - cx, points[:, 1] - cy), radius)
    assert np.all(on_walls | in_box | on_circle)
    offsets = np.abs(points - arena_grid.occupied_centers())
    assert np.all(offsets <= CELL / 2 + 1e-12)


@settings(max_examples=100, deadline=None)
@given(st.floats(-1.0, 3.0), st.floats(-0.5, 2.5))
def test_world_to_cell_round_trip(x: float, y: float) -> None:
    grid = OccupancyGrid.empty((-1.0, -0.5, 3.0, 2.5), CELL)
    cell = grid.world_to_cell([x, y])
    centre = grid.cell_to_world(cell)
    assert np.all(np.abs(centre - [x, y]) <= CELL / 2 + 1e-12)
    np.testing.assert_array_equal(grid.world_to_cell(centre), cell)


def test_every_cell_centre_maps_back_to_its_cell() -> None:
    grid = OccupancyGrid.empty((-0.3, 0.2, 1.7, 2.05), CELL)
    cells = np.stack(
        np.meshgrid(np.arange(grid.shape[0]), np.arange(grid.shape[1]), indexing="ij"), axis=-1
    ).reshape(-1, 2)
    np.testing.assert_array_equal(grid.world_to_cell(grid.cell_to_world(cells)), cells)
    assert grid.contains_cell(cells).all()
    assert not grid.contains_cell(np.array([[-1, 0], [0, grid.shape[1]]])).any()


def test_map_built_from_sweeps_lies_on_the_known_map(arena_grid: OccupancyGrid) -> None:
    truth = [
        Pose(1.0, 1.0, 0.0),
        Pose(1.2, 0.9, math.pi / 2),
        Pose(0.9, 0.8, math.pi),
        Pose(1.1, 1.1, -math.pi / 2),
    ]
    sweeps = [_sweep(pose) for pose in truth]
    built = OccupancyGrid.from_sweeps(sweeps, truth, ARENA_BOUNDS, CELL)
    assert built.occupied.sum() > 40
    # Noise-free echoes end on the outlines, so every hit cell touches an outline.
    assert not np.any(built.occupied & ~arena_grid.occupied)
    assert built.hit_counts.sum() == sum(int(np.isfinite(s.ranges).sum()) for s in sweeps)


def test_sweep_map_counts_hits_and_passes_along_a_ray() -> None:
    sweep = Sweep(np.array([0.0]), np.array([0.51]), (0.0, 0.0))
    grid = OccupancyGrid.from_sweeps([sweep], [Pose(0.11, 0.525, 0.0)], (0.0, 0.0, 1.0, 1.0))
    assert {tuple(cell) for cell in grid.occupied_cells()} == {(12, 10)}
    np.testing.assert_allclose(grid.obstacle_points_m[12, 10], [0.62, 0.525], atol=1e-12)
    passed = {tuple(cell) for cell in np.argwhere(grid.pass_counts > 0)}
    assert passed == {(ix, 10) for ix in range(2, 12)}
    assert grid.pass_counts.max() == 1


def test_min_hit_fraction_clears_cells_more_often_crossed_than_hit() -> None:
    hit_once = Sweep(np.array([0.0]), np.array([0.3]))
    crossing = Sweep(np.array([0.0, 0.0]), np.array([0.6, 0.6]))
    poses = [Pose(0.11, 0.525, 0.0), Pose(0.11, 0.525, 0.0)]
    grid = OccupancyGrid.from_sweeps(
        [hit_once, crossing], poses, (0.0, 0.0, 1.0, 1.0), min_hit_fraction=0.5
    )
    assert grid.hit_counts[8, 10] == 1 and grid.pass_counts[8, 10] == 2
    assert not grid.occupied[8, 10]
    assert grid.occupied[14, 10]


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: OccupancyGrid.empty((1.0, 0.0, 1.0, 2.0)), "bounds"),
        (lambda: OccupancyGrid.empty((0.0, 0.0, 1.0, 1.0), cell_size=0.0), "cell_size"),
        (lambda: OccupancyGrid.from_segments(np.zeros((2, 3)), None, ARENA_BOUNDS), "segments"),
        (
            lambda: OccupancyGrid.from_segments(
                np.zeros((0, 2, 2)), [[0.5, 0.5, -0.1]], ARENA_BOUNDS
            ),
            "circles",
        ),
        (lambda: OccupancyGrid.from_sweeps([], [Pose(0, 0, 0)], ARENA_BOUNDS), "poses"),
        (lambda: Sweep(np.zeros(3), np.zeros(2)), "ranges"),
        (lambda: Sweep(np.zeros(2), np.array([1.0, -0.1])), "ranges"),
        (lambda: Sweep(np.zeros(2), np.ones(2), sensor_offset=(0.0,)), "sensor_offset"),
        (lambda: Sweep(np.zeros((2, 2)), np.ones((2, 2))), "angles"),
    ],
)
def test_grid_and_sweep_reject_bad_arguments_by_name(call, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        call()


# -- voting localization (sec. 3.3) ------------------------------------------------------------

# Poses whose 90-degree sector sees a corner or an object, so one sweep fixes the pose.
ONE_SWEEP_POSES = [
    Pose(1.03, 0.87, 0.4),
    Pose(0.62, 0.83, 2.6),
    Pose(1.37, 1.42, -0.9),
    Pose(1.58, 1.21, math.radians(-135.0)),
]


@pytest.mark.parametrize("truth", ONE_SWEEP_POSES)
def test_one_sweep_recovers_the_pose_within_one_cell_and_one_heading_step(
    arena_grid: OccupancyGrid, truth: Pose
) -> None:
    # One 90-degree sweep resolves heading to about half a cell over the range (~1.5 deg at
    # 1 m), so this test searches in 2-degree steps.
    step = math.radians(2.0)
    prior = Pose(truth.x + 0.06, truth.y - 0.04, truth.theta + math.radians(3.3))
    result = vote_localize(
        arena_grid,
        [_sweep(truth)],
        search_center=prior,
        heading_step_rad=step,
        anchor="obstacle_point",
    )
    assert isinstance(result, VoteLocalization)
    assert result.status == "ok", result.message
    assert _position_error(result.pose, truth) <= CELL
    assert _heading_error(result.pose, truth) <= step + 1e-12
    assert result.heading_rad == result.pose.theta
    assert result.vote_map.shape == arena_grid.shape
    assert 0 < result.votes <= result.vote_map.max()


@pytest.mark.parametrize("truth", ONE_SWEEP_POSES)
def test_paper_cell_centre_voting_recovers_the_position_within_one_cell(
    arena_grid: OccupancyGrid, truth: Pose
) -> None:
    prior = Pose(truth.x + 0.06, truth.y - 0.04, truth.theta + math.radians(3.3))
    result = vote_localize(arena_grid, [_sweep(truth)], search_center=prior)
    assert result.status == "ok", result.message
    assert _position_error(result.pose, truth) <= CELL
    # Anchoring at cell centres blurs the votes by half a cell, which at ~1 m range is
    # about 1.5 degrees: the heading is resolved to a few steps only.
    assert _heading_error(result.pose, truth) <= math.radians(3.0) + 1e-12


MOVES = [
    IDENTITY,
    Pose(0.10, 0.05, math.pi / 2),
    Pose(0.15, 0.15, math.pi),
    Pose(0.05, 0.20, -math.pi / 2),
]


@pytest.mark.parametrize("count", [2, 3, 4])
@pytest.mark.parametrize("anchor", ["cell_center", "obstacle_point"])
def test_sweeps_combined_through_dead_reckoning_recover_the_first_pose(
    arena_grid: OccupancyGrid, count: int, anchor: str
) -> None:
    truth = Pose(0.93, 0.71, 0.4)
    sweeps = [_sweep(truth, move) for move in MOVES[:count]]
    prior = Pose(truth.x - 0.05, truth.y + 0.05, truth.theta - math.radians(4.4))
    result = vote_localize(arena_grid, sweeps, search_center=prior, anchor=anchor)
    assert result.status == "ok", result.message
    assert _position_error(result.pose, truth) <= CELL
    steps = 1.0 if anchor == "obstacle_point" else 3.0
    assert _heading_error(result.pose, truth) <= math.radians(steps) + 1e-12
    expected_last = truth.compose(MOVES[count - 1])
    assert _position_error(result.last_sweep_pose, expected_last) <= CELL + 0.25 * math.radians(3)


def test_obstacle_point_anchor_removes_the_half_cell_shift(arena_grid: OccupancyGrid) -> None:
    truth = Pose(0.93, 0.71, 0.4)
    sweeps = [_sweep(truth, move) for move in MOVES]
    result = vote_localize(arena_grid, sweeps, search_center=truth, anchor="obstacle_point")
    assert _position_error(result.pose, truth) <= CELL / 4


def test_four_noisy_sweeps_still_localize_within_one_cell(arena_grid: OccupancyGrid) -> None:
    rng = np.random.default_rng(2024)
    truth = Pose(0.93, 0.71, 0.4)
    prior = Pose(truth.x + 0.05, truth.y - 0.04, truth.theta + math.radians(3.0))
    for _ in range(5):
        sweeps = noisy_sweeps(truth, MOVES, rng)
        for anchor in ("cell_center", "obstacle_point"):
            result = vote_localize(arena_grid, sweeps, search_center=prior, anchor=anchor)
            assert result.status == "ok"
            assert _position_error(result.pose, truth) <= CELL
            assert _heading_error(result.pose, truth) <= math.radians(3.0) + 1e-12


def test_a_map_built_from_sweeps_localizes_a_new_pose(arena_grid: OccupancyGrid) -> None:
    # Sec. 2.2 then sec. 3.3: survey the arena with full turns at known poses, then localize.
    full_turn = np.radians(np.arange(-180.0, 180.0, 1.0))
    survey = [Pose(x, y, 0.0) for x in (0.3, 1.0, 1.7) for y in (0.3, 1.0, 1.7)]
    built = OccupancyGrid.from_sweeps(
        [_sweep(pose, angles=full_turn) for pose in survey], survey, ARENA_BOUNDS
    )
    assert not np.any(built.occupied & ~arena_grid.occupied)
    assert built.occupied.sum() > 0.8 * arena_grid.occupied.sum()
    truth = Pose(0.93, 0.71, 0.4)
    sweeps = [_sweep(truth, move) for move in MOVES]
    prior = Pose(truth.x + 0.05, truth.y - 0.04, truth.theta + math.radians(3.0))
    result = vote_localize(built, sweeps, search_center=prior)
    assert result.status == "ok"
    assert _position_error(result.pose, truth) <= CELL


def test_grid_survives_a_pickle_round_trip(arena_grid: OccupancyGrid) -> None:
    copy = pickle.loads(pickle.dumps(arena_grid))
    np.testing.assert_array_equal(copy.occupied, arena_grid.occupied)
    np.testing.assert_array_equal(copy.obstacle_points_m, arena_grid.obstacle_points_m)
    truth = Pose(0.93, 0.71, 0.4)
    result = vote_localize(copy, [_sweep(truth, m) for m in MOVES], search_center=truth)
    assert _position_error(result.pose, truth) <= CELL


def test_sweeps_without_their_odometry_do_not_localize(arena_grid: OccupancyGrid) -> None:
    truth = Pose(0.93, 0.71, 0.4)
    honest = [_sweep(truth, move) for move in MOVES]
    blind = [Sweep(s.angles, s.ranges, s.sensor_offset, IDENTITY) for s in honest]
    prior = Pose(truth.x - 0.05, truth.y + 0.05, truth.theta)
    good = vote_localize(arena_grid, honest, search_center=prior, anchor="obstacle_point")
    bad = vote_localize(arena_grid, blind, search_center=prior, anchor="obstacle_point")
    assert _position_error(good.pose, truth) <= CELL
    assert good.votes > 2 * bad.votes


def test_sensor_offset_is_taken_into_account(arena_grid: OccupancyGrid) -> None:
    truth = Pose(1.03, 0.87, 0.4)
    sweep = _sweep(truth, offset=(0.08, 0.03))
    result = vote_localize(arena_grid, [sweep], search_center=truth, anchor="obstacle_point")
    assert _position_error(result.pose, truth) <= CELL / 2
    ignored = Sweep(sweep.angles, sweep.ranges, (0.0, 0.0))
    wrong = vote_localize(arena_grid, [ignored], search_center=truth, anchor="obstacle_point")
    assert _position_error(wrong.pose, truth) > CELL


def test_full_circle_heading_search_without_prior(arena_grid: OccupancyGrid) -> None:
    truth = Pose(0.93, 0.71, 0.4)
    sweeps = [_sweep(truth, move) for move in MOVES]
    result = vote_localize(arena_grid, sweeps, anchor="obstacle_point")
    assert result.status == "ok"
    assert _position_error(result.pose, truth) <= CELL
    assert _heading_error(result.pose, truth) <= math.radians(1.0) + 1e-12


def test_raw_maximum_selection_also_recovers_the_pose(arena_grid: OccupancyGrid) -> None:
    truth = Pose(0.93, 0.71, 0.4)
    sweeps = [_sweep(truth, move) for move in MOVES]
    for refine in ("vote_mean", "cell_center"):
        result = vote_localize(
            arena_grid, sweeps, search_center=truth, selection="max", refine=refine
        )
        assert result.status == "ok"
        assert _position_error(result.pose, truth) <= CELL


def test_search_circle_keeps_the_estimate_inside_it(arena_grid: OccupancyGrid) -> None:
    truth = Pose(1.03, 0.87, 0.4)
    centre = Pose(1.5, 1.5, 0.4)
    result = vote_localize(arena_grid, [_sweep(truth)], search_center=centre, search_radius=0.2)
    if result.ok:
        assert _position_error(result.pose, centre) <= 0.2 + 1e-12
        assert _position_error(result.pose, truth) > 0.3
    else:
        assert result.status == "no_votes"


def test_a_lone_wall_is_reported_ambiguous_when_asked(arena_grid: OccupancyGrid) -> None:
    # Facing the top wall from 0.45 m: the sector sees only that wall, so the position along it
    # is unconstrained.
    truth = Pose(1.16, 1.54, 1.46)
    sweep = _sweep(truth)
    assert vote_localize(arena_grid, [sweep], search_center=truth).ok
    result = vote_localize(arena_grid, [sweep], search_center=truth, ambiguity_ratio=0.9)
    assert result.status == "ambiguous"
    assert result.pose is None and result.heading_rad is None
    well_posed = vote_localize(
        arena_grid,
        [_sweep(Pose(0.93, 0.71, 0.4), m) for m in MOVES],
        search_center=Pose(0.93, 0.71, 0.4),
        ambiguity_ratio=0.9,
    )
    assert well_posed.ok


@pytest.mark.parametrize(
    "sweep",
    [
        Sweep(np.array([]), np.array([])),
        Sweep(SECTOR, np.full(SECTOR.size, np.nan)),
        Sweep(SECTOR, np.full(SECTOR.size, np.inf)),
    ],
)
def test_sweep_without_echoes_reports_empty_sweep(arena_grid: OccupancyGrid, sweep: Sweep) -> None:
    result = vote_localize(arena_grid, [sweep], search_center=Pose(1.0, 1.0, 0.0))
    assert result.status == "empty_sweep"
    assert result.pose is None and result.heading_rad is None and result.votes == 0


def test_readings_beyond_max_range_count_as_no_echo(arena_grid: OccupancyGrid) -> None:
    sweep = Sweep(SECTOR, np.full(SECTOR.size, 3.5))
    result = vote_localize(arena_grid, [sweep], search_center=Pose(1.0, 1.0, 0.0), max_range_m=3.0)
    assert result.status == "empty_sweep"


def test_empty_map_gives_no_votes() -> None:
    grid = OccupancyGrid.empty(ARENA_BOUNDS)
    result = vote_localize(grid, [_sweep(Pose(1.0, 1.0, 0.0))], search_center=Pose(1.0, 1.0, 0.0))
    assert result.status == "no_votes"
    assert result.pose is None


def test_heading_candidates_around_a_prior() -> None:
    candidates = heading_candidates_around(math.pi - 0.01, math.radians(2.0), math.radians(1.0))
    assert candidates.size == 5
    assert np.all(candidates <= math.pi) and np.all(candidates > -math.pi)
    assert abs(angle_difference(candidates[2], math.pi - 0.01)) < 1e-12


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"sweeps": []}, "sweeps"),
        (
            {"sweeps": [Sweep(SECTOR, np.ones(SECTOR.size), odometry=Pose(0.1, 0.0, 0.0))]},
            "odometry",
        ),
        ({"search_radius": 0.5}, "search_radius"),
        ({"search_center": Pose(1, 1, 0), "search_radius": -1.0}, "search_radius"),
        ({"heading_candidates": []}, "heading_candidates"),
        ({"search_center": [1.0]}, "search_center"),
        ({"selection": "best"}, "selection"),
        ({"anchor": "corner"}, "anchor"),
        ({"ambiguity_ratio": 1.5}, "ambiguity_ratio"),
        ({"grid": "map"}, "grid"),
    ],
)
def test_vote_localize_rejects_bad_arguments_by_name(
    arena_grid: OccupancyGrid, kwargs: dict, name: str
) -> None:
    arguments = {"grid": arena_grid, "sweeps": [Sweep(SECTOR, np.ones(SECTOR.size))]}
    arguments.update(kwargs)
    with pytest.raises(ValueError, match=name):
        vote_localize(**arguments)


# -- the paper's Table 1 -----------------------------------------------------------------------


def test_paper_table_1_errors_stay_below_one_cell() -> None:
    errors = np.linalg.norm(TABLE_1_ESTIMATED_POSITIONS_M - TABLE_1_TRUE_POSITIONS_M, axis=1)
    # Row 7: (183.01 - 180.00, 193.21 - 190.00) cm = (3.01, 3.21) cm.
    assert errors.max() == pytest.approx(math.hypot(0.0301, 0.0321), abs=1e-12)
    assert np.argmax(errors) == 6
    assert np.all(errors < CELL)


def test_ekf_symmetry_check_tests_both_triangles() -> None:
    """``|a_ij - a_ji| <= atol + rtol |a_ji|`` holds one way round but not the other for this
    pair: numpy's allclose against the transpose rejects the matrix, whichever entry is where,
    and so does the check."""
    from sonar_gym.localization import ekf

    smaller, larger = 0.6469621279872788, 0.6469621286352409
    for upper, lower in ((smaller, larger), (larger, smaller)):
        matrix = np.eye(3)
        matrix[0, 1], matrix[1, 0] = upper, lower
        assert not np.allclose(matrix, matrix.T, rtol=1e-9, atol=1e-12)
        with pytest.raises(ValueError, match="symmetric"):
            ekf._covariance(matrix, 3, "covariance")


@settings(max_examples=200, deadline=None)
@given(
    st.floats(min_value=-8.0, max_value=2.0),
    st.floats(min_value=-14.0, max_value=-6.0),
    st.integers(min_value=0, max_value=2**31 - 1),
)
def test_ekf_symmetry_check_is_numpys_allclose(
    scale_exp: float, skew_exp: float, seed: int
) -> None:
    from sonar_gym.localization import ekf

    rng = np.random.default_rng(seed)
    base = rng.normal(size=(3, 3)) * 10.0**scale_exp
    matrix = base @ base.T + 10.0**skew_exp * rng.normal(size=(3, 3)) * 10.0**scale_exp
    np.fill_diagonal(matrix, np.abs(np.diag(matrix)))  # variances stay valid
    symmetric = np.allclose(
        matrix, matrix.T, rtol=1e-9, atol=1e-12 * max(1.0, float(np.abs(matrix).max()))
    )
    if symmetric:
        assert np.array_equal(ekf._covariance(matrix, 3, "covariance"), matrix)
    else:
        with pytest.raises(ValueError, match="symmetric"):
            ekf._covariance(matrix, 3, "covariance")
