"""One-way beacon ranging: exact 3D distances, the counter, dropouts and firing times."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from sonar_gym.pose import Pose
from sonar_gym.sonar.acoustics import speed_of_sound_mps
from sonar_gym.sonar.echoes import PATH_END_TOLERANCE
from sonar_gym.sonar.ranging import BeaconRanger
from sonar_gym.validation import MIN_TIMER_PERIOD_S
from tests.sonar.worlds import world

EMITTERS = [
    {"name": "T1", "position": [0.0, 0.0, 2.4]},
    {"name": "T2", "position": [0.2, 0.0, 2.4]},
    {"name": "T3", "position": [0.0, 0.2, 2.4]},
]


def ceiling_room(temperature_c: float = 20.0, **tables):
    return world(
        temperature_c,
        room={"min": [-2, -2], "max": [2, 2]},
        emitters=EMITTERS,
        robot={"radius": 0.25, "sensor_height": 0.5},
        **tables,
    )


def exact_distances(pose: Pose, receivers, height: float, emitters=EMITTERS) -> np.ndarray:
    out = np.empty((len(receivers), len(emitters)))
    for j, xy in enumerate(receivers):
        x, y = pose.transform_point(xy)
        for i, emitter in enumerate(emitters):
            ex, ey, ez = emitter["position"]
            out[j, i] = math.sqrt((ex - x) ** 2 + (ey - y) ** 2 + (ez - height) ** 2)
    return out


def test_noise_free_distances_are_the_3d_distances() -> None:
    ranger = BeaconRanger.wu_tsai(noise=False, quantisation=False)
    pose = Pose(0.7, -0.4, 0.6)
    measured = ranger.measure(ceiling_room(), pose, np.random.default_rng(0))
    np.testing.assert_allclose(
        measured.distances, exact_distances(pose, ranger.receivers_xy, 0.5), rtol=1e-12
    )
    assert measured.emitter_names == ("T1", "T2", "T3")


def test_the_50_khz_counter_reads_whole_counts_at_most_one_count_short() -> None:
    ranger = BeaconRanger.wu_tsai(noise=False)
    pose = Pose(-0.3, 0.9, -2.0)
    measured = ranger.measure(ceiling_room(), pose, np.random.default_rng(0)).distances
    quantum = ranger.range_quantum_m
    assert quantum == pytest.approx(343.2 * 20e-6, rel=1e-3)  # 6.9 mm
    counts = measured / quantum
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-6)
    shortfall = exact_distances(pose, ranger.receivers_xy, 0.5) - measured
    assert np.all((shortfall >= 0) & (shortfall < quantum))


def test_assumed_speed_scales_the_distances() -> None:
    ranger = BeaconRanger.wu_tsai(noise=False, quantisation=False)
    pose = Pose(0.1, 0.2, 0.3)
    measured = ranger.measure(ceiling_room(27.0), pose, np.random.default_rng(0)).distances
    exact = exact_distances(pose, ranger.receivers_xy, 0.5)
    np.testing.assert_allclose(
        measured / exact, speed_of_sound_mps(20.0) / speed_of_sound_mps(27.0), rtol=1e-12
    )
    calibrated = ranger.with_assumed_speed(speed_of_sound_mps(27.0)).measure(
        ceiling_room(27.0), pose, None
    )
    np.testing.assert_allclose(calibrated.distances, exact, rtol=1e-12)


def test_a_free_wall_blocks_and_a_box_does_not() -> None:
    ranger = BeaconRanger(noise=False, quantisation=False)
    wall = ceiling_room(walls=[{"a": [1.0, -1.0], "b": [1.0, 1.0]}])
    box = ceiling_room(boxes=[{"center": [1.0, 0.0], "size": [0.3, 2.0]}])
    behind = Pose(1.5, 0.0, 0.0)
    assert np.all(np.isnan(ranger.measure(wall, behind, None).distances))
    assert np.all(np.isfinite(ranger.measure(box, behind, None).distances))
    assert np.all(np.isfinite(ranger.measure(wall, Pose(0.5, 0.0, 0.0), None).distances))


def test_emitters_out_of_range_are_dropouts() -> None:
    ranger = BeaconRanger(noise=False, quantisation=False, max_range_m=2.9)
    measured = ranger.measure(ceiling_room(), Pose(1.6, 1.6, 0.0), None, emitter_names=["T1", "T3"])
    exact = exact_distances(Pose(1.6, 1.6), ranger.receivers_xy, 0.5, [EMITTERS[0], EMITTERS[2]])
    np.testing.assert_array_equal(np.isnan(measured.distances), exact > 2.9)
    assert np.isnan(measured.distances).any() and np.isfinite(measured.distances).any()


def test_emitters_fire_in_sequence_and_timestamps_follow() -> None:
    ranger = BeaconRanger.wu_tsai(firing_interval_s=0.04, noise=False, quantisation=False)
    measured = ranger.measure(ceiling_room(), Pose(0.0, 0.0, 0.0), None, emitter_names=["T3", "T1"])
    assert measured.emitter_names == ("T3", "T1")
    assert measured.duration_s == pytest.approx(0.08)
    tof = measured.distances / speed_of_sound_mps(20.0)
    np.testing.assert_allclose(measured.timestamps_s, tof + np.array([0.0, 0.04]), rtol=1e-12)


def test_noise_is_seeded_and_unbiased() -> None:
    ranger = BeaconRanger(range_noise_std_m=0.01, quantisation=False)
    pose = Pose(0.0, 0.0, 0.0)
    first = ranger.measure(ceiling_room(), pose, np.random.default_rng(5)).distances
    again = ranger.measure(ceiling_room(), pose, np.random.default_rng(5)).distances
    np.testing.assert_array_equal(first, again)
    samples = np.concatenate(
        [
            ranger.measure(ceiling_room(), pose, np.random.default_rng(s)).distances.ravel()
            for s in range(300)
        ]
    )
    exact = exact_distances(pose, ranger.receivers_xy, 0.5)[0, 0]
    assert np.mean(samples[::3]) == pytest.approx(exact, abs=0.003)
    assert np.std(samples[::3]) == pytest.approx(0.01, rel=0.15)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"receivers_xy": ()}, "receivers_xy"),
        ({"timer_period_s": -1.0}, "timer_period_s"),
        ({"timer_period_s": 5e-324}, "timer_period_s"),
        ({"timer_period_s": 1e-13}, "timer_period_s"),
        ({"max_range_m": 0.0}, "max_range_m"),
        ({"height_m": math.inf}, "height_m"),
    ],
)
def test_bad_ranger_arguments_raise_naming_the_argument(kwargs, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        BeaconRanger(**kwargs)


def test_unknown_emitter_names_raise() -> None:
    with pytest.raises(ValueError, match="T9"):
        BeaconRanger().measure(ceiling_room(), Pose(0, 0), None, emitter_names=["T9"])


def route_samples() -> tuple[np.ndarray, np.ndarray]:
    """Positions on both sides of a free wall at x = 1 and near the corners, with headings."""
    xy = np.array([[0.5, 0.0], [1.5, 0.0], [1.6, 1.6], [-1.7, 1.2], [0.0, -1.9], [1.2, -0.4]])
    headings = np.array([0.0, 0.6, -2.0, 3.0, 1.1, -0.3])
    return xy, headings


def test_a_route_in_one_call_matches_one_measure_per_sample_for_a_seed() -> None:
    room = ceiling_room(walls=[{"a": [1.0, -1.0], "b": [1.0, 1.0]}])
    ranger = BeaconRanger.wu_tsai(range_noise_std_m=0.01, max_range_m=2.9)
    xy, headings = route_samples()
    route = ranger.measure_route(room, xy, np.random.default_rng(11), headings_rad=headings)
    rng = np.random.default_rng(11)
    for k, ((x, y), theta) in enumerate(zip(xy, headings, strict=True)):
        single = ranger.measure(room, Pose(x, y, theta), rng)
        np.testing.assert_array_equal(route.distances[k], single.distances)
        np.testing.assert_array_equal(route.timestamps_s[k], single.timestamps_s)
        assert route.round_duration_s == single.duration_s
    assert route.emitter_names == single.emitter_names
    dropped = np.isnan(route.distances)
    assert dropped.any() and not dropped.all()


def test_route_true_distances_and_dropouts_follow_the_geometry() -> None:
    room = ceiling_room(walls=[{"a": [1.0, -1.0], "b": [1.0, 1.0]}])
    ranger = BeaconRanger.wu_tsai(noise=False, quantisation=False, max_range_m=2.9)
    xy, headings = route_samples()
    route = ranger.measure_route(room, xy, None, headings_rad=headings)
    for k, ((x, y), theta) in enumerate(zip(xy, headings, strict=True)):
        exact = exact_distances(Pose(x, y, theta), ranger.receivers_xy, 0.5)
        np.testing.assert_allclose(route.true_distances[k], exact, rtol=1e-12)
        heard = np.isfinite(route.distances[k])
        np.testing.assert_allclose(route.distances[k][heard], exact[heard], rtol=1e-12)
    # Behind the wall (x = 1.5, |y| < 1) every path to the emitters near the origin is cut.
    assert np.all(np.isnan(route.distances[1]))
    np.testing.assert_array_equal(np.isnan(route.distances[2]), route.true_distances[2] > 2.9)
    np.testing.assert_array_equal(route.round_durations_s, np.full(len(xy), 3 * 0.05))


def test_route_noise_is_seeded_unbiased_and_quantised() -> None:
    ranger = BeaconRanger(range_noise_std_m=0.01, timer_period_s=1e-6)
    xy = np.zeros((4000, 2))
    first = ranger.measure_route(ceiling_room(), xy, np.random.default_rng(3))
    again = ranger.measure_route(ceiling_room(), xy, np.random.default_rng(3))
    np.testing.assert_array_equal(first.distances, again.distances)
    exact = exact_distances(Pose(0.0, 0.0), ranger.receivers_xy, 0.5)[0, 0]
    samples = first.distances[:, 0, 0]
    assert np.mean(samples) == pytest.approx(exact, abs=0.001)
    assert np.std(samples) == pytest.approx(0.01, rel=0.05)
    counts = first.distances / ranger.range_quantum_m
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-6)


def test_the_finest_counter_allowed_reads_the_exact_distance() -> None:
    xy = np.zeros((3, 2))
    finest = BeaconRanger(range_noise_std_m=0.0, timer_period_s=MIN_TIMER_PERIOD_S)
    exact = BeaconRanger(range_noise_std_m=0.0, timer_period_s=0.0)
    finest_route = finest.measure_route(ceiling_room(), xy, None)
    exact_route = exact.measure_route(ceiling_room(), xy, None)
    assert np.all(np.isfinite(finest_route.distances))
    np.testing.assert_allclose(finest_route.distances, exact_route.distances, rtol=0.0, atol=1e-9)


@pytest.mark.parametrize(
    ("xy", "headings", "name"),
    [
        (np.zeros((3, 3)), None, "xy"),
        (np.array([[0.0, np.nan]]), None, "xy"),
        (np.zeros(2), None, "xy"),
        (np.zeros((3, 2)), np.zeros(2), "headings_rad"),
        (np.zeros((1, 2)), np.array([np.inf]), "headings_rad"),
    ],
)
def test_bad_routes_raise_naming_the_argument(xy, headings, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        BeaconRanger(noise=False).measure_route(ceiling_room(), xy, None, headings_rad=headings)


def test_a_known_route_geometry_ranges_as_the_whole_route_call() -> None:
    room = ceiling_room(walls=[{"a": [1.0, -1.0], "b": [1.0, 1.0]}])
    ranger = BeaconRanger.wu_tsai(range_noise_std_m=0.01, max_range_m=2.9)
    xy, headings = route_samples()
    geometry = ranger.route_geometry(room, xy, ["T3", "T1"], headings_rad=headings)
    for seed in (1, 2):
        again = ranger.measure_geometry(geometry, room.temperature_c, np.random.default_rng(seed))
        whole = ranger.measure_route(
            room, xy, np.random.default_rng(seed), ["T3", "T1"], headings_rad=headings
        )
        np.testing.assert_array_equal(again.distances, whole.distances)
        np.testing.assert_array_equal(again.timestamps_s, whole.timestamps_s)
    assert geometry.emitter_names == ("T3", "T1")
    assert not geometry.heard.flags.writeable


@pytest.mark.parametrize("noise", [True, False])
def test_repeated_rounds_at_one_pose_match_a_route_that_repeats_the_pose(noise: bool) -> None:
    room = ceiling_room(walls=[{"a": [1.0, -1.0], "b": [1.0, 1.0]}])
    ranger = BeaconRanger.wu_tsai(range_noise_std_m=0.01, max_range_m=2.9, noise=noise)
    for pose in (Pose(1.6, 1.6, -2.0), Pose(0.5, 0.0, 0.6), Pose(1.5, 0.0, 0.0)):
        repeated = ranger.measure_repeated(room, pose, 7, np.random.default_rng(5), ["T2", "T1"])
        route = ranger.measure_route(
            room,
            np.repeat(pose.position[None, :], 7, axis=0),
            np.random.default_rng(5),
            ["T2", "T1"],
            headings_rad=np.full(7, pose.theta),
        )
        for field in ("distances", "true_distances", "timestamps_s"):
            np.testing.assert_array_equal(getattr(repeated, field), getattr(route, field))
            assert getattr(repeated, field).shape == (7, 2, 2)
        assert repeated.round_duration_s == route.round_duration_s
        assert repeated.emitter_names == ("T2", "T1")
    # the rounds differ by their jitter only when there is jitter
    rounds = ranger.measure_repeated(room, Pose(0.5, 0.0, 0.6), 7, np.random.default_rng(5))
    assert (np.ptp(rounds.distances, axis=0) > 0).any() == noise


@pytest.mark.parametrize("n_rounds", [0, -2, 1.5, True])
def test_bad_round_counts_raise_naming_the_argument(n_rounds) -> None:
    with pytest.raises(ValueError, match="n_rounds"):
        BeaconRanger(noise=False).measure_repeated(ceiling_room(), Pose(0.0, 0.0), n_rounds, None)


def _array_form_geometry(ranger, room, xy, headings, emitters=EMITTERS):
    """The numpy array form the compiled geometry loop replaced: distances and what is heard."""
    offsets = np.asarray(ranger.receivers_xy)
    cos, sin = np.cos(headings)[:, None], np.sin(headings)[:, None]
    receiver_x = xy[:, 0, None] + cos * offsets[:, 0] - sin * offsets[:, 1]
    receiver_y = xy[:, 1, None] + sin * offsets[:, 0] + cos * offsets[:, 1]
    emitter_xyz = np.array([e["position"] for e in emitters])
    path_x = emitter_xyz[:, 0] - receiver_x[:, :, None]
    path_y = emitter_xyz[:, 1] - receiver_y[:, :, None]
    rise = emitter_xyz[:, 2] - room.scenario.robot.sensor_height
    distance = np.sqrt((path_x * path_x + path_y * path_y) + rise * rise)
    n_walls = 4 + len(room.scenario.walls)
    a = room.geometry.segment_starts[:n_walls]
    d = room.geometry.segment_ends[:n_walls] - a
    px, py = path_x[..., None], path_y[..., None]
    w_x = (a[:, 0] - receiver_x[..., None])[:, :, None, :]
    w_y = (a[:, 1] - receiver_y[..., None])[:, :, None, :]
    denominator = px * d[:, 1] - py * d[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = (w_x * d[:, 1] - w_y * d[:, 0]) / denominator
        v = (w_x * py - w_y * px) / denominator
    limit = 1.0 - PATH_END_TOLERANCE
    crossing = (u > PATH_END_TOLERANCE) & (u < limit) & (v >= 0.0) & (v <= 1.0)
    return distance, (distance <= ranger.max_range_m) & ~crossing.any(axis=-1)


def test_the_compiled_geometry_gives_the_bits_of_the_array_form() -> None:
    room = ceiling_room(
        walls=[{"a": [1.0, -1.0], "b": [1.0, 1.0]}, {"a": [-1.5, 0.3], "b": [0.2, 0.3]}]
    )
    ranger = BeaconRanger(
        receivers_xy=((0.1, 0.2), (-0.3, 0.05), (0.0, -0.2)), max_range_m=2.5, noise=False
    )
    rng = np.random.default_rng(11)
    xy = rng.uniform(-1.9, 1.9, (500, 2))
    headings = rng.uniform(-math.pi, math.pi, 500)
    geometry = ranger.route_geometry(room, xy, headings_rad=headings)
    distance, heard = _array_form_geometry(ranger, room, xy, headings)
    assert heard.any() and not heard.all()  # both walls and the range cut some paths
    assert geometry.true_distances.tobytes() == distance.tobytes()
    np.testing.assert_array_equal(geometry.heard, heard)


def test_repeated_rounds_follow_a_change_of_scenario_and_of_emitters() -> None:
    """The pose-independent part is kept between calls only for the same world and emitters."""
    ranger = BeaconRanger.wu_tsai(noise=False, quantisation=False)
    pose = Pose(0.7, -0.4, 0.6)
    room = ceiling_room()
    first = ranger.measure_repeated(room, pose, 2, None, ["T1", "T2"]).distances
    np.testing.assert_allclose(
        first[0], exact_distances(pose, ranger.receivers_xy, 0.5)[:, :2], rtol=1e-12
    )
    swapped = ranger.measure_repeated(room, pose, 2, None, ("T2", "T1")).distances
    np.testing.assert_array_equal(swapped[:, :, ::-1], first)
    moved = [{**e, "position": [e["position"][0] + 0.5, *e["position"][1:]]} for e in EMITTERS]
    other = world(
        20.0,
        room={"min": [-2, -2], "max": [2, 2]},
        emitters=moved,
        robot={"radius": 0.25, "sensor_height": 0.5},
    )
    again = ranger.measure_repeated(other, pose, 2, None, ["T1", "T2"]).distances
    np.testing.assert_allclose(
        again[0], exact_distances(pose, ranger.receivers_xy, 0.5, moved)[:, :2], rtol=1e-12
    )
    walled = ceiling_room(walls=[{"a": [0.5, -1.0], "b": [0.5, 1.0]}])
    assert np.isnan(ranger.measure_repeated(walled, pose, 2, None, ["T1"]).distances).all()
    assert not np.isnan(ranger.measure_repeated(room, pose, 2, None, ["T1"]).distances).any()


@pytest.mark.parametrize(("noise", "quantisation"), [(True, True), (True, False), (False, True)])
def test_the_compiled_rounds_give_the_bits_of_the_array_form(
    noise: bool, quantisation: bool
) -> None:
    room = ceiling_room(walls=[{"a": [1.0, -1.0], "b": [1.0, 1.0]}])
    ranger = BeaconRanger.wu_tsai(noise=noise, quantisation=quantisation, max_range_m=2.3)
    rng = np.random.default_rng(4)
    xy = rng.uniform(-1.9, 1.9, (300, 2))
    geometry = ranger.route_geometry(room, xy, headings_rad=rng.uniform(-3.0, 3.0, 300))
    assert geometry.heard.any() and not geometry.heard.all()
    measured = ranger.measure_geometry(geometry, 31.0, np.random.default_rng(9))
    # the array form: steps 2-4 of the module docstring on whole arrays
    true_speed = speed_of_sound_mps(31.0)
    tof = geometry.true_distances / true_speed
    if noise:
        normals = np.random.default_rng(9).standard_normal(tof.shape)
        tof = np.maximum(tof + normals * (ranger.range_noise_std_m / true_speed), 0.0)
    if quantisation:
        tof = np.floor(tof / ranger.timer_period_s) * ranger.timer_period_s
    start = ranger.firing_interval_s * np.arange(3, dtype=np.float64)
    heard = geometry.heard
    distances = np.where(heard, tof * ranger.assumed_speed_of_sound_mps, np.nan)
    timestamps = np.where(heard, start + tof, start + ranger.firing_interval_s)
    assert measured.distances.tobytes() == distances.tobytes()
    assert measured.timestamps_s.tobytes() == timestamps.tobytes()


@pytest.mark.parametrize("quantisation", [True, False])
def test_a_jitter_as_large_as_the_distance_never_reads_below_zero(quantisation: bool) -> None:
    """The counter starts when the emitter fires: a time of flight cannot come out negative."""
    room = ceiling_room()
    ranger = dataclasses.replace(
        BeaconRanger.wu_tsai(quantisation=quantisation), range_noise_std_m=2.0
    )
    rounds = ranger.measure_repeated(room, Pose(0.0, 0.0, 0.0), 400, np.random.default_rng(1))
    distances = rounds.distances[np.isfinite(rounds.distances)]
    assert distances.size > 1000
    assert distances.min() == 0.0 and (distances > 0.0).mean() > 0.3
    starts = ranger.firing_interval_s * np.arange(rounds.distances.shape[-1])
    assert (rounds.timestamps_s >= starts).all()


def test_emitter_names_may_be_any_iterable_of_names_once() -> None:
    ranger = BeaconRanger.wu_tsai(noise=False)
    rounds = ranger.measure_repeated(ceiling_room(), Pose(0.2, 0.1), 2, None, iter(["T3", "T1"]))
    assert rounds.emitter_names == ("T3", "T1") and rounds.distances.shape == (2, 2, 2)
