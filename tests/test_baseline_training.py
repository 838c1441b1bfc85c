"""The baseline trainer: return bookkeeping, behaviour cloning, selection and the shipped format."""

from __future__ import annotations

import csv
import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import torch

from sonar_gym.agents.learned import load_policy_agent
from sonar_gym.train import baseline_training as bt
from sonar_gym.train.evaluation import make_env, run_episode

torch.set_num_threads(1)


def test_forward_discounted_sums_restart_at_each_episode() -> None:
    rewards = np.array([1.0, 2.0, 3.0, 10.0, 20.0])
    starts = np.array([True, False, False, True, False])
    # by hand with gamma 0.5: 1, 2 + 0.5, 3 + 1.25; then 10, 20 + 5
    assert bt._discounted(rewards, starts, 0.5) == pytest.approx([1.0, 2.5, 4.25, 10.0, 25.0])


def test_returns_to_go_stop_at_each_episode_end() -> None:
    rewards = np.array([1.0, 2.0, 3.0, 10.0, 20.0])
    starts = np.array([True, False, False, True, False])
    # by hand with gamma 0.5: 1 + 0.5 * (2 + 0.5 * 3), 2 + 1.5, 3; then 10 + 10, 20
    assert bt._returns_to_go(rewards, starts, 0.5) == pytest.approx([2.75, 3.5, 3.0, 20.0, 20.0])


def test_teacher_is_the_best_candidate_on_validation() -> None:
    levels = {"paper": -4.6, "sector": -4.4, "random": -18.0}
    assert bt.choose_teacher(levels, ("paper", "sector")) == "sector"
    assert bt.choose_teacher(levels, ("paper",)) == "paper"


def test_every_env_has_a_recipe_with_disjoint_seed_streams() -> None:
    from sonar_gym.pretrained import EVALUATION_SEED_START, VALIDATION_SEED_START
    from sonar_gym.train.evaluation import registered_env_ids

    assert set(bt.RECIPES) == set(registered_env_ids())
    for recipe in bt.RECIPES.values():
        teacher_seeds = max(recipe.training_seeds) * bt.TEACHER_SEED_STRIDE + recipe.demo_episodes
        assert teacher_seeds < min(EVALUATION_SEED_START, VALIDATION_SEED_START)
        assert VALIDATION_SEED_START + recipe.validation_episodes <= EVALUATION_SEED_START or (
            EVALUATION_SEED_START + 10_000 <= VALIDATION_SEED_START
        )


def _tiny_recipe(**changes: object) -> bt.BaselineRecipe:
    base = dataclasses.replace(
        bt.RECIPES["SonarGym/Trilateration-v0"],
        demo_episodes=12,
        clone_epochs=60,
        timesteps=0,
        validation_episodes=3,
        training_seeds=(0,),
    )
    return dataclasses.replace(base, **changes)


def test_cloning_reproduces_the_teachers_actions() -> None:
    """After cloning, the deterministic policy picks the teacher's action in the states the
    teacher visited, far more often than the untrained one (Trilateration has 7 actions)."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from sonar_gym.train.training import load_config, make_training_vec_env

    recipe = _tiny_recipe()
    config = load_config(recipe.env_id, bt.ALGO)
    venv = VecNormalize(
        make_training_vec_env(recipe.env_id, 1, 0, {}, None), **config.vec_normalize_kwargs("ppo")
    )
    model = PPO(config.policy, venv, seed=0, policy_kwargs=config.sb3_policy_kwargs())
    demos = bt.collect_demonstrations(recipe.env_id, {}, "adaptive", range(recipe.demo_episodes))
    before = model.predict(venv.normalize_obs(demos.observations), deterministic=True)[0]
    bt.clone_teacher(model, venv, demos, recipe.clone_epochs, seed=0)
    after = model.predict(venv.normalize_obs(demos.observations), deterministic=True)[0]
    venv.close()
    agreement = float(np.mean(after == demos.actions))
    assert agreement >= 0.75, agreement  # chance: 1 in 7
    assert agreement > float(np.mean(before == demos.actions)) + 0.3


def test_a_seed_run_keeps_its_best_checkpoint_and_ships_loadable(tmp_path: Path) -> None:
    recipe = _tiny_recipe(timesteps=256, eval_every=128, demo_episodes=4, clone_epochs=5)
    run = bt.train_seed(recipe, "adaptive", 0, tmp_path / "run")
    assert [point.timesteps for point in run.curve][0] == 0
    assert run.best_reward == max(point.mean_reward for point in run.curve)
    levels = {"paper": -20.0, "adaptive": -17.0, "random": -30.0}
    out = bt.write_shipped(recipe, "adaptive", levels, [run], tmp_path / "Trilateration-v0")
    for name in (
        "model.zip",
        "vecnormalize.pkl",
        "run.json",
        "learning_curve.csv",
        "training.json",
    ):
        assert (out / name).is_file(), name
    training = json.loads((out / "training.json").read_text())
    assert training["teacher"] == "adaptive" and training["levels"] == levels
    assert training["selected_timesteps"] == run.best_timesteps
    with (out / "learning_curve.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == len(run.curve)
    env = make_env(recipe.env_id)
    agent = load_policy_agent(out, env)
    # the shipped policy scores what the selection measured on the validation seeds
    rewards = [run_episode(env, agent, seed).reward for seed in bt.validation_seeds(recipe)]
    env.close()
    assert np.mean(rewards) == pytest.approx(run.best_reward, rel=1e-9, abs=1e-9)


def test_teacher_episodes_are_dealt_over_the_variants() -> None:
    recipe = dataclasses.replace(
        bt.RECIPES["SonarGym/BlockExpansion-v0"],
        demo_episodes=4,
        demo_variants=({}, {"layout": "random", "path": "random"}),
    )
    mixed = bt.teacher_demonstrations(recipe, "spread", training_seed=1)
    assert int(mixed.episode_starts.sum()) == 4
    plain = bt.collect_demonstrations(
        recipe.env_id, {}, "spread", [bt.TEACHER_SEED_STRIDE, bt.TEACHER_SEED_STRIDE + 2]
    )
    jittered = bt.collect_demonstrations(
        recipe.env_id,
        {"layout": "random", "path": "random"},
        "spread",
        [bt.TEACHER_SEED_STRIDE + 1, bt.TEACHER_SEED_STRIDE + 3],
    )
    assert np.array_equal(
        mixed.observations, np.concatenate([plain.observations, jittered.observations])
    )
    assert not np.array_equal(plain.observations, jittered.observations[: len(plain.observations)])
