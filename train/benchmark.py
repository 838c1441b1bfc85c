"""Speed as a user feels it: random-action steps per second and PPO training steps per second.

One run, one process, reported as tables and written to JSON:

- **the reset cost of a large room** (:mod:`sonar_gym.train.bench_room`): ``gym.make`` and four
  resets of BeaconScan in ``beom_cho_lab`` with 1,500 extra walls;
- **sonar pan throughput**, the rows of ``sonar_gym.train.bench_sonar.pan_throughput()`` (each
  with its ratio to bare pymunk ray casts), or a note when that module does not provide them;
- **PPO on CartPole-v1** (the yardstick every RL user knows), measured before the first env and
  after every env, so each env is bracketed by two CartPole runs and drift of the machine's
  load during the run is visible;
- per env, **random-action steps per second** (``action_space.sample()``, a new episode with
  seed ``seed + k`` whenever one ends, the time of ``reset`` included), and **SB3 PPO
  env-steps per second** (``PPO("MlpPolicy", n_steps=512, batch_size=64, n_epochs=4)``, one
  env, torch on one thread, until the wall-time budget is spent)
  with its ratio to CartPole's PPO rate beside it (the mean of the two runs that bracket the
  env: load on a shared machine drifts over minutes, and a whole run takes several);
- per env, PPO's **ceiling**: the same PPO on a stand-in env with the env's observation and
  action spaces and its mean episode length whose ``step`` costs nothing
  (:class:`FreeEnv`). Its ratio to CartPole is the best the env could reach were it free: the
  learner's own cost grows with the spaces (a ``MultiDiscrete`` head is several
  categorical distributions), and that part no env work can remove;
- per env, the **share of wall time per phase**: the env's own ``env.unwrapped.timing``
  phases (e.g. ``sensing``, ``localization``), the rest of ``reset``/``step`` (``env other``),
  and for PPO everything outside the env (``learner``: policy, rollout buffer, updates);
- per env with a native vector env (a ``vector_entry_point``, e.g. BeaconScan), **vector
  throughput**: env-steps per second of :data:`VECTOR_NUM_ENVS` robots under random actions
  through ``gym.make_vec(..., vectorization_mode="vector_entry_point")`` against
  ``vectorization_mode="sync"``, in alternating runs of the same budget.

The budget is wall time, so the numbers are rates, not counts: the machine's load moves them,
which is why the ratio to CartPole in the same run is the number to compare across machines.
"""

from __future__ import annotations

import copy
import importlib
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym

from sonar_gym.train import UsageError
from sonar_gym.train.bench_room import DEFAULT_EXTRA_WALLS, RoomReset, room_reset
from sonar_gym.train.evaluation import check_env_kwargs, make_env

REFERENCE_ENV_ID = "CartPole-v1"
PPO_N_STEPS = 512
PPO_BATCH_SIZE = 64
PPO_N_EPOCHS = 4
DEFAULT_SECONDS = 20.0
RANDOM_SHARE_OF_BUDGET = 0.5
"""The random-action run gets this fraction of the per-env budget (it needs less to settle)."""
CEILING_SHARE_OF_BUDGET = 0.5
"""The free-env PPO run gets this fraction of the per-env budget (its rate is steady)."""
REFERENCE_SHARE_OF_BUDGET = 0.5
"""Each CartPole-v1 PPO run gets this fraction of the per-env budget (one before the first env,
one after every env)."""
VECTOR_NUM_ENVS = 8
"""Sub-envs of the vector throughput runs."""
VECTOR_SHARE_OF_BUDGET = 0.1
"""Each vector throughput run gets this fraction of the per-env budget (2 s at the default)."""
VECTOR_PAIRS = 2
"""Alternating sync / native run pairs per env (the machine's load drifts)."""
VECTOR_MODES = ("sync", "vector_entry_point")
ENV_OTHER = "env other"
LEARNER = "learner"


class StepClock(gym.Wrapper):
    """Adds up the wall time spent inside ``reset`` and ``step`` (seconds), and counts them."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.env_seconds = 0.0
        self.steps = 0
        self.resets = 0

    def reset(self, **kwargs: Any) -> Any:
        start = time.perf_counter()
        try:
            return self.env.reset(**kwargs)
        finally:
            self.env_seconds += time.perf_counter() - start
            self.resets += 1

    def step(self, action: Any) -> Any:
        start = time.perf_counter()
        try:
            return self.env.step(action)
        finally:
            self.env_seconds += time.perf_counter() - start
            self.steps += 1


class FreeEnv(gym.Env[Any, Any]):
    """A stand-in with a real env's spaces whose ``reset`` and ``step`` cost (almost) nothing.

    It returns a fresh copy of one fixed observation (a seeded sample of the space), reward 0,
    and ends every episode after ``episode_steps`` steps, so PPO on it measures the learner
    alone for those spaces and that episode length.
    """

    def __init__(
        self, observation_space: gym.Space[Any], action_space: gym.Space[Any], episode_steps: int
    ) -> None:
        if episode_steps < 1:
            raise ValueError(f"episode_steps must be at least 1, got {episode_steps}")
        self.observation_space = observation_space
        self.action_space = action_space
        self.episode_steps = episode_steps
        observation_space.seed(0)
        self._observation = observation_space.sample()
        self._steps = 0

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        super().reset(seed=seed)
        self._steps = 0
        return copy.deepcopy(self._observation), {}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        self._steps += 1
        observation = copy.deepcopy(self._observation)
        return observation, 0.0, self._steps >= self.episode_steps, False, {}


def _timing_snapshot(env: gym.Env) -> dict[str, float]:
    timing = getattr(env.unwrapped, "timing", None)
    if not isinstance(timing, Mapping):
        return {}
    return {str(phase): float(seconds) for phase, seconds in timing.items()}


def phase_shares(
    wall_seconds: float,
    env_seconds: float,
    env_phases: Mapping[str, float],
    outside: str | None = None,
) -> dict[str, float]:
    """Fractions of ``wall_seconds`` per phase: each of ``env_phases`` (seconds), the rest of
    ``env_seconds`` as :data:`ENV_OTHER`, and, when ``outside`` names it, the time outside the
    env. Empty when ``wall_seconds`` is not positive. The shares sum to 1 when ``outside`` is
    given (to the env's share otherwise)."""
    if wall_seconds <= 0.0:
        return {}
    shares = {phase: seconds / wall_seconds for phase, seconds in env_phases.items()}
    shares[ENV_OTHER] = max(0.0, env_seconds - sum(env_phases.values())) / wall_seconds
    if outside is not None:
        shares[outside] = max(0.0, 1.0 - sum(shares.values()))
    return shares


@dataclass(frozen=True)
class RandomRate:
    """Random actions on one env for a wall-time budget.

    Attributes:
        env_id: the env.
        steps: ``env.step`` calls.
        episodes: episodes started (``reset`` calls).
        seconds: wall time of the whole loop, seconds.
        env_seconds: wall time inside ``reset`` and ``step``, seconds.
        phase_seconds: increase of ``env.unwrapped.timing`` per phase, seconds (empty when
            the env keeps no ``timing``).
    """

    env_id: str
    steps: int
    episodes: int
    seconds: float
    env_seconds: float
    phase_seconds: Mapping[str, float] = field(default_factory=dict)

    @property
    def steps_per_s(self) -> float:
        """Steps per second of the loop (``reset`` time included)."""
        return self.steps / self.seconds if self.seconds > 0 else math.inf

    @property
    def phase_shares(self) -> dict[str, float]:
        """Share of the loop's wall time per env phase (see :func:`phase_shares`)."""
        return phase_shares(self.seconds, self.env_seconds, self.phase_seconds)


@dataclass(frozen=True)
class PPORate:
    """SB3 PPO training on one env for a wall-time budget.

    Attributes:
        env_id: the env.
        timesteps: env steps PPO collected.
        updates: rollout + update cycles.
        seconds: wall time of the training, seconds.
        env_seconds: wall time inside the env's ``reset`` and ``step``, seconds.
        phase_seconds: increase of ``env.unwrapped.timing`` per phase, seconds.
    """

    env_id: str
    timesteps: int
    updates: int
    seconds: float
    env_seconds: float
    phase_seconds: Mapping[str, float] = field(default_factory=dict)

    @property
    def steps_per_s(self) -> float:
        """Env steps per second of training."""
        return self.timesteps / self.seconds if self.seconds > 0 else math.inf

    @property
    def phase_shares(self) -> dict[str, float]:
        """Share of the training's wall time per env phase and :data:`LEARNER`."""
        return phase_shares(self.seconds, self.env_seconds, self.phase_seconds, LEARNER)


def random_rate(
    env_id: str,
    seconds: float,
    env_kwargs: Mapping[str, Any] | None = None,
    seed: int = 0,
) -> RandomRate:
    """Step ``env_id`` with ``action_space.sample()`` until ``seconds`` of wall time pass (at
    least one step), resetting with seed ``seed + k`` whenever an episode ends."""
    if not seconds > 0.0:
        raise ValueError(f"seconds must be positive, got {seconds}")
    env = StepClock(make_env(env_id, env_kwargs))
    try:
        env.action_space.seed(seed)
        before = _timing_snapshot(env)
        episodes = 0
        start = time.perf_counter()
        env.reset(seed=seed)
        episodes += 1
        while True:
            _, _, terminated, truncated, _ = env.step(env.action_space.sample())
            if time.perf_counter() - start >= seconds:
                break
            if terminated or truncated:
                env.reset(seed=seed + episodes)
                episodes += 1
        elapsed = time.perf_counter() - start
        after = _timing_snapshot(env)
    finally:
        env.close()
    phases = {phase: after[phase] - before.get(phase, 0.0) for phase in after}
    return RandomRate(env_id, env.steps, episodes, elapsed, env.env_seconds, phases)


def ppo_rate(
    env_id: str,
    seconds: float,
    env_kwargs: Mapping[str, Any] | None = None,
    seed: int = 0,
    n_steps: int = PPO_N_STEPS,
) -> PPORate:
    """Train ``PPO("MlpPolicy", n_steps, batch_size=64, n_epochs=4)`` on one ``env_id`` until
    ``seconds`` of wall time pass (checked after every env step, so at least one step).

    The budget can end inside a rollout: for an env too slow to fill one rollout in the budget
    the rate leaves out PPO's update, which then costs little next to the env anyway (the
    ``learner`` share says how much). Torch runs on the threads it is given
    (:func:`run_benchmark` sets one).
    """
    return _train_for(env_id, make_env(env_id, env_kwargs), seconds, seed, n_steps)


def ceiling_rate(
    env_id: str,
    seconds: float,
    episode_steps: int,
    env_kwargs: Mapping[str, Any] | None = None,
    seed: int = 0,
    n_steps: int = PPO_N_STEPS,
) -> PPORate:
    """:func:`ppo_rate` on a :class:`FreeEnv` with ``env_id``'s spaces and ``episode_steps``:
    the PPO rate the env would allow if its ``reset`` and ``step`` cost nothing."""
    env = make_env(env_id, env_kwargs)
    try:
        free = FreeEnv(env.observation_space, env.action_space, episode_steps)
    finally:
        env.close()
    return _train_for(env_id, free, seconds, seed, n_steps)


def _train_for(env_id: str, env: gym.Env, seconds: float, seed: int, n_steps: int) -> PPORate:
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback

    if not seconds > 0.0:
        env.close()
        raise ValueError(f"seconds must be positive, got {seconds}")

    class WallTimeBudget(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.start = time.perf_counter()

        def _on_training_start(self) -> None:
            self.start = time.perf_counter()

        def _on_step(self) -> bool:
            return time.perf_counter() - self.start < seconds

    clocked = StepClock(env)
    try:
        model = PPO(
            "MlpPolicy",
            clocked,
            n_steps=n_steps,
            batch_size=min(PPO_BATCH_SIZE, n_steps),
            n_epochs=PPO_N_EPOCHS,
            seed=seed,
            device="cpu",
            verbose=0,
        )
        before = _timing_snapshot(clocked)
        start = time.perf_counter()
        model.learn(total_timesteps=10**12, callback=WallTimeBudget())
        elapsed = time.perf_counter() - start
        after = _timing_snapshot(clocked)
        timesteps = int(model.num_timesteps)
        updates = int(model._n_updates) // PPO_N_EPOCHS
    finally:
        clocked.close()
    phases = {phase: after[phase] - before.get(phase, 0.0) for phase in after}
    return PPORate(env_id, timesteps, updates, elapsed, clocked.env_seconds, phases)


@dataclass(frozen=True)
class VectorRate:
    """Random actions on ``num_envs`` sub-envs of one vector env for a wall-time budget.

    Attributes:
        env_id: the env.
        mode: ``make_vec``'s ``vectorization_mode``: ``"sync"`` or ``"vector_entry_point"``.
        num_envs: sub-envs.
        steps: vector ``step`` calls (each steps every sub-env, autoresets included).
        seconds: wall time of the loop, seconds (the first ``reset`` included).
    """

    env_id: str
    mode: str
    num_envs: int
    steps: int
    seconds: float

    @property
    def env_steps_per_s(self) -> float:
        """Sub-env steps per second (``steps * num_envs / seconds``)."""
        return self.steps * self.num_envs / self.seconds if self.seconds > 0 else math.inf


@dataclass(frozen=True)
class VectorSpeed:
    """One env's vector throughput: alternating ``sync`` and native runs, in the order run."""

    env_id: str
    num_envs: int
    runs: tuple[VectorRate, ...]

    def env_steps_per_s(self, mode: str) -> float:
        """Sub-env steps per second over every run of ``mode`` (steps over summed seconds)."""
        runs = [run for run in self.runs if run.mode == mode]
        seconds = sum(run.seconds for run in runs)
        steps = sum(run.steps * run.num_envs for run in runs)
        return steps / seconds if seconds > 0 else math.nan

    @property
    def native_over_sync(self) -> float:
        """The native vector env's rate over ``SyncVectorEnv``'s (above 1: the native is
        faster)."""
        sync = self.env_steps_per_s("sync")
        return self.env_steps_per_s("vector_entry_point") / sync if sync > 0 else math.nan

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict."""
        return {
            "env_id": self.env_id,
            "num_envs": self.num_envs,
            "runs": [{**vars(run), "env_steps_per_s": run.env_steps_per_s} for run in self.runs],
            "sync_env_steps_per_s": self.env_steps_per_s("sync"),
            "native_env_steps_per_s": self.env_steps_per_s("vector_entry_point"),
            "native_over_sync": self.native_over_sync,
        }


def has_native_vector_env(env_id: str) -> bool:
    """Whether ``env_id`` is registered, with a ``vector_entry_point``."""
    spec = gym.registry.get(env_id)
    return spec is not None and spec.vector_entry_point is not None


def vector_rate(
    env_id: str,
    mode: str,
    seconds: float,
    num_envs: int = VECTOR_NUM_ENVS,
    env_kwargs: Mapping[str, Any] | None = None,
    seed: int = 0,
) -> VectorRate:
    """Step ``gym.make_vec(env_id, num_envs, vectorization_mode=mode)`` with
    ``action_space.sample()`` until ``seconds`` of wall time pass (at least one step); the
    sub-envs autoreset (``seed`` seeds the first reset and the actions)."""
    if not seconds > 0.0:
        raise ValueError(f"seconds must be positive, got {seconds}")
    envs = gym.make_vec(
        env_id, num_envs=num_envs, vectorization_mode=mode, **dict(env_kwargs or {})
    )
    try:
        envs.action_space.seed(seed)
        steps = 0
        start = time.perf_counter()
        envs.reset(seed=seed)
        while True:
            envs.step(envs.action_space.sample())
            steps += 1
            if time.perf_counter() - start >= seconds:
                break
        elapsed = time.perf_counter() - start
    finally:
        envs.close()
    return VectorRate(env_id, mode, num_envs, steps, elapsed)


def vector_speed(
    env_id: str,
    seconds: float,
    num_envs: int = VECTOR_NUM_ENVS,
    env_kwargs: Mapping[str, Any] | None = None,
    pairs: int = VECTOR_PAIRS,
) -> VectorSpeed:
    """:func:`vector_rate` of ``sync`` then the native vector env, ``pairs`` times, each run
    ``seconds`` long, with the same seed and actions in both modes."""
    runs = [
        vector_rate(env_id, mode, seconds, num_envs, env_kwargs)
        for _ in range(pairs)
        for mode in VECTOR_MODES
    ]
    return VectorSpeed(env_id, num_envs, tuple(runs))


def pan_throughput() -> tuple[list[dict[str, Any]], str | None]:
    """Rows from ``sonar_gym.train.bench_sonar.pan_throughput()``, or no rows and the reason."""
    try:
        module = importlib.import_module("sonar_gym.train.bench_sonar")
    except ImportError as error:
        return [], f"pan throughput skipped: train.bench_sonar cannot be imported ({error})"
    function = getattr(module, "pan_throughput", None)
    if not callable(function):
        return [], "pan throughput skipped: train.bench_sonar has no pan_throughput()"
    result = function()
    rows: Sequence[Any] = [result] if isinstance(result, Mapping) else list(result)
    if not all(isinstance(row, Mapping) for row in rows):
        return [], "pan throughput skipped: pan_throughput() did not return mappings"
    return [dict(row) for row in rows], None


@dataclass(frozen=True)
class EnvSpeed:
    """The rates of one env, and PPO's ratio to CartPole-v1's PPO rate beside it.

    ``ceiling`` is PPO on a :class:`FreeEnv` with the env's spaces and mean episode length;
    ``reference_steps_per_s`` is CartPole-v1's PPO rate, the mean of the two runs that bracket
    this env's runs.
    """

    env_id: str
    random: RandomRate
    ppo: PPORate
    reference_steps_per_s: float
    ceiling: PPORate

    @property
    def ppo_over_reference(self) -> float:
        """PPO env-steps/s here over PPO env-steps/s on CartPole-v1 (1 = as fast as CartPole)."""
        if self.reference_steps_per_s <= 0.0:
            return math.nan
        return self.ppo.steps_per_s / self.reference_steps_per_s

    @property
    def ceiling_over_reference(self) -> float:
        """PPO env-steps/s on the free stand-in over CartPole-v1's: the most the env allows."""
        if self.reference_steps_per_s <= 0.0:
            return math.nan
        return self.ceiling.steps_per_s / self.reference_steps_per_s

    @property
    def env_seconds_per_step(self) -> float:
        """Wall time a PPO step costs beyond the free stand-in's, seconds: the env's share."""
        return 1.0 / self.ppo.steps_per_s - 1.0 / self.ceiling.steps_per_s


def _rate_to_dict(rate: RandomRate | PPORate) -> dict[str, Any]:
    data: dict[str, Any] = {
        key: value for key, value in vars(rate).items() if key not in ("env_id", "phase_seconds")
    }
    data.update(
        steps_per_s=rate.steps_per_s,
        phase_seconds=dict(rate.phase_seconds),
        phase_shares=rate.phase_shares,
    )
    return data


@dataclass(frozen=True)
class BenchmarkReport:
    """Everything one benchmark run measured, and what it could not.

    Attributes:
        seconds: the per-env wall-time budget of PPO, seconds (random actions get
            :data:`RANDOM_SHARE_OF_BUDGET` of it, each CartPole run
            :data:`REFERENCE_SHARE_OF_BUDGET`).
        ppo_n_steps: PPO's rollout length.
        pan_rows: rows of :func:`pan_throughput`.
        room_reset: make and resets in a room with many walls (None when not measured).
        references: PPO on CartPole-v1, in the order run: before the first env, then after
            each env (a failed env too), so ``envs[i]`` lies between ``references[i]`` and
            ``references[i + 1]`` when no env failed.
        envs: the rates per env that ran.
        failures: env id -> error text, for envs that could not run.
        notes: measurements skipped and why.
        vectors: vector throughput of the envs with a native vector env.
    """

    seconds: float
    ppo_n_steps: int
    pan_rows: tuple[Mapping[str, Any], ...]
    room_reset: RoomReset | None
    references: tuple[PPORate, ...]
    envs: tuple[EnvSpeed, ...]
    failures: Mapping[str, str]
    notes: tuple[str, ...]
    vectors: tuple[VectorSpeed, ...] = ()

    @property
    def reference_before(self) -> PPORate:
        """PPO on CartPole-v1 before the first env."""
        return self.references[0]

    @property
    def reference_after(self) -> PPORate:
        """PPO on CartPole-v1 after the last env."""
        return self.references[-1]

    @property
    def reference_steps_per_s(self) -> float:
        """CartPole-v1 PPO env-steps/s, the mean over all its runs."""
        return sum(run.steps_per_s for run in self.references) / len(self.references)

    @property
    def reference_drift(self) -> float:
        """CartPole-v1 PPO rate after over before (1 = the machine's load did not change)."""
        before = self.reference_before.steps_per_s
        return self.reference_after.steps_per_s / before if before > 0 else math.nan

    @property
    def reference_spread(self) -> float:
        """CartPole-v1's fastest PPO run over its slowest (1 = every run at the same rate)."""
        rates = [run.steps_per_s for run in self.references]
        return max(rates) / min(rates) if min(rates) > 0 else math.nan

    def to_dict(self, meta: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """A JSON-ready dict (``meta`` first)."""
        return {
            "meta": {
                "seconds": self.seconds,
                "ppo": {
                    "policy": "MlpPolicy",
                    "n_steps": self.ppo_n_steps,
                    "batch_size": PPO_BATCH_SIZE,
                    "n_epochs": PPO_N_EPOCHS,
                    "n_envs": 1,
                    "torch_threads": 1,
                },
                **dict(meta or {}),
            },
            "pan": [dict(row) for row in self.pan_rows],
            "room_reset": None if self.room_reset is None else self.room_reset.to_dict(),
            "reference": {
                "env_id": REFERENCE_ENV_ID,
                "before": _rate_to_dict(self.reference_before),
                "after": _rate_to_dict(self.reference_after),
                "runs": [_rate_to_dict(run) for run in self.references],
                "ppo_steps_per_s": self.reference_steps_per_s,
                "drift_after_over_before": self.reference_drift,
                "fastest_over_slowest": self.reference_spread,
            },
            "envs": [
                {
                    "env_id": speed.env_id,
                    "random": _rate_to_dict(speed.random),
                    "ppo": _rate_to_dict(speed.ppo),
                    "cartpole_ppo_steps_per_s": speed.reference_steps_per_s,
                    "ppo_over_cartpole": speed.ppo_over_reference,
                    "ceiling": _rate_to_dict(speed.ceiling),
                    "ceiling_over_cartpole": speed.ceiling_over_reference,
                    "env_seconds_per_ppo_step": speed.env_seconds_per_step,
                }
                for speed in self.envs
            ],
            "vector": [speed.to_dict() for speed in self.vectors],
            "failures": dict(self.failures),
            "notes": list(self.notes),
        }


BenchmarkProgress = Callable[[str], None]
"""Called with a line saying what is measured next (status display)."""


def run_benchmark(
    env_ids: Sequence[str],
    seconds: float = DEFAULT_SECONDS,
    env_kwargs: Mapping[str, Any] | None = None,
    on_stage: BenchmarkProgress | None = None,
    *,
    ppo_n_steps: int = PPO_N_STEPS,
    measure_pan: bool = True,
    measure_vector: bool = True,
) -> BenchmarkReport:
    """Pan throughput, CartPole PPO, then per env random actions, PPO, PPO on the env's free
    stand-in and CartPole PPO again: each env's ratios are to the two CartPole runs around it.
    Last, the vector throughput of the envs with a native vector env.

    Torch is set to one thread for the run (and restored after). An env that raises is
    recorded in ``failures`` and the others still run.

    Args:
        env_ids: the envs to measure.
        seconds: PPO wall-time budget per env (positive); each CartPole run gets
            :data:`REFERENCE_SHARE_OF_BUDGET` of it.
        env_kwargs: keyword arguments for every env's ``gym.make`` (checked first).
        on_stage: told what is measured next.
        ppo_n_steps: PPO's rollout length (512 in every reported number; smaller only to
            test the plumbing quickly).
        measure_pan: False skips the pan rows and the large-room reset (with a note).
        measure_vector: False skips the vector throughput (with a note); it takes
            ``2 * VECTOR_PAIRS * VECTOR_SHARE_OF_BUDGET * seconds`` per env with a native
            vector env (8 s at the default).

    Raises:
        UsageError: an env's constructor does not take a key of ``env_kwargs``.
        ValueError: ``seconds`` is not positive.
    """
    import torch

    if not seconds > 0.0:
        raise ValueError(f"seconds must be positive, got {seconds}")
    for env_id in env_ids:
        check_env_kwargs(env_id, env_kwargs or {})

    def stage(text: str) -> None:
        if on_stage is not None:
            on_stage(text)

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        notes: list[str] = []
        pan_rows: list[dict[str, Any]] = []
        room: RoomReset | None = None
        if measure_pan:
            stage("sonar pan throughput")
            pan_rows, note = pan_throughput()
            notes.extend([note] if note else [])
            stage(f"resets of a room with {DEFAULT_EXTRA_WALLS} extra walls")
            room = room_reset()
        else:
            notes.append("pan throughput and large-room reset skipped: not requested")
        reference_seconds = REFERENCE_SHARE_OF_BUDGET * seconds

        def reference_run(when: str) -> PPORate:
            stage(f"{REFERENCE_ENV_ID}: PPO for {reference_seconds:g} s ({when})")
            return ppo_rate(REFERENCE_ENV_ID, reference_seconds, n_steps=ppo_n_steps)

        references = [reference_run("before the envs")]
        speeds: list[EnvSpeed] = []
        failures: dict[str, str] = {}
        for env_id in env_ids:
            measured: tuple[RandomRate, PPORate, PPORate] | None = None
            try:
                stage(f"{env_id}: random actions for {RANDOM_SHARE_OF_BUDGET * seconds:g} s")
                random = random_rate(env_id, RANDOM_SHARE_OF_BUDGET * seconds, env_kwargs)
                stage(f"{env_id}: PPO for {seconds:g} s")
                ppo = ppo_rate(env_id, seconds, env_kwargs, n_steps=ppo_n_steps)
                ceiling_seconds = CEILING_SHARE_OF_BUDGET * seconds
                stage(f"{env_id}: PPO on a free stand-in for {ceiling_seconds:g} s")
                episode_steps = max(1, round(random.steps / random.episodes))
                ceiling = ceiling_rate(
                    env_id, ceiling_seconds, episode_steps, env_kwargs, n_steps=ppo_n_steps
                )
                measured = (random, ppo, ceiling)
            except UsageError:
                raise
            except Exception as error:  # a broken env must not hide the other envs' numbers
                failures[env_id] = f"{type(error).__name__}: {error}"
            references.append(reference_run(f"after {env_id}"))
            if measured is not None:
                beside = 0.5 * (references[-2].steps_per_s + references[-1].steps_per_s)
                random, ppo, ceiling = measured
                speeds.append(EnvSpeed(env_id, random, ppo, beside, ceiling))
        vectors = _vector_speeds(env_ids, seconds, env_kwargs, stage, failures, measure_vector)
        if not measure_vector:
            notes.append("vector throughput skipped: not requested")
    finally:
        torch.set_num_threads(threads)
    return BenchmarkReport(
        seconds=seconds,
        ppo_n_steps=ppo_n_steps,
        pan_rows=tuple(pan_rows),
        room_reset=room,
        references=tuple(references),
        envs=tuple(speeds),
        failures=failures,
        notes=tuple(notes),
        vectors=vectors,
    )


def _vector_speeds(
    env_ids: Sequence[str],
    seconds: float,
    env_kwargs: Mapping[str, Any] | None,
    stage: BenchmarkProgress,
    failures: dict[str, str],
    measure: bool,
) -> tuple[VectorSpeed, ...]:
    """:func:`vector_speed` of each env in ``env_ids`` with a native vector env that has not
    failed already (an error is recorded in ``failures``, under ``"<id> (vector)"``)."""
    if not measure:
        return ()
    run_seconds = VECTOR_SHARE_OF_BUDGET * seconds
    speeds: list[VectorSpeed] = []
    for env_id in env_ids:
        if env_id in failures or not has_native_vector_env(env_id):
            continue
        stage(
            f"{env_id}: {VECTOR_NUM_ENVS} envs, sync vs native vector, "
            f"{VECTOR_PAIRS} x 2 runs of {run_seconds:g} s"
        )
        try:
            speeds.append(vector_speed(env_id, run_seconds, env_kwargs=env_kwargs))
        except Exception as error:  # a broken env must not hide the other envs' numbers
            failures[f"{env_id} (vector)"] = f"{type(error).__name__}: {error}"
    return tuple(speeds)
