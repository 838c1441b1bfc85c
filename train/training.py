"""Train stable-baselines3 agents on the environments, with tuned configs, logs and resume.

A run directory ``DIR`` (default ``runs/<env-short>-<algo>-<seed>``) receives:

``model.zip``            the final model
``vecnormalize.pkl``     the ``VecNormalize`` statistics (observations; rewards too for PPO)
``run.json``             env id, algorithm, env arguments, seed, timesteps, config, versions
``checkpoints/``         ``rl_model_<N>_steps.zip`` and ``rl_model_vecnormalize_<N>_steps.pkl``
``monitor/``             one ``Monitor`` CSV per vector-env worker
``episodes.csv``         every finished training episode: global timestep, reward, length
``learning_curve.png``   episode reward against timesteps, with a moving average
``tb/``                  TensorBoard logs

Hyper-parameters come from ``train/configs/<env-short>.<algo>.toml`` (for example
``beacon_scan.ppo.toml``), falling back to ``default.<algo>.toml``; ``--config`` names another
file. The RL Zoo reads the same values from ``train/hyperparams/<algo>.yml``, generated from
these files by ``python -m sonar_gym.train.zoo`` (see :mod:`sonar_gym.train.zoo`). A config
file holds::

    policy = "MlpPolicy"        # stable-baselines3 policy name
    n_envs = 4                  # vector-env workers
    checkpoint_every = 10000    # timesteps between checkpoints
    eval_episodes = 20          # episodes of the evaluation printed after training
    [hyperparameters]           # keyword arguments of the algorithm's constructor
    [policy_kwargs]             # net_arch = [64, 64], activation_fn = "tanh" | "relu" | ...
    [vec_normalize]             # norm_obs, norm_reward, clip_obs, clip_reward
"""

from __future__ import annotations

import csv
import functools
import inspect
import json
import re
import shlex
import shutil
import time
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

import gymnasium as gym
import numpy as np
from stable_baselines3.common.callbacks import BaseCallback, CallbackList, CheckpointCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecEnv, VecNormalize

from sonar_gym.agents.learned import (
    MODEL_FILE,
    RUN_FILE,
    VECNORMALIZE_FILE,
    algorithm_class,
    detect_algorithm,
    find_run_metadata,
    vecnormalize_path_for,
)
from sonar_gym.train import UsageError
from sonar_gym.train.evaluation import ALL_ENVS, make_env, resolve_env_ids, software_versions
from sonar_gym.train.report import plot_learning_curve

CONFIG_DIR = Path(__file__).with_name("configs")
TRAINABLE_ALGORITHMS = ("ppo", "sac", "dqn", "a2c")
ALLOWED_ACTION_SPACES: dict[str, tuple[type[gym.Space[Any]], ...]] = {
    "ppo": (gym.spaces.Box, gym.spaces.Discrete, gym.spaces.MultiDiscrete, gym.spaces.MultiBinary),
    "a2c": (gym.spaces.Box, gym.spaces.Discrete, gym.spaces.MultiDiscrete, gym.spaces.MultiBinary),
    "sac": (gym.spaces.Box,),
    "dqn": (gym.spaces.Discrete,),
}
ACTIVATION_CLASSES = {
    "tanh": "Tanh",
    "relu": "ReLU",
    "elu": "ELU",
    "leaky_relu": "LeakyReLU",
    "gelu": "GELU",
    "silu": "SiLU",
}
"""Activation names a config may give -> the ``torch.nn`` class each stands for."""
ACTIVATIONS = tuple(ACTIVATION_CLASSES)
CONFIG_KEYS = (
    "policy",
    "n_envs",
    "checkpoint_every",
    "eval_episodes",
    "hyperparameters",
    "policy_kwargs",
    "vec_normalize",
)
VEC_NORMALIZE_KEYS = ("norm_obs", "norm_reward", "clip_obs", "clip_reward", "epsilon")
# Constructor arguments the trainer sets itself, never a config file.
_RESERVED_ARGUMENTS = ("policy", "env", "tensorboard_log", "policy_kwargs", "seed", "verbose")
CHECKPOINT_DIR = "checkpoints"
CHECKPOINT_PREFIX = "rl_model"
EPISODES_FILE = "episodes.csv"
LEARNING_CURVE_FILE = "learning_curve.png"


# --------------------------------------------------------------------------------------------
# names and configs


def env_short_name(env_id: str) -> str:
    """``"SonarGym/BeaconScan-v0"`` -> ``"beacon_scan"``: no namespace or version, snake case."""
    name = env_id.rsplit("/", 1)[-1]
    name = re.sub(r"-v\d+$", "", name)
    name = re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", name)
    return re.sub(r"[^a-z0-9]+", "_", name.lower()).strip("_")


def default_run_dir(env_id: str, algo: str, seed: int) -> Path:
    """``runs/<env-short>-<algo>-<seed>``."""
    return Path("runs") / f"{env_short_name(env_id)}-{algo}-{seed}"


def check_algorithm_allowed(algo: str, action_space: gym.Space[Any]) -> None:
    """Refuse an algorithm the action space does not allow.

    Raises:
        UsageError: unknown algorithm, or (SAC: Box only; DQN: Discrete only) a mismatch; the
            message names the spaces the algorithm allows and the algorithms the space allows.
    """
    if algo not in ALLOWED_ACTION_SPACES:
        raise UsageError(f"unknown algorithm {algo!r}; choose one of {list(TRAINABLE_ALGORITHMS)}")
    allowed = ALLOWED_ACTION_SPACES[algo]
    if isinstance(action_space, allowed):
        return
    fitting = [
        name for name, spaces in ALLOWED_ACTION_SPACES.items() if isinstance(action_space, spaces)
    ]
    raise UsageError(
        f"{algo.upper()} needs a {' or '.join(s.__name__ for s in allowed)} action space, but the "
        f"env's is {action_space}; algorithms for it: {fitting or 'none'}"
    )


@dataclass(frozen=True)
class TrainingConfig:
    """Hyper-parameters of one algorithm on one env, as read from a config file.

    Attributes:
        source: the file read.
        policy: stable-baselines3 policy name.
        n_envs: vector-env workers.
        checkpoint_every: timesteps between checkpoints (summed over workers).
        eval_episodes: episodes of the evaluation after training.
        hyperparameters: keyword arguments of the algorithm's constructor.
        policy_kwargs: ``policy_kwargs`` (``activation_fn`` as a name).
        vec_normalize: keyword arguments of ``VecNormalize``.
    """

    source: Path
    policy: str = "MlpPolicy"
    n_envs: int = 4
    checkpoint_every: int = 10_000
    eval_episodes: int = 20
    hyperparameters: Mapping[str, Any] = field(default_factory=dict)
    policy_kwargs: Mapping[str, Any] = field(default_factory=dict)
    vec_normalize: Mapping[str, Any] = field(default_factory=dict)

    def sb3_policy_kwargs(self) -> dict[str, Any]:
        """``policy_kwargs`` with ``activation_fn`` turned into the torch module class."""
        kwargs = dict(self.policy_kwargs)
        if "activation_fn" in kwargs:
            import torch

            kwargs["activation_fn"] = getattr(torch.nn, ACTIVATION_CLASSES[kwargs["activation_fn"]])
        return kwargs

    def vec_normalize_kwargs(self, algo: str) -> dict[str, Any]:
        """Keyword arguments of ``VecNormalize`` for ``algo``: observations always normalised,
        rewards for PPO only, unless the config's ``[vec_normalize]`` says otherwise; returns
        discounted with the algorithm's ``gamma``."""
        return {
            "norm_obs": True,
            "norm_reward": algo == "ppo",
            "gamma": float(self.hyperparameters.get("gamma", 0.99)),
            **self.vec_normalize,
        }


def config_path_for(env_id: str, algo: str) -> Path:
    """``configs/<env-short>.<algo>.toml`` when it exists, else ``configs/default.<algo>.toml``."""
    specific = CONFIG_DIR / f"{env_short_name(env_id)}.{algo}.toml"
    return specific if specific.is_file() else CONFIG_DIR / f"default.{algo}.toml"


def load_config(env_id: str, algo: str, path: str | Path | None = None) -> TrainingConfig:
    """Read and check the config of ``algo`` on ``env_id`` (``path`` overrides the lookup).

    Raises:
        UsageError: missing file, TOML error, or a key that is not allowed (named, with the
            allowed ones).
    """
    source = Path(path) if path is not None else config_path_for(env_id, algo)
    if not source.is_file():
        raise UsageError(f"no config file at {source}")
    try:
        data = tomllib.loads(source.read_text())
    except tomllib.TOMLDecodeError as error:
        raise UsageError(f"{source}: {error}") from error
    unknown = sorted(set(data) - set(CONFIG_KEYS))
    if unknown:
        raise UsageError(f"{source}: unknown keys {unknown}; allowed: {list(CONFIG_KEYS)}")
    accepted = [
        name
        for name in inspect.signature(algorithm_class(algo)).parameters
        if name not in _RESERVED_ARGUMENTS and not name.startswith("_")
    ]
    hyperparameters = dict(data.get("hyperparameters", {}))
    unknown = sorted(set(hyperparameters) - set(accepted))
    if unknown:
        raise UsageError(
            f"{source}: [hyperparameters] {unknown} are not arguments of {algo.upper()}; "
            f"allowed: {accepted}"
        )
    vec_normalize = dict(data.get("vec_normalize", {}))
    unknown = sorted(set(vec_normalize) - set(VEC_NORMALIZE_KEYS))
    if unknown:
        raise UsageError(
            f"{source}: [vec_normalize] {unknown} not allowed; allowed: {list(VEC_NORMALIZE_KEYS)}"
        )
    policy_kwargs = dict(data.get("policy_kwargs", {}))
    if policy_kwargs.get("activation_fn", "tanh") not in ACTIVATIONS:
        raise UsageError(
            f"{source}: activation_fn {policy_kwargs['activation_fn']!r} not allowed; "
            f"allowed: {list(ACTIVATIONS)}"
        )
    for key in ("n_envs", "checkpoint_every", "eval_episodes"):
        if key in data and (not isinstance(data[key], int) or data[key] < 1):
            raise UsageError(f"{source}: {key} must be a positive integer, got {data[key]!r}")
    return TrainingConfig(
        source=source,
        policy=str(data.get("policy", "MlpPolicy")),
        n_envs=int(data.get("n_envs", 4)),
        checkpoint_every=int(data.get("checkpoint_every", 10_000)),
        eval_episodes=int(data.get("eval_episodes", 20)),
        hyperparameters=hyperparameters,
        policy_kwargs=policy_kwargs,
        vec_normalize=vec_normalize,
    )


# --------------------------------------------------------------------------------------------
# environments


def make_spec_env(spec: gym.envs.registration.EnvSpec, **env_kwargs: Any) -> gym.Env:
    """``gym.make`` from an ``EnvSpec`` (picklable, so subprocess workers need no registry)."""
    return gym.make(spec, **env_kwargs)


def make_training_vec_env(
    env_id: str,
    n_envs: int,
    seed: int,
    env_kwargs: Mapping[str, Any],
    monitor_dir: Path | None,
    subproc: bool = False,
    append_monitor: bool = False,
) -> VecEnv:
    """``make_vec_env`` over ``env_id`` (``DummyVecEnv``, or ``SubprocVecEnv`` with ``subproc``),
    each worker wrapped in ``Monitor`` writing to ``monitor_dir``."""
    return make_vec_env(
        functools.partial(make_spec_env, gym.spec(env_id)),
        n_envs=n_envs,
        seed=seed,
        env_kwargs=dict(env_kwargs),
        monitor_dir=None if monitor_dir is None else str(monitor_dir),
        monitor_kwargs={"override_existing": not append_monitor},
        vec_env_cls=SubprocVecEnv if subproc else DummyVecEnv,
    )


# --------------------------------------------------------------------------------------------
# callbacks and curves


class EpisodeLogCallback(BaseCallback):
    """Appends every finished training episode to a CSV: global timestep, reward, length."""

    def __init__(self, path: Path) -> None:
        super().__init__()
        self.path = path

    def _on_training_start(self) -> None:
        if not self.path.exists():
            self.path.write_text("timesteps,reward,length\n")

    def _on_step(self) -> bool:
        rows = [
            (self.num_timesteps, info["episode"]["r"], info["episode"]["l"])
            for info in self.locals.get("infos", ())
            if "episode" in info
        ]
        if rows:
            with self.path.open("a", newline="") as handle:
                csv.writer(handle).writerows(rows)
        return True


def read_episode_log(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Timesteps and rewards from an :class:`EpisodeLogCallback` CSV (empty if none)."""
    if not path.is_file():
        return np.empty(0), np.empty(0)
    with path.open() as handle:
        rows = list(csv.DictReader(handle))
    timesteps = np.array([float(row["timesteps"]) for row in rows])
    rewards = np.array([float(row["reward"]) for row in rows])
    return timesteps, rewards


# --------------------------------------------------------------------------------------------
# training


@dataclass(frozen=True)
class TrainingResult:
    """What a training run produced. Paths inside ``out_dir``; rewards are episode sums."""

    out_dir: Path
    env_id: str
    algo: str
    model_path: Path
    vecnormalize_path: Path
    run_file: Path
    learning_curve_path: Path
    total_timesteps: int
    eval_episodes: int
    eval_mean_reward: float | None
    eval_std_reward: float | None
    env_kwargs: Mapping[str, Any]


@dataclass(frozen=True)
class _ResumePoint:
    model_path: Path
    vecnormalize_path: Path
    metadata: Mapping[str, Any]
    run_dir: Path | None


def _resume_point(checkpoint: str | Path) -> _ResumePoint:
    model_path = Path(checkpoint)
    if model_path.is_dir():
        model_path = model_path / MODEL_FILE
    if not model_path.is_file():
        raise UsageError(f"--resume: no checkpoint at {checkpoint}")
    stats_path = vecnormalize_path_for(model_path)
    if not stats_path.is_file():
        raise UsageError(f"--resume: the VecNormalize statistics {stats_path} are missing")
    metadata = find_run_metadata(model_path) or {}
    run_dir = None
    for directory in (model_path.parent, model_path.parent.parent):
        if (directory / RUN_FILE).is_file():
            run_dir = directory
            break
    return _ResumePoint(model_path, stats_path, metadata, run_dir)


@dataclass(frozen=True)
class _Request:
    """A training request with everything resolved: env, algorithm, arguments, directories."""

    env_id: str
    algo: str
    env_kwargs: Mapping[str, Any]
    config: TrainingConfig
    n_envs: int
    run_dir: Path
    resume: _ResumePoint | None
    previous: Mapping[str, Any]

    @property
    def continuing_in_place(self) -> bool:
        """Resuming inside the run directory the checkpoint belongs to."""
        return (
            self.resume is not None
            and self.resume.run_dir is not None
            and self.resume.run_dir.resolve() == self.run_dir.resolve()
        )


def _resolve_request(
    env_id: str | None,
    algo: str | None,
    out_dir: str | Path | None,
    seed: int,
    n_envs: int | None,
    config_path: str | Path | None,
    resume: str | Path | None,
    env_kwargs: Mapping[str, Any] | None,
    overwrite: bool,
) -> _Request:
    resume_point = _resume_point(resume) if resume is not None else None
    previous: dict[str, Any] = dict(resume_point.metadata) if resume_point else {}
    if resume_point is not None:
        try:
            saved_algo = previous.get("algo") or detect_algorithm(resume_point.model_path)
        except ValueError as error:
            raise UsageError(f"--resume: {error}") from error
        if algo is not None and algo != saved_algo:
            raise UsageError(f"--resume: the checkpoint was trained with {saved_algo}, not {algo}")
        algo = saved_algo
        saved_env = previous.get("env_id")
        if env_id is not None and saved_env is not None and env_id != saved_env:
            raise UsageError(f"--resume: the checkpoint was trained on {saved_env}, not {env_id}")
        env_id = env_id or saved_env
    if env_id is None or env_id == ALL_ENVS:
        raise UsageError("--env needs one env id (optional only when --resume names a run)")
    if algo is None or algo not in TRAINABLE_ALGORITHMS:
        what = "--algo is required" if algo is None else f"unknown algorithm {algo!r}"
        raise UsageError(f"{what}; choose one of {list(TRAINABLE_ALGORITHMS)}")
    env_id = resolve_env_ids(env_id)[0]
    kwargs = {**previous.get("env_kwargs", {}), **dict(env_kwargs or {})}
    probe = make_env(env_id, kwargs)
    try:
        check_algorithm_allowed(algo, probe.action_space)
    finally:
        probe.close()
    config = load_config(env_id, algo, config_path)
    workers = n_envs if n_envs is not None else config.n_envs
    if workers < 1:
        raise UsageError(f"--n-envs must be at least 1, got {workers}")
    if out_dir is not None:
        run_dir = Path(out_dir)
    elif resume_point is not None and resume_point.run_dir is not None:
        run_dir = resume_point.run_dir
    else:
        run_dir = default_run_dir(env_id, algo, seed)
    if (run_dir / MODEL_FILE).exists() and resume_point is None and not overwrite:
        raise UsageError(
            f"{run_dir} already holds a trained model; use --resume {run_dir / MODEL_FILE} to "
            "continue it, --out for another directory, or --overwrite"
        )
    return _Request(env_id, algo, kwargs, config, workers, run_dir, resume_point, previous)


def _prepare_run_dir(request: _Request) -> None:
    if request.resume is None:  # a fresh run: no logs of an earlier one may remain
        for stale in (CHECKPOINT_DIR, "monitor", "tb"):
            shutil.rmtree(request.run_dir / stale, ignore_errors=True)
        (request.run_dir / EPISODES_FILE).unlink(missing_ok=True)
    request.run_dir.mkdir(parents=True, exist_ok=True)


def _build_model(request: _Request, seed: int, subproc: bool) -> tuple[Any, VecNormalize]:
    """A new model on a fresh ``VecNormalize``, or the checkpoint with its statistics."""
    run_dir = request.run_dir
    algorithm = algorithm_class(request.algo)
    if request.resume is None:
        venv = VecNormalize(
            make_training_vec_env(
                request.env_id,
                request.n_envs,
                seed,
                request.env_kwargs,
                run_dir / "monitor",
                subproc,
            ),
            **request.config.vec_normalize_kwargs(request.algo),
        )
        model = algorithm(
            request.config.policy,
            venv,
            seed=seed,
            verbose=0,
            tensorboard_log=str(run_dir / "tb"),
            policy_kwargs=request.config.sb3_policy_kwargs(),
            **request.config.hyperparameters,
        )
        return model, venv
    base = make_training_vec_env(
        request.env_id,
        request.n_envs,
        seed + int(request.previous.get("total_timesteps", 0)),  # new episodes, not a replay
        request.env_kwargs,
        run_dir / "monitor",
        subproc,
        append_monitor=request.continuing_in_place,
    )
    venv = VecNormalize.load(str(request.resume.vecnormalize_path), base)
    venv.training = True
    model = algorithm.load(
        request.resume.model_path,
        env=venv,
        tensorboard_log=str(run_dir / "tb"),
        print_system_info=False,
    )
    return model, venv


def _run_info(
    request: _Request,
    model: Any,
    venv: VecNormalize,
    seed: int,
    subproc: bool,
    trained_timesteps: int,
    wall_time_s: float,
) -> dict[str, Any]:
    """``run.json``: what was trained, how, and the segments of training so far."""
    segment = {
        "timesteps": trained_timesteps,
        "from": str(request.resume.model_path) if request.resume else None,
        "wall_time_s": round(wall_time_s, 3),
        "n_envs": request.n_envs,
        "seed": seed,
        "subproc": subproc,
    }
    fresh = {
        "config_file": str(request.config.source),
        "policy": request.config.policy,
        "hyperparameters": dict(request.config.hyperparameters),
        "policy_kwargs": dict(request.config.policy_kwargs),
    }
    return {
        "env_id": request.env_id,
        "algo": request.algo,
        "env_kwargs": dict(request.env_kwargs),
        "seed": request.previous.get("seed", seed),
        "total_timesteps": int(model.num_timesteps),
        "segments": [*request.previous.get("segments", []), segment],
        # a resumed model keeps the hyper-parameters it was created with
        **{key: request.previous.get(key, value) for key, value in fresh.items()},
        "vec_normalize": {
            "norm_obs": bool(venv.norm_obs),
            "norm_reward": bool(venv.norm_reward),
            "clip_obs": float(venv.clip_obs),
            "clip_reward": float(venv.clip_reward),
        },
        "versions": software_versions(),
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }


def train(
    env_id: str | None,
    algo: str | None,
    timesteps: int,
    out_dir: str | Path | None = None,
    seed: int = 0,
    n_envs: int | None = None,
    config_path: str | Path | None = None,
    resume: str | Path | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
    subproc: bool = False,
    progress_bar: bool = True,
    eval_episodes: int | None = None,
    overwrite: bool = False,
) -> TrainingResult:
    """Train ``algo`` on ``env_id`` for ``timesteps`` steps (or ``timesteps`` more with
    ``resume``), save everything into the run directory and evaluate the final policy.

    Args:
        env_id: registered env id (taken from the run's ``run.json`` when resuming and None).
        algo: one of :data:`TRAINABLE_ALGORITHMS` (likewise taken from the run when resuming).
        timesteps: environment steps to train (summed over the vector-env workers; on-policy
            algorithms round up to whole rollouts of ``n_steps * n_envs``).
        out_dir: run directory; default ``runs/<env-short>-<algo>-<seed>``, or the resumed run's.
        seed: seed of the algorithm and of the workers (worker ``i`` gets ``seed + i``).
        n_envs: vector-env workers (default from the config).
        config_path: config file instead of the tuned one for (env, algo).
        resume: a model or checkpoint ``.zip`` (or run directory) to continue from, with its
            ``VecNormalize`` statistics; its step counter continues.
        env_kwargs: keyword arguments for ``gym.make`` (merged over the resumed run's).
        subproc: ``SubprocVecEnv`` instead of ``DummyVecEnv``.
        progress_bar: stable-baselines3's progress bar.
        eval_episodes: episodes of the final evaluation (default from the config; 0 skips it).
        overwrite: allow a fresh run into a directory that already holds a model.

    Raises:
        UsageError: unknown env or algorithm, an algorithm the action space does not allow, a
            bad config or env argument, a missing checkpoint, or an existing run directory.
            Nothing is written before these checks pass.
    """
    if timesteps < 1:
        raise UsageError(f"--timesteps must be at least 1, got {timesteps}")
    request = _resolve_request(
        env_id, algo, out_dir, seed, n_envs, config_path, resume, env_kwargs, overwrite
    )
    _prepare_run_dir(request)
    run_dir = request.run_dir
    started = time.time()
    model, venv = _build_model(request, seed, subproc)
    initial_timesteps = int(model.num_timesteps)
    checkpoints = CheckpointCallback(
        save_freq=max(request.config.checkpoint_every // request.n_envs, 1),
        save_path=str(run_dir / CHECKPOINT_DIR),
        name_prefix=CHECKPOINT_PREFIX,
        save_vecnormalize=True,
    )
    model_path = run_dir / MODEL_FILE
    stats_path = run_dir / VECNORMALIZE_FILE
    try:
        model.learn(
            total_timesteps=timesteps,
            callback=CallbackList([checkpoints, EpisodeLogCallback(run_dir / EPISODES_FILE)]),
            progress_bar=progress_bar,
            reset_num_timesteps=request.resume is None,
            tb_log_name=request.algo,
        )
        model.save(model_path)
        venv.save(str(stats_path))
    finally:
        venv.close()
    run_info = _run_info(
        request,
        model,
        venv,
        seed,
        subproc,
        trained_timesteps=int(model.num_timesteps) - initial_timesteps,
        wall_time_s=time.time() - started,
    )
    run_file = run_dir / RUN_FILE
    run_file.write_text(json.dumps(run_info, indent=2) + "\n")
    curve_timesteps, curve_rewards = read_episode_log(run_dir / EPISODES_FILE)
    curve_path = plot_learning_curve(
        curve_timesteps.tolist(),
        curve_rewards.tolist(),
        run_dir / LEARNING_CURVE_FILE,
        title=f"{request.algo.upper()} on {request.env_id}",
    )
    episodes = request.config.eval_episodes if eval_episodes is None else eval_episodes
    mean_reward = std_reward = None
    if episodes > 0:
        mean_reward, std_reward = evaluate_trained_policy(
            model_path, stats_path, request.env_id, request.env_kwargs, episodes, seed
        )
    return TrainingResult(
        out_dir=run_dir,
        env_id=request.env_id,
        algo=request.algo,
        model_path=model_path,
        vecnormalize_path=stats_path,
        run_file=run_file,
        learning_curve_path=curve_path,
        total_timesteps=int(model.num_timesteps),
        eval_episodes=episodes,
        eval_mean_reward=mean_reward,
        eval_std_reward=std_reward,
        env_kwargs=request.env_kwargs,
    )


def evaluate_trained_policy(
    model_path: Path,
    vecnormalize_path: Path,
    env_id: str,
    env_kwargs: Mapping[str, Any],
    episodes: int,
    seed: int,
) -> tuple[float, float]:
    """Mean and standard deviation of the episode reward of the deterministic policy, by
    stable-baselines3's ``evaluate_policy`` on raw (unnormalised) rewards."""
    spec = gym.spec(env_id)
    base = DummyVecEnv([lambda: Monitor(make_spec_env(spec, **env_kwargs))])
    venv = VecNormalize.load(str(vecnormalize_path), base)
    venv.training = False
    venv.norm_reward = False
    venv.seed(seed)
    try:
        model = algorithm_class(detect_algorithm(model_path)).load(model_path, device="cpu")
        # without return_episode_rewards, evaluate_policy returns (mean, std) as floats
        mean_reward, std_reward = cast(
            tuple[float, float],
            evaluate_policy(model, venv, n_eval_episodes=episodes, deterministic=True),
        )
    finally:
        venv.close()
    return float(mean_reward), float(std_reward)


def evaluate_command(result: TrainingResult) -> str:
    """The ``sonar-gym evaluate`` command line for the trained policy."""
    parts = ["sonar-gym", "evaluate", "--env", result.env_id, "--agent", str(result.model_path)]
    for key, value in result.env_kwargs.items():
        parts += ["--env-arg", f"{key}={_env_arg_text(value)}"]
    return " ".join(shlex.quote(part) for part in parts)


def _env_arg_text(value: Any) -> str:
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, (list, dict)) or value is None:
        return json.dumps(value)
    return str(value)
