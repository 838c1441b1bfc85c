"""Soak: every env for many seeded random steps, and eight envs in an ``AsyncVectorEnv``.

Slow group only (``pytest -m slow tests/test_soak.py``). ``SONAR_GYM_SOAK_STEPS`` sets the
steps per env (default 100,000); a small value checks the machinery in seconds. Memory is
the process's resident set size, read from ``/proc/self/statm`` (Linux); after a warm-up of
a tenth of the steps it may grow by at most :data:`RSS_GROWTH_LIMIT_MB`.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.registration import ENVIRONMENTS

SOAK_STEPS = int(os.environ.get("SONAR_GYM_SOAK_STEPS", "100000"))
RSS_GROWTH_LIMIT_MB = 64.0
"""Allowed resident-memory growth after warm-up, MiB: caches fill early, leaks keep growing."""
VECTOR_ENVS = 8


def rss_mb() -> float:
    """Resident set size of this process, MiB (Linux ``/proc``, where the slow group runs)."""
    resident_pages = int(Path("/proc/self/statm").read_text().split()[1])
    return resident_pages * os.sysconf("SC_PAGE_SIZE") / 2**20


@pytest.mark.slow
@pytest.mark.timeout(3600)  # 1e5 steps of the slowest env take about ten minutes on one core
@pytest.mark.parametrize("env_id", sorted(ENVIRONMENTS))
def test_env_soaks_without_leak_nan_or_exception(env_id: str) -> None:
    env = gym.make(env_id)
    env.action_space.seed(0)
    env.reset(seed=0)
    warm_up = max(SOAK_STEPS // 10, 1)
    baseline = rss_mb()
    episodes = 0
    for step in range(SOAK_STEPS):
        if step == warm_up:
            baseline = rss_mb()
        observation, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        assert np.all(np.isfinite(observation)), (step, observation)
        assert math.isfinite(float(reward)), (step, reward)
        if terminated or truncated:
            episodes += 1
            env.reset(seed=episodes)
    growth = rss_mb() - baseline
    assert growth <= RSS_GROWTH_LIMIT_MB, f"{env_id}: RSS grew {growth:.1f} MiB after warm-up"
    env.close()


@pytest.mark.slow
@pytest.mark.parametrize("env_id", sorted(ENVIRONMENTS))
def test_async_vector_env_of_eight_runs(env_id: str) -> None:
    envs = gym.vector.AsyncVectorEnv([lambda: gym.make(env_id)] * VECTOR_ENVS)
    try:
        envs.action_space.seed(0)
        observations, _ = envs.reset(seed=0)
        assert observations.shape[0] == VECTOR_ENVS
        for _ in range(max(SOAK_STEPS // 100, 5)):
            observations, rewards, *_ = envs.step(envs.action_space.sample())
            assert np.all(np.isfinite(observations))
            assert np.all(np.isfinite(rewards))
    finally:
        envs.close()
