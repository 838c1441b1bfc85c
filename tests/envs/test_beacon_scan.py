"""BeaconScan-specific behaviour: arguments, actions, calibration, the paper's accuracy."""

from __future__ import annotations

import json
import math
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import sonar_gym  # noqa: F401
from tests.envs.episodes import run_episode

ENV_ID = "SonarGym/BeaconScan-v0"


@pytest.mark.parametrize(
    ("argument", "value"),
    [
        ("temperature_c", 99.0),
        ("sensing_cost_per_s", -1.0),
        ("increments_deg", (1, 4)),
        ("sector_widths_deg", (45,)),
        ("n_range_bins", 7),
        ("start_pose", "anywhere"),
        ("localization_method", "magic"),
        ("rcd_extraction", "guess"),
        ("action_type", "box"),
        ("scenario", "no_such_room"),
        ("max_steps", 0),
        ("allow_calibration", "yes"),
    ],
)
def test_bad_argument_is_named_in_the_error(argument: str, value: object) -> None:
    with pytest.raises(ValueError, match=argument if argument != "scenario" else "no_such_room"):
        gym.make(ENV_ID, **{argument: value})


@pytest.mark.parametrize("env_id", [ENV_ID, "SonarGym/ActiveBeaconScan-v0"])
def test_an_odd_sector_width_is_refused_by_name(env_id: str) -> None:
    """A pan spans its centre +- half the width on the scan memory's 1 deg grid."""
    with pytest.raises(ValueError, match="sector_widths_deg.*even"):
        gym.make(env_id, sector_widths_deg=(45, 90), increments_deg=(1,))


@pytest.mark.parametrize("env_id", [ENV_ID, "SonarGym/ActiveBeaconScan-v0"])
def test_every_offered_width_and_increment_pans_from_every_centre(env_id: str) -> None:
    env = gym.make(env_id, sector_widths_deg=(2, 6, 30, 358, 360), increments_deg=(1, 2))
    env.reset(seed=3)
    unwrapped = env.unwrapped
    centres = range(0, 360, 360 // unwrapped.config.n_sector_centres)
    steps = 0
    for centre in list(centres)[::7]:
        for width in unwrapped.config.sector_widths_deg:
            for increment in unwrapped.config.increments_deg:
                _, reward, terminated, truncated, _ = env.step(
                    unwrapped.encode_action("pan", centre, width, increment)
                )
                assert np.isfinite(reward)
                steps += 1
                if terminated or truncated:
                    env.reset(seed=steps)
    assert steps >= 10


HIDDEN_BEACONS = """
[room]
min = [-3, -3]
max = [3, 3]
[[walls]]
a = [0, -3]
b = [0, 3]
[[cylinders]]
center = [1.5, 0]
radius = 0.02
role = "small_beacon"
[[cylinders]]
center = [-1.5, 0]
radius = 0.05
role = "large_beacon"
"""


@pytest.mark.parametrize("env_id", [ENV_ID, "SonarGym/ActiveBeaconScan-v0"])
def test_beacons_no_free_pose_sees_together_are_refused_at_make(
    env_id: str, tmp_path: Path
) -> None:
    """A wall between the beacons: the default start pose cannot exist, and gym.make says so
    (start_pose='any' still runs there)."""
    path = tmp_path / "hidden.toml"
    path.write_text(HIDDEN_BEACONS)
    with pytest.raises(ValueError, match="argument 'scenario'.*start_pose='any'"):
        gym.make(env_id, scenario=str(path))
    env = gym.make(env_id, scenario=str(path), start_pose="any")
    observation, _ = env.reset(seed=0)
    assert np.isfinite(observation).all()


def test_scenario_without_beacons_is_rejected() -> None:
    with pytest.raises(ValueError, match="small_beacon"):
        gym.make(ENV_ID, scenario="kim_arena")


@pytest.mark.parametrize("action_type", ["multi_discrete", "discrete"])
def test_encode_and_decode_are_inverse(action_type: str) -> None:
    env = gym.make(ENV_ID, action_type=action_type).unwrapped
    for kind in ("calibrate", "localize"):
        assert env.decode_action(env.encode_action(kind)).kind == kind
    command = env.decode_action(env.encode_action("pan", 130, 60, 2))
    assert (command.kind, command.centre_deg, command.width_deg, command.increment_deg) == (
        "pan",
        130,
        60,
        2,
    )


@pytest.mark.parametrize("centre_deg", [math.nan, math.inf, -math.inf, None, "90", True])
def test_a_pan_centre_that_is_not_a_finite_number_is_refused_naming_it(centre_deg: Any) -> None:
    env = gym.make(ENV_ID).unwrapped
    with pytest.raises(ValueError, match=r"argument 'centre_deg' must be a finite number; got"):
        env.encode_action("pan", centre_deg=centre_deg)


@pytest.mark.parametrize(
    ("action_type", "action", "allowed"),
    [
        (
            "multi_discrete",
            [0, 36, 0, 0],
            r"4 integers, in \[0, 2\], \[0, 35\], \[0, 4\], \[0, 2\]",
        ),
        ("multi_discrete", [0, 0, -1, 0], r"4 integers, in \[0, 2\], \[0, 35\]"),
        ("multi_discrete", [3, 0, 0, 0], r"4 integers, in \[0, 2\]"),
        ("discrete", 10_000, r"an integer in \[0, 541\]"),
        ("discrete", -1, r"an integer in \[0, 541\]"),
    ],
)
def test_decoding_an_action_outside_the_space_names_it_and_the_allowed_range(
    action_type: str, action: Any, allowed: str
) -> None:
    env = gym.make(ENV_ID, action_type=action_type).unwrapped
    with pytest.raises(ValueError, match=rf"argument 'action' must be .*: {allowed}.*; got"):
        env.decode_action(action)


def _paper_agent_errors(
    episodes: int, **env_kwargs: object
) -> tuple[list[str], np.ndarray, np.ndarray]:
    env = gym.make(ENV_ID, temperature_c=20.0, **env_kwargs)
    statuses, position_errors, heading_errors = [], [], []
    for seed in range(episodes):
        _, info = run_episode(env, "paper", seed)
        statuses.append(info["status"])
        if info["status"] == "ok":
            position_errors.append(info["position_error_m"])
            heading_errors.append(info["heading_error_rad"])
    return statuses, np.array(position_errors), np.degrees(heading_errors)


def test_paper_agent_meets_the_papers_error_bounds_whenever_it_localizes() -> None:
    statuses, position_errors, heading_errors = _paper_agent_errors(100)
    # A beacon RCD cut short by a nearer wall heard through the filled side-lobe nulls gives
    # "no_pair" from about one pose in six; when a pose comes out it is the paper's quality.
    assert statuses.count("ok") >= 75
    assert np.percentile(position_errors, 95) <= 0.03
    assert np.median(position_errors) <= 0.02
    assert np.percentile(heading_errors, 95) <= 2.0


def test_walls_no_longer_pair_up_the_paper_method_rarely_returns_a_wrong_pose() -> None:
    statuses, position_errors, _ = _paper_agent_errors(60)
    assert np.mean(position_errors > 0.1) <= 0.05
    gated_statuses, gated_errors, _ = _paper_agent_errors(60, prior_gate_m=0.4)
    assert np.mean(gated_errors > 0.1) <= np.mean(position_errors > 0.1)


def test_occlusion_aware_extraction_localizes_more_poses_and_keeps_the_papers_answers() -> None:
    paper_env = gym.make(ENV_ID, temperature_c=20.0)
    aware_env = gym.make(ENV_ID, temperature_c=20.0, rcd_extraction="occlusion_aware")
    paper = [run_episode(paper_env, "paper", seed)[1] for seed in range(200)]
    aware = [run_episode(aware_env, "paper", seed)[1] for seed in range(200)]
    paper_ok = [i["status"] == "ok" for i in paper]
    aware_ok = [i["status"] == "ok" for i in aware]
    # about 1 pose in 10 has a beacon RCD cut by a nearer echo (200 seeds: 83.5 % -> 90 %)
    assert sum(aware_ok) >= sum(paper_ok) + 10
    for by_paper, by_aware in zip(paper, aware, strict=True):
        if by_paper["status"] == "ok":
            np.testing.assert_array_equal(by_aware["estimated_pose"], by_paper["estimated_pose"])
    rebuilt_errors = [
        a["position_error_m"]
        for p, a in zip(paper, aware, strict=True)
        if a["status"] == "ok" and p["status"] != "ok"
    ]
    assert np.median(rebuilt_errors) <= 0.03


def test_uncalibrated_sensor_is_biased_and_calibration_removes_the_bias() -> None:
    hot_no_calibration = gym.make(ENV_ID, temperature_c=40.0, allow_calibration=False)
    hot_calibrated = gym.make(ENV_ID, temperature_c=40.0, allow_calibration=True)
    biased = [run_episode(hot_no_calibration, "paper", s)[1] for s in range(20)]
    corrected = [run_episode(hot_calibrated, "paper", s)[1] for s in range(20)]

    def within_bounds(infos: list[dict]) -> float:
        return float(
            np.mean([i["status"] == "ok" and i["position_error_m"] <= 0.03 for i in infos])
        )

    assert all(i["calibrated"] for i in corrected)
    # c(40 C) / c(20 C) - 1 = 3.3 %: every range is 5-10 cm long, so eq. (7)'s 4 cm test
    # rejects the beacon pair or the pose comes out centimetres off
    assert within_bounds(biased) <= within_bounds(corrected) - 0.5
    corrected_errors = [i["position_error_m"] for i in corrected if i["status"] == "ok"]
    assert np.median(corrected_errors) <= 0.02


def test_calibration_after_the_pan_still_corrects_it() -> None:
    env = gym.make(ENV_ID, temperature_c=35.0).unwrapped
    env.reset(seed=4)
    env.step(env.encode_action("pan", 0, 360, 1))
    before = env._episode.memory.as_scans(env._episode.sonar.assumed_speed_of_sound_mps)[0].ranges
    env.step(env.encode_action("calibrate"))
    after = env._episode.memory.as_scans(env._episode.sonar.assumed_speed_of_sound_mps)[0].ranges
    finite = np.isfinite(before)
    ratio = np.median(after[finite] / before[finite])
    assert ratio == pytest.approx(math.sqrt((1 + 35 / 273.15) / (1 + 20 / 273.15)), rel=5e-3)


def test_sector_agent_senses_for_less_time_than_the_paper_agent() -> None:
    # 100 seeds: over 15 one missed beacon moves the success count by a whole step
    env = gym.make(ENV_ID, temperature_c=20.0)
    paper = [run_episode(env, "paper", s)[1] for s in range(100)]
    sector = [run_episode(env, "sector", s)[1] for s in range(100)]
    assert np.mean([i["sensing_time_s"] for i in sector]) < 0.6 * np.mean(
        [i["sensing_time_s"] for i in paper]
    )
    successes = [sum(i["status"] == "ok" for i in infos) for infos in (paper, sector)]
    assert successes[1] >= successes[0] - 3, successes


def test_truncation_counts_as_failure() -> None:
    env = gym.make(ENV_ID, max_steps=2)
    env.reset(seed=0)
    calibrate = env.unwrapped.encode_action("calibrate")
    _, _, terminated, truncated, _ = env.step(calibrate)
    assert not (terminated or truncated)
    _, reward, terminated, truncated, info = env.step(calibrate)
    assert truncated and not terminated
    assert info["status"] == "truncated"
    assert reward <= -env.unwrapped.config.failure_penalty


def test_localize_without_scanning_fails_with_the_penalty() -> None:
    env = gym.make(ENV_ID, failure_penalty=7.0)
    env.reset(seed=0)
    _, reward, terminated, _, info = env.step(env.unwrapped.encode_action("localize"))
    assert terminated and info["status"] != "ok"
    assert reward == pytest.approx(-7.0)


def test_random_scenario_changes_the_room_per_episode() -> None:
    env = gym.make(ENV_ID, scenario="random").unwrapped
    env.reset(seed=1)
    first = env.world.scenario
    env.reset(seed=2)
    assert env.world.scenario != first


def comb_lab(path: Path, n_teeth: int = 1500) -> Path:
    """The paper lab with ``n_teeth`` extra 1 cm walls standing on its four walls, as JSON.

    The teeth run inwards from the room's walls, 1.5 cm apart, so they add 1,500 segments
    and 1,500 T-junctions without changing where the robot fits or what it sees of the
    beacons.
    """
    with open(resources.files("sonar_gym") / "scenarios" / "beom_cho_lab.toml", "rb") as file:
        data = tomllib.load(file)
    (x0, y0), (x1, y1) = data["room"]["min"], data["room"]["max"]
    inward = {
        "bottom": (0.0, 0.01),
        "top": (0.0, -0.01),
        "left": (0.01, 0.0),
        "right": (-0.01, 0.0),
    }
    feet = []
    for k in range(n_teeth):
        side = ("bottom", "top", "left", "right")[k % 4]
        along = 0.05 + 0.015 * (k // 4)
        if side in ("bottom", "top"):
            feet.append((side, (x0 + along, y0 if side == "bottom" else y1)))
        else:
            feet.append((side, (x0 if side == "left" else x1, y0 + along * (y1 - y0) / (x1 - x0))))
    data["walls"] = data.get("walls", []) + [
        {"a": list(foot), "b": [foot[0] + inward[side][0], foot[1] + inward[side][1]]}
        for side, foot in feet
    ]
    data["meta"]["name"] = "comb_lab"
    target = path / "comb_lab.json"
    target.write_text(json.dumps(data), encoding="utf-8")
    return target


def test_a_large_room_is_built_once_and_reset_only_places_the_robot(tmp_path: Path) -> None:
    path = comb_lab(tmp_path)
    env = gym.make(ENV_ID, scenario=str(path)).unwrapped
    env.reset(seed=0)
    world = env.world
    assert world.geometry.n_segments == 4 + 5 + 1500 + 4 * len(world.scenario.boxes)
    for seed in (1, 2, 3):
        observation, info = env.reset(seed=seed)
        assert env.world is world  # the pymunk space and geometry are reused
        fresh_env = gym.make(ENV_ID, scenario=str(path)).unwrapped
        fresh_observation, fresh_info = fresh_env.reset(seed=seed)
        assert fresh_env.world is not world
        np.testing.assert_array_equal(observation, fresh_observation)
        np.testing.assert_array_equal(info["true_pose"], fresh_info["true_pose"])
        assert info["temperature_c"] == fresh_info["temperature_c"]
        pan = env.encode_action("pan", 0, 90, 2)
        np.testing.assert_array_equal(env.step(pan)[0], fresh_env.step(pan)[0])


def test_seeded_episodes_do_not_depend_on_the_episodes_before() -> None:
    env = gym.make(ENV_ID)
    for seed in (0, 1, 2):
        run_episode(env, "paper", seed)
    _, reused = run_episode(env, "paper", 3)
    _, fresh = run_episode(gym.make(ENV_ID), "paper", 3)
    for key in ("true_pose", "estimated_pose"):
        np.testing.assert_array_equal(reused[key], fresh[key])
    assert reused["temperature_c"] == fresh["temperature_c"]


def reference_observation(env: Any) -> np.ndarray:
    """The observation as the env docstring's table defines it, slot by slot."""
    episode, config = env._episode, env.config
    memory, max_range = episode.memory, episode.sonar.transducer.max_range_m
    layout = env.observation_layout
    observation = np.zeros(env.observation_space.shape, dtype=np.float32)
    ranges = memory.ranges(episode.sonar.assumed_speed_of_sound_mps)
    bins = (np.arange(memory.n_slots) * config.n_range_bins) // memory.n_slots
    bin_ranges, bin_scanned = np.ones(config.n_range_bins), np.zeros(config.n_range_bins)
    for slot, bin_index in enumerate(bins):
        if np.isfinite(ranges[slot]):
            bin_ranges[bin_index] = min(bin_ranges[bin_index], min(ranges[slot] / max_range, 1.0))
        bin_scanned[bin_index] = max(bin_scanned[bin_index], float(memory.scanned[slot]))
    observation[layout["bin_ranges"]] = bin_ranges
    observation[layout["bin_scanned"]] = bin_scanned
    (x_min, y_min), (x_max, y_max) = env.world.scenario.bounds
    prior = episode.prior
    observation[layout["prior_xy"]] = np.clip(
        [2 * (prior.x - x_min) / (x_max - x_min) - 1, 2 * (prior.y - y_min) / (y_max - y_min) - 1],
        -1.0,
        1.0,
    )
    observation[layout["prior_heading"]] = [math.cos(prior.theta), math.sin(prior.theta)]
    for role in ("small_beacon", "large_beacon"):
        beacon = env.world.scenario.beacon(role)
        dx, dy = beacon.center[0] - prior.x, beacon.center[1] - prior.y
        bearing = math.remainder(math.atan2(dy, dx) - prior.theta, 2 * math.pi)
        observation[layout[role]] = [
            math.cos(bearing),
            math.sin(bearing),
            min(math.hypot(dx, dy) / max_range, 1.0),
        ]
    observation[layout["sensing_time"]] = min(episode.sensing_time_s / config.time_budget_s, 1.0)
    observation[layout["calibrated"]] = float(episode.calibrated)
    observation[layout["steps"]] = min(episode.steps / config.max_steps, 1.0)
    observation[layout["calibration_allowed"]] = float(config.allow_calibration)
    observation[layout["coverage"]] = memory.scanned.mean()
    return observation


@pytest.mark.parametrize("n_range_bins", [72, 360, 8])
def test_observation_equals_its_slot_by_slot_definition(n_range_bins: int) -> None:
    env = gym.make(ENV_ID, temperature_c=30.0, n_range_bins=n_range_bins).unwrapped
    observation, _ = env.reset(seed=11)
    np.testing.assert_allclose(observation, reference_observation(env), rtol=0, atol=1e-6)
    for action in (
        env.encode_action("pan", 90, 90, 2),
        env.encode_action("calibrate"),
        env.encode_action("pan", 200, 60, 5),
        env.encode_action("pan", 0, 360, 1),
    ):
        observation = env.step(action)[0]
        np.testing.assert_allclose(observation, reference_observation(env), rtol=0, atol=1e-6)


def test_each_observation_is_its_own_array() -> None:
    env: Any = gym.make("SonarGym/BeaconScan-v0", temperature_c=20.0)
    first, _ = env.reset(seed=4)
    kept = first.copy()
    first[:] = 0.5  # a learner may write into what it was given
    pan = env.unwrapped.encode_action("pan", centre_deg=0, width_deg=90, increment_deg=2)
    second, *_ = env.step(pan)
    third, *_ = env.step(env.unwrapped.encode_action("calibrate"))
    assert not np.shares_memory(second, third)
    np.testing.assert_array_equal(first, np.full_like(first, 0.5))
    steps = env.unwrapped.observation_layout["steps"]
    assert second[steps] == pytest.approx(1 / 12) and third[steps] == pytest.approx(2 / 12)
    assert kept[steps] == 0.0 and env.observation_space.contains(second)
    scanned = env.unwrapped.observation_layout["bin_scanned"]
    assert kept[scanned].sum() == 0.0 and second[scanned].sum() > 0.0
