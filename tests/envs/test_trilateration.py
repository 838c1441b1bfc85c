"""Trilateration-specific behaviour: arguments, episode structure, reward, fixes, agents."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.agents import make_agent
from sonar_gym.envs.trilateration import (
    TransmitterFrame,
    predicted_fix_covariance,
    quantised_range_error,
)
from sonar_gym.localization.wu_tsai import PAPER_RECEIVER_OFFSETS_M, localize
from sonar_gym.pose import Pose, angle_difference
from sonar_gym.scenario import load_scenario
from sonar_gym.sonar.acoustics import speed_of_sound_mps
from sonar_gym.sonar.ranging import BeaconRanger
from sonar_gym.world import World

ENV_ID = "SonarGym/Trilateration-v0"
A_M = 0.2
EXACT_RANGING = {"range_noise_std_m": 0.0, "counter_rate_hz": 1e9}
NOISE_FREE_ODOMETRY = {
    "encoder_std_m_per_sqrt_m": 0.0,
    "wheel_scale_error_std": 0.0,
    "slip_probability_per_m": 0.0,
}


def run_episode(env: gym.Env, agent_name: str, seed: int) -> tuple[float, list[dict]]:
    agent = make_agent(agent_name, env)
    agent.reset(seed=seed)
    observation, info = env.reset(seed=seed)
    total, infos = 0.0, []
    while True:
        observation, reward, terminated, truncated, info = env.step(agent.act(observation))
        total += reward
        infos.append(info)
        if terminated or truncated:
            return total, infos


def receivers_xyz(pose_in_t: Pose, z_m: float) -> np.ndarray:
    points = [pose_in_t.transform_point(xy) for xy in PAPER_RECEIVER_OFFSETS_M]
    return np.array([[x, y, z_m] for x, y in points])


def exact_distances(pose_in_t: Pose, z_m: float) -> np.ndarray:
    transmitters = np.array([[0.0, 0.0, 0.0], [A_M, 0.0, 0.0], [0.0, A_M, 0.0]])
    receivers = receivers_xyz(pose_in_t, z_m)
    return np.linalg.norm(receivers[:, None, :] - transmitters[None, :, :], axis=2)


# --------------------------------------------------------------------------------------------
# arguments


@pytest.mark.parametrize(
    ("argument", "value"),
    [
        ("fix_counts", ()),
        ("fix_counts", (0, 10, 10)),
        ("fix_counts", (-1, 5)),
        ("fix_counts", (1.5,)),
        ("route_length_m", 0.0),
        ("n_decision_points", 0),
        ("n_decision_points", 2.5),
        ("correction", "average"),
        ("sensing_cost_per_s", -0.1),
        ("position_scale_m", 0.0),
        ("heading_scale_deg", 0.0),
        ("temperature_c", 99.0),
        ("counter_rate_hz", 0.0),
        ("range_noise_std_m", -0.001),
        ("firing_interval_s", 0.0),
        ("slip_probability_per_m", 1.5),
        ("initial_heading_std_deg", -1.0),
        ("robot_speed_mps", 0.0),
    ],
)
def test_bad_argument_is_named_in_the_error(argument: str, value: object) -> None:
    with pytest.raises(ValueError, match=argument):
        gym.make(ENV_ID, **{argument: value})


def test_legs_that_do_not_fit_in_the_room_are_rejected() -> None:
    with pytest.raises(ValueError, match="route_length_m"):
        gym.make(ENV_ID, route_length_m=20.0, n_decision_points=2)


def test_unknown_scenario_and_scenario_without_transmitters_are_rejected() -> None:
    with pytest.raises(ValueError, match="no_such_room"):
        gym.make(ENV_ID, scenario="no_such_room")
    with pytest.raises(ValueError, match="emitters"):
        gym.make(ENV_ID, scenario="kim_arena")


def test_actions_map_to_fix_counts_and_the_paper_action_is_ten() -> None:
    env = gym.make(ENV_ID).unwrapped
    assert env.action_space.n == 7
    for n in (0, 1, 2, 3, 5, 10, 20):
        assert env.fix_count(env.action_for(n)) == n
    assert env.fix_count(env.paper_action) == 10
    assert (
        gym.make(ENV_ID, fix_counts=(0, 4, 12)).unwrapped.fix_count(
            gym.make(ENV_ID, fix_counts=(0, 4, 12)).unwrapped.paper_action
        )
        == 12
    )
    with pytest.raises(ValueError, match="n_fixes"):
        env.action_for(7)


# --------------------------------------------------------------------------------------------
# episode structure and reward


def test_episode_has_one_step_per_decision_point_and_ends_ok() -> None:
    env = gym.make(ENV_ID, n_decision_points=5, route_length_m=4.0)
    _, info = env.reset(seed=2)
    assert info["status"] == "running" and info["decision_point"] == 0
    layout = env.unwrapped.observation_layout
    action = env.unwrapped.action_for(3)
    for step in range(1, 6):
        observation, _, terminated, truncated, info = env.step(action)
        assert not truncated
        assert terminated == (step == 5)
        assert info["status"] == ("ok" if step == 5 else "running")
        assert info["decision_point"] == step
        assert info["sensing_time_s"] == pytest.approx(step * 3 * 3 * 0.05, abs=1e-12)
        if step < 5:
            assert observation[layout["progress"]][0] == pytest.approx(step / 5)
            assert observation[layout["steps_remaining"]][0] == pytest.approx((5 - step) / 5)


def test_reward_is_the_documented_error_score_minus_the_time_cost() -> None:
    cost, position_scale, heading_scale_deg = 0.7, 0.02, 2.0
    env = gym.make(
        ENV_ID,
        sensing_cost_per_s=cost,
        position_scale_m=position_scale,
        heading_scale_deg=heading_scale_deg,
    )
    env.reset(seed=9)
    for n in (0, 2, 5, 20):
        _, reward, _, _, info = env.step(env.unwrapped.action_for(n))
        truth, estimate = info["true_pose"], info["estimated_pose"]
        position_error = math.hypot(*(estimate[:2] - truth[:2]))
        heading_error = abs(angle_difference(estimate[2], truth[2]))
        assert info["position_error_m"] == pytest.approx(position_error, rel=1e-12)
        assert info["heading_error_rad"] == pytest.approx(heading_error, rel=1e-12)
        assert info["measurement_time_s"] == pytest.approx(n * 3 * 0.05, abs=1e-12)
        expected = -(
            position_error / position_scale + heading_error / math.radians(heading_scale_deg)
        )
        expected -= cost * n * 0.15
        assert reward == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("firing_interval_s", [0.05, 0.07])
def test_measurement_time_is_the_sum_of_the_round_durations(firing_interval_s: float) -> None:
    """The rounds' durations summed as numpy sums them, also when a fix count comes again."""
    env = gym.make(ENV_ID, firing_interval_s=firing_interval_s, n_decision_points=12)
    env.reset(seed=2)
    duration = 3 * firing_interval_s
    for n in (20, 3, 20, 10, 3, 1, 10):
        info = env.step(env.unwrapped.action_for(n))[4]
        expected = float(np.sum(np.full(n, duration)))
        assert info["measurement_time_s"] == expected
        assert info["sensing_time_s"] > 0.0


def test_no_fix_keeps_dead_reckoning_and_a_fix_resets_the_since_fix_features() -> None:
    env = gym.make(ENV_ID, route_length_m=6.0, n_decision_points=6)
    layout = env.unwrapped.observation_layout
    observation, _ = env.reset(seed=4)
    first_distance = observation[layout["distance_since_fix"]][0]
    assert first_distance * 6.0 == pytest.approx(1.0, rel=0.05)  # one 1 m leg driven
    observation, _, _, _, info = env.step(env.unwrapped.action_for(0))
    assert info["fix_status"] == "no_fix" and info["n_fixes_ok"] == 0
    assert info["position_error_m"] == info["dead_reckoning_position_error_m"]
    assert "fix_position_error_m" not in info
    assert observation[layout["distance_since_fix"]][0] > first_distance
    assert observation[layout["time_since_fix"]][0] > 0.0
    observation, _, _, _, info = env.step(env.unwrapped.action_for(10))
    assert info["fix_status"] == "ok" and info["n_fixes_ok"] == 10
    assert info["position_error_m"] == pytest.approx(info["fix_position_error_m"])  # replace
    # the next observation is after one more leg from the fix
    assert observation[layout["distance_since_fix"]][0] * 6.0 == pytest.approx(1.0, rel=0.05)


def test_exact_ranging_gives_the_true_pose_through_the_closed_form() -> None:
    env = gym.make(ENV_ID, **EXACT_RANGING)
    env.reset(seed=1)
    for _ in range(4):
        _, _, _, _, info = env.step(env.unwrapped.action_for(1))
        assert info["position_error_m"] < 1e-5
        assert info["heading_error_rad"] < 1e-4
        assert info["fix_z_m"] == pytest.approx(0.5 - 2.4, abs=1e-5)  # receivers 1.9 m below


def test_noise_free_odometry_keeps_dead_reckoning_exact_and_certain() -> None:
    env = gym.make(ENV_ID, **NOISE_FREE_ODOMETRY)
    layout = env.unwrapped.observation_layout
    observation, _ = env.reset(seed=6)
    for _ in range(6):
        assert observation[layout["dead_reckoning_position_std"]][0] == 0.0
        observation, _, _, _, info = env.step(env.unwrapped.action_for(0))
        assert info["position_error_m"] < 1e-3
        assert info["heading_error_rad"] < 1e-3


def test_dead_reckoning_drifts_and_its_predicted_spread_grows() -> None:
    env = gym.make(ENV_ID)
    layout = env.unwrapped.observation_layout
    errors = []
    for seed in range(10):
        observation, _ = env.reset(seed=seed)
        spreads = []
        for _ in range(8):
            spreads.append(observation[layout["dead_reckoning_heading_std"]][0])
            observation, _, _, _, info = env.step(env.unwrapped.action_for(0))
        errors.append(info["position_error_m"])
        assert all(b > a for a, b in itertools.pairwise(spreads))
    assert np.median(errors) > 0.01  # centimetres after 4 m of dead reckoning


def test_fuse_correction_shrinks_the_predicted_spread_below_both_sources() -> None:
    env = gym.make(
        ENV_ID, correction="fuse", initial_position_std_m=0.05, initial_heading_std_deg=3.0
    )
    env.reset(seed=3)
    before = env.unwrapped._episode.covariance.copy()
    fix_position_std = math.sqrt(
        np.trace(env.unwrapped.fix_covariance(env.unwrapped._episode.estimate, 5)[:2, :2])
    )
    _, _, _, _, info = env.step(env.unwrapped.action_for(5))
    assert info["predicted_position_std_m"] < math.sqrt(before[0, 0] + before[1, 1])
    assert info["predicted_position_std_m"] < fix_position_std
    assert info["position_error_m"] != pytest.approx(info["fix_position_error_m"])


# --------------------------------------------------------------------------------------------
# the uncertainty models


def test_range_error_without_jitter_is_all_persistent_truncation() -> None:
    quantum = 0.00694
    model = quantised_range_error(0.0, quantum)
    assert model.total_variance_m2 == pytest.approx(quantum**2 / 12.0, rel=1e-4)
    assert model.persistent_variance_m2 == pytest.approx(model.total_variance_m2, rel=1e-9)
    assert model.averaging_factor(20) == pytest.approx(1.0)


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("jitter_m", [5e-324, 1e-300, 1e-12])
def test_a_vanishing_jitter_gives_the_counter_alone_without_overflow(jitter_m: float) -> None:
    quantum = 0.00694
    alone = quantised_range_error(0.0, quantum)
    model = quantised_range_error(jitter_m, quantum)
    assert model.total_variance_m2 == pytest.approx(alone.total_variance_m2, rel=1e-6)
    assert model.persistent_variance_m2 == pytest.approx(alone.persistent_variance_m2, rel=1e-6)


def test_range_error_without_counter_is_the_jitter_and_averages_as_one_over_n() -> None:
    model = quantised_range_error(0.003, 0.0)
    assert model.total_variance_m2 == pytest.approx(0.003**2, rel=1e-12)
    assert model.persistent_variance_m2 == 0.0
    assert model.averaging_factor(10) == pytest.approx(0.1, rel=1e-12)


@pytest.mark.parametrize("quantum", [0.00694, 3.43e-7])
def test_the_limit_form_continues_the_average_where_it_takes_over(quantum: float) -> None:
    """From 4 quanta of jitter on, the model is the closed form noise^2 + q^2 / 12: it meets
    the phase average there, and it needs no table (a 1 GHz counter under 0.5 m of jitter
    would have asked for 512 x 23 million floats)."""
    below = quantised_range_error(np.nextafter(4.0 * quantum, 0.0), quantum)
    limit = quantised_range_error(4.0 * quantum, quantum)
    assert limit.total_variance_m2 == pytest.approx(below.total_variance_m2, rel=1e-12)
    assert limit.persistent_variance_m2 == 0.0 and below.persistent_variance_m2 < 1e-20
    huge = quantised_range_error(0.5, quantum)
    assert huge.total_variance_m2 == pytest.approx(0.25 + quantum**2 / 12.0, rel=1e-15)


def test_range_error_with_large_jitter_is_jitter_plus_uniform_quantisation() -> None:
    model = quantised_range_error(0.02, 0.00694)
    assert model.total_variance_m2 == pytest.approx(0.02**2 + 0.00694**2 / 12.0, rel=1e-3)
    assert model.persistent_variance_m2 < 1e-6 * model.total_variance_m2


def test_range_error_model_matches_monte_carlo_of_the_counter() -> None:
    quantum, jitter = 0.00694, 0.002
    model = quantised_range_error(jitter, quantum)
    rng = np.random.default_rng(0)
    distances = rng.uniform(1.0, 3.0, size=4000)
    repeats = distances[:, None] + rng.normal(0.0, jitter, size=(4000, 12))
    errors = quantum * np.floor(repeats / quantum) - distances[:, None]
    errors -= errors.mean()
    assert np.var(errors) == pytest.approx(model.total_variance_m2, rel=0.05)
    assert np.var(errors.mean(axis=1)) == pytest.approx(model.variance_of_mean(12), rel=0.1)


@settings(max_examples=25, deadline=None)
@given(
    x=st.floats(-1.5, 1.5),
    y=st.floats(-1.5, 1.5),
    heading=st.floats(-math.pi, math.pi),
    z=st.floats(-2.2, -1.2),
)
def test_fix_covariance_is_the_linearised_closed_form(
    x: float, y: float, heading: float, z: float
) -> None:
    # Independent check: differentiate the paper's localize() numerically in each distance.
    pose = Pose(x, y, heading)
    distances = exact_distances(pose, z)
    step = 1e-7
    jacobian = np.zeros((3, 6))
    for k in range(6):
        columns = []
        for sign in (1.0, -1.0):
            perturbed = distances.copy()
            perturbed.flat[k] += sign * step
            fix = localize(perturbed, A_M, PAPER_RECEIVER_OFFSETS_M).fix
            assert fix is not None
            columns.append(np.array([fix.x, fix.y, fix.heading]))
        difference = columns[0] - columns[1]
        difference[2] = angle_difference(columns[0][2], columns[1][2])
        jacobian[:, k] = difference / (2.0 * step)
    variance = 1e-6
    expected = variance * jacobian @ jacobian.T
    predicted = predicted_fix_covariance(pose, z, A_M, variance)
    np.testing.assert_allclose(predicted, expected, rtol=1e-4, atol=1e-6 * np.abs(expected).max())


def test_fix_error_grows_away_from_below_the_transmitters() -> None:
    near = predicted_fix_covariance(Pose(0.07, 0.07, 0.3), -1.9, A_M, 1e-6)
    far = predicted_fix_covariance(Pose(1.5, -1.5, 0.3), -1.9, A_M, 1e-6)
    assert np.trace(far[:2, :2]) > 1.5 * np.trace(near[:2, :2])
    assert far[2, 2] > 1.5 * near[2, 2]
    # ... and so does the simulated scatter of single fixes
    world = World(load_scenario("wu_tsai_room"), temperature_c=27.0)
    ranger = BeaconRanger.wu_tsai().with_assumed_speed(speed_of_sound_mps(27.0))
    rng = np.random.default_rng(3)
    rms = {}
    for name, pose in (("near", Pose(0.07, 0.07, 0.3)), ("far", Pose(1.5, -1.5, 0.3))):
        errors = []
        for _ in range(300):
            fix = localize(
                ranger.measure(world, pose, rng).distances, A_M, PAPER_RECEIVER_OFFSETS_M
            ).fix
            assert fix is not None
            errors.append((fix.x - pose.x) ** 2 + (fix.y - pose.y) ** 2)
        rms[name] = math.sqrt(np.mean(errors))
    assert rms["far"] > 1.2 * rms["near"]


def test_predicted_spread_of_averaged_fixes_matches_the_simulated_scatter() -> None:
    env = gym.make(ENV_ID).unwrapped
    world = World(load_scenario("wu_tsai_room"), temperature_c=27.0)
    rng = np.random.default_rng(11)
    pose = Pose(0.8, -0.5, 2.0)
    for n in (1, 10):
        predicted = env.fix_covariance(pose, n)
        samples = []
        for _ in range(150):
            fixes = [
                localize(
                    env.ranger.measure(world, pose, rng).distances, A_M, PAPER_RECEIVER_OFFSETS_M
                ).fix
                for _ in range(n)
            ]
            x = np.mean([f.x for f in fixes])
            y = np.mean([f.y for f in fixes])
            theta = math.atan2(
                np.mean([math.sin(f.heading) for f in fixes]),
                np.mean([math.cos(f.heading) for f in fixes]),
            )
            samples.append((x - pose.x, y - pose.y, angle_difference(theta, pose.theta)))
        samples = np.array(samples)
        measured_position = math.sqrt(np.mean(samples[:, 0] ** 2 + samples[:, 1] ** 2))
        measured_heading = math.sqrt(np.mean(samples[:, 2] ** 2))
        assert measured_position == pytest.approx(math.sqrt(np.trace(predicted[:2, :2])), rel=0.3)
        assert measured_heading == pytest.approx(math.sqrt(predicted[2, 2]), rel=0.3)


def test_transmitter_frame_of_a_rotated_ceiling_places_fixes_in_the_world(tmp_path: Path) -> None:
    angle = math.radians(30.0)
    origin = (0.3, -0.2)
    points = [
        origin,
        (origin[0] + A_M * math.cos(angle), origin[1] + A_M * math.sin(angle)),
        (origin[0] - A_M * math.sin(angle), origin[1] + A_M * math.cos(angle)),
    ]
    emitters = "\n".join(
        f'[[emitters]]\nname = "T{k}"\nposition = [{x!r}, {y!r}, 2.6]\n'
        for k, (x, y) in enumerate(points, 1)
    )
    path = tmp_path / "rotated.toml"
    path.write_text(
        '[meta]\nname = "rotated"\n[room]\nmin = [-2.0, -2.0]\nmax = [2.0, 2.0]\n'
        f"{emitters}[robot]\nradius = 0.25\nwheel_base = 0.35\nsensor_height = 0.6\n"
    )
    frame = TransmitterFrame.from_scenario(load_scenario(path))
    assert frame.rotation_rad == pytest.approx(angle, abs=1e-12)
    assert frame.spacing_m == pytest.approx(A_M, rel=1e-12)
    pose = Pose(-1.0, 0.7, 2.5)
    back = frame.to_world(frame.to_transmitter(pose))
    assert (back.x, back.y) == pytest.approx((pose.x, pose.y), abs=1e-12)
    assert angle_difference(back.theta, pose.theta) == pytest.approx(0.0, abs=1e-12)
    env = gym.make(ENV_ID, scenario=str(path), **EXACT_RANGING)
    env.reset(seed=0)
    _, _, _, _, info = env.step(env.unwrapped.action_for(1))
    assert info["position_error_m"] < 1e-5 and info["heading_error_rad"] < 1e-4
    assert info["fix_z_m"] == pytest.approx(0.6 - 2.6, abs=1e-5)


# --------------------------------------------------------------------------------------------
# agents


def test_paper_agent_takes_ten_fixes_and_its_errors_are_of_the_papers_order() -> None:
    env = gym.make(ENV_ID)
    position, heading = [], []
    for seed in range(5):
        _, infos = run_episode(env, "paper", seed)
        assert {info["n_fixes"] for info in infos} == {10}
        position += [info["position_error_m"] for info in infos]
        heading += [info["heading_error_rad"] for info in infos]
    # Tables I-II: estimates within 0.5-3.6 cm and 0.5-1.7 deg of the truth (the 50 kHz
    # counter gives wider heading scatter here than the paper's; see train/reproduce/wu_tsai).
    assert 0.003 < np.mean(position) < 0.036
    assert math.radians(0.5) < np.mean(heading) < math.radians(5.0)


def test_adaptive_agent_beats_the_paper_agent_on_paired_seeds() -> None:
    env = gym.make(ENV_ID)
    differences = []
    for seed in range(1000, 1030):
        paper, _ = run_episode(env, "paper", seed)
        adaptive, _ = run_episode(env, "adaptive", seed)
        differences.append(adaptive - paper)
    mean = float(np.mean(differences))
    standard_error = float(np.std(differences, ddof=1)) / math.sqrt(len(differences))
    assert mean > 1.0
    assert mean > 2.0 * standard_error


def test_adaptive_agent_skips_fixes_when_dead_reckoning_is_good_and_measures_when_it_is_not() -> (
    None
):
    env = gym.make(ENV_ID)
    agent = make_agent("adaptive", env)
    counts_first, counts_after_drift = [], []
    for seed in range(5):
        agent.reset(seed)
        observation, _ = env.reset(seed=seed)
        counts_first.append(env.unwrapped.fix_count(agent.act(observation)))  # known start
        for _ in range(8):  # 4.5 m of dead reckoning in all
            observation, *_ = env.step(env.unwrapped.action_for(0))
        counts_after_drift.append(env.unwrapped.fix_count(agent.act(observation)))
    assert counts_first == [0] * 5
    assert min(counts_after_drift) >= 5


def test_fix_covariance_of_receivers_at_one_place_raises_naming_the_argument() -> None:
    with pytest.raises(ValueError, match="receivers_xy"):
        predicted_fix_covariance(Pose(0.3, 0.2, 0.1), -1.9, A_M, 1e-6, ((0.1, 0.0), (0.1, 0.0)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_observation_vector_matches_the_feature_spec_written_by_name(seed: int) -> None:
    from sonar_gym.envs.features import Heading, ScaledPosition
    from sonar_gym.envs.trilateration_observation import (
        OBSERVATION,
        FeatureScales,
        saturate,
        trilateration_observation,
    )
    from sonar_gym.localization.wu_tsai_models import heading_std_rad, position_std_m

    rng = np.random.default_rng(seed)
    scales = FeatureScales(
        centre_xy=rng.uniform(-1, 1, 2),
        half_size_xy=rng.uniform(1, 3, 2),
        transmitter_centroid_xy=rng.uniform(-1, 1, 2),
        route_length_m=8.0,
        position_scale_m=0.05,
        heading_scale_rad=math.radians(3.0),
        n_decision_points=16,
    )
    x, y = rng.uniform(-4, 4, 2).tolist()
    estimate = Pose(x, y, float(rng.uniform(-3, 3)))  # partly beyond the room
    covariance, single = (np.diag(rng.uniform(0, 1e-3, 3)) for _ in range(2))
    vector = trilateration_observation(scales, estimate, covariance, single, 3.0, 12.0, 5)
    writer = OBSERVATION.writer()
    writer["estimated_xy"] = ScaledPosition.centred_values(
        estimate.position, scales.centre_xy, scales.half_size_xy
    )
    writer["estimated_heading"] = Heading.values(estimate.theta)
    writer["time_since_fix"] = 3.0 / 13.0
    writer["distance_since_fix"] = 1.0
    writer["dead_reckoning_position_std"] = saturate(position_std_m(covariance), 0.05)
    writer["dead_reckoning_heading_std"] = saturate(heading_std_rad(covariance), math.radians(3))
    offset = estimate.position - scales.transmitter_centroid_xy
    writer["transmitter_offset"] = np.clip(offset / scales.half_size_xy, -1.0, 1.0)
    writer["transmitter_distance"] = min(
        float(np.linalg.norm(offset)) / float(np.linalg.norm(scales.half_size_xy)), 1.0
    )
    writer["fix_position_std"] = saturate(position_std_m(single), 0.05)
    writer["fix_heading_std"] = saturate(heading_std_rad(single), math.radians(3))
    writer["progress"] = 5 / 16
    writer["steps_remaining"] = 11 / 16
    assert vector.dtype == np.float32
    np.testing.assert_array_equal(vector, writer.vector)


def test_transmitter_frame_changes_keep_the_pose_checks_on_overflow() -> None:
    frame = TransmitterFrame((1.0, -2.0, 2.6), math.radians(30.0), A_M, ("T1", "T2", "T3"))
    pose = Pose(-1.0, 0.7, 2.5)
    back = frame.to_world(frame.to_transmitter(pose)).as_array()
    assert back == pytest.approx(pose.as_array(), abs=1e-12)
    with pytest.raises(ValueError, match=r"Pose\.[xy] must be finite"):
        frame.to_world(Pose(1.5e308, 1.5e308, 0.0))
    with pytest.raises(ValueError, match=r"Pose\.[xy] must be finite"):
        frame.to_transmitter(Pose(1.7e308, 1.7e308, 0.0))


def test_the_largest_jitter_and_finest_counter_allowed_run_episodes() -> None:
    """``range_noise_std_m=0.5`` against ranges of a metre or two (the counter cannot read a
    negative time of flight) and a 1 GHz counter under it (the error model's closed form)."""
    for kwargs in ({"fix_counts": [200]}, {"counter_rate_hz": 1e9}):
        env = gym.make("SonarGym/Trilateration-v0", range_noise_std_m=0.5, **kwargs)
        env.reset(seed=8)
        for _ in range(16):
            observation, reward, terminated, truncated, _ = env.step(0)
            assert np.isfinite(observation).all() and math.isfinite(reward)
            if terminated or truncated:
                break
