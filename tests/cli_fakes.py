"""A tiny stand-in environment and agents for the command-line tests.

``CliFake/Locate-v0`` hides a position ``x`` in [0, 1] m. Each "sense" action measures it
with Gaussian noise (0.1 s of sensing time); "localize" ends the episode with the mean of the
measurements as the estimate. The end-of-episode ``info`` has the keys every SonarGym env
reports: ``position_error_m``, ``heading_error_rad`` (left out with ``report_heading=False``),
``sensing_time_s`` and ``status`` (``"ok"``, or ``"no_measurement"`` when localizing before
any sensing). The same task is registered with three action spaces: Discrete(2) (0 sense,
1 localize), Box(1) in [-1, 1] (> 0 localizes) and MultiDiscrete([2, 3]) (first entry).

Agents: ``scripted`` senses ``SCRIPTED_MEASUREMENTS`` times then localizes; ``coin`` flips a
seeded coin; ``patient`` never localizes (episodes end by the time limit). Import this module
to register all of it.
"""

from __future__ import annotations

import time
from typing import Any

import gymnasium as gym
import numpy as np

from sonar_gym.agents.base import register_agent

DISCRETE_ID = "CliFake/Locate-v0"
BOX_ID = "CliFake/LocateBox-v0"
MULTI_DISCRETE_ID = "CliFake/LocateMulti-v0"
FAKE_NAMESPACE = "CliFake"
SENSE_TIME_S = 0.1
SENSING_COST = 0.05
SCRIPTED_MEASUREMENTS = 3
MAX_EPISODE_STEPS = 8


class FakeLocateEnv(gym.Env[np.ndarray, Any]):
    """Estimate a hidden scalar position by repeated noisy measurement (see the module)."""

    metadata = {"render_modes": []}

    def __init__(
        self,
        noise_std_m: float = 0.05,
        action_kind: str = "discrete",
        report_heading: bool = True,
        label: str = "fake",
    ) -> None:
        if not 0.0 <= noise_std_m <= 1.0:
            raise ValueError(f"argument 'noise_std_m' must lie in [0, 1]; got {noise_std_m!r}")
        if action_kind not in ("discrete", "box", "multi_discrete"):
            raise ValueError(
                "argument 'action_kind' must be one of ['discrete', 'box', 'multi_discrete']; "
                f"got {action_kind!r}"
            )
        self.noise_std_m = noise_std_m
        self.action_kind = action_kind
        self.report_heading = report_heading
        self.label = label
        self.observation_space = gym.spaces.Box(-10.0, 10.0, shape=(3,), dtype=np.float32)
        self.action_space: gym.Space[Any] = {
            "discrete": gym.spaces.Discrete(2),
            "box": gym.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32),
            "multi_discrete": gym.spaces.MultiDiscrete([2, 3]),
        }[action_kind]
        self.timing = {"sensing": 0.0, "localization": 0.0}
        self._true_position_m = 0.0
        self._measurements: list[float] = []

    def _observation(self) -> np.ndarray:
        count = len(self._measurements)
        mean = float(np.mean(self._measurements)) if count else 0.0
        return np.array([mean, count / MAX_EPISODE_STEPS, count * SENSE_TIME_S], dtype=np.float32)

    def _wants_localize(self, action: Any) -> bool:
        if self.action_kind == "discrete":
            return int(action) == 1
        if self.action_kind == "box":
            return float(np.asarray(action).reshape(-1)[0]) > 0.0
        return int(np.asarray(action).reshape(-1)[0]) == 1

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        self._true_position_m = float(self.np_random.uniform(0.0, 1.0))
        self._measurements = []
        return self._observation(), {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if self._wants_localize(action):
            tick = time.perf_counter()
            count = len(self._measurements)
            estimate = float(np.mean(self._measurements)) if count else 0.5
            error_m = abs(estimate - self._true_position_m)
            info: dict[str, Any] = {
                "position_error_m": error_m,
                "sensing_time_s": count * SENSE_TIME_S,
                "status": "ok" if count else "no_measurement",
            }
            if self.report_heading:
                info["heading_error_rad"] = 0.5 * error_m
            self.timing["localization"] += time.perf_counter() - tick
            return self._observation(), -error_m, True, False, info
        tick = time.perf_counter()
        noise = float(self.np_random.normal(0.0, self.noise_std_m))
        self._measurements.append(self._true_position_m + noise)
        self.timing["sensing"] += time.perf_counter() - tick
        return self._observation(), -SENSING_COST * SENSE_TIME_S, False, False, {}


class ScriptedAgent:
    """Senses :data:`SCRIPTED_MEASUREMENTS` times, then localizes."""

    name = "scripted"

    def __init__(self, env: gym.Env) -> None:
        self.action_kind = env.unwrapped.action_kind
        self._steps = 0

    def reset(self, seed: int | None = None) -> None:
        self._steps = 0

    def act(self, observation: Any) -> Any:
        localize = self._steps >= SCRIPTED_MEASUREMENTS
        self._steps += 1
        if self.action_kind == "discrete":
            return int(localize)
        if self.action_kind == "box":
            return np.array([1.0 if localize else -1.0], dtype=np.float32)
        return np.array([int(localize), 0], dtype=np.int64)


class CoinAgent:
    """Localizes with probability 1/2 at each step (seeded by ``reset``)."""

    name = "coin"

    def __init__(self, env: gym.Env) -> None:
        self.action_space = env.action_space
        self._rng = np.random.default_rng(0)

    def reset(self, seed: int | None = None) -> None:
        self._rng = np.random.default_rng(seed)

    def act(self, observation: Any) -> Any:
        localize = bool(self._rng.random() < 0.5)
        if isinstance(self.action_space, gym.spaces.Discrete):
            return int(localize)
        if isinstance(self.action_space, gym.spaces.Box):
            return np.array([1.0 if localize else -1.0], dtype=np.float32)
        return np.array([int(localize), 0], dtype=np.int64)


class PatientAgent:
    """Never localizes, so every episode ends by the time limit."""

    name = "patient"

    def __init__(self, env: gym.Env) -> None:
        self.action_kind = env.unwrapped.action_kind

    def reset(self, seed: int | None = None) -> None:
        """Nothing to reset."""

    def act(self, observation: Any) -> Any:
        if self.action_kind == "discrete":
            return 0
        if self.action_kind == "box":
            return np.array([-1.0], dtype=np.float32)
        return np.array([0, 0], dtype=np.int64)


def register_fakes() -> None:
    """Register the fake envs and agents (idempotent)."""
    for env_id, kind in (
        (DISCRETE_ID, "discrete"),
        (BOX_ID, "box"),
        (MULTI_DISCRETE_ID, "multi_discrete"),
    ):
        if env_id not in gym.registry:
            gym.register(
                id=env_id,
                entry_point="tests.cli_fakes:FakeLocateEnv",
                kwargs={"action_kind": kind},
                max_episode_steps=MAX_EPISODE_STEPS,
            )
        register_agent("scripted", ScriptedAgent, env_id)
        register_agent("coin", CoinAgent, env_id)
        register_agent("patient", PatientAgent, env_id)


register_fakes()
