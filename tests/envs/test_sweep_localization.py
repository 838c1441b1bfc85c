"""SweepLocalization (Kim et al.): arguments, episode structure, the EKF wiring, the agents."""

from __future__ import annotations

import math
import pickle
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.agents import agent_names, make_agent
from sonar_gym.agents.sweep_localization import CovarianceAgent, PaperAgent, _decode_estimate
from sonar_gym.polyline import leg_is_free as _leg_is_free
from sonar_gym.envs.sweep_localization import (
    HEADING_STD_SCALE_RAD,
    POSITION_STD_SCALE_M,
    SweepLocalizationEnv,
    _relative_pose,
)
from sonar_gym.localization.kim_grid import occupancy_grid_of
from sonar_gym.polyline import Route
from sonar_gym.localization.kim import TABLE_1_ESTIMATED_POSITIONS_M, TABLE_1_TRUE_POSITIONS_M
from sonar_gym.pose import Pose, angle_difference, wrap_angle
from sonar_gym.scenario import load_scenario, scenario_from_dict
from sonar_gym.world import World

ENV_ID = "SonarGym/SweepLocalization-v0"
SRF04_PAN_SPEED_DEG_S = 300.0
SRF04_LISTEN_S = 0.05
WHEEL_BASE_M = 0.15  # kim_arena
TABLE_1_MEAN_ERROR_M = float(
    np.mean(np.linalg.norm(TABLE_1_ESTIMATED_POSITIONS_M - TABLE_1_TRUE_POSITIONS_M, axis=1))
)


def _episode_return(env: gym.Env, agent: object, seed: int) -> float:
    observation, _ = env.reset(seed=seed)
    agent.reset(seed)  # type: ignore[attr-defined]
    total, done = 0.0, False
    while not done:
        action = agent.act(observation)  # type: ignore[attr-defined]
        observation, reward, terminated, truncated, _ = env.step(action)
        total += reward
        done = terminated or truncated
    return total


# -- arguments -------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("argument", "value"),
    [
        ("route", "circle"),
        ("route_length_m", 0.1),
        ("decision_points", "everywhere"),
        ("decision_spacing_m", -0.4),
        ("sweep_spacing_m", 2.0),
        ("max_sweeps", 3),
        ("max_sweeps", 4.5),
        ("sweep_width_deg", 45),
        ("sweep_step_deg", 0.0),
        ("anchor", "corner"),
        ("heading_step_deg", 10.0),
        ("sensing_cost_per_s", -0.1),
        ("max_error_loss", 0.0),
        ("wheel_scale_error_bound", 0.5),
        ("slip_probability_per_m", 1.5),
        ("fix_position_std_m", 0.0),
        ("fix_heading_std_deg", float("nan")),
        ("innovation_gate", 0.0),
        ("temperature_c", 80.0),
        ("n_range_bins", 0),
        ("scenario", "no_such_arena"),
    ],
)
def test_bad_argument_is_named_in_the_error(argument: str, value: object) -> None:
    with pytest.raises(ValueError, match=argument):
        gym.make(ENV_ID, **{argument: value})


def test_table1_route_needs_its_positions_free_in_the_scenario() -> None:
    with pytest.raises(ValueError, match="route"):
        gym.make(ENV_ID, scenario="beom_cho_lab")
    gym.make(ENV_ID, scenario="beom_cho_lab", route="random").reset(seed=0)


def test_encode_action_rejects_unknown_sectors_and_counts() -> None:
    env = gym.make(ENV_ID).unwrapped
    with pytest.raises(ValueError, match="sector"):
        env.encode_action(2, "up")
    with pytest.raises(ValueError, match="n_sweeps"):
        env.encode_action(5, "front")
    np.testing.assert_array_equal(env.encode_action(4, "back"), [4, 3])


def test_spaces_follow_the_configuration() -> None:
    env = gym.make(ENV_ID, max_sweeps=6, n_range_bins=5)
    np.testing.assert_array_equal(env.action_space.nvec, [7, 4])
    assert env.observation_space.shape == (20,)
    layout = env.unwrapped.observation_layout
    assert sum(s.stop - s.start for s in layout.values()) == 20


# -- episode structure -----------------------------------------------------------------------------


@pytest.mark.parametrize(("decision_points", "decisions"), [("spacing", 9), ("waypoints", 7)])
def test_table1_route_has_one_decision_per_station(decision_points: str, decisions: int) -> None:
    # Table 1's polyline is 3.27 m: ceil(3.27 / 0.4) = 9 stations; or its 7 points.
    length = float(np.sum(np.linalg.norm(np.diff(TABLE_1_TRUE_POSITIONS_M, axis=0), axis=1)))
    assert decisions == (math.ceil(length / 0.4) if decision_points == "spacing" else 7)
    env = gym.make(ENV_ID, decision_points=decision_points)
    observation, info = env.reset(seed=4)
    assert info["status"] == "running"
    layout = env.unwrapped.observation_layout
    assert observation[layout["steps_remaining"]][0] == 1.0
    for step in range(1, decisions + 1):
        observation, _, terminated, truncated, info = env.step(env.unwrapped.encode_action(0))
        assert not truncated
        assert terminated == (step == decisions)
        assert info["status"] == ("ok" if step == decisions else "running")
    assert observation[layout["route_progress"]][0] == pytest.approx(1.0)
    assert observation[layout["steps_remaining"]][0] == 0.0


@pytest.mark.parametrize(("width_deg", "pings"), [(90, 19), (180, 37)])
@pytest.mark.parametrize("n_sweeps", [0, 1, 4])
def test_sweep_time_is_servo_travel_plus_listening(
    width_deg: int, pings: int, n_sweeps: int
) -> None:
    env = gym.make(ENV_ID, sweep_width_deg=width_deg)
    env.reset(seed=0)
    _, _, _, _, info = env.step(env.unwrapped.encode_action(n_sweeps, "left"))
    per_sweep = width_deg / SRF04_PAN_SPEED_DEG_S + pings * SRF04_LISTEN_S
    assert info["step_sensing_time_s"] == pytest.approx(n_sweeps * per_sweep, rel=1e-12)
    assert info["sensing_time_s"] == pytest.approx(n_sweeps * per_sweep, rel=1e-12)
    assert info["n_sweeps"] == n_sweeps and info["sector"] == "left"
    assert (info["fix_status"] == "none") == (n_sweeps == 0)


@pytest.mark.parametrize("n_sweeps", [0, 2])
def test_reward_is_scaled_pose_error_minus_sensing_cost(n_sweeps: int) -> None:
    env = gym.make(ENV_ID, sensing_cost_per_s=0.37)
    env.reset(seed=2)
    _, reward, _, _, info = env.step(env.unwrapped.encode_action(n_sweeps))
    expected = (
        -(info["position_error_m"] / 0.1 + info["heading_error_rad"] / math.radians(5.0))
        - 0.37 * info["step_sensing_time_s"]
    )
    assert reward == pytest.approx(expected, rel=1e-12)
    truth, estimate = info["true_pose"], info["estimated_pose"]
    assert info["position_error_m"] == pytest.approx(
        math.hypot(*(truth[:2] - estimate[:2])), rel=1e-12
    )


def test_a_fix_shrinks_the_covariance_that_dead_reckoning_grows() -> None:
    env = gym.make(ENV_ID)
    observation, _ = env.reset(seed=6)
    layout = env.unwrapped.observation_layout
    env.step(env.unwrapped.encode_action(0))
    clone = pickle.loads(pickle.dumps(env))
    blind, _, _, _, _ = env.step(env.unwrapped.encode_action(0))
    sighted, _, _, _, info = clone.step(clone.unwrapped.encode_action(3))
    assert info["fix_status"] == "ok"
    assert np.all(blind[layout["estimate_std"]] > observation[layout["estimate_std"]])
    assert np.all(sighted[layout["estimate_std"]] < blind[layout["estimate_std"]])
    assert sighted[layout["last_fix_ok"]][0] == 1.0 and blind[layout["last_fix_ok"]][0] == 0.0
    assert sighted[layout["distance_since_fix"]][0] < blind[layout["distance_since_fix"]][0]


# -- the EKF in the env (Kim et al. secs. 3.1-3.2 and their slips) ---------------------------------


def test_heading_variance_grows_by_one_over_the_wheel_base_squared() -> None:
    # Exact encoders (no noise), so the increments are the commanded turn and straight move.
    # F(k)'s last row is [1/l, -1/l]: a turn by a adds k|a|/l and a straight d adds 2kd/l^2
    # to P_thth; the printed T/1 would add k|a| l / 2 + 2 k d.
    scale_error = 0.01
    env = gym.make(
        ENV_ID,
        encoder_std_m_per_sqrt_m=0.0,
        wheel_scale_error_bound=scale_error,
        slip_probability_per_m=0.0,
    )
    _, info = env.reset(seed=9)
    estimate = Pose.from_array(info["estimated_pose"])
    route = Route.through(TABLE_1_TRUE_POSITIONS_M)
    target = route.point_at(0.4)
    turn = abs(
        angle_difference(math.atan2(target[1] - estimate.y, target[0] - estimate.x), estimate.theta)
    )
    distance = math.dist(target, estimate.position)
    k = scale_error**2 / 3.0
    assert env.unwrapped.config.ekf_variance_per_m == pytest.approx(k, rel=1e-15)
    start_variance = math.radians(2.0) ** 2
    _, _, _, _, info = env.step(env.unwrapped.encode_action(0))
    expected = start_variance + k * turn / WHEEL_BASE_M + 2.0 * k * distance / WHEEL_BASE_M**2
    literal = start_variance + k * turn * WHEEL_BASE_M / 2.0 + 2.0 * k * distance
    assert info["covariance_diagonal"][2] == pytest.approx(expected, rel=1e-9)
    assert abs(info["covariance_diagonal"][2] - literal) > 0.1 * expected


def test_fix_corrects_the_ekf_with_the_inverted_gain() -> None:
    # At the route's end nothing moves after the sweep, so the estimate in info is the update.
    env = gym.make(ENV_ID, decision_points="waypoints")
    env.reset(seed=1)
    for _ in range(6):
        env.step(env.unwrapped.encode_action(1))
    episode = env.unwrapped._episode
    prior, covariance = episode.estimate, episode.covariance.copy()
    _, _, terminated, _, info = env.step(env.unwrapped.encode_action(1))
    assert terminated and info["fix_status"] == "ok"
    noise = np.diag([0.03**2, 0.03**2, math.radians(4.0) ** 2])
    measured = info["fix_measured_pose"]
    innovation = np.array(
        [measured[0] - prior.x, measured[1] - prior.y, wrap_angle(measured[2] - prior.theta)]
    )
    gain = covariance @ np.linalg.inv(covariance + noise)
    expected = prior.as_array() + gain @ innovation
    np.testing.assert_allclose(info["estimated_pose"][:2], expected[:2], rtol=0, atol=1e-12)
    assert abs(angle_difference(info["estimated_pose"][2], expected[2])) < 1e-12
    literal = prior.as_array() + covariance @ (covariance + noise) @ innovation
    assert np.linalg.norm(literal[:2] - expected[:2]) > 1e-4
    np.testing.assert_allclose(
        info["covariance_diagonal"], np.diag((np.eye(3) - gain) @ covariance), rtol=1e-9
    )


def test_innovation_gate_rejects_every_fix_when_tiny() -> None:
    env = gym.make(ENV_ID, innovation_gate=1e-12)
    env.reset(seed=3)
    _, _, _, _, info = env.step(env.unwrapped.encode_action(2))
    assert info["fix_status"] == "gated"
    assert info["distance_since_fix_m"] > 0.0


# -- geometry helpers ------------------------------------------------------------------------------


def test_route_points_and_targets_follow_the_polyline() -> None:
    route = Route.through(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]]))
    np.testing.assert_array_equal(route.cumulative_m, [0.0, 3.0, 7.0])
    np.testing.assert_allclose(route.point_at(5.0), [3.0, 2.0], atol=1e-15)
    np.testing.assert_allclose(route.point_at(99.0), [3.0, 4.0], atol=1e-15)
    targets = route.targets_between(1.0, 5.0)
    np.testing.assert_allclose(targets, [[3.0, 0.0], [3.0, 2.0]], atol=1e-15)
    assert route.truncated(5.0).length_m == pytest.approx(5.0, rel=1e-15)


@settings(max_examples=50, deadline=None)
@given(
    st.floats(-2, 2),
    st.floats(-2, 2),
    st.floats(-math.pi, math.pi),
    st.floats(-2, 2),
    st.floats(-2, 2),
    st.floats(-math.pi, math.pi),
)
def test_relative_pose_composes_back(
    x0: float, y0: float, t0: float, x1: float, y1: float, t1: float
) -> None:
    reference, pose = Pose(x0, y0, t0), Pose(x1, y1, t1)
    back = reference.compose(_relative_pose(reference, pose))
    assert back.x == pytest.approx(pose.x, abs=1e-9) and back.y == pytest.approx(pose.y, abs=1e-9)
    assert abs(angle_difference(back.theta, pose.theta)) < 1e-9


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_routes_have_the_requested_length_and_free_legs(seed: int) -> None:
    env = gym.make(ENV_ID, route="random", route_length_m=2.5)
    env.reset(seed=seed)
    route = env.unwrapped._episode.route
    assert route.length_m == pytest.approx(2.5, rel=1e-12)
    world = World(load_scenario("kim_arena"))
    for start, stop in zip(route.vertices[:-1], route.vertices[1:], strict=True):
        assert _leg_is_free(world, start, stop)


def test_known_map_marks_mapped_outlines_and_leaves_free_space() -> None:
    grid = occupancy_grid_of(load_scenario("kim_arena"))
    assert grid.shape == (44, 44)  # 2.2 m at 5 cm
    # The partition y = 0.9 lies on a cell edge: the cells on both sides are marked.
    assert grid.occupied[tuple(grid.world_to_cell(np.array([1.9, 0.875])))]
    assert grid.occupied[tuple(grid.world_to_cell(np.array([1.9, 0.925])))]
    assert not grid.occupied[tuple(grid.world_to_cell(np.array([1.0, 1.0])))]
    hidden = scenario_from_dict(
        {
            "room": {"min": [0.0, 0.0], "max": [2.0, 2.0]},
            "walls": [{"a": [0.5, 1.025], "b": [1.5, 1.025], "mapped": False}],
        }
    )
    assert not occupancy_grid_of(hidden).occupied[tuple(grid.world_to_cell(np.array([1.0, 1.025])))]


# -- agents ----------------------------------------------------------------------------------------


def test_agents_are_registered() -> None:
    assert {"paper", "covariance", "random"} <= set(agent_names(ENV_ID))
    env = gym.make(ENV_ID)
    assert isinstance(make_agent("paper", env), PaperAgent)


def test_observation_decodes_to_the_ekf_estimate() -> None:
    env = gym.make(ENV_ID)
    observation, info = env.reset(seed=5)
    observation, _, _, _, info = env.step(env.unwrapped.encode_action(0))
    decoded = _decode_estimate(env.unwrapped, observation)
    np.testing.assert_allclose([decoded.x, decoded.y], info["estimated_pose"][:2], atol=1e-6)
    assert abs(angle_difference(decoded.theta, info["estimated_pose"][2])) < 1e-6


def test_covariance_agent_sweeps_only_when_uncertain_toward_its_best_sector() -> None:
    env = gym.make(ENV_ID)
    agent = CovarianceAgent(env)
    observation, _ = env.reset(seed=0)
    std = env.unwrapped.observation_layout["estimate_std"]
    certain, uncertain = observation.copy(), observation.copy()
    certain[std] = [
        0.01 / POSITION_STD_SCALE_M,
        0.01 / POSITION_STD_SCALE_M,
        math.radians(1.0) / HEADING_STD_SCALE_RAD,
    ]
    uncertain[std] = [
        0.05 / POSITION_STD_SCALE_M,
        0.01 / POSITION_STD_SCALE_M,
        math.radians(1.0) / HEADING_STD_SCALE_RAD,
    ]
    assert agent.act(certain)[0] == 0
    count, sector = agent.act(uncertain)
    estimate = _decode_estimate(env.unwrapped, uncertain)
    losses = [
        agent.predicted_loss(estimate, centre)
        for centre in (0.0, math.pi / 2, -math.pi / 2, math.pi)
    ]
    assert count == 2 and sector == int(np.argmin(losses))
    assert all(math.isfinite(loss) and loss >= 0.0 for loss in losses)


def test_paper_agent_errors_are_of_the_paper_order() -> None:
    env = gym.make(ENV_ID)
    agent = PaperAgent(env)
    errors = []
    for seed in range(4):
        observation, _ = env.reset(seed=seed)
        done = False
        while not done:
            observation, _, terminated, truncated, info = env.step(agent.act(observation))
            done = terminated or truncated
            assert info["n_sweeps"] == 3 and info["sector"] == "front"
            errors.append(info["fix_position_error_m"])
    # Table 1: mean 2.75 cm (0.8-4.4 cm); the text: typically 10 cm, at worst 20 cm.
    assert 0.5 * TABLE_1_MEAN_ERROR_M <= float(np.mean(errors)) <= 2.0 * TABLE_1_MEAN_ERROR_M
    assert max(errors) < 2.0 * 0.20


def test_covariance_heuristic_beats_the_paper_procedure() -> None:
    env = gym.make(ENV_ID)
    seeds = range(12)
    paper = [_episode_return(env, PaperAgent(env), seed) for seed in seeds]
    heuristic = [_episode_return(env, CovarianceAgent(env), seed) for seed in seeds]
    assert np.mean(heuristic) > np.mean(paper) + 1.0


def test_a_room_too_large_for_the_voting_map_is_refused_by_name(tmp_path: Path) -> None:
    """The 5 cm voting map and its free-distance table grow with the area: past 100 m x 100 m
    gym.make names the scenario instead of running the machine out of memory."""
    path = tmp_path / "hall.toml"
    path.write_text(
        """
[room]
min = [-50.05, -50]
max = [50.05, 50]
"""
    )
    with pytest.raises(ValueError, match=r"argument 'scenario'.*100\.1 m x 100 m.*4,000,000"):
        gym.make(ENV_ID, scenario=str(path))


def test_the_tracks_hold_the_positions_after_each_drive_as_their_arrays_did() -> None:
    env = gym.make("SonarGym/SweepLocalization-v0").unwrapped
    assert isinstance(env, SweepLocalizationEnv)
    env.reset(seed=5)
    episode = env._require_episode()
    expected_true = [episode.world.robot_pose.position]
    expected_estimate = [episode.estimate.position]
    for n_sweeps in (0, 2, 1):
        drives = len(episode.true_track)
        env.step(env.encode_action(n_sweeps, "front"))
        assert len(episode.true_track) > drives
        expected_true.append(episode.world.robot_pose.position)
        expected_estimate.append(episode.estimate.position)
    for track, expected in (
        (episode.true_track, expected_true),
        (episode.estimate_track, expected_estimate),
    ):
        drawn = np.array(track)
        assert drawn.dtype == np.float64 and drawn.shape == (len(track), 2)
        assert drawn[0].tobytes() == expected[0].tobytes()
        assert drawn[-1].tobytes() == expected[-1].tobytes()
