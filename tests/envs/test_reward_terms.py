"""Every env gives its reward as named terms through the base and reports the shared info keys.

The base sums a step's terms in order into the reward and copies them into
``info["rewards"]``; every registered task opts in to the enforced :data:`INFO_KEYS`.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.envs.base import INFO_KEYS, REWARD_TERMS, SonarEnv, StepOutcome
from sonar_gym.agents import make_agent
from sonar_gym.envs.block_expansion import BlockExpansionEnv
from sonar_gym.registration import ENVIRONMENTS
from sonar_gym.train.evaluation import run_episode
from tests.fuzzing import fuzz_settings
from tests.test_fuzz_actions import action_in

ENV_IDS = sorted(ENVIRONMENTS)
MAX_ACTIONS = 14
"""Long enough to reach BeaconScan's truncation after ``max_steps`` = 12 decisions."""
TERM_NAMES = {
    "SonarGym/BeaconScan-v0": ["sensing_cost", "pose_error", "failure"],
    "SonarGym/ActiveBeaconScan-v0": ["sensing_cost", "pose_error", "failure"],
    "SonarGym/SweepLocalization-v0": ["pose_error", "sensing_cost"],
    "SonarGym/Trilateration-v0": ["pose_error", "sensing_cost"],
    "SonarGym/BlockExpansion-v0": ["sensing_cost", "path_loss"],
    "SonarGym/WallCorrection-v0": ["pose_error", "sensing_cost", "collision"],
}
"""Each env's terms, in the order its reward adds them (written out, not read from the envs)."""


@cache
def env_for(env_id: str) -> gym.Env:
    return gym.make(env_id)


def assert_shared_info(info: dict[str, Any]) -> None:
    assert set(INFO_KEYS) <= set(info), sorted(info)
    for key in ("position_error_m", "heading_error_rad", "sensing_time_s"):
        assert isinstance(info[key], float) and math.isfinite(info[key]) and info[key] >= 0.0


@pytest.mark.parametrize("env_id", ENV_IDS)
@fuzz_settings(25)
@given(data=st.data(), seed=st.integers(0, 2**31 - 1))
def test_reward_terms_sum_to_the_reward_under_random_actions(
    env_id: str, data: st.DataObject, seed: int
) -> None:
    env = env_for(env_id)
    actions = data.draw(st.lists(action_in(env.action_space), min_size=1, max_size=MAX_ACTIONS))
    _, info = env.reset(seed=seed)
    assert_shared_info(info)
    total, per_term = 0.0, dict.fromkeys(TERM_NAMES[env_id], 0.0)
    for action in actions:
        _, reward, terminated, truncated, info = env.step(action)
        terms = info["rewards"]
        assert list(terms) == TERM_NAMES[env_id]
        assert all(isinstance(value, float) and math.isfinite(value) for value in terms.values())
        assert math.fsum(terms.values()) == pytest.approx(reward, rel=1e-12, abs=1e-12)
        assert_shared_info(info)
        total += reward
        for name, value in terms.items():
            per_term[name] += value
        if terminated or truncated:
            break
    record = env.unwrapped.episode
    assert record.total_reward == pytest.approx(total, rel=1e-12, abs=1e-12)
    assert record.reward_terms == pytest.approx(per_term, rel=1e-12, abs=1e-12)


def test_every_term_name_is_a_documented_one() -> None:
    assert {name for names in TERM_NAMES.values() for name in names} <= set(REWARD_TERMS)
    assert set(TERM_NAMES) == set(ENV_IDS)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_every_env_enforces_the_shared_info_keys(env_id: str) -> None:
    assert set(INFO_KEYS) <= set(type(env_for(env_id).unwrapped).required_info_keys)


def test_block_expansion_reports_a_zero_heading_error_since_it_estimates_no_heading() -> None:
    env = gym.make("SonarGym/BlockExpansion-v0")
    _, info = env.reset(seed=0)
    assert info["heading_error_rad"] == 0.0
    _, _, _, _, info = env.step(env.action_space.sample())
    assert info["heading_error_rad"] == 0.0 and info["position_error_m"] > 0.0
    assert env.unwrapped.unestimated_info_keys == ("heading_error_rad",)


@pytest.mark.parametrize(
    ("env_id", "has_heading"),
    [("SonarGym/BlockExpansion-v0", False), ("SonarGym/Trilateration-v0", True)],
)
def test_evaluation_leaves_out_a_heading_error_the_task_does_not_estimate(
    env_id: str, has_heading: bool
) -> None:
    env = gym.make(env_id)
    record = run_episode(env, make_agent("paper", env), seed=0)
    assert (record.heading_error_rad is not None) == has_heading
    assert record.position_error_m is not None


class _ForgetfulBlockExpansion(BlockExpansionEnv):
    """BlockExpansion whose steps forget ``heading_error_rad`` (a task with a missing key)."""

    def _apply_action(self, action: Any) -> StepOutcome:
        outcome = super()._apply_action(action)
        del outcome.info["heading_error_rad"]
        return outcome


def test_a_task_that_omits_a_required_key_fails_naming_it() -> None:
    env = _ForgetfulBlockExpansion()
    env.reset(seed=0)
    with pytest.raises(RuntimeError, match=r"lacks the required key\(s\) \['heading_error_rad'\]"):
        env.step(env.action_space.sample())


class _TermsEnv(SonarEnv):
    """Every step pays the terms given to the constructor; one step per episode."""

    def __init__(self, terms: dict[str, float]) -> None:
        super().__init__()
        self.observation_space = gym.spaces.Box(0.0, 1.0, shape=(1,), dtype=np.float32)
        self.action_space = gym.spaces.Discrete(1)
        self.observation_layout = {"zero": slice(0, 1)}
        self.terms = terms

    def _reset_task(self, options: dict[str, Any] | None) -> dict[str, Any]:
        return {}

    def _apply_action(self, action: Any) -> StepOutcome:
        return StepOutcome(reward_terms=self.terms, terminated=True)

    def _observe(self) -> np.ndarray:
        return np.zeros(1, dtype=np.float32)

    def _render_frame(self) -> np.ndarray:
        return np.zeros((2, 2, 3), dtype=np.uint8)


def _reward(terms: dict[str, float]) -> float:
    env = _TermsEnv(terms)
    env.reset(seed=0)
    return float(env.step(0)[1])


def test_terms_are_summed_left_to_right_as_written_by_hand() -> None:
    # (1e16 + 1.0) rounds back to 1e16, so the plain sum is 0.0 where a compensated one is 1.0
    assert _reward({"a": 1e16, "b": 1.0, "c": -1e16}) == 0.0
    assert _reward({"a": 1.0, "b": 1e16, "c": -1e16}) == 0.0
    assert _reward({"a": 1e16, "c": -1e16, "b": 1.0}) == 1.0


def test_a_zero_placeholder_term_keeps_a_negative_zero_reward() -> None:
    reward = _reward({"sensing_cost": -0.0, "failure": 0.0})
    assert reward == 0.0 and math.copysign(1.0, reward) == -1.0
    assert math.copysign(1.0, _reward({"sensing_cost": 0.0, "failure": -0.0})) == 1.0


def test_terms_whose_sum_overflows_are_refused() -> None:
    with pytest.raises(RuntimeError, match="overflow"):
        _reward({"a": -1.7e308, "b": -1.7e308})
