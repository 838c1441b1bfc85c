"""BlockExpansion-specific behaviour: arguments, the d encodings, the episode structure, the
sensor seam, the reward, the paper's accuracy and the spread agent's advantage."""

from __future__ import annotations

import doctest
import math
import pickle

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sonar_gym.envs.block_expansion as block_expansion_module
import sonar_gym  # noqa: F401
from sonar_gym.agents import make_agent
from sonar_gym.agents.block_expansion import (
    PAPER_FIRST_TRIPLE_M,
    PAPER_SECOND_TRIPLE_M,
    condition_number,
    dilution_of_precision,
    replay_extraction,
)
from sonar_gym.envs.block_expansion import DECREASING_GAP_M, FIRING_INTERVAL_S
from sonar_gym.maps import MAP_FRAME_CENTRE_M as FRAME_CENTRE_M
from sonar_gym.maps import MAP_FRAME_HALF_SPAN_M as FRAME_HALF_SPAN_M
from sonar_gym.localization.roh import (
    TABLE_I_BEACONS_MM,
    TABLE_II_III_D_MM,
    ThreePointExtractor,
    distance_to_segment,
    paper_centroid,
    parabolic_path,
    radical_centre,
)
from sonar_gym.sonar.acoustics import speed_of_sound_mps

ENV_ID = "SonarGym/BlockExpansion-v0"
PAPER_TABLE_III_SIGMA_PRIME_450_250_50_MM = 16.3


def run_episode(env: gym.Env, agent_name: str, seed: int) -> tuple[float, dict, int]:
    agent = make_agent(agent_name, env)
    agent.reset(seed=seed)
    observation, _ = env.reset(seed=seed)
    total, steps = 0.0, 0
    while True:
        observation, reward, terminated, truncated, info = env.step(agent.act(observation))
        total += reward
        steps += 1
        if terminated or truncated:
            return total, info, steps


def mean_and_half_width(values: list[float]) -> tuple[float, float]:
    array = np.asarray(values)
    return float(array.mean()), 1.96 * float(array.std(ddof=1)) / math.sqrt(len(array))


# --- arguments and spaces ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("argument", "value"),
    [
        ("n_areas", 4),
        ("n_areas", 2.5),
        ("layout", "grid"),
        ("path", "straight"),
        ("decisions", "sometimes"),
        ("ordering", "sorted"),
        ("distance_range_m", (0.5, 0.1)),
        ("distance_range_m", 0.5),
        ("range_noise_std_m", -0.001),
        ("timer_period_s", 1.0),
        ("timer_period_s", 5e-324),
        ("max_range_m", 0.0),
        ("beacon_prior_std_m", -1.0),
        ("sigma_scale_m", 0.0),
        ("failure_penalty", -1.0),
        ("sensing_cost_per_s", -0.1),
        ("trilateration_method", "magic"),
    ],
)
def test_bad_argument_is_named_in_the_error(argument: str, value: object) -> None:
    with pytest.raises(ValueError, match=argument.replace("[", r"\[")):
        gym.make(ENV_ID, **{argument: value})


@pytest.mark.parametrize(
    ("kwargs", "shape"),
    [
        ({}, (3,)),
        ({"n_areas": 3}, (3,)),
        ({"n_areas": 3, "decisions": "all_at_once"}, (6,)),
        ({"n_areas": 2, "decisions": "all_at_once"}, (3,)),
    ],
)
def test_action_space_holds_one_triple_per_boundary_decided(kwargs: dict, shape: tuple) -> None:
    env = gym.make(ENV_ID, **kwargs)
    assert env.action_space.shape == shape
    assert env.action_space.dtype == np.float32
    assert np.all(env.action_space.low == -1.0) and np.all(env.action_space.high == 1.0)


def test_observation_layout_tiles_the_observation() -> None:
    env = gym.make(ENV_ID).unwrapped
    covered = sorted(
        index for part in env.observation_layout.values() for index in range(part.start, part.stop)
    )
    assert covered == list(range(env.observation_space.shape[0]))


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0.02, 0.8), min_size=3, max_size=3))
def test_free_ordering_encodes_any_distances_and_decodes_them_back(distances: list[float]) -> None:
    env = gym.make(ENV_ID).unwrapped
    (decoded,) = env.decode_action(env.encode_distances(distances))
    np.testing.assert_allclose(decoded, distances, atol=1e-6)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3))
def test_decreasing_ordering_always_gives_strictly_decreasing_distances(
    action: list[float],
) -> None:
    env = gym.make(ENV_ID, ordering="decreasing").unwrapped
    (d,) = env.decode_action(np.asarray(action, dtype=np.float32))
    low, high = env.config.distance_range_m
    assert low - 1e-12 <= d[2] and d[0] <= high + 1e-12
    assert d[0] - d[1] >= DECREASING_GAP_M - 1e-9
    assert d[1] - d[2] >= DECREASING_GAP_M - 1e-9


@pytest.mark.parametrize("row_mm", TABLE_II_III_D_MM)
def test_decreasing_ordering_expresses_every_row_of_tables_ii_iii(row_mm: tuple) -> None:
    env = gym.make(ENV_ID, ordering="decreasing").unwrapped
    distances = [d / 1000.0 for d in row_mm]
    (decoded,) = env.decode_action(env.encode_distances(distances))
    np.testing.assert_allclose(decoded, distances, atol=1e-6)


# --- the paper's setup and the sensor seam --------------------------------------------------


def test_default_episode_is_table_i_and_the_paper_like_parabola() -> None:
    env = gym.make(ENV_ID).unwrapped
    env.reset(seed=0)
    for name, position in env.beacons_m.items():
        np.testing.assert_array_equal(position, np.array(TABLE_I_BEACONS_MM[name]) / 1000.0)
    assert sorted(env.beacons_m) == ["A", "B", "C", "D"]
    np.testing.assert_array_equal(env.path_m, parabolic_path(x_end_m=1.3))


def test_noise_free_ranging_localizes_the_whole_path_exactly() -> None:
    env = gym.make(ENV_ID, n_areas=3, range_noise_std_m=0.0, timer_period_s=0.0)
    total, info, steps = run_episode(env, "paper", seed=1)
    assert steps == 2 and info["status"] == "ok"
    assert info["sigma_prime_m"] < 1e-9 and info["sigma_m"] < 1e-9
    assert max(info["calibration_errors_m"].values()) < 1e-9
    assert total == pytest.approx(-info["sigma_prime_m"] / 0.03, abs=1e-12)


def test_ranges_come_from_the_ranger_counter_and_its_time_is_counted() -> None:
    period_s = 1e-4
    env = gym.make(ENV_ID, range_noise_std_m=0.0, timer_period_s=period_s)
    unwrapped = env.unwrapped
    env.reset(seed=2)
    ranges = unwrapped.measured_ranges_m
    path = unwrapped.path_m
    beacons = np.array(list(unwrapped.beacons_m.values()))
    height = unwrapped.sensor_height_m
    true = np.sqrt(
        ((path[:, None, :] - beacons[None, :, :2]) ** 2).sum(axis=2)
        + (beacons[None, :, 2] - height) ** 2
    )
    quantum = speed_of_sound_mps(20.0) * period_s
    counts = ranges / quantum
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-6)
    assert np.all(ranges <= true + 1e-12) and np.all(true - ranges < quantum)
    _, _, _, _, info = env.step(unwrapped.encode_distances(PAPER_FIRST_TRIPLE_M))
    assert info["sensing_time_s"] == pytest.approx(len(path) * len(beacons) * FIRING_INTERVAL_S)


def test_beacons_out_of_range_drop_out_and_cost_the_capped_losses() -> None:
    env = gym.make(ENV_ID, max_range_m=0.5)
    env.reset(seed=0)
    assert np.all(np.isnan(env.unwrapped.measured_ranges_m))
    _, reward, terminated, _, info = env.step(env.unwrapped.encode_distances(PAPER_FIRST_TRIPLE_M))
    assert terminated and info["status"] == "not_reached"
    assert info["failed_fix_fraction"] == 1.0
    assert reward == pytest.approx(-2.0 * env.unwrapped.config.failure_penalty)
    assert math.isfinite(info["position_error_m"])


def test_localization_follows_the_papers_centroid_reading_not_the_radical_centre() -> None:
    env = gym.make(ENV_ID, range_noise_std_m=0.005)
    unwrapped = env.unwrapped
    env.reset(seed=4)
    env.step(unwrapped.encode_distances(PAPER_FIRST_TRIPLE_M))
    beacons = np.array([unwrapped.beacons_m[name] for name in "ABC"])
    ranges = unwrapped.measured_ranges_m[0, :3]
    radii = np.sqrt(ranges**2 - (beacons[:, 2] - unwrapped.sensor_height_m) ** 2)
    expected, fell_back = paper_centroid(beacons[:, :2], radii)
    assert not fell_back
    first_fix = unwrapped.result.localizations[0].position
    np.testing.assert_allclose(first_fix, expected, atol=1e-12)
    # the literal reading (the radical axes' common point) is a different estimate
    assert np.linalg.norm(first_fix - radical_centre(beacons[:, :2], radii)) > 1e-5


# --- episode structure and reward -------------------------------------------------------------


def test_two_areas_take_one_decision_and_reward_minus_sigma_prime_over_its_scale() -> None:
    env = gym.make(ENV_ID, sigma_scale_m=0.06)
    total, info, steps = run_episode(env, "paper", seed=0)
    assert steps == 1 and info["status"] == "ok" and info["failed_fix_fraction"] == 0.0
    assert total == pytest.approx(-info["sigma_prime_m"] / 0.06, rel=1e-12)
    assert info["position_error_m"] == info["sigma_prime_m"]


def test_sensing_cost_is_charged_per_second_of_ranging() -> None:
    free, info, _ = run_episode(gym.make(ENV_ID), "paper", seed=0)
    charged, _, _ = run_episode(gym.make(ENV_ID, sensing_cost_per_s=0.01), "paper", seed=0)
    assert free - charged == pytest.approx(0.01 * info["sensing_time_s"], rel=1e-9)


def test_three_areas_ask_for_the_second_triple_after_the_first_calibration() -> None:
    env = gym.make(ENV_ID, n_areas=3)
    unwrapped = env.unwrapped
    layout = unwrapped.observation_layout
    observation, _ = env.reset(seed=0)
    assert list(observation[layout["boundary"]]) == [1.0, 0.0]
    assert observation[layout["progress"]][0] == 0.0
    assert observation[layout["beacons"]][4 * 3 + 3] == 0.0  # D: rough prior only
    observation, reward, terminated, _, info = env.step(
        unwrapped.encode_distances(PAPER_FIRST_TRIPLE_M)
    )
    assert not terminated and reward == 0.0 and info["status"] == "running"
    assert list(observation[layout["boundary"]]) == [0.0, 1.0]
    switch = unwrapped.result.calibrations[0].switch_index
    n = len(unwrapped.path_m)
    assert observation[layout["progress"]][0] == pytest.approx(switch / (n - 1), rel=1e-6)
    slot_d = observation[layout["beacons"]][12:16]
    assert slot_d[3] == 0.5  # D: calibrated
    calibrated = unwrapped.result.calibrations[0].calibration.position
    np.testing.assert_allclose(
        slot_d[:3], (calibrated - FRAME_CENTRE_M) / FRAME_HALF_SPAN_M, atol=1e-6
    )
    assert observation[layout["previous_calibration"]][0] == 1.0
    assert info["sensing_time_s"] == pytest.approx(switch * 5 * FIRING_INTERVAL_S)
    _, _, terminated, _, info = env.step(unwrapped.encode_distances(PAPER_SECOND_TRIPLE_M))
    assert terminated and info["sensing_time_s"] == pytest.approx(n * 5 * FIRING_INTERVAL_S)
    assert len(info["distances_m"]) == 2


def test_a_failed_first_calibration_ends_a_three_area_episode_with_the_penalty() -> None:
    env = gym.make(ENV_ID, n_areas=3)
    env.reset(seed=0)
    rise_then_fall = env.unwrapped.encode_distances([0.1, 0.7, 0.05])
    _, reward, terminated, _, info = env.step(rise_then_fall)
    assert terminated and info["status"] == "not_reached"
    assert info["calibration_statuses"] == {"D": "not_reached"}
    sigma_loss = min(info["sigma_prime_m"] / 0.03, 10.0)
    assert reward == pytest.approx(-(sigma_loss + 10.0))


def test_deciding_per_boundary_or_all_at_once_gives_the_same_episode() -> None:
    per_boundary = gym.make(ENV_ID, n_areas=3)
    at_once = gym.make(ENV_ID, n_areas=3, decisions="all_at_once")
    first, first_info, _ = run_episode(per_boundary, "paper", seed=3)
    second, second_info, _ = run_episode(at_once, "paper", seed=3)
    assert first == second
    assert first_info["calibration_errors_m"] == second_info["calibration_errors_m"]
    assert first_info["sensing_time_s"] == pytest.approx(second_info["sensing_time_s"])


def test_three_area_episode_pickles_between_its_decisions() -> None:
    env = gym.make(ENV_ID, n_areas=3)
    env.reset(seed=5)
    env.step(env.unwrapped.encode_distances(PAPER_FIRST_TRIPLE_M))
    clone = pickle.loads(pickle.dumps(env))
    action = env.unwrapped.encode_distances(PAPER_SECOND_TRIPLE_M)
    original, copied = env.step(action), clone.step(action)
    np.testing.assert_array_equal(original[0], copied[0])
    assert original[1:4] == copied[1:4]
    assert original[4]["calibration_errors_m"] == copied[4]["calibration_errors_m"]


def test_encoding_the_wrong_number_of_distances_is_an_error() -> None:
    env = gym.make(ENV_ID, n_areas=3, decisions="all_at_once").unwrapped
    with pytest.raises(ValueError, match="distances_m must hold 6"):
        env.encode_distances(PAPER_FIRST_TRIPLE_M)


def test_random_layouts_and_paths_vary_and_cross_every_boundary_once() -> None:
    env = gym.make(ENV_ID, n_areas=3, layout="random", path="random").unwrapped
    paths = []
    for seed in range(4):
        env.reset(seed=seed)
        beacons = {name: np.array(xyz) for name, xyz in env.beacons_m.items()}
        path = env.path_m
        paths.append(path[len(path) // 2])
        for a, b in (("B", "C"), ("B", "D")):
            direction = beacons[b][:2] - beacons[a][:2]
            offset = path - beacons[a][:2]
            side = np.sign(direction[0] * offset[:, 1] - direction[1] * offset[:, 0])
            assert np.count_nonzero(side[1:] != side[:-1]) == 1
    assert len({tuple(np.round(p, 6)) for p in paths}) == 4


def test_env_docstring_example_holds() -> None:
    finder = doctest.DocTestFinder()
    runner = doctest.DocTestRunner()
    for test in finder.find(block_expansion_module.BlockExpansionEnv, globs={}):
        runner.run(test)
    assert runner.failures == 0 and runner.tries > 0


# --- agents -------------------------------------------------------------------------------------


def test_paper_agent_errors_are_of_the_papers_order() -> None:
    env = gym.make(ENV_ID)
    sigma_primes = []
    for seed in range(6):
        _, info, _ = run_episode(env, "paper", seed)
        assert info["distances_m"] == [pytest.approx(list(PAPER_FIRST_TRIPLE_M), abs=1e-6)]
        if info["status"] == "ok":
            sigma_primes.append(1000.0 * info["sigma_prime_m"])
    median = float(np.median(sigma_primes))
    paper = PAPER_TABLE_III_SIGMA_PRIME_450_250_50_MM
    assert paper / 4.0 < median < paper * 4.0


def test_spread_agent_beats_the_paper_over_two_areas() -> None:
    env = gym.make(ENV_ID)
    paper = [run_episode(env, "paper", seed)[0] for seed in range(8)]
    spread = [run_episode(env, "spread", seed)[0] for seed in range(8)]
    paper_mean, paper_half = mean_and_half_width(paper)
    spread_mean, spread_half = mean_and_half_width(spread)
    assert spread_mean - spread_half > paper_mean + paper_half


def test_spread_agent_calibrates_both_beacons_over_three_areas() -> None:
    env = gym.make(ENV_ID, n_areas=3)
    for seed in range(3):
        spread, info, steps = run_episode(env, "spread", seed)
        assert info["status"] == "ok" and steps == 2
        paper, _, _ = run_episode(env, "paper", seed)
        assert spread > paper


def test_spread_agent_respects_the_decreasing_ordering() -> None:
    env = gym.make(ENV_ID, ordering="decreasing")
    _, info, _ = run_episode(env, "spread", seed=0)
    ((d1, d2, d3),) = info["distances_m"]
    assert d1 > d2 > d3 and info["status"] == "ok"


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.integers(0, 26), min_size=3, max_size=3),
    st.integers(0, 300),
)
def test_replayed_extraction_matches_the_papers_extractor(triple: list[int], start: int) -> None:
    path = parabolic_path(x_end_m=1.3)
    boundary_a = np.array(TABLE_I_BEACONS_MM["B"][:2]) / 1000.0
    boundary_b = np.array(TABLE_I_BEACONS_MM["C"][:2]) / 1000.0
    grid = np.linspace(0.02, 0.8, 27)
    distance = distance_to_segment(path, boundary_a, boundary_b)
    (replayed,) = replay_extraction(distance, grid, np.array([triple]), start)
    extractor = ThreePointExtractor(boundary_a, boundary_b, grid[triple])
    for index in range(start, len(path)):
        extractor.update(path[index], index)
    expected = list(extractor.result().indices) + [len(path)] * (3 - extractor.found)
    assert list(replayed) == expected


def test_condition_number_and_dilution_of_precision_match_their_definitions() -> None:
    rng = np.random.default_rng(0)
    u, v = rng.normal(size=(5, 2)), rng.normal(size=(5, 2))
    singular = np.linalg.svd(np.stack([u, v], axis=1), compute_uv=False)
    np.testing.assert_allclose(condition_number(u, v), singular[:, 0] / singular[:, 1], rtol=1e-9)
    assert condition_number(np.array([[1.0, 0.0]]), np.array([[2.0, 0.0]]))[0] == np.inf
    points = rng.uniform(0.0, 2.0, size=(4, 3, 2))
    beacon = np.array([1.0, 1.0, 1.5])
    result = dilution_of_precision(points, beacon, 0.3)
    for k in range(4):
        offsets = beacon - np.column_stack([points[k], np.full(3, 0.3)])
        h = offsets / np.linalg.norm(offsets, axis=1, keepdims=True)
        expected = math.sqrt(np.trace(np.linalg.inv(h.T @ h)))
        assert result[k] == pytest.approx(expected, rel=1e-9)


def test_ranging_along_a_route_reuses_its_geometry_only_for_the_same_beacons() -> None:
    from sonar_gym.routes import range_along_route

    env = gym.make(ENV_ID)
    env.reset(seed=0)
    unwrapped = env.unwrapped
    episode = unwrapped._require_episode()
    names = tuple(episode.beacons_m)
    geometry = unwrapped.ranger.route_geometry(episode.world, episode.path, names)
    fresh, _ = range_along_route(
        unwrapped.ranger, episode.world, episode.path, names, np.random.default_rng(3)
    )
    reused, durations = range_along_route(
        unwrapped.ranger, episode.world, episode.path, names, np.random.default_rng(3), geometry
    )
    np.testing.assert_array_equal(fresh, reused)
    np.testing.assert_allclose(durations, len(names) * FIRING_INTERVAL_S)
    with pytest.raises(ValueError, match="geometry"):
        range_along_route(
            unwrapped.ranger,
            episode.world,
            episode.path,
            names[::-1],
            np.random.default_rng(3),
            geometry,
        )


@pytest.mark.parametrize(
    "action",
    [[5.0, 5.0, 5.0], [0.0, -1.5, 0.0], [math.nan, 0.0, 0.0], [0.0, math.inf, 0.0], [0.1, 0.2]],
)
def test_decoding_an_action_outside_the_space_names_it_and_the_allowed_range(
    action: list[float],
) -> None:
    env = gym.make(ENV_ID).unwrapped
    with pytest.raises(
        ValueError, match=r"argument 'action' must be .*: 3 finite numbers in \[-1, 1\]; got"
    ):
        env.decode_action(action)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0, width=32), min_size=3, max_size=3))
def test_every_element_of_the_space_decodes_inside_the_distance_range(action: list[float]) -> None:
    env = gym.make(ENV_ID).unwrapped
    (d,) = env.decode_action(np.asarray(action, dtype=np.float32))
    low, high = env.config.distance_range_m
    assert all(low <= value <= high for value in d)
