"""Train the shipped baseline policies: a teacher warm start, PPO fine-tuning, selection by
validation reward.

One recipe per env (:data:`RECIPES`). For each training seed:

1. **Warm start (behaviour cloning).** The best scripted agent on the validation seeds (the
   *teacher*: the paper's procedure or the env's heuristic) plays ``demo_episodes`` episodes
   on seeds of its own stream. The ``VecNormalize`` statistics are fitted to those
   observations and returns, then the PPO policy is trained to maximise the log-likelihood of
   the teacher's actions and its value head to regress the teacher's normalised discounted
   returns.
2. **PPO fine-tuning** for ``timesteps`` env steps with the env's tuned config
   (``train/configs/<env>.ppo.toml``) and the recipe's overrides.
3. **Selection.** Every ``eval_every`` steps (and right after the warm start) the deterministic
   policy is scored on the fixed validation seeds; the best checkpoint is kept.

The seed with the best validation reward ships. Validation seeds start at
:data:`~sonar_gym.pretrained.VALIDATION_SEED_START`, the seeds of the evaluation table at
:data:`~sonar_gym.pretrained.EVALUATION_SEED_START`; the training streams (SB3 seeds 0, 1, 2 and
the teacher's episodes below 1,000,000) never reach either.

Output (per env, the shipped-policy format of :mod:`sonar_gym.pretrained`): ``model.zip``,
``vecnormalize.pkl``, ``run.json``, ``learning_curve.csv`` and ``training.json``.
"""

from __future__ import annotations

import csv
import json
import shutil
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecNormalize

from sonar_gym.agents.learned import (
    MODEL_FILE,
    RUN_FILE,
    VECNORMALIZE_FILE,
    PolicyAgent,
    algorithm_class,
)
from sonar_gym.pretrained import (
    DEFAULT_VALIDATION_EPISODES,
    LEARNING_CURVE_COLUMNS,
    LEARNING_CURVE_FILE,
    TRAINING_FILE,
    TRAINING_SEEDS,
    VALIDATION_SEED_START,
)
from sonar_gym.train.evaluation import (
    evaluate_agents,
    make_env,
    make_named_agent,
    parse_env_args,
    run_episode,
    software_versions,
    t_confidence_interval,
)
from sonar_gym.train.training import load_config, make_training_vec_env

ALGO = "ppo"
TEACHER_SEED_STRIDE = 100_000
"""Teacher episodes of training seed ``s`` use the seeds ``s * stride + i``."""


@dataclass(frozen=True)
class BaselineRecipe:
    """How the shipped policy of one env is trained.

    Attributes:
        env_id: the env.
        candidates: scripted agents the teacher is chosen from (best on the validation seeds).
        timesteps: PPO env steps per training seed after the warm start.
        demo_episodes: teacher episodes for the warm start.
        demo_variants: ``gym.make`` arguments (over ``env_kwargs``) the teacher's episodes are
            spread over in turn, e.g. ``({}, {"scenario": "random"})`` to show it random rooms
            too (rooms of the teacher's own seeds, never the validation or evaluation ones).
        clone_epochs: passes over the demonstrations.
        eval_every: env steps between validation scores.
        validation_episodes: validation seeds per score.
        training_seeds: SB3 seeds; one run each.
        hyperparameters: overrides of the env's PPO config.
        env_kwargs: ``gym.make`` arguments of training and of the shipped policy.
    """

    env_id: str
    candidates: tuple[str, ...]
    timesteps: int
    demo_episodes: int = 300
    demo_variants: tuple[Mapping[str, Any], ...] = ({},)
    clone_epochs: int = 30
    eval_every: int = 4096
    validation_episodes: int = DEFAULT_VALIDATION_EPISODES
    training_seeds: tuple[int, ...] = TRAINING_SEEDS
    hyperparameters: Mapping[str, Any] = field(default_factory=dict)
    env_kwargs: Mapping[str, Any] = field(default_factory=dict)


_FINE_TUNING = {"learning_rate": 1e-4, "ent_coef": 0.0}
_RANDOM_LAYOUT = {"layout": "random", "path": "random"}
RECIPES: dict[str, BaselineRecipe] = {
    recipe.env_id: recipe
    for recipe in (
        BaselineRecipe("SonarGym/BeaconScan-v0", ("paper", "sector"), 20_000,
                       demo_episodes=15_000, demo_variants=({}, {"scenario": "random"}),
                       clone_epochs=100, validation_episodes=1000, hyperparameters=_FINE_TUNING),
        BaselineRecipe("SonarGym/ActiveBeaconScan-v0", ("paper", "retry"), 40_000,
                       demo_episodes=3000, clone_epochs=150, hyperparameters=_FINE_TUNING),
        BaselineRecipe("SonarGym/SweepLocalization-v0", ("paper", "covariance"), 20_000,
                       demo_episodes=100, hyperparameters=_FINE_TUNING),
        BaselineRecipe("SonarGym/Trilateration-v0", ("paper", "adaptive"), 40_000,
                       demo_episodes=100, hyperparameters=_FINE_TUNING),
        BaselineRecipe("SonarGym/BlockExpansion-v0", ("paper", "spread"), 8_192,
                       demo_episodes=600, demo_variants=({}, _RANDOM_LAYOUT), eval_every=2048,
                       hyperparameters={"learning_rate": 1e-4}),
        BaselineRecipe("SonarGym/WallCorrection-v0", ("paper", "both_walls"), 8_192,
                       demo_episodes=100, eval_every=2048, validation_episodes=60,
                       hyperparameters=_FINE_TUNING),
    )
}  # fmt: skip


# --------------------------------------------------------------------------------------------
# scripted levels and demonstrations


def validation_seeds(recipe: BaselineRecipe) -> list[int]:
    """The fixed validation seeds of ``recipe``."""
    return [VALIDATION_SEED_START + i for i in range(recipe.validation_episodes)]


def scripted_levels(recipe: BaselineRecipe) -> dict[str, float]:
    """Mean validation reward of each candidate teacher and of ``random``."""
    results = evaluate_agents(
        [recipe.env_id],
        [*recipe.candidates, "random"],
        episodes=recipe.validation_episodes,
        seed=VALIDATION_SEED_START,
        env_kwargs=recipe.env_kwargs,
    )
    return {
        result.agent: float(np.mean([record.reward for record in result.records]))
        for result in results
    }


@dataclass(frozen=True)
class Demonstrations:
    """A teacher's transitions: raw observations, actions, rewards, episode starts."""

    observations: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    episode_starts: np.ndarray

    FIELDS: ClassVar[tuple[str, ...]] = ("observations", "actions", "rewards", "episode_starts")


def collect_demonstrations(
    env_id: str, env_kwargs: Mapping[str, Any], teacher: str, seeds: Sequence[int]
) -> Demonstrations:
    """Play ``teacher`` for one episode per seed and record every transition."""
    env = make_env(env_id, env_kwargs)
    agent = make_named_agent(teacher, env)
    observations, actions, rewards, starts = [], [], [], []
    try:
        for seed in seeds:
            agent.reset(seed=seed)
            observation, _ = env.reset(seed=seed)
            done, first = False, True
            while not done:
                action = agent.act(observation)
                observations.append(np.asarray(observation, dtype=np.float32))
                actions.append(np.asarray(action))
                next_observation, reward, terminated, truncated, _ = env.step(action)
                rewards.append(float(reward))
                starts.append(first)
                first, done, observation = False, terminated or truncated, next_observation
    finally:
        env.close()
    return Demonstrations(
        np.stack(observations), np.stack(actions), np.array(rewards), np.array(starts)
    )


def teacher_demonstrations(
    recipe: BaselineRecipe, teacher: str, training_seed: int
) -> Demonstrations:
    """``recipe.demo_episodes`` episodes of ``teacher`` on training seed ``training_seed``'s
    stream, dealt in turn over ``recipe.demo_variants``."""
    seeds = [training_seed * TEACHER_SEED_STRIDE + i for i in range(recipe.demo_episodes)]
    variants = recipe.demo_variants
    parts = [
        collect_demonstrations(
            recipe.env_id, {**recipe.env_kwargs, **variant}, teacher, seeds[i :: len(variants)]
        )
        for i, variant in enumerate(variants)
    ]
    return Demonstrations(
        *(np.concatenate([getattr(part, name) for part in parts]) for name in Demonstrations.FIELDS)
    )


def _discounted(rewards: np.ndarray, starts: np.ndarray, gamma: float) -> np.ndarray:
    """Forward discounted sums (what ``VecNormalize`` tracks for its reward scale)."""
    running, out = 0.0, np.empty_like(rewards)
    for i, (reward, start) in enumerate(zip(rewards, starts, strict=True)):
        running = reward + (0.0 if start else gamma * running)
        out[i] = running
    return out


def _returns_to_go(rewards: np.ndarray, starts: np.ndarray, gamma: float) -> np.ndarray:
    """Discounted return from each step to its episode's end."""
    out, running = np.empty_like(rewards), 0.0
    for i in range(len(rewards) - 1, -1, -1):
        ends_here = i + 1 == len(rewards) or starts[i + 1]
        running = rewards[i] + (0.0 if ends_here else gamma * running)
        out[i] = running
    return out


def clone_teacher(
    model: Any, venv: VecNormalize, demos: Demonstrations, epochs: int, seed: int
) -> float:
    """Fit ``venv``'s statistics to ``demos``, then train ``model``'s policy to imitate the
    teacher's actions and its value head on the normalised returns. Returns the final mean
    negative log-likelihood of the teacher's actions."""
    gamma = float(model.gamma)
    venv.obs_rms.update(demos.observations.astype(np.float64))
    if venv.norm_reward:
        venv.ret_rms.update(_discounted(demos.rewards, demos.episode_starts, gamma))
        scale = float(np.sqrt(venv.ret_rms.var + venv.epsilon))
        rewards = np.clip(demos.rewards / scale, -venv.clip_reward, venv.clip_reward)
    else:
        rewards = demos.rewards
    targets = _returns_to_go(rewards, demos.episode_starts, gamma)
    policy = model.policy
    observations = torch.as_tensor(venv.normalize_obs(demos.observations), dtype=torch.float32)
    actions = torch.as_tensor(demos.actions)
    value_targets = torch.as_tensor(targets, dtype=torch.float32)
    optimizer = torch.optim.Adam(policy.parameters(), lr=1e-3)
    generator = torch.Generator().manual_seed(seed)
    batch_size = 256
    nll = float("nan")
    policy.set_training_mode(True)
    for _ in range(epochs):
        order = torch.randperm(len(observations), generator=generator)
        losses = []
        for start in range(0, len(order), batch_size):
            index = order[start : start + batch_size]
            values, log_prob, _ = policy.evaluate_actions(observations[index], actions[index])
            action_loss = -log_prob.mean()
            loss = action_loss + 0.5 * torch.nn.functional.mse_loss(
                values.flatten(), value_targets[index]
            )
            optimizer.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(policy.parameters(), 0.5)
            optimizer.step()
            losses.append(action_loss.item())
        nll = float(np.mean(losses))
    policy.set_training_mode(False)
    return nll


# --------------------------------------------------------------------------------------------
# validation and selection


def policy_rewards(model: Any, venv: VecNormalize, env: gym.Env, seeds: list[int]) -> np.ndarray:
    """Episode rewards of the deterministic policy on ``seeds`` in ``env`` (raw rewards)."""
    agent = PolicyAgent("candidate", model, env.action_space, venv)
    return np.array([run_episode(env, agent, seed).reward for seed in seeds])


@dataclass
class CurvePoint:
    """One validation score of a training run."""

    training_seed: int
    timesteps: int
    wall_time_s: float
    mean_reward: float
    ci95: float


class ValidationCallback(BaseCallback):
    """Scores the policy on the validation seeds every ``every`` steps; keeps the best."""

    def __init__(
        self,
        recipe: BaselineRecipe,
        training_seed: int,
        best_dir: Path,
        started: float,
        curve: list[CurvePoint],
        on_score: Callable[[CurvePoint], None] | None = None,
    ) -> None:
        super().__init__()
        self.recipe = recipe
        self.training_seed = training_seed
        self.best_dir = best_dir
        self.started = started
        self.curve = curve
        self.on_score = on_score
        self.best_reward = -np.inf
        self.best_timesteps = 0
        self._next = recipe.eval_every
        self.env = make_env(recipe.env_id, recipe.env_kwargs)  # one env for every score

    def score(self, timesteps: int) -> CurvePoint:
        """Score now; save the model and statistics if this is the best so far."""
        venv = self.model.get_vec_normalize_env()
        if venv is None:
            raise RuntimeError("the baseline trainer always wraps its envs in VecNormalize")
        rewards = policy_rewards(self.model, venv, self.env, validation_seeds(self.recipe))
        point = CurvePoint(
            self.training_seed,
            timesteps,
            round(time.time() - self.started, 2),
            float(rewards.mean()),
            t_confidence_interval(rewards.tolist()).half_width or 0.0,
        )
        self.curve.append(point)
        if point.mean_reward > self.best_reward:
            self.best_reward, self.best_timesteps = point.mean_reward, timesteps
            self.best_dir.mkdir(parents=True, exist_ok=True)
            self.model.save(self.best_dir / MODEL_FILE)
            venv.save(str(self.best_dir / VECNORMALIZE_FILE))
        if self.on_score is not None:
            self.on_score(point)
        return point

    def _on_step(self) -> bool:
        if self.num_timesteps >= self._next:
            self._next += self.recipe.eval_every
            self.score(self.num_timesteps)
        return True


@dataclass(frozen=True)
class SeedRun:
    """What one training seed produced."""

    training_seed: int
    best_dir: Path
    best_reward: float
    best_timesteps: int
    wall_time_s: float
    clone_nll: float
    curve: list[CurvePoint]


def train_seed(
    recipe: BaselineRecipe,
    teacher: str,
    training_seed: int,
    run_dir: Path,
    on_score: Callable[[CurvePoint], None] | None = None,
) -> SeedRun:
    """Warm start from ``teacher``, fine-tune with PPO, keep the best validation checkpoint."""
    torch.manual_seed(training_seed)
    config = load_config(recipe.env_id, ALGO)
    started = time.time()
    venv = VecNormalize(
        make_training_vec_env(recipe.env_id, config.n_envs, training_seed, recipe.env_kwargs, None),
        **config.vec_normalize_kwargs(ALGO),
    )
    model = algorithm_class(ALGO)(
        config.policy,
        venv,
        seed=training_seed,
        verbose=0,
        policy_kwargs=config.sb3_policy_kwargs(),
        **{**dict(config.hyperparameters), **dict(recipe.hyperparameters)},
    )
    demos = teacher_demonstrations(recipe, teacher, training_seed)
    nll = clone_teacher(model, venv, demos, recipe.clone_epochs, training_seed)
    curve: list[CurvePoint] = []
    callback = ValidationCallback(recipe, training_seed, run_dir / "best", started, curve, on_score)
    callback.init_callback(model)
    callback.score(0)
    try:
        if recipe.timesteps > 0:
            model.learn(total_timesteps=recipe.timesteps, callback=callback)
            callback.score(int(model.num_timesteps))
    finally:
        venv.close()
        callback.env.close()
    return SeedRun(
        training_seed,
        run_dir / "best",
        callback.best_reward,
        callback.best_timesteps,
        round(time.time() - started, 2),
        nll,
        curve,
    )


def choose_teacher(levels: Mapping[str, float], candidates: Sequence[str]) -> str:
    """The candidate with the highest validation reward."""
    return max(candidates, key=lambda name: levels[name])


def write_shipped(
    recipe: BaselineRecipe,
    teacher: str,
    levels: Mapping[str, float],
    runs: Sequence[SeedRun],
    out_dir: Path,
    search: Sequence[Mapping[str, Any]] = (),
) -> Path:
    """Copy the best seed's policy into ``out_dir`` in the shipped-policy format."""
    best = max(runs, key=lambda run: run.best_reward)
    out_dir.mkdir(parents=True, exist_ok=True)
    for name in (MODEL_FILE, VECNORMALIZE_FILE):
        shutil.copyfile(best.best_dir / name, out_dir / name)
    config = load_config(recipe.env_id, ALGO)
    run_info = {
        "env_id": recipe.env_id,
        "algo": ALGO,
        "env_kwargs": dict(recipe.env_kwargs),
        "seed": best.training_seed,
        "total_timesteps": best.best_timesteps,
        "config_file": config.source.name,
        "policy": config.policy,
        "hyperparameters": {**dict(config.hyperparameters), **dict(recipe.hyperparameters)},
        "policy_kwargs": dict(config.policy_kwargs),
        "vec_normalize": config.vec_normalize_kwargs(ALGO),
        "versions": software_versions(),
    }
    (out_dir / RUN_FILE).write_text(json.dumps(run_info, indent=2) + "\n")
    with (out_dir / LEARNING_CURVE_FILE).open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(LEARNING_CURVE_COLUMNS)
        for run in runs:
            for point in run.curve:
                writer.writerow(
                    [point.training_seed, point.timesteps, point.wall_time_s,
                     f"{point.mean_reward:.6f}", f"{point.ci95:.6f}"]
                )  # fmt: skip
    training = {
        "env_id": recipe.env_id,
        "algo": ALGO,
        "method": (
            f"behaviour cloning of the {teacher!r} agent ({recipe.demo_episodes} episodes over "
            f"{[dict(v) for v in recipe.demo_variants]}, "
            f"{recipe.clone_epochs} epochs), then PPO fine-tuning; the best validation "
            "checkpoint of the best seed ships"
        ),
        "teacher": teacher,
        "timesteps_per_seed": recipe.timesteps,
        "training_seeds": [run.training_seed for run in runs],
        "selected_seed": best.training_seed,
        "selected_timesteps": best.best_timesteps,
        "validation_seeds": {"start": VALIDATION_SEED_START, "count": recipe.validation_episodes},
        "levels": dict(levels),
        "best_validation_reward": {str(run.training_seed): run.best_reward for run in runs},
        "wall_time_s": {str(run.training_seed): run.wall_time_s for run in runs},
        "clone_nll": {str(run.training_seed): run.clone_nll for run in runs},
        "recipe": {key: value for key, value in asdict(recipe).items() if key != "env_id"},
        "search": list(search),
    }
    (out_dir / TRAINING_FILE).write_text(json.dumps(training, indent=2, default=list) + "\n")
    return out_dir


def _print_score(point: CurvePoint) -> None:
    print(
        f"  seed {point.training_seed} step {point.timesteps:>7,}: "
        f"{point.mean_reward:8.3f} +- {point.ci95:.3f} ({point.wall_time_s:.0f} s)",
        flush=True,
    )


def training_budget(env_ids: Sequence[str]) -> str:
    """A line per env: PPO steps per seed, seeds, teacher episodes."""
    lines = []
    for env_id in env_ids:
        recipe = RECIPES[env_id]
        lines.append(
            f"{env_id}: {len(recipe.training_seeds)} seeds x ({recipe.demo_episodes} teacher "
            f"episodes + {recipe.timesteps:,} PPO steps), scored every {recipe.eval_every:,} "
            f"steps on {recipe.validation_episodes} validation seeds"
        )
    return "\n".join(lines)


def train_baselines(
    env_ids: Sequence[str],
    out_dir: Path,
    progress: bool = True,
    env_kwargs: Mapping[str, Any] | None = None,
) -> dict[str, Path]:
    """Train every env's recipe; returns env id -> directory in the shipped-policy format.

    ``env_kwargs`` replace the recipes' ``gym.make`` arguments, for training and validation
    alike: ``{"scenario": "random"}`` trains BeaconScan's policies over seeded random rooms.
    """
    shipped = {}
    for env_id in env_ids:
        recipe = RECIPES[env_id]
        if env_kwargs is not None:
            recipe = replace(recipe, env_kwargs=dict(env_kwargs))
        name = env_id.rsplit("/", 1)[-1]
        levels = scripted_levels(recipe)
        teacher = choose_teacher(levels, recipe.candidates)
        if progress:
            print(f"{env_id}: teacher {teacher!r}; validation levels {levels}", flush=True)
        report = _print_score if progress else None
        runs = [
            train_seed(recipe, teacher, seed, out_dir / "runs" / name / f"seed{seed}", report)
            for seed in recipe.training_seeds
        ]
        shipped[env_id] = write_shipped(recipe, teacher, levels, runs, out_dir / name)
    return shipped


def _main(argv: Sequence[str] | None = None) -> None:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", nargs="+", default=list(RECIPES))
    parser.add_argument("--out", type=Path, default=Path("results/baselines/training"))
    parser.add_argument(
        "--env-arg", action="append", metavar="KEY=VALUE", help="gym.make argument; repeatable"
    )
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    env_kwargs = parse_env_args(args.env_arg) if args.env_arg else None
    print(training_budget(args.env), flush=True)
    for env_id, path in train_baselines(args.env, args.out, env_kwargs=env_kwargs).items():
        print(f"{env_id}: {path}")


if __name__ == "__main__":
    _main()


__all__ = ["RECIPES", "BaselineRecipe", "train_baselines", "training_budget"]
