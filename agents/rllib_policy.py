"""A policy trained with RLlib (``sonar-gym train --backend rllib``), loaded as an agent.

An RLlib run directory holds an algorithm checkpoint (``rllib_checkpoint.json`` at its top);
the single-agent policy sits under ``learner_group/learner/rl_module/default_policy`` (RLlib's
new API stack). The agent acts greedily: the most likely action of the policy's distribution.
Ray is an optional extra (``pip install -e ".[ray]"``), imported only when an agent is made.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

RLLIB_CHECKPOINT_FILE = "rllib_checkpoint.json"
"""The file RLlib writes at the top of every algorithm checkpoint."""
POLICY_SUBDIR = Path("learner_group") / "learner" / "rl_module" / "default_policy"
"""Where an algorithm checkpoint keeps the single-agent policy."""
RAY_INSTALL_HINT = (
    "pip install -e '.[ray]' (with the README's set-up: .venv/bin/pip install -e '.[ray]')"
)


def is_rllib_run(path: str | Path) -> bool:
    """Whether ``path`` is a directory holding an RLlib algorithm checkpoint."""
    try:
        return (Path(path) / RLLIB_CHECKPOINT_FILE).is_file()
    except OSError:  # a name too long for the file system is no run directory either
        return False


class RLlibPolicyAgent:
    """The greedy policy of an RLlib PPO checkpoint, as an agent (``act(observation)``).

    The env the agent is made for must have the observation and action spaces the policy
    was trained on; a mismatch is refused when the agent is made.
    """

    def __init__(self, run_dir: str | Path, env: gym.Env) -> None:
        try:
            from ray.rllib.core.rl_module.rl_module import RLModule
        except ImportError as error:
            raise ImportError(f"an RLlib policy needs Ray: {RAY_INSTALL_HINT}") from error
        import torch

        path = Path(run_dir)
        if not is_rllib_run(path):
            raise ValueError(f"{path} is not an RLlib checkpoint (no {RLLIB_CHECKPOINT_FILE})")
        self.name = str(path)
        self._torch = torch
        self._module = RLModule.from_checkpoint(str((path / POLICY_SUBDIR).resolve()))
        if self._module.observation_space.shape != env.observation_space.shape:
            raise ValueError(
                f"{path}: the policy was trained on observations of shape "
                f"{self._module.observation_space.shape}; this env gives "
                f"{env.observation_space.shape}"
            )
        if self._module.action_space != env.action_space:
            raise ValueError(
                f"{path}: the policy acts in {self._module.action_space}; this env's action "
                f"space is {env.action_space}"
            )
        self._action_space = env.action_space
        self._distribution = self._module.get_inference_action_dist_cls()

    def reset(self, seed: int | None = None) -> None:
        """A greedy feed-forward policy keeps no state between episodes."""

    def act(self, observation: Any) -> Any:
        """The most likely action of the policy for ``observation``."""
        batch = self._torch.as_tensor(np.asarray(observation, dtype=np.float32)[None])
        with self._torch.no_grad():
            output = self._module.forward_inference({"obs": batch})
        logits = output["action_dist_inputs"]
        action = self._distribution.from_logits(logits).to_deterministic().sample()
        value = action.cpu().numpy()[0]
        space = self._action_space
        if isinstance(space, gym.spaces.Discrete):
            return int(value)
        action_array = np.asarray(value, dtype=space.dtype).reshape(space.shape)
        if isinstance(space, gym.spaces.Box):
            return np.clip(action_array, space.low, space.high)  # a Gaussian's mean may overshoot
        return action_array
