"""The policies shipped in ``sonar_gym/pretrained/``: present for every env, loadable as agent
``learned``, recorded honestly, and reproducing in this process what their trainer measured."""

from __future__ import annotations

import csv
import json

import gymnasium as gym
import numpy as np
import pytest
import torch

from sonar_gym import pretrained
from sonar_gym.agents import make_agent
from sonar_gym.train.evaluation import registered_env_ids, run_episode

torch.set_num_threads(1)
ENV_IDS = registered_env_ids()
FAST_TO_REPLAY = ("SonarGym/BlockExpansion-v0", "SonarGym/BeaconScan-v0")


def _training(env_id: str) -> dict:
    return json.loads((pretrained.policy_dir(env_id) / pretrained.TRAINING_FILE).read_text())


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_a_policy_ships_for_every_env_and_acts_in_its_space(env_id: str) -> None:
    env = gym.make(env_id)
    agent = make_agent("learned", env)
    observation, _ = env.reset(seed=pretrained.EVALUATION_SEED_START)
    for _ in range(3):
        action = agent.act(observation)
        assert env.action_space.contains(action)
        observation, reward, terminated, truncated, _ = env.step(action)
        assert np.isfinite(reward) and np.all(np.isfinite(observation))
        if terminated or truncated:
            break
    env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_the_training_record_is_consistent(env_id: str) -> None:
    training = _training(env_id)
    assert training["env_id"] == env_id
    assert len(training["training_seeds"]) >= 3
    assert set(training["training_seeds"]) <= set(pretrained.TRAINING_SEEDS)
    assert training["selected_seed"] in training["training_seeds"]
    assert training["validation_seeds"]["start"] == pretrained.VALIDATION_SEED_START
    assert {"paper", "random"} <= set(training["levels"])
    best = training["best_validation_reward"]
    # the shipped seed is the best one, and its recorded best is a point of the curve
    assert best[str(training["selected_seed"])] == max(best.values())
    with (pretrained.policy_dir(env_id) / pretrained.LEARNING_CURVE_FILE).open() as handle:
        rows = list(csv.DictReader(handle))
    assert {int(row["training_seed"]) for row in rows} == set(training["training_seeds"])
    selected = [
        float(row["mean_reward"])
        for row in rows
        if int(row["training_seed"]) == training["selected_seed"]
        and int(row["timesteps"]) == training["selected_timesteps"]
    ]
    assert max(selected) == pytest.approx(best[str(training["selected_seed"])], abs=1e-6)


@pytest.mark.parametrize("env_id", FAST_TO_REPLAY)
def test_the_shipped_policy_scores_what_its_trainer_measured(env_id: str) -> None:
    """Replays the validation seeds in this process: same files, same seeds, same number."""
    training = _training(env_id)
    env = gym.make(env_id)
    agent = make_agent("learned", env)
    seeds = range(
        training["validation_seeds"]["start"],
        training["validation_seeds"]["start"] + training["validation_seeds"]["count"],
    )
    rewards = [run_episode(env, agent, seed).reward for seed in seeds]
    env.close()
    recorded = training["best_validation_reward"][str(training["selected_seed"])]
    assert float(np.mean(rewards)) == pytest.approx(recorded, abs=1e-6)


def _evaluation_records(env_id: str, agents: list[str], episodes: int) -> dict[str, list]:
    """Each agent's episodes on the first ``episodes`` evaluation seeds, by agent name."""
    from sonar_gym.train.evaluation import evaluate_agents

    results = evaluate_agents(
        [env_id], agents, episodes=episodes, seed=pretrained.EVALUATION_SEED_START
    )
    return {result.agent: list(result.records) for result in results}


# what README's table claims, on the evaluation seeds nobody trained or selected on; over
# 200 seeds BeaconScan's interval is too wide to decide (see the next test)
BEATS_THE_PAPER = tuple(env_id for env_id in ENV_IDS if env_id != "SonarGym/BeaconScan-v0")
BEATS_THE_HEURISTIC = ("SonarGym/SweepLocalization-v0", "SonarGym/ActiveBeaconScan-v0")


@pytest.mark.slow
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_the_learned_agent_against_the_paper_and_the_heuristic(env_id: str) -> None:
    from sonar_gym.train.baselines import beats, heuristic_agent, paired_difference

    heuristic = heuristic_agent(env_id)
    results = _evaluation_records(
        env_id, ["learned", "paper", heuristic], pretrained.DEFAULT_EVALUATION_EPISODES
    )
    versus_paper = paired_difference(results["learned"], results["paper"])
    versus_heuristic = paired_difference(results["learned"], results[heuristic])
    assert beats(versus_paper) is (env_id in BEATS_THE_PAPER), versus_paper
    assert beats(versus_heuristic) is (env_id in BEATS_THE_HEURISTIC), versus_heuristic


@pytest.mark.slow
def test_moving_learned_agent_localizes_from_95_percent_of_lab_poses() -> None:
    from sonar_gym.train.evaluation import evaluate_agents, summarize

    (result,) = evaluate_agents(
        ["SonarGym/ActiveBeaconScan-v0"],
        ["learned"],
        episodes=pretrained.DEFAULT_EVALUATION_EPISODES,
        seed=pretrained.EVALUATION_SEED_START,
    )
    summary = summarize(result.records)
    assert summary.success_rate >= 0.95
    assert summary.position_error_p95_m is not None and summary.position_error_p95_m <= 0.03


# over the wide evaluation, where 200 seeds cannot decide: BeaconScan against the paper (a
# pose only one agent fails moves the difference by 20), Trilateration against the adaptive
# planner (a gain of about 0.15 inside an interval of +-0.4)
WIDE_CLAIMS = (("SonarGym/BeaconScan-v0", "paper"), ("SonarGym/Trilateration-v0", "heuristic"))


@pytest.mark.slow
@pytest.mark.parametrize(("env_id", "reference"), WIDE_CLAIMS)
def test_the_learned_agent_beats_its_reference_over_the_wide_evaluation(
    env_id: str, reference: str
) -> None:
    from sonar_gym.train.baselines import beats, heuristic_agent, paired_difference

    other = heuristic_agent(env_id) if reference == "heuristic" else reference
    results = _evaluation_records(env_id, ["learned", other], pretrained.WIDE_EVALUATION_EPISODES)
    difference = paired_difference(results["learned"], results[other])
    assert beats(difference), difference
