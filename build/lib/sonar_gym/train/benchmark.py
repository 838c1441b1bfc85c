"""Speed of the simulation: sonar pans per second and environment steps per second.

Three measurements, reported as tables and written to ``results/benchmark.json``:

- pan throughput, from ``sonar_gym.train.bench_sonar.pan_throughput()`` when that module provides it
  (a mapping or a list of mappings, one per configuration, e.g. ``{"name": ..., "pans_per_s":
  ..., "pings_per_s": ...}``); otherwise skipped with a note;
- environment steps per second per env, driven by the env's ``paper`` agent (else the first
  registered agent), counting the time inside ``reset`` and ``step`` and, separately, the
  whole loop with the agent's ``act``;
- where the env exposes ``env.unwrapped.timing`` (cumulative seconds per phase, e.g.
  ``{"sensing": s, "localization": s}``), the share of the env's time spent in each phase.
"""

from __future__ import annotations

import importlib
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from sonar_gym.agents import base as agent_registry
from sonar_gym.train import UsageError
from sonar_gym.train.evaluation import check_env_kwargs, make_env

PREFERRED_AGENT = "paper"


@dataclass(frozen=True)
class EnvThroughput:
    """Steps per second of one env under one agent.

    Attributes:
        env_id: the env.
        agent: the agent that chose the actions.
        steps: ``env.step`` calls measured.
        episodes: episodes started (``reset`` calls).
        env_seconds: wall time inside ``reset`` and ``step``, seconds.
        loop_seconds: wall time of the whole loop including ``act``, seconds.
        phase_seconds: increase of ``env.unwrapped.timing`` per phase over the run, seconds
            (empty when the env has no ``timing``).
    """

    env_id: str
    agent: str
    steps: int
    episodes: int
    env_seconds: float
    loop_seconds: float
    phase_seconds: Mapping[str, float] = field(default_factory=dict)

    @property
    def env_steps_per_s(self) -> float:
        """Steps per second counting only the env's time."""
        return self.steps / self.env_seconds if self.env_seconds > 0 else math.inf

    @property
    def loop_steps_per_s(self) -> float:
        """Steps per second of the whole loop (env and agent)."""
        return self.steps / self.loop_seconds if self.loop_seconds > 0 else math.inf

    @property
    def phase_shares(self) -> dict[str, float]:
        """Fraction of the env's time per phase (plus ``"other"`` for the rest, if any)."""
        if not self.phase_seconds or self.env_seconds <= 0:
            return {}
        total = max(self.env_seconds, sum(self.phase_seconds.values()))
        shares = {phase: seconds / total for phase, seconds in self.phase_seconds.items()}
        rest = 1.0 - sum(shares.values())
        if rest > 1e-9:
            shares["other"] = rest
        return shares


def _timing_snapshot(env: Any) -> dict[str, float]:
    timing = getattr(env.unwrapped, "timing", None)
    if not isinstance(timing, Mapping):
        return {}
    return {str(phase): float(seconds) for phase, seconds in timing.items()}


def choose_agent(env_id: str) -> str:
    """The agent that drives the benchmark: ``paper`` when registered, else the first one."""
    names = agent_registry.agent_names(env_id)
    if PREFERRED_AGENT in names:
        return PREFERRED_AGENT
    if not names:
        raise ValueError(f"no agents are registered for {env_id}")
    return names[0]


def env_throughput(
    env_id: str,
    steps: int,
    agent_name: str | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
    seed: int = 0,
) -> EnvThroughput:
    """Run ``steps`` env steps of ``agent_name`` (default :func:`choose_agent`) on ``env_id``,
    starting a new episode (seed ``seed + k``) whenever one ends, and time them."""
    if steps < 1:
        raise ValueError(f"steps must be at least 1, got {steps}")
    name = agent_name or choose_agent(env_id)
    env = make_env(env_id, env_kwargs)
    try:
        agent = agent_registry.make_agent(name, env)
        before = _timing_snapshot(env)
        env_seconds = 0.0
        episodes = 0
        done = True
        observation: Any = None
        loop_start = time.perf_counter()
        for _ in range(steps):
            if done:
                agent.reset(seed=seed + episodes)
                tick = time.perf_counter()
                observation, _ = env.reset(seed=seed + episodes)
                env_seconds += time.perf_counter() - tick
                episodes += 1
            action = agent.act(observation)
            tick = time.perf_counter()
            observation, _, terminated, truncated, _ = env.step(action)
            env_seconds += time.perf_counter() - tick
            done = terminated or truncated
        loop_seconds = time.perf_counter() - loop_start
        after = _timing_snapshot(env)
    finally:
        env.close()
    phases = {phase: after[phase] - before.get(phase, 0.0) for phase in after}
    return EnvThroughput(env_id, name, steps, episodes, env_seconds, loop_seconds, phases)


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


def throughput_to_dict(result: EnvThroughput) -> dict[str, Any]:
    """A JSON-ready dict of ``result`` with the derived rates and shares."""
    return {
        "env_id": result.env_id,
        "agent": result.agent,
        "steps": result.steps,
        "episodes": result.episodes,
        "env_seconds": result.env_seconds,
        "loop_seconds": result.loop_seconds,
        "env_steps_per_s": result.env_steps_per_s,
        "loop_steps_per_s": result.loop_steps_per_s,
        "phase_seconds": dict(result.phase_seconds),
        "phase_shares": result.phase_shares,
    }


@dataclass(frozen=True)
class BenchmarkReport:
    """Everything one benchmark measured, and what it could not.

    Attributes:
        steps: env steps per env.
        pan_rows: rows of :func:`pan_throughput`.
        envs: throughput per env that ran.
        failures: env id -> error text, for envs that could not run.
        notes: measurements skipped and why.
    """

    steps: int
    pan_rows: tuple[Mapping[str, Any], ...]
    envs: tuple[EnvThroughput, ...]
    failures: Mapping[str, str]
    notes: tuple[str, ...]

    def to_dict(self, meta: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """A JSON-ready dict (``meta`` first)."""
        return {
            "meta": {"steps": self.steps, **dict(meta or {})},
            "pan": [dict(row) for row in self.pan_rows],
            "envs": [throughput_to_dict(result) for result in self.envs],
            "failures": dict(self.failures),
            "notes": list(self.notes),
        }


def run_benchmark(
    env_ids: Sequence[str],
    steps: int,
    env_kwargs: Mapping[str, Any] | None = None,
    on_env_start: Callable[[str, str], None] | None = None,
) -> BenchmarkReport:
    """Pan throughput, then :func:`env_throughput` for each env with :func:`choose_agent`.

    An env that raises while running is recorded in ``failures`` (the others still run);
    ``on_env_start(env_id, agent)`` is called before each env (status display).

    Raises:
        UsageError: an env's constructor does not take a key of ``env_kwargs``.
    """
    pan_rows, note = pan_throughput()
    notes = [note] if note else []
    for env_id in env_ids:
        check_env_kwargs(env_id, env_kwargs or {})
    throughputs: list[EnvThroughput] = []
    failures: dict[str, str] = {}
    for env_id in env_ids:
        try:
            agent = choose_agent(env_id)
            if on_env_start is not None:
                on_env_start(env_id, agent)
            throughputs.append(env_throughput(env_id, steps, agent, env_kwargs))
        except UsageError:
            raise
        except Exception as error:  # a broken env must not hide the other envs' numbers
            failures[env_id] = f"{type(error).__name__}: {error}"
    return BenchmarkReport(
        steps=steps,
        pan_rows=tuple(pan_rows),
        envs=tuple(throughputs),
        failures=failures,
        notes=tuple(notes),
    )
