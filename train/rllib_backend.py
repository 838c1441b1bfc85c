"""Training with RLlib on a Ray cluster: ``sonar-gym train --backend rllib``.

RLlib's remote env runners are fresh processes that never ran ``import sonar_gym``, so a
plain ``"SonarGym/..."`` id is unknown there (RLlib then fails with a misleading
``IndexError``). Two ways work, and this module uses the first:

- register an env *creator* under the id with ``ray.tune.registry.register_env``; the creator
  imports ``sonar_gym`` inside the runner before it calls ``gym.make``;
- or give RLlib the id with Gymnasium's module prefix, ``"sonar_gym:SonarGym/BeaconScan-v0"``,
  which makes ``gym.make`` import ``sonar_gym`` first.

The algorithm is PPO, whose RLlib implementation takes every action space the envs have
(``Discrete``, ``MultiDiscrete`` and ``Box``). A run directory holds RLlib's checkpoint
(``rllib_checkpoint.json`` and its components), ``run.json`` (env id, env arguments, seed,
timesteps, versions, the PPO settings) and ``progress.csv`` (one row per training iteration).
:class:`sonar_gym.agents.rllib_policy.RLlibPolicyAgent` loads the policy of such a directory, so
``sonar-gym evaluate --agent DIR`` runs it like any other agent.

Ray and RLlib are an optional extra (``pip install -e ".[ray]"``); nothing here imports them
until a function needs them.
"""

from __future__ import annotations

import csv
import json
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from sonar_gym.agents.rllib_policy import RAY_INSTALL_HINT
from sonar_gym.train import UsageError

RLLIB_ALGORITHMS = ("ppo",)
"""Algorithms ``--backend rllib`` trains (PPO fits every action space of the suite)."""
RUN_FILE = "run.json"
PROGRESS_FILE = "progress.csv"


@dataclass(frozen=True)
class RLlibSettings:
    """The PPO settings of an RLlib run (RLlib's own names).

    Attributes:
        train_batch_size_per_learner: env steps collected per training iteration.
        minibatch_size: samples per SGD minibatch.
        num_epochs: passes over each batch.
        lr: learning rate.
        gamma: discount factor.
    """

    train_batch_size_per_learner: int = 512
    minibatch_size: int = 64
    num_epochs: int = 4
    lr: float = 3e-4
    gamma: float = 0.99


def require_ray() -> Any:
    """Import ``ray`` or raise :class:`UsageError` saying how to install the extra."""
    try:
        import ray
    except ImportError as error:
        raise UsageError(f"the rllib backend and --ray need Ray: {RAY_INSTALL_HINT}") from error
    return ray


def env_creator(env_id: str) -> Callable[[Mapping[str, Any]], gym.Env]:
    """A creator for ``register_env`` that imports ``sonar_gym`` in the process that runs it."""

    def create(env_config: Mapping[str, Any]) -> gym.Env:
        import sonar_gym  # noqa: F401  (registers the ids in a fresh env-runner process)

        return gym.make(env_id, **dict(env_config))

    return create


def init_ray(address: str | None) -> None:
    """Connect to the cluster at ``address``, or start a local Ray instance (once)."""
    ray = require_ray()
    if ray.is_initialized():
        return
    if address is None:
        ray.init(include_dashboard=False, log_to_driver=False)
    else:
        ray.init(address=address, log_to_driver=False)


@dataclass(frozen=True)
class RLlibTrainingResult:
    """What :func:`train_rllib` produced.

    Attributes:
        run_dir: the run directory (RLlib checkpoint, ``run.json``, ``progress.csv``).
        timesteps: env steps sampled over the whole run.
        iterations: training iterations.
        seconds: wall time of the training loop, seconds.
        mean_episode_reward: mean return of the last iteration's finished episodes (None if none).
    """

    run_dir: Path
    timesteps: int
    iterations: int
    seconds: float
    mean_episode_reward: float | None


def _sampled_steps(result: Mapping[str, Any]) -> int:
    runners = result.get("env_runners", {})
    value = runners.get(
        "num_env_steps_sampled_lifetime", result.get("num_env_steps_sampled_lifetime")
    )
    return int(value or 0)


def _mean_return(result: Mapping[str, Any]) -> float | None:
    value = result.get("env_runners", {}).get("episode_return_mean")
    if value is None or not np.isfinite(value):
        return None
    return float(value)


def train_rllib(
    env_id: str,
    timesteps: int,
    out_dir: str | Path,
    *,
    algo: str = "ppo",
    seed: int = 0,
    num_env_runners: int = 1,
    address: str | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
    settings: RLlibSettings | None = None,
    overwrite: bool = False,
    on_iteration: Callable[[int, int], None] | None = None,
) -> RLlibTrainingResult:
    """Train ``algo`` with RLlib on ``env_id`` for at least ``timesteps`` env steps.

    Args:
        env_id: a registered ``SonarGym/`` id.
        timesteps: env steps to sample (whole iterations of ``train_batch_size_per_learner``).
        out_dir: run directory for the checkpoint, ``run.json`` and ``progress.csv``.
        algo: one of :data:`RLLIB_ALGORITHMS`.
        seed: RLlib's seed (env runners and learner).
        num_env_runners: remote env-runner processes (0 samples in the driver).
        address: a running Ray cluster (``"auto"``, ``"ray://host:10001"``); None starts a
            local instance.
        env_kwargs: ``gym.make`` arguments, passed to every runner as the env config.
        settings: PPO settings (default :class:`RLlibSettings`).
        overwrite: replace an existing run directory.
        on_iteration: called with (steps so far, ``timesteps``) after each iteration.

    Raises:
        UsageError: unknown algorithm, Ray missing, or an existing run directory.
    """
    if algo not in RLLIB_ALGORITHMS:
        raise UsageError(f"--backend rllib trains {list(RLLIB_ALGORITHMS)}; got --algo {algo!r}")
    if num_env_runners < 0:
        raise UsageError(f"--num-env-runners must be >= 0; got {num_env_runners}")
    run_dir = Path(out_dir)
    if run_dir.exists() and any(run_dir.iterdir()) and not overwrite:
        raise UsageError(f"run directory {run_dir} exists and is not empty; add --overwrite")
    run_dir.mkdir(parents=True, exist_ok=True)
    ppo_settings = settings or RLlibSettings()
    kwargs = dict(env_kwargs or {})
    gym.make(env_id, **kwargs).close()  # a bad id or argument fails here, not in a runner

    init_ray(address)
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.tune.registry import register_env

    register_env(env_id, env_creator(env_id))
    config = (
        PPOConfig()
        .environment(env_id, env_config=kwargs)
        .env_runners(num_env_runners=num_env_runners)
        .training(**asdict(ppo_settings))
        .debugging(seed=seed)
    )
    algorithm = config.build_algo()
    start = time.perf_counter()
    steps = iterations = 0
    mean_return: float | None = None
    try:
        with (run_dir / PROGRESS_FILE).open("w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(["iteration", "env_steps", "episode_return_mean", "seconds"])
            while steps < timesteps:
                result = algorithm.train()
                iterations += 1
                steps = _sampled_steps(result)
                mean_return = _mean_return(result)
                writer.writerow([iterations, steps, mean_return, time.perf_counter() - start])
                handle.flush()
                if on_iteration is not None:
                    on_iteration(steps, timesteps)
        seconds = time.perf_counter() - start
        algorithm.save_to_path(str(run_dir.resolve()))
    finally:
        algorithm.stop()
    _write_run_file(run_dir, env_id, kwargs, seed, steps, ppo_settings, num_env_runners)
    return RLlibTrainingResult(run_dir, steps, iterations, seconds, mean_return)


def _write_run_file(
    run_dir: Path,
    env_id: str,
    env_kwargs: Mapping[str, Any],
    seed: int,
    timesteps: int,
    settings: RLlibSettings,
    num_env_runners: int,
) -> None:
    import ray

    record = {
        "backend": "rllib",
        "env_id": env_id,
        "algo": "ppo",
        "env_kwargs": dict(env_kwargs),
        "seed": seed,
        "timesteps": timesteps,
        "num_env_runners": num_env_runners,
        "settings": asdict(settings),
        "versions": {"ray": ray.__version__, "gymnasium": gym.__version__},
    }
    (run_dir / RUN_FILE).write_text(json.dumps(record, indent=2) + "\n")
