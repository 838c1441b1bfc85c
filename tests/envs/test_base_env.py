"""The shared env base: reward terms, the episode record, enforced info keys, truncation."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

from sonar_gym.envs.base import INFO_KEYS, SonarEnv, StepOutcome, unwrap_sonar_env


class _CountdownEnv(SonarEnv):
    """Action 1 ends the episode; every step pays the terms given to the constructor."""

    def __init__(
        self, terms: dict[str, float] | None = None, reward: float = 0.0, info: Any = None
    ) -> None:
        super().__init__()
        self.observation_space = gym.spaces.Box(0.0, 100.0, shape=(1,), dtype=np.float32)
        self.action_space = gym.spaces.Discrete(2)
        self.observation_layout = {"steps": slice(0, 1)}
        self.terms = terms
        self.reward = reward
        self.info = {} if info is None else info
        self.steps = 0

    def _reset_task(self, options: dict[str, Any] | None) -> dict[str, Any]:
        self.steps = 0
        return {}

    def _apply_action(self, action: Any) -> StepOutcome:
        self.steps += 1
        return StepOutcome(
            self.reward, terminated=action == 1, info=dict(self.info), reward_terms=self.terms
        )

    def _observe(self) -> np.ndarray:
        return np.array([self.steps], dtype=np.float32)

    def _render_frame(self) -> np.ndarray:
        return np.zeros((2, 2, 3), dtype=np.uint8)


class _StrictEnv(_CountdownEnv):
    required_info_keys = INFO_KEYS


def test_reward_terms_are_summed_and_copied_into_info() -> None:
    env = _CountdownEnv(terms={"pose_error": -0.75, "sensing_time": -0.125})
    env.reset(seed=0)
    _, reward, _, _, info = env.step(0)
    _, second_reward, terminated, _, _ = env.step(1)
    assert reward == second_reward == -0.875
    assert info["rewards"] == {"pose_error": -0.75, "sensing_time": -0.125}
    assert terminated
    record = env.episode
    assert (record.steps, record.total_reward, record.done) == (2, -1.75, True)
    assert record.reward_terms == {"pose_error": -1.5, "sensing_time": -0.25}


def test_a_task_without_terms_keeps_its_reward_and_info_unchanged() -> None:
    env = _CountdownEnv(reward=-2.0, info={"status": "sensing"})
    env.reset(seed=0)
    _, reward, terminated, truncated, info = env.step(0)
    assert (reward, terminated, truncated, info) == (-2.0, False, False, {"status": "sensing"})


def test_reward_and_terms_together_are_refused() -> None:
    env = _CountdownEnv(terms={"pose_error": -1.0}, reward=-1.0)
    env.reset(seed=0)
    with pytest.raises(RuntimeError, match="either reward or reward_terms"):
        env.step(0)


def test_a_non_finite_reward_term_is_refused_by_name() -> None:
    env = _CountdownEnv(terms={"pose_error": float("nan"), "sensing_time": -0.1})
    env.reset(seed=0)
    with pytest.raises(RuntimeError, match="non-finite reward term.*pose_error"):
        env.step(0)


def test_required_info_keys_are_enforced_when_a_task_opts_in() -> None:
    env = _StrictEnv(info={"status": "ok", "position_error_m": 0.1})
    env.reset(seed=0)
    with pytest.raises(RuntimeError, match=r"'heading_error_rad', 'sensing_time_s'"):
        env.step(0)


def test_max_decisions_truncates_and_says_so() -> None:
    env = _CountdownEnv()
    env.max_decisions = 2
    env.reset(seed=0)
    assert env.step(0)[2:4] == (False, False)
    _, _, terminated, truncated, info = env.step(0)
    assert (terminated, truncated, info["status"]) == (False, True, "truncated")
    with pytest.raises(RuntimeError, match="call reset"):
        env.step(0)


def test_episode_count_changes_exactly_at_reset() -> None:
    env = _CountdownEnv()
    assert env.episode_count == 0
    env.reset(seed=0)
    env.step(0)
    assert env.episode_count == 1
    env.reset()
    assert (env.episode_count, env.episode.steps) == (2, 0)


def test_unwrap_sonar_env_finds_the_env_under_wrappers_and_refuses_others() -> None:
    env = _CountdownEnv()
    assert unwrap_sonar_env(gym.wrappers.TimeLimit(env, 5)) is env
    with pytest.raises(ValueError, match="sonar_gym environment.*CartPoleEnv.*CartPole-v1"):
        unwrap_sonar_env(gym.make("CartPole-v1"))
