"""Real training runs on every registered environment (the slow group: ``make test-slow``).

Each run trains PPO for a few thousand steps with the env's tuned config, saves the model and
its VecNormalize statistics, loads it back as an agent and evaluates it against the random
agent on the same seeds. A policy that has learned nothing would not reliably beat random.
"""

from __future__ import annotations

from pathlib import Path

import pytest

import sonar_gym  # noqa: F401
from sonar_gym.registration import ENVIRONMENTS
from sonar_gym.train.evaluation import evaluate_agents
from sonar_gym.train.training import train

pytestmark = pytest.mark.slow


# Environment steps per run: episodes differ from 1 decision (BlockExpansion) to dozens, and a
# step costs from about 1 ms (BeaconScan) to about 70 ms (BlockExpansion).
TIMESTEPS = {
    "SonarGym/BeaconScan-v0": 20_000,
    "SonarGym/ActiveBeaconScan-v0": 40_000,  # the shipped policy's recipe
    "SonarGym/SweepLocalization-v0": 8_192,
    "SonarGym/Trilateration-v0": 8_192,
    "SonarGym/BlockExpansion-v0": 2_048,
    "SonarGym/WallCorrection-v0": 4_096,
}


@pytest.mark.timeout(1800)
@pytest.mark.parametrize("env_id", sorted(ENVIRONMENTS))
def test_ppo_trains_saves_loads_and_beats_random(env_id: str, tmp_path: Path) -> None:
    result = train(
        env_id,
        "ppo",
        timesteps=TIMESTEPS[env_id],
        out_dir=tmp_path / "run",
        seed=0,
        progress_bar=False,
        eval_episodes=0,
    )
    assert result.model_path.exists() and result.vecnormalize_path.exists()
    assert result.learning_curve_path.exists()
    results = evaluate_agents([env_id], [str(result.model_path), "random"], episodes=30, seed=1000)
    reward = {r.agent: r.summary.reward.mean for r in results}
    learned = next(value for name, value in reward.items() if name != "random")
    assert learned > reward["random"]
