"""Trained stable-baselines3 policies as agents.

``load_policy_agent(path, env)`` loads a model saved by ``sonar-gym train`` (``DIR/model.zip``
or a checkpoint ``DIR/checkpoints/rl_model_<N>_steps.zip``; a run directory ``DIR`` works
too). The algorithm comes from the ``run.json`` written beside the model at training, else from
the zip itself. Observations are normalised with the ``VecNormalize`` statistics saved beside
the model (``vecnormalize.pkl``, or ``rl_model_vecnormalize_<N>_steps.pkl`` for a checkpoint),
exactly as during training, and actions are the policy's deterministic ones.
"""

from __future__ import annotations

import json
import pickle
import re
import zipfile
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

MODEL_FILE = "model.zip"
VECNORMALIZE_FILE = "vecnormalize.pkl"
RUN_FILE = "run.json"
ALGORITHMS = ("ppo", "a2c", "sac", "dqn", "td3")
_CHECKPOINT = re.compile(r"^(?P<prefix>.+)_(?P<steps>\d+)_steps\.zip$")
# Schedules are saved as pickled closures; replaced on load since acting never uses them.
_INFERENCE_ONLY_OBJECTS: dict[str, Any] = {
    "learning_rate": 0.0,
    "lr_schedule": lambda _: 0.0,
    "clip_range": lambda _: 0.0,
    "exploration_schedule": lambda _: 0.0,
}


def algorithm_class(algo: str) -> Any:
    """The stable-baselines3 class of ``algo`` (one of :data:`ALGORITHMS`).

    Raises:
        ValueError: unknown algorithm name.
    """
    import stable_baselines3

    if algo not in ALGORITHMS:
        raise ValueError(f"unknown algorithm {algo!r}; choose one of {list(ALGORITHMS)}")
    return getattr(stable_baselines3, algo.upper())


def resolve_model_path(path: str | Path) -> Path:
    """The model file meant by ``path``: the file itself, or ``model.zip`` of a run directory.

    Raises:
        ValueError: nothing loadable at ``path``.
    """
    candidate = Path(path)
    if candidate.is_dir():
        candidate = candidate / MODEL_FILE
    if not candidate.is_file():
        raise ValueError(f"no saved model at {str(path)!r} (expected a .zip or a run directory)")
    return candidate


def find_run_metadata(model_path: Path) -> dict[str, Any] | None:
    """The ``run.json`` of the run the model belongs to (beside it, or one directory up for a
    checkpoint), or None."""
    for directory in (model_path.parent, model_path.parent.parent):
        run_file = directory / RUN_FILE
        if run_file.is_file():
            data: dict[str, Any] = json.loads(run_file.read_text())
            return data
    return None


def detect_algorithm(model_path: Path) -> str:
    """The algorithm that saved ``model_path``: from ``run.json``, else from the zip's data.

    Raises:
        ValueError: the file is not a stable-baselines3 model of a known algorithm.
    """
    metadata = find_run_metadata(model_path)
    if metadata is not None and metadata.get("algo") in ALGORITHMS:
        return str(metadata["algo"])
    try:
        with zipfile.ZipFile(model_path) as archive:
            data = json.loads(archive.read("data"))
    except (zipfile.BadZipFile, KeyError, json.JSONDecodeError) as error:
        raise ValueError(f"{model_path} is not a stable-baselines3 model: {error}") from error
    policy_module = str(data.get("policy_class", {}).get("__module__", ""))
    for algo in ("sac", "dqn", "td3"):
        if policy_module == f"stable_baselines3.{algo}.policies":
            return algo
    if policy_module == "stable_baselines3.common.policies":
        return "ppo" if "clip_range" in data else "a2c"
    raise ValueError(
        f"cannot tell the algorithm of {model_path} (policy module {policy_module!r}); "
        f'write {RUN_FILE} beside it with "algo" one of {list(ALGORITHMS)}'
    )


def vecnormalize_path_for(model_path: Path) -> Path:
    """Where the ``VecNormalize`` statistics of ``model_path`` are saved: ``vecnormalize.pkl``
    beside a final model, ``<prefix>_vecnormalize_<N>_steps.pkl`` beside a checkpoint."""
    match = _CHECKPOINT.match(model_path.name)
    if match is None:
        return model_path.with_name(VECNORMALIZE_FILE)
    return model_path.with_name(f"{match['prefix']}_vecnormalize_{match['steps']}_steps.pkl")


def _load_normalizer(path: Path, observation_space: gym.Space[Any]) -> Any:
    with path.open("rb") as handle:
        normalizer = pickle.load(handle)
    normalizer.training = False
    expected_shape = getattr(observation_space, "shape", None)
    saved_shape = getattr(getattr(normalizer, "obs_rms", None), "mean", np.empty(0)).shape
    if normalizer.norm_obs and expected_shape is not None and saved_shape != expected_shape:
        raise ValueError(
            f"{path} normalises observations of shape {saved_shape}, "
            f"but the env's observations have shape {expected_shape}"
        )
    return normalizer


class PolicyAgent:
    """A trained policy: normalises the observation, then acts deterministically."""

    def __init__(
        self, name: str, model: Any, action_space: gym.Space[Any], normalizer: Any | None = None
    ) -> None:
        self.name = name
        self.model = model
        self.action_space = action_space
        self.normalizer = normalizer

    def reset(self, seed: int | None = None) -> None:
        """Nothing to reset: the policy is deterministic and has no memory."""

    def act(self, observation: Any) -> Any:
        """The policy's deterministic action for ``observation`` (raw, as the env gives it)."""
        model_input = np.asarray(observation, dtype=np.float32)
        if self.normalizer is not None:
            model_input = self.normalizer.normalize_obs(model_input).astype(np.float32)
        action, _ = self.model.predict(model_input, deterministic=True)
        if isinstance(self.action_space, gym.spaces.Discrete):
            return int(np.asarray(action).reshape(()))
        return np.asarray(action, dtype=self.action_space.dtype).reshape(self.action_space.shape)


def load_policy_agent(path: str | Path, env: gym.Env) -> PolicyAgent:
    """Load the model at ``path`` (a ``.zip`` or a run directory) as an agent for ``env``.

    Raises:
        ValueError: no model at ``path``; the algorithm cannot be told; the run used
            ``VecNormalize`` but its statistics are missing; or the model's spaces do not match
            ``env``'s.
    """
    model_path = resolve_model_path(path)
    algo = detect_algorithm(model_path)
    model = algorithm_class(algo).load(
        model_path, device="cpu", custom_objects=_INFERENCE_ONLY_OBJECTS
    )
    metadata = find_run_metadata(model_path) or {}
    hint = (
        f" (it was trained with the env arguments {metadata['env_kwargs']})"
        if metadata.get("env_kwargs")
        else ""
    )
    if model.observation_space.shape != env.observation_space.shape:
        raise ValueError(
            f"{model_path} was trained on observations of shape {model.observation_space.shape}, "
            f"but the env's have shape {env.observation_space.shape}{hint}"
        )
    if model.action_space != env.action_space:
        raise ValueError(
            f"{model_path} acts in {model.action_space}, but the env's action space is "
            f"{env.action_space}{hint}"
        )
    stats_path = vecnormalize_path_for(model_path)
    normalizer = None
    if stats_path.is_file():
        normalizer = _load_normalizer(stats_path, env.observation_space)
    elif metadata.get("vec_normalize", {}).get("norm_obs"):
        raise ValueError(
            f"{model_path} was trained on normalised observations, but {stats_path} is missing"
        )
    return PolicyAgent(f"{algo}:{model_path}", model, env.action_space, normalizer)


LEARNED_AGENT = "learned"


def shipped_policy_agent(env: gym.Env) -> PolicyAgent:
    """The ``learned`` agent: the policy shipped for ``env``'s id
    (:func:`sonar_gym.pretrained.find_policy`), acting deterministically.

    Raises:
        ValueError: no policy ships for the env's id, or its spaces differ from ``env``'s.
    """
    from sonar_gym import pretrained

    env_id = env.spec.id if env.spec is not None else ""
    agent = load_policy_agent(pretrained.find_policy(env_id), env)
    agent.name = LEARNED_AGENT
    return agent
