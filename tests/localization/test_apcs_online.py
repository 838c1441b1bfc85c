"""The on-line APCS loop against per-sample references, and its argument contract."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.localization.apcs import (
    DEFAULT_PARAMETERS,
    WallVector,
    correct_with_detected_wall,
)
from sonar_gym.localization.apcs_online import (
    APCSTracker,
    WallStream,
    fit_measurement_variances,
    nearest_facing_walls,
)
from sonar_gym.localization.kim import predict, proportional_encoder_noise
from sonar_gym.localization.result import OK
from sonar_gym.maps import map_wall_vectors
from sonar_gym.odometry import predict_run
from sonar_gym.pose import Pose
from sonar_gym.scenario import load_scenario

BASE_M = 0.3
VARIANCE_PER_M = 3e-7


def _increments(rng: np.random.Generator, count: int) -> tuple[np.ndarray, np.ndarray]:
    left = 0.03 + rng.normal(0.0, 0.002, count)
    right = 0.03 + rng.normal(0.0, 0.002, count)
    turns = rng.random(count) < 0.2  # some turns in place among the straight steps
    half = rng.normal(0.0, 0.05, count) * BASE_M
    left[turns], right[turns] = -half[turns], half[turns]
    return left, right


@pytest.mark.parametrize("count", [1, 7, 300])
def test_predict_run_is_kims_prediction_command_by_command(count: int) -> None:
    rng = np.random.default_rng(count)
    left, right = _increments(rng, count)
    pose = Pose(1.0, -2.0, 3.1)  # near pi: the heading wraps on the way
    covariance = np.array([[1e-4, 3e-5, 1e-6], [3e-5, 2e-4, -2e-6], [1e-6, -2e-6, 1e-5]])
    poses, covariances = predict_run(pose, covariance, left, right, BASE_M, VARIANCE_PER_M)
    reference, reference_covariance = pose, covariance
    for k in range(count):
        reference, reference_covariance = predict(
            reference,
            reference_covariance,
            left[k],
            right[k],
            BASE_M,
            encoder_noise=proportional_encoder_noise(left[k], right[k], VARIANCE_PER_M),
            integration="midpoint",
        )
        assert poses[k + 1, :2] == pytest.approx(reference.position, abs=1e-12)
        assert math.remainder(poses[k + 1, 2] - reference.theta, 2 * math.pi) == pytest.approx(
            0.0, abs=1e-12
        )
        assert -math.pi < poses[k + 1, 2] <= math.pi
        np.testing.assert_allclose(covariances[k + 1], reference_covariance, rtol=1e-9, atol=1e-18)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("encoder_left_m", [0.03, math.nan]),
        ("encoder_right_m", [0.03]),
        ("covariance", np.eye(2)),
        ("wheel_base_m", 0.0),
        ("variance_per_m", -1.0),
    ],
)
def test_predict_run_rejects_bad_arguments_by_name(field: str, value: object) -> None:
    arguments: dict[str, object] = {
        "pose": Pose(0.0, 0.0, 0.0),
        "covariance": np.eye(3) * 1e-4,
        "encoder_left_m": [0.03, 0.03],
        "encoder_right_m": [0.03, 0.03],
        "wheel_base_m": BASE_M,
        "variance_per_m": VARIANCE_PER_M,
    }
    arguments[field] = value
    with pytest.raises(ValueError, match=field):
        predict_run(**arguments)  # type: ignore[arg-type]


def _corridor_readings(
    rng: np.random.Generator, count: int, wall_y: float = 1.0
) -> tuple[np.ndarray, np.ndarray]:
    """Noisy left ranges to a wall at ``wall_y`` along a straight drive, with some dropouts."""
    true_y = np.linspace(0.0, 0.02, count)
    ranges = wall_y - true_y + rng.normal(0.0, 0.001, count)
    ranges[rng.random(count) < 0.05] = np.nan
    return true_y, ranges


def test_pending_erps_are_the_erps_add_gives_reading_by_reading() -> None:
    rng = np.random.default_rng(1)
    _, ranges = _corridor_readings(rng, 40)
    xy = np.column_stack([0.03 * np.arange(40), np.zeros(40)])
    headings = rng.normal(0.0, 0.002, 40)
    batch = WallStream("left")
    batch.add(xy[0] - [0.03, 0.0], 0.0, 0.97)  # a stored reading for the first pair
    points, phis, valid = batch.pending_erps(xy, headings, ranges)
    single = WallStream("left")
    single.add(xy[0] - [0.03, 0.0], 0.0, 0.97)
    for k in range(40):
        erp, _ = single.add(xy[k], headings[k], ranges[k])
        assert valid[k] == (erp is not None)
        if erp is not None:
            assert points[k] == pytest.approx(erp, abs=1e-12)
    assert np.all(np.isfinite(points)) and np.all(np.isfinite(phis))


def _reference_loop(
    wall_map: tuple[WallVector, ...],
    estimate: Pose,
    covariance: np.ndarray,
    left: np.ndarray,
    right: np.ndarray,
    samples: list[int],
    ranges: np.ndarray,
) -> tuple[Pose, np.ndarray, int, int]:
    """Fig. 2 sample by sample: predict every command, add each reading, correct on a match."""
    stream = WallStream("left")
    sample_index = 0
    corrections = detections = 0
    fixed = (1e-4, math.radians(1.0) ** 2)
    for k in range(len(left)):
        estimate, covariance = predict(
            estimate,
            covariance,
            left[k],
            right[k],
            BASE_M,
            encoder_noise=proportional_encoder_noise(left[k], right[k], VARIANCE_PER_M),
            integration="midpoint",
        )
        if sample_index < len(samples) and samples[sample_index] == k:
            _, groups = stream.add(estimate.position, estimate.theta, ranges[sample_index])
            sample_index += 1
            for group in groups:
                if group.fit.wall is None:
                    continue
                detections += 1
                _, correction = correct_with_detected_wall(
                    estimate, covariance, group.fit.wall, wall_map, *fixed, DEFAULT_PARAMETERS
                )
                if correction.status == OK and correction.pose is not None:
                    stream.move_frame(estimate, correction.pose)
                    estimate, covariance = correction.pose, np.array(correction.covariance)
                    corrections += 1
    return estimate, covariance, corrections, detections


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_tracker_run_is_the_sample_by_sample_loop(seed: int) -> None:
    rng = np.random.default_rng(seed)
    count = 120
    left = 0.03 * (1.0 + rng.normal(0.0, 0.003, count))
    right = 0.03 * (1.0 + rng.normal(0.0, 0.003, count))
    samples = list(range(0, count, 1 + seed))
    _, ranges = _corridor_readings(rng, len(samples))
    wall_map = (WallVector((-1.0, 1.0), (10.0, 1.0), name="left_wall"),)
    start = Pose(0.0, 0.004, 0.002)
    covariance = np.diag([1e-4, 1e-4, 1e-5])
    tracker = APCSTracker(
        wall_map,
        start,
        covariance,
        wheel_base_m=BASE_M,
        variance_per_m=VARIANCE_PER_M,
        range_variance_m2=1e-4,
        bearing_variance_rad2=math.radians(1.0) ** 2,
    )
    result = tracker.run(left, right, samples, {"left": ranges})
    estimate, reference_covariance, corrections, detections = _reference_loop(
        wall_map, start, covariance, left, right, samples, ranges
    )
    assert corrections > 0  # the loop is exercised, not only dead reckoning
    assert len(result.walls) == detections
    assert sum(wall.pose_after is not wall.pose_before for wall in result.walls) == corrections
    assert tracker.estimate.as_array() == pytest.approx(estimate.as_array(), abs=1e-9)
    np.testing.assert_allclose(tracker.covariance, reference_covariance, rtol=1e-6, atol=1e-15)
    assert result.consumed == count


def test_tracker_stops_at_the_first_stop_after_a_correction() -> None:
    rng = np.random.default_rng(5)
    count = 120
    left = np.full(count, 0.03)
    right = np.full(count, 0.03)
    samples = list(range(count))
    _, ranges = _corridor_readings(rng, count)
    wall_map = (WallVector((-1.0, 1.0), (10.0, 1.0)),)
    tracker = APCSTracker(
        wall_map,
        Pose(0.0, 0.01, 0.0),
        np.diag([1e-4, 1e-4, 1e-5]),
        wheel_base_m=BASE_M,
        variance_per_m=VARIANCE_PER_M,
        range_variance_m2=1e-4,
        bearing_variance_rad2=math.radians(1.0) ** 2,
    )
    stops = list(range(10, count + 1, 10))
    result = tracker.run(left, right, samples, {"left": ranges}, stops=stops)
    first = next(wall for wall in result.walls if wall.pose_after is not wall.pose_before)
    assert result.consumed == next(stop for stop in stops if stop > first.command_index)
    assert len(result.estimated_path) == result.consumed
    assert all(wall.command_index < result.consumed for wall in result.walls)


@pytest.mark.parametrize(
    ("arguments", "name"),
    [
        ({"sample_commands": [3, 2]}, "sample_commands"),
        ({"sample_commands": [0, 1], "readings": {"left": [1.0]}}, "readings"),
        ({"sample_commands": [0], "readings": {"up": [1.0]}}, "side"),
    ],
)
def test_tracker_run_rejects_bad_arguments_by_name(arguments: dict, name: str) -> None:
    tracker = APCSTracker(
        (),
        Pose(0.0, 0.0, 0.0),
        np.eye(3) * 1e-4,
        wheel_base_m=BASE_M,
        variance_per_m=VARIANCE_PER_M,
        range_variance_m2=1e-4,
        bearing_variance_rad2=1e-4,
    )
    with pytest.raises(ValueError, match=name):
        tracker.run([0.03] * 4, [0.03] * 4, **arguments)


def test_stream_rejects_non_finite_positions_and_headings() -> None:
    stream = WallStream("left")
    with pytest.raises(ValueError, match="sensor_xy"):
        stream.add([math.nan, 0.0], 0.0, 1.0)
    with pytest.raises(ValueError, match="headings_rad"):
        stream.add([0.0, 0.0], math.inf, 1.0)
    with pytest.raises(ValueError, match="side"):
        WallStream("up")


def test_nearest_facing_walls_rejects_non_finite_or_misshaped_rays() -> None:
    walls = map_wall_vectors(load_scenario("apcs_corridor"))
    with pytest.raises(ValueError, match="origins"):
        nearest_facing_walls(walls, [[math.nan, 0.0]], [0.0, 1.0])
    with pytest.raises(ValueError, match="direction"):
        nearest_facing_walls(walls, [[1.0, 0.0]], [0.0, 1.0, 0.0])


def test_fit_measurement_variances_rejects_an_unknown_mode() -> None:
    stream = WallStream("left")
    for k in range(6):
        stream.add([0.03 * k, 0.0], 0.0, 1.0)
    (group,) = stream.flush()
    with pytest.raises(ValueError, match="mode"):
        fit_measurement_variances(group, Pose(0.0, 0.0, 0.0), (1e-4, 1e-4), "median")


@settings(max_examples=60, deadline=None)
@given(
    ranges=st.lists(
        st.one_of(st.floats(0.0, 10.0), st.just(math.nan), st.just(math.inf)),
        min_size=2,
        max_size=30,
    ),
    heading=st.floats(-math.pi, math.pi),
    spacing=st.floats(0.0, 0.2),
)
def test_any_finite_run_keeps_a_status_and_never_nan(
    ranges: list[float], heading: float, spacing: float
) -> None:
    tracker = APCSTracker(
        (WallVector((-1.0, 1.0), (10.0, 1.0)),),
        Pose(0.0, 0.0, heading),
        np.eye(3) * 1e-4,
        wheel_base_m=BASE_M,
        variance_per_m=VARIANCE_PER_M,
        range_variance_m2=1e-4,
        bearing_variance_rad2=1e-4,
    )
    count = len(ranges)
    result = tracker.run(
        [spacing] * count, [spacing] * count, list(range(count)), {"left": ranges, "right": ranges}
    )
    for side in ("left", "right"):
        tracker.flush(side, result)
    assert np.all(np.isfinite(tracker.estimate.as_array()))
    assert np.all(np.isfinite(tracker.covariance))
    assert np.all(np.isfinite(result.estimated_path))
    for wall in result.walls:
        assert isinstance(wall.correction.status, str) and wall.correction.status
    assert all(math.isfinite(x) and math.isfinite(y) for x, y, _ in result.erps)


def test_tracker_map_is_independent_of_later_edits() -> None:
    walls = [WallVector((-1.0, 1.0), (10.0, 1.0))]
    tracker = APCSTracker(
        walls,
        Pose(0.0, 0.0, 0.0),
        np.eye(3) * 1e-4,
        wheel_base_m=BASE_M,
        variance_per_m=VARIANCE_PER_M,
        range_variance_m2=1e-4,
        bearing_variance_rad2=1e-4,
    )
    walls.append(dataclasses.replace(walls[0], name="other"))
    assert len(tracker.wall_map) == 1


@pytest.mark.parametrize("readings", [2, 4, 5, 6, 12])
def test_closed_groups_get_fit_wall_groups_verdict(readings: int) -> None:
    from sonar_gym.localization.apcs import EstimatedReflectionPoints, fit_wall_group

    stream = WallStream("left")
    groups = []
    for k in range(readings):
        groups += stream.add([0.03 * k, 0.0], 0.0, 1.0 + 0.001 * (k % 2))[1]
    groups += stream.flush()
    assert groups
    for group in groups:
        erps = EstimatedReflectionPoints.from_points(
            group.points, np.full(len(group.points), math.pi / 2.0)
        )
        expected = fit_wall_group(erps, range(len(group.points)))
        assert group.fit.status == expected.status
        assert group.fit.erp_indices == expected.erp_indices


@pytest.mark.parametrize("seed", range(6))
def test_stream_groups_are_group_erps_of_its_erps(seed: int) -> None:
    """Reading by reading, the closed groups split the ERP sequence as group_erps does: at
    every jump beyond the grouping distance and at the largest group size."""
    from sonar_gym.localization.apcs import group_erps

    rng = np.random.default_rng(seed)
    stream = WallStream("left")
    erps: list[np.ndarray] = []
    groups = []
    base_range = 1.0
    for k in range(120):
        if rng.random() < 0.08:  # a step in the wall: a discontinuity of the ERPs
            base_range = float(rng.uniform(0.5, 2.0))
        range_m = math.nan if rng.random() < 0.05 else base_range + rng.normal(0.0, 0.002)
        erp, closed = stream.add([0.03 * k, 0.0], 0.0, range_m)
        if erp is not None:
            erps.append(erp)
        groups += closed
    groups += stream.flush()
    expected = group_erps(np.array(erps))
    assert len(expected) > 3
    assert [len(group.points) for group in groups] == [len(group) for group in expected]
    for group, indices in zip(groups, expected, strict=True):
        assert np.array_equal(group.points, np.array(erps)[list(indices)])
