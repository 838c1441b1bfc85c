"""WallCorrection-specific behaviour: arguments, the map, the on-line APCS, episodes, agents."""

from __future__ import annotations

import doctest
import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import sonar_gym.envs.wall_correction as wall_correction_module
import sonar_gym  # noqa: F401  (registers the ids)
from tests.envs.episodes import run_episode
from sonar_gym.agents import make_agent
from sonar_gym.envs.wall_correction import (
    SIDES,
    WallStream,
    map_wall_vectors,
    nearest_facing_walls,
    rejection_reason,
)
from sonar_gym.localization.apcs import (
    AMBIGUOUS,
    REJECT_DISTANCE,
    REJECT_ORIENTATION,
    WallVector,
    detect_walls,
    estimated_reflection_points,
    group_erps,
    match_wall,
)
from sonar_gym.pose import Pose
from sonar_gym.scenario import load_scenario, scenario_from_dict

ENV_ID = "SonarGym/WallCorrection-v0"
LEFT_BEAM_RAD = math.pi / 2.0


# --- arguments ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("argument", "value"),
    [
        ("n_legs", 0),
        ("standoffs_m", (0.0, 0.7)),
        ("standoffs_m", (0.2, 0.2)),
        ("sample_spacings_cm", (3, 4)),
        ("motion_step_cm", 0),
        ("transition_m", 2.0),
        ("route_margin_m", 6.0),
        ("obstacle_depth_range_m", (0.3, 0.1)),
        ("range_noise_std_m", -0.001),
        ("bearing_std_deg", 0.0),
        ("correction_method", "magic"),
        ("measurement_variances", "guess"),
        ("action_type", "box"),
        ("sensing_cost_per_s", -1.0),
        ("n_unmapped_obstacles", 1.5),
    ],
)
def test_bad_argument_is_named_in_the_error(argument: str, value: object) -> None:
    with pytest.raises(ValueError, match=argument):
        gym.make(ENV_ID, **{argument: value})


def test_unknown_scenario_is_named_in_the_error() -> None:
    with pytest.raises(ValueError, match="no_such_corridor"):
        gym.make(ENV_ID, scenario="no_such_corridor")


# --- the map --------------------------------------------------------------------------------


def test_the_corridor_map_has_the_occupied_side_on_the_left_of_every_vector() -> None:
    scenario = load_scenario("apcs_corridor")
    walls = map_wall_vectors(scenario)
    # 4 room walls and the 9 mapped faces of the three pillars; wall B is not in the map.
    assert len(walls) == 13
    assert not any(w.start == (3.8, 0.7) or w.end == (3.8, 0.7) for w in walls)
    north = [w for w in walls if w.start[1] == 1.0 and w.end[1] == 1.0 and w.length == 10.0]
    south = [w for w in walls if w.start[1] == -1.0 and w.end[1] == -1.0 and w.length == 10.0]
    assert [(w.start, w.end) for w in north] == [((0.0, 1.0), (10.0, 1.0))]
    assert [(w.start, w.end) for w in south] == [((10.0, -1.0), (0.0, -1.0))]
    # The free side (the right, where the normal points) of every vector is the corridor.
    for wall in walls:
        middle = 0.5 * (wall.start_point + wall.end_point)
        free_probe = middle + 0.01 * wall.normal
        assert -1.0 < free_probe[1] < 1.0 and 0.0 < free_probe[0] < 10.0, wall
        assert not (2.0 < free_probe[0] < 2.4 and free_probe[1] > 0.85), wall
        assert not (6.0 < free_probe[0] < 6.4 and free_probe[1] > 0.85), wall
        assert not (4.0 < free_probe[0] < 4.4 and free_probe[1] < -0.85), wall


def test_mapped_boxes_face_outwards_and_unmapped_ones_are_left_out() -> None:
    scenario = scenario_from_dict(
        {
            "room": {"min": [0.0, 0.0], "max": [4.0, 4.0]},
            "boxes": [
                {"center": [2.0, 2.0], "size": [1.0, 0.5]},
                {"center": [1.0, 1.0], "size": [0.2, 0.2], "mapped": False},
            ],
        }
    )
    walls = map_wall_vectors(scenario)
    box_sides = [w for w in walls if w.name.startswith("box_0")]
    assert len(walls) == 8 and len(box_sides) == 4
    for side in box_sides:
        middle = 0.5 * (side.start_point + side.end_point)
        outward = middle - np.array([2.0, 2.0])
        assert float(outward @ side.normal) > 0.0


def test_nearest_facing_walls_sees_the_pillar_face_in_front_of_the_room_wall() -> None:
    walls = map_wall_vectors(load_scenario("apcs_corridor"))
    origins = np.array([[1.0, 0.0], [2.2, 0.0], [4.2, 0.0]])
    ids, distances = nearest_facing_walls(walls, origins, np.array([0.0, 1.0]))
    np.testing.assert_allclose(distances, [1.0, 0.85, 1.0], rtol=1e-12)
    assert walls[ids[1]].start == (2.0, 0.85) and walls[ids[1]].end == (2.4, 0.85)
    ids, distances = nearest_facing_walls(walls, origins, np.array([0.0, -1.0]))
    np.testing.assert_allclose(distances, [1.0, 1.0, 0.85], rtol=1e-12)


def test_map_ahead_features_measure_the_flat_stretches_of_each_leg() -> None:
    env = gym.make(ENV_ID).unwrapped
    step = wall_correction_module.MAP_PROFILE_STEP_M / env.leg_length_m
    features = env._map_ahead  # (legs, [left run, left distance, right run, right distance])
    # Legs of 1.5 m from x = 0.5: leg 0 has no pillar; leg 1 meets the left pillar at
    # x = 2.0-2.4 (longest stretch 2.4-3.5 = 1.1 m); leg 2 the right pillar at 4.0-4.4
    # (longest 4.4-5.0 = 0.6 m); every median distance is the 1 m to the room walls / 5 m.
    np.testing.assert_allclose(features[0], [1.0, 0.2, 1.0, 0.2], atol=1e-12)
    assert abs(features[1, 0] - 1.1 / 1.5) <= 2 * step
    assert abs(features[2, 2] - 0.6 / 1.5) <= 2 * step
    np.testing.assert_allclose(features[:, [1, 3]], 0.2, atol=1e-12)


# --- rejection reasons ----------------------------------------------------------------------


def test_rejection_reason_names_the_first_failed_condition_of_the_nearest_wall() -> None:
    north = WallVector((0.0, 1.0), (10.0, 1.0), name="north")
    pillar = WallVector((2.0, 0.85), (2.4, 0.85), name="pillar")
    wall_map = [north, pillar]
    on_wall_b = WallVector((3.9, 0.7), (4.1, 0.7))  # 30 cm in front of the north wall
    assert rejection_reason(match_wall(on_wall_b, wall_map)) == REJECT_DISTANCE
    tilted = WallVector((1.0, 1.0), (1.2, 1.0 + 0.2 * math.tan(math.radians(1.0))))
    assert rejection_reason(match_wall(tilted, wall_map)) == REJECT_ORIENTATION
    on_north = WallVector((1.0, 1.0), (1.2, 1.0))
    assert rejection_reason(match_wall(on_north, wall_map)) is None
    twin = WallVector((0.0, 1.05), (10.0, 1.05))
    assert rejection_reason(match_wall(on_north, [north, twin])) == AMBIGUOUS


# --- the on-line APCS stream -------------------------------------------------------------------


def _straight_readings(x: np.ndarray, wall_y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    positions = np.column_stack([x, np.zeros_like(x)])
    return positions, wall_y - positions[:, 1]


def _stream_groups(stream: WallStream, positions: np.ndarray, ranges: np.ndarray) -> list:
    groups = []
    for position, range_m in zip(positions, ranges, strict=True):
        _, closed = stream.add(position, 0.0, float(range_m))
        groups.extend(closed)
    groups.extend(stream.flush())
    return groups


def test_wall_stream_finds_the_groups_and_walls_of_the_batch_procedure() -> None:
    x = np.arange(0.0, 1.5, 0.03)
    wall_y = np.where(x < 0.75, 1.0, 0.8)  # a step of 20 cm: a discontinuity between the walls
    positions, ranges = _straight_readings(x, wall_y)
    groups = _stream_groups(WallStream("left"), positions, ranges)
    erps = estimated_reflection_points(positions, LEFT_BEAM_RAD, ranges)
    batch_groups = group_erps(erps)
    assert [len(g.points) for g in groups] == [len(g) for g in batch_groups]
    for group, batch in zip(groups, batch_groups, strict=True):
        np.testing.assert_allclose(group.points, erps.points[list(batch)], rtol=0, atol=1e-12)
    walls = [g.fit.wall for g in groups if g.fit.wall is not None]
    batch_walls = detect_walls(erps)
    assert len(walls) == len(batch_walls) > 0
    for wall, batch_wall in zip(walls, batch_walls, strict=True):
        np.testing.assert_allclose(wall.start, batch_wall.start, atol=1e-12)
        np.testing.assert_allclose(wall.end, batch_wall.end, atol=1e-12)
        assert wall.start[1] == pytest.approx(wall.end[1], abs=1e-12)
        assert wall.start[1] in (pytest.approx(1.0, abs=1e-12), pytest.approx(0.8, abs=1e-12))
        assert wall.end[0] > wall.start[0]  # free side (the robot) on the right


def test_wall_stream_closes_a_group_as_soon_as_it_holds_eight_erps() -> None:
    stream = WallStream("left")
    closed_at = []
    for index, x in enumerate(np.arange(0.0, 0.3, 0.03)):
        _, closed = stream.add(np.array([x, 0.0]), 0.0, 1.0)
        if closed:
            closed_at.append((index, len(closed[0].points)))
    assert closed_at == [(8, 8)]  # readings 1..8 give ERPs 1..8; the 8th closes the group


def test_a_right_side_stream_yields_vectors_with_the_wall_on_their_left() -> None:
    x = np.arange(0.0, 0.3, 0.03)
    positions = np.column_stack([x, np.zeros_like(x)])
    stream = WallStream("right")
    groups = []
    for position in positions:
        groups.extend(stream.add(position, 0.0, 0.9)[1])
    wall = groups[0].fit.wall
    assert wall is not None
    np.testing.assert_allclose([wall.start[1], wall.end[1]], [-0.9, -0.9], atol=1e-12)
    assert wall.end[0] < wall.start[0]


def test_moving_the_frame_keeps_a_group_consistent_across_a_correction() -> None:
    """After a rigid change of the estimate's frame, the old and new readings fit one wall."""
    before = Pose(0.12, 0.0, 0.0)
    after = Pose(0.15, -0.02, math.radians(0.3))  # the corrected estimate of the same pose
    shift = after.compose(
        Pose(-before.x, -before.y, 0.0)
    )  # frame change: p' = after + R(p - before)

    def in_new_frame(point: np.ndarray) -> np.ndarray:
        return shift.transform_point(point)

    stream = WallStream("left")
    for x in (0.0, 0.03, 0.06, 0.09, 0.12):  # the true wall is y = 1 in the old frame
        stream.add(np.array([x, 0.0]), 0.0, 1.0)
    stream.move_frame(before, after)
    groups = []
    for x in (0.15, 0.18, 0.21, 0.24):
        position = in_new_frame(np.array([x, 0.0]))
        groups.extend(stream.add(position, after.theta, 1.0)[1])
    groups.extend(stream.flush())
    assert len(groups) == 1 and len(groups[0].points) == 8
    wall = groups[0].fit.wall
    assert wall is not None and wall.residual_variance_m2 < 1e-20
    expected_start = in_new_frame(np.array([0.03, 1.0]))
    expected_end = in_new_frame(np.array([0.24, 1.0]))
    np.testing.assert_allclose(wall.start, expected_start, atol=1e-9)
    np.testing.assert_allclose(wall.end, expected_end, atol=1e-9)


# --- actions and episodes ---------------------------------------------------------------------


@pytest.mark.parametrize("action_type", ["multi_discrete", "discrete"])
def test_encode_and_decode_are_inverse(action_type: str) -> None:
    env = gym.make(ENV_ID, action_type=action_type).unwrapped
    for side in SIDES:
        for spacing in env.config.sample_spacings_cm:
            for standoff in env.config.standoffs_m:
                command = env.decode_action(env.encode_action(side, spacing, standoff))
                assert (command.side, command.spacing_cm, command.standoff_m) == (
                    side,
                    spacing,
                    standoff,
                )
                assert env.action_space.contains(env.encode_action(side, spacing, standoff))


def test_an_episode_is_n_legs_long_and_reports_its_progress() -> None:
    env = gym.make(ENV_ID, n_legs=3)
    observation, info = env.reset(seed=4)
    assert info["status"] == "running" and info["leg"] == 0
    action = env.unwrapped.encode_action("left", 3, 0.0)
    statuses = []
    for leg in range(1, 4):
        observation, reward, terminated, truncated, info = env.step(action)
        statuses.append(info["status"])
        assert info["leg"] == leg and not truncated
        assert env.observation_space.contains(observation)
        for key in ("n_matched_walls", "n_rejected_walls", "position_error_m", "heading_error_rad"):
            assert np.isfinite(info[key])
    assert terminated and statuses == ["running", "running", "ok"]
    assert info["n_detected_walls"] == info["n_matched_walls"] + info["n_rejected_walls"]
    assert info["n_corrections"] <= info["n_matched_walls"]
    layout = env.unwrapped.observation_layout
    assert observation[layout["progress"]][0] == 1.0
    np.testing.assert_array_equal(observation[layout["map_ahead"]], 0.0)
    true_x = env.unwrapped.true_pose.x
    assert true_x == pytest.approx(env.unwrapped.leg_starts_x[-1], abs=0.05)


def test_the_reward_is_the_pose_error_minus_sensing_cost_and_collisions() -> None:
    env = gym.make(ENV_ID, n_legs=2, sensing_cost_per_s=0.3, collision_penalty=7.0)
    env.reset(seed=1)
    listen_s = env.unwrapped.sonars.transducer.listen_time_s
    sensing_before = 0.0
    for side, spacing in (("none", 3), ("both", 6)):
        _, reward, _, _, info = env.step(env.unwrapped.encode_action(side, spacing, 0.0))
        leg_sensing = info["sensing_time_s"] - sensing_before
        sensing_before = info["sensing_time_s"]
        expected = (
            -(info["position_error_m"] / 0.05 + info["heading_error_rad"] / math.radians(2.0))
            - 0.3 * leg_sensing
            - 7.0 * (info["collisions"] > 0)
        )
        assert reward == pytest.approx(expected, rel=1e-12)
        if side == "none":
            assert leg_sensing == 0.0 and info["n_detected_walls"] == 0
        else:
            # one listening time per sampling instant, every 6 cm of the 4.5 m leg (about 75),
            # though both sonars fire at each instant
            instants = leg_sensing / listen_s
            expected_instants = env.unwrapped.leg_length_m / 0.06
            assert instants == pytest.approx(round(instants), abs=1e-9)
            assert expected_instants - 2 <= instants <= expected_instants + 2
            assert env.unwrapped._require_episode().last_leg.samples == 2 * round(instants)


def test_driving_into_an_unmapped_obstacle_costs_the_collision_penalty(tmp_path: Path) -> None:
    scenario = tmp_path / "blocked_corridor.toml"
    scenario.write_text(
        "[room]\nmin = [0.0, -1.0]\nmax = [10.0, 1.0]\n\n"
        "[[boxes]]\ncenter = [5.0, 0.6]\nsize = [0.4, 0.4]\nmapped = false\n\n"
        "[robot]\nradius = 0.2\nwheel_base = 0.3\n"
    )
    env = gym.make(
        ENV_ID, scenario=str(scenario), n_legs=3, n_unmapped_obstacles=0, collision_penalty=50.0
    )
    env.reset(seed=0)
    rewards, collisions = [], []
    # Legs of 3 m from x = 0.5; the unmapped box (y = 0.4-0.8) stands in the second leg.
    for standoff in (0.0, 0.4, 0.0):
        _, reward, _, _, info = env.step(env.unwrapped.encode_action("none", 3, standoff))
        rewards.append(reward)
        collisions.append(info["collisions"])
    assert collisions == [0, 1, 1]
    assert rewards[0] > -50.0 and rewards[1] < -50.0 and rewards[2] > -50.0


def test_odometry_alone_drifts_and_the_paper_agent_corrects_it() -> None:
    """The paper's procedure keeps the error at the centimetre level (sec. 6, Fig. 15)."""
    env = gym.make(ENV_ID)
    apcs, odometry, matched, wall_b_matched = [], [], [], 0
    for seed in range(6):
        _, info = run_episode(env, "paper", seed)
        apcs.append(info["position_error_m"])
        odometry.append(info["odometry_position_error_m"])
        matched.append(info["n_matched_walls"])
        for detection in env.unwrapped.trace.detections:
            (x0, y0), (_, y1) = detection.wall.start, detection.wall.end
            on_b = abs(y0 - 0.7) < 0.05 and abs(y1 - 0.7) < 0.05 and 3.7 < x0 < 4.8
            wall_b_matched += on_b and detection.matched
    assert min(matched) >= 3
    assert wall_b_matched == 0
    assert np.median(apcs) < 0.03
    assert np.median(apcs) < np.median(odometry)


def test_without_sensing_the_estimate_is_the_dead_reckoning() -> None:
    env = gym.make(ENV_ID, n_legs=2)
    env.reset(seed=2)
    for _ in range(2):
        _, _, _, _, info = env.step(env.unwrapped.encode_action("none", 3, 0.0))
    odometry = env.unwrapped._require_episode().robot.odometry_pose
    np.testing.assert_allclose(info["estimated_pose"], odometry.as_array(), atol=1e-9)


def test_the_docstring_example_holds() -> None:
    results = doctest.testmod(wall_correction_module, optionflags=doctest.ELLIPSIS)
    assert results.attempted > 0 and results.failed == 0


# --- agents ---------------------------------------------------------------------------------


def test_the_paper_agent_senses_the_nearer_wall_every_3_cm_from_the_centre_line() -> None:
    env = gym.make(ENV_ID)
    unwrapped = env.unwrapped
    agent = make_agent("paper", env)
    observation, _ = env.reset(seed=0)
    command = unwrapped.decode_action(agent.act(observation))
    # The corridor is symmetric: a tie, and the paper's experiment used the left side.
    assert (command.side, command.spacing_cm, command.standoff_m) == ("left", 3, 0.0)
    nearer_right = observation.copy()
    nearer_right[unwrapped.observation_layout["map_ahead"]] = [1.0, 0.2, 1.0, 0.1]
    assert unwrapped.decode_action(agent.act(nearer_right)).side == "right"


def test_the_both_walls_agent_runs_both_sonars_and_can_pause_when_confident() -> None:
    from sonar_gym.agents.wall_correction import BothWallsAgent

    env = gym.make(ENV_ID)
    unwrapped = env.unwrapped
    observation, _ = env.reset(seed=0)
    command = unwrapped.decode_action(make_agent("both_walls", env).act(observation))
    assert (command.side, command.spacing_cm, command.standoff_m) == ("both", 3, 0.0)
    pausing = BothWallsAgent(env, pause_when_confident=True)
    pausing.reset(0)
    confident = observation.copy()
    confident[unwrapped.observation_layout["position_std"]] = 0.0
    confident[unwrapped.observation_layout["heading_std"]] = 0.0
    sides = [unwrapped.decode_action(pausing.act(confident)).side for _ in range(3)]
    assert sides == ["none", "both", "none"]  # never two paused legs in a row


def test_sensing_both_walls_beats_the_papers_single_wall_at_the_same_sensing_time() -> None:
    env = gym.make(ENV_ID)
    paper, both = [], []
    for seed in range(10):
        paper.append(run_episode(env, "paper", seed))
        both.append(run_episode(env, "both_walls", seed))
    paper_rewards = np.array([reward for reward, _ in paper])
    both_rewards = np.array([reward for reward, _ in both])
    for (_, paper_info), (_, both_info) in zip(paper, both, strict=True):
        assert both_info["sensing_time_s"] == pytest.approx(paper_info["sensing_time_s"], rel=1e-9)
        assert both_info["n_matched_walls"] > paper_info["n_matched_walls"]
    assert both_rewards.mean() > paper_rewards.mean()
    assert both_rewards.min() > paper_rewards.min()  # the drift that loses the heading


@pytest.mark.parametrize("action", [[5, 5, 5], [0, -1, 0], [4, 0, 0], [0, 0, 5]])
def test_decoding_an_action_outside_the_space_names_it_and_the_allowed_range(
    action: list[int],
) -> None:
    env = gym.make(ENV_ID).unwrapped
    with pytest.raises(
        ValueError,
        match=r"argument 'action' must be .*: 3 integers, in \[0, 3\], \[0, 2\], \[0, 4\]; got",
    ):
        env.decode_action(action)
