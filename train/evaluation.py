"""Run agents on environments over seeds and summarise what they achieved.

Episode ``i`` of an evaluation uses the seed ``seed + i`` for the environment's ``reset`` and
for the agent's ``reset``, for every agent alike, so agents are compared on the same episodes
(paired comparisons). Each episode becomes an :class:`EpisodeRecord` built from the ``info``
the environment returns at the episode's end: ``position_error_m`` (E_xy of Beom & Cho
eq. (16), metres), ``heading_error_rad`` (E_theta of eq. (16), radians; left out where the
task has no heading: absent, or named in the env's ``unestimated_info_keys``),
``sensing_time_s`` (cumulative, seconds) and ``status`` (``"ok"`` when the localization
succeeded, otherwise the reason it failed).

The summary per agent (:class:`AgentSummary`) gives the success rate, the median and 95th
percentile of E_xy and E_theta over the successful episodes, the mean sensing time over all
episodes, and the mean episode reward with a two-sided Student-t confidence interval.

Selecting what to run is part of this module too: env ids (``"all"`` = every registered
``SonarGym/`` id), agent names per env, and ``--env-arg KEY=VALUE`` keyword arguments for
``gym.make``, validated against the environment's constructor. A bad selection raises
:class:`train.UsageError` with the allowed values.
"""

from __future__ import annotations

import contextlib
import difflib
import hashlib
import importlib.metadata
import inspect
import json
import math
import platform
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from scipy import stats

import sonar_gym  # noqa: F401  (registers the SonarGym/ ids)
from sonar_gym.agents import base as agent_registry
from sonar_gym.train import UsageError

ENV_NAMESPACE = "SonarGym"
DEFAULT_ENV_ID = "SonarGym/BeaconScan-v0"
ALL_ENVS = "all"
SUCCESS_STATUS = "ok"
TRUNCATED_STATUS = "truncated"
STEP_LIMIT_STATUS = "step_limit"
DEFAULT_MAX_STEPS_PER_EPISODE = 10_000
MAX_FOLDER_NAME = 100

EvaluationPlan = dict[str, list[str]]
"""Agent names to evaluate, per env id, in order."""

EpisodeCallback = Callable[[str, str, "EpisodeRecord"], None]
"""Called after each episode with the env id, the agent name and the episode's record."""


@dataclass(frozen=True)
class EpisodeRecord:
    """What one episode of one agent gave.

    Attributes:
        seed: the seed of ``env.reset`` and ``agent.reset``.
        reward: undiscounted sum of the rewards.
        position_error_m: E_xy at the episode's end, metres (None when the env did not report it).
        heading_error_rad: E_theta at the episode's end, radians (None where undefined).
        sensing_time_s: cumulative sensing time of the episode, seconds (None if not reported).
        status: ``"ok"`` when the localization succeeded, else the env's reason (or
            ``"truncated"`` / ``"step_limit"`` when the episode was cut short without one).
        steps: number of ``env.step`` calls.
    """

    seed: int
    reward: float
    position_error_m: float | None
    heading_error_rad: float | None
    sensing_time_s: float | None
    status: str
    steps: int

    @property
    def succeeded(self) -> bool:
        """True when the localization succeeded (``status == "ok"``)."""
        return self.status == SUCCESS_STATUS


@dataclass(frozen=True)
class ConfidenceInterval:
    """A two-sided Student-t confidence interval for a mean.

    ``half_width`` is ``t_{(1+confidence)/2, n-1} * s / sqrt(n)`` with ``s`` the sample
    standard deviation (``ddof=1``); None when fewer than two values exist.
    """

    mean: float
    half_width: float | None
    confidence: float
    n: int

    @property
    def low(self) -> float | None:
        """Lower end, or None when undefined."""
        return None if self.half_width is None else self.mean - self.half_width

    @property
    def high(self) -> float | None:
        """Upper end, or None when undefined."""
        return None if self.half_width is None else self.mean + self.half_width


@dataclass(frozen=True)
class AgentSummary:
    """Statistics of one agent on one env. Metres, radians and seconds.

    Error statistics are over the successful episodes only and None when there were none.
    Percentiles use linear interpolation between order statistics (numpy's default).
    """

    episodes: int
    successes: int
    success_rate: float
    position_error_median_m: float | None
    position_error_p95_m: float | None
    heading_error_median_rad: float | None
    heading_error_p95_rad: float | None
    sensing_time_mean_s: float | None
    reward: ConfidenceInterval


@dataclass(frozen=True)
class AgentResult:
    """All episodes of one agent on one env, and their summary."""

    env_id: str
    agent: str
    records: tuple[EpisodeRecord, ...]
    summary: AgentSummary


# --------------------------------------------------------------------------------------------
# statistics


def t_confidence_interval(values: Sequence[float], confidence: float = 0.95) -> ConfidenceInterval:
    """Mean of ``values`` with its two-sided Student-t confidence interval.

    Raises:
        ValueError: ``values`` is empty, or ``confidence`` is not in (0, 1).
    """
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must lie in (0, 1), got {confidence}")
    data = np.asarray(values, dtype=float)
    if data.size == 0:
        raise ValueError("values must hold at least one number")
    mean = float(data.mean())
    if data.size < 2:
        return ConfidenceInterval(mean=mean, half_width=None, confidence=confidence, n=1)
    standard_error = float(data.std(ddof=1)) / math.sqrt(data.size)
    t_quantile = float(stats.t.ppf(0.5 + confidence / 2.0, df=data.size - 1))
    return ConfidenceInterval(
        mean=mean, half_width=t_quantile * standard_error, confidence=confidence, n=int(data.size)
    )


def _median_and_p95(values: Sequence[float]) -> tuple[float | None, float | None]:
    if len(values) == 0:
        return None, None
    median, p95 = np.percentile(np.asarray(values, dtype=float), [50.0, 95.0])
    return float(median), float(p95)


def summarize(records: Sequence[EpisodeRecord], confidence: float = 0.95) -> AgentSummary:
    """Summary statistics of the episodes of one agent on one env (see :class:`AgentSummary`).

    Raises:
        ValueError: ``records`` is empty.
    """
    if len(records) == 0:
        raise ValueError("records must hold at least one episode")
    successful = [record for record in records if record.succeeded]
    position_errors = [r.position_error_m for r in successful if r.position_error_m is not None]
    heading_errors = [r.heading_error_rad for r in successful if r.heading_error_rad is not None]
    sensing_times = [r.sensing_time_s for r in records if r.sensing_time_s is not None]
    position_median, position_p95 = _median_and_p95(position_errors)
    heading_median, heading_p95 = _median_and_p95(heading_errors)
    return AgentSummary(
        episodes=len(records),
        successes=len(successful),
        success_rate=len(successful) / len(records),
        position_error_median_m=position_median,
        position_error_p95_m=position_p95,
        heading_error_median_rad=heading_median,
        heading_error_p95_rad=heading_p95,
        sensing_time_mean_s=float(np.mean(sensing_times)) if sensing_times else None,
        reward=t_confidence_interval([r.reward for r in records], confidence),
    )


# --------------------------------------------------------------------------------------------
# selecting envs, agents and env arguments


def registered_env_ids(namespace: str = ENV_NAMESPACE) -> list[str]:
    """Registered env ids of ``namespace``, in registration order."""
    return [env_id for env_id in gym.registry if env_id.startswith(f"{namespace}/")]


def resolve_env_ids(selection: str | Sequence[str], namespace: str = ENV_NAMESPACE) -> list[str]:
    """The env ids meant by ``selection``: ids, or ``"all"`` for every id of ``namespace``.

    Raises:
        UsageError: an id is not registered (the message lists the registered ones).
    """
    requested = [selection] if isinstance(selection, str) else list(selection)
    known = registered_env_ids(namespace)
    env_ids: list[str] = []
    for env_id in requested:
        expanded = known if env_id == ALL_ENVS else [env_id]
        if env_id == ALL_ENVS and not known:
            raise UsageError(f"no {namespace}/ environments are registered")
        for candidate in expanded:
            if candidate not in gym.registry:
                guesses = difflib.get_close_matches(candidate, known, n=1, cutoff=0.6)
                hint = f" (did you mean {guesses[0]!r}?)" if guesses else ""
                raise UsageError(
                    f"unknown env {candidate!r}{hint}; choose one of {known + [ALL_ENVS]} "
                    "(or any other registered Gymnasium id)"
                )
            if candidate not in env_ids:
                env_ids.append(candidate)
    return env_ids


def _looks_like_model(name: str) -> bool:
    try:
        return name.endswith(".zip") or Path(name).exists()
    except OSError:  # e.g. a name too long for the file system is no model either
        return False


def resolve_agent_names(
    env_ids: Sequence[str], requested: Sequence[str] | None = None
) -> EvaluationPlan:
    """Agent names to run per env: ``requested`` for every env, or all registered ones.

    A requested name is either registered for the env (see
    :func:`sonar_gym.agents.base.agent_names`) or the path of a saved model (``.zip`` file or
    run directory).

    Raises:
        UsageError: a name is neither (the message lists the agents of that env), or a model
            path does not exist.
    """
    plan: EvaluationPlan = {}
    for env_id in env_ids:
        available = agent_registry.agent_names(env_id)
        if not requested:
            if not available:
                raise UsageError(f"no agents are registered for {env_id}")
            plan[env_id] = list(available)
            continue
        for name in requested:
            if name in available or agent_registry.is_conditional(name):
                continue  # a conditional agent that does not fit says why when it is made
            if _looks_like_model(name):
                if not Path(name).exists():
                    raise UsageError(f"no saved model at {name!r}")
                continue
            raise UsageError(
                f"unknown agent {name!r} for {env_id}; choose one of {available} "
                "or give the path of a saved model (.zip)"
            )
        plan[env_id] = list(dict.fromkeys(requested))
    return plan


def parse_env_value(text: str) -> Any:
    """A ``--env-arg`` value: bool (true/false), None (none), int, float, JSON list/object, or
    the string itself."""
    lowered = text.strip().lower()
    if lowered in ("true", "false"):
        return lowered == "true"
    if lowered in ("none", "null"):
        return None
    for convert in (int, float):
        with contextlib.suppress(ValueError):
            return convert(text)
    if text.strip()[:1] in ("[", "{"):
        try:
            return json.loads(text)
        except json.JSONDecodeError as error:
            raise UsageError(f"--env-arg value {text!r} is not valid JSON: {error}") from error
    return text


def parse_env_args(items: Sequence[str] | None) -> dict[str, Any]:
    """``["KEY=VALUE", ...]`` to keyword arguments for ``gym.make``.

    Raises:
        UsageError: an item has no ``=`` or an empty key, or a key repeats.
    """
    kwargs: dict[str, Any] = {}
    for item in items or ():
        key, separator, value = item.partition("=")
        key = key.strip()
        if not separator or not key.isidentifier():
            raise UsageError(f"--env-arg expects KEY=VALUE with KEY a Python name, got {item!r}")
        if key in kwargs:
            raise UsageError(f"--env-arg {key} is given twice")
        kwargs[key] = parse_env_value(value)
    return kwargs


def env_argument_names(env_id: str) -> list[str] | None:
    """Keyword arguments the env's constructor accepts, or None when it takes ``**kwargs``."""
    spec = gym.spec(env_id)
    try:
        creator = (
            gym.envs.registration.load_env_creator(spec.entry_point)
            if isinstance(spec.entry_point, str)
            else spec.entry_point
        )
        if creator is None:
            return None
        parameters = inspect.signature(creator).parameters.values()
    except (ImportError, AttributeError, TypeError, ValueError):
        return None  # gym.make will report what is wrong with the entry point
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters):
        return None
    return [
        p.name
        for p in parameters
        if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    ]


def check_env_kwargs(env_id: str, env_kwargs: Mapping[str, Any]) -> None:
    """Check that ``env_id``'s constructor accepts every key of ``env_kwargs``.

    Raises:
        UsageError: a key is not an argument of the env (the message lists the arguments).
    """
    if not env_kwargs:
        return
    allowed = env_argument_names(env_id)
    if allowed is None:
        return
    unknown = sorted(set(env_kwargs) - set(allowed))
    if unknown:
        raise UsageError(
            f"{env_id} has no argument {', '.join(unknown)}; its arguments are {sorted(allowed)}"
        )


def make_env(env_id: str, env_kwargs: Mapping[str, Any] | None = None) -> gym.Env:
    """``gym.make(env_id, **env_kwargs)`` with the arguments checked first.

    Raises:
        UsageError: unknown argument names, or values the env rejects (its message kept).
    """
    kwargs = dict(env_kwargs or {})
    check_env_kwargs(env_id, kwargs)
    try:
        return gym.make(env_id, **kwargs)
    except (TypeError, ValueError) as error:
        raise UsageError(f"{env_id} rejected the arguments {kwargs}: {error}") from error


def make_named_agent(name: str, env: gym.Env) -> agent_registry.Agent:
    """:func:`sonar_gym.agents.base.make_agent`, with a saved model that does not fit ``env``
    (or is not a model at all), and a built-in agent whose procedure the env's arguments do not
    allow, reported as a :class:`train.UsageError`."""
    env_id = env.spec.id if env.spec is not None else ""
    if name in agent_registry.agent_names(env_id) and not agent_registry.is_conditional(name):
        try:
            return agent_registry.make_agent(name, env)
        except agent_registry.AgentEnvMismatchError as error:
            raise UsageError(str(error)) from error
    try:
        return agent_registry.make_agent(name, env)
    except ValueError as error:
        raise UsageError(f"agent {name!r} cannot act in {env_id}: {error}") from error


def validate_plan(plan: Mapping[str, Sequence[str]], env_kwargs: Mapping[str, Any]) -> None:
    """Check, before anything runs, that every env of ``plan`` accepts ``env_kwargs`` and that
    every agent of ``plan`` can be made for its env (saved models load and fit, built-in agents
    find the choices their procedures need).

    Raises:
        UsageError: the first problem found.
    """
    for env_id, names in plan.items():
        env = make_env(env_id, env_kwargs)
        try:
            for name in names:
                make_named_agent(name, env)
        finally:
            env.close()


def software_versions() -> dict[str, str]:
    """Versions of the packages behind a result (for the record in JSON files)."""

    def version(package: str) -> str:
        try:
            return importlib.metadata.version(package)
        except importlib.metadata.PackageNotFoundError:
            return "unknown"

    packages = ("sonar-gym", "gymnasium", "numpy", "scipy", "stable-baselines3", "torch")
    versions = {package: version(package) for package in packages}
    versions["python"] = platform.python_version()
    return versions


# --------------------------------------------------------------------------------------------
# running episodes


def _optional_float(value: Any) -> float | None:
    if value is None:
        return None
    number = float(value)
    return None if math.isnan(number) else number


def run_episode(
    env: gym.Env,
    agent: agent_registry.Agent,
    seed: int,
    max_steps: int = DEFAULT_MAX_STEPS_PER_EPISODE,
) -> EpisodeRecord:
    """Play one episode of ``agent`` on ``env`` from ``reset(seed=seed)``.

    The episode ends when the env terminates or truncates, or after ``max_steps`` steps
    (status ``"step_limit"``), a guard for envs registered without a time limit.
    """
    agent.reset(seed=seed)
    observation, info = env.reset(seed=seed)
    total_reward = 0.0
    steps = 0
    terminated = truncated = False
    while not (terminated or truncated) and steps < max_steps:
        action = agent.act(observation)
        observation, reward, terminated, truncated, info = env.step(action)
        total_reward += float(reward)
        steps += 1
    if "status" in info:
        status = str(info["status"])
    elif terminated or truncated:
        status = TRUNCATED_STATUS
    else:
        status = STEP_LIMIT_STATUS
    unestimated = getattr(env.unwrapped, "unestimated_info_keys", ())
    return EpisodeRecord(
        seed=seed,
        reward=total_reward,
        position_error_m=_optional_float(info.get("position_error_m")),
        heading_error_rad=(
            None
            if "heading_error_rad" in unestimated
            else _optional_float(info.get("heading_error_rad"))
        ),
        sensing_time_s=_optional_float(info.get("sensing_time_s")),
        status=status,
        steps=steps,
    )


def play_seeds(
    env_id: str,
    agent_name: str,
    env_kwargs: Mapping[str, Any],
    seeds: Sequence[int],
    max_steps: int,
) -> list[EpisodeRecord]:
    """Play one episode per seed with a fresh env and agent (what a Ray task runs; importing
    this module registers the ids in a fresh worker process)."""
    env = make_env(env_id, env_kwargs)
    try:
        agent = make_named_agent(agent_name, env)
        return [run_episode(env, agent, seed, max_steps) for seed in seeds]
    finally:
        env.close()


def evaluate_agents(
    env_ids: str | Sequence[str],
    agent_names: Sequence[str] | Mapping[str, Sequence[str]] | None = None,
    episodes: int = 50,
    seed: int = 0,
    env_kwargs: Mapping[str, Any] | None = None,
    *,
    on_episode: EpisodeCallback | None = None,
    max_steps_per_episode: int = DEFAULT_MAX_STEPS_PER_EPISODE,
    ray: bool = False,
    ray_address: str | None = None,
) -> list[AgentResult]:
    """Evaluate agents on envs; episode ``i`` uses seed ``seed + i`` for every agent.

    Args:
        env_ids: env ids, or ``"all"`` for every registered ``SonarGym/`` id.
        agent_names: names (or model paths) run on every env, a mapping env id -> names, or
            None for every agent registered for each env.
        episodes: episodes per agent and env (at least 1).
        seed: seed of the first episode.
        env_kwargs: keyword arguments for every ``gym.make`` (checked per env).
        on_episode: called after each episode (progress display).
        max_steps_per_episode: guard against envs without a time limit.
        ray: spread the episodes over a Ray cluster (:mod:`sonar_gym.train.distributed`);
            the records equal the local run's for the same seeds.
        ray_address: the cluster (``"auto"``, ``"ray://host:10001"``); None starts Ray locally.

    Returns:
        One :class:`AgentResult` per (env, agent), envs in the given order, agents in order.

    Raises:
        UsageError: unknown env or agent, or env arguments the env does not take.
        ValueError: ``episodes`` < 1.
    """
    if episodes < 1:
        raise ValueError(f"episodes must be at least 1, got {episodes}")
    resolved_env_ids = resolve_env_ids(env_ids)
    if isinstance(agent_names, Mapping):
        plan = {
            env_id: resolve_agent_names([env_id], agent_names.get(env_id))[env_id]
            for env_id in resolved_env_ids
        }
    else:
        plan = resolve_agent_names(resolved_env_ids, agent_names)
    kwargs = dict(env_kwargs or {})
    validate_plan(plan, kwargs)

    if ray:
        from sonar_gym.train.distributed import evaluate_plan_on_ray

        records_by_key = evaluate_plan_on_ray(
            plan,
            episodes,
            seed,
            kwargs,
            max_steps_per_episode,
            play_seeds,
            address=ray_address,
            on_episode=on_episode,
        )
        return [
            AgentResult(
                env_id=env_id,
                agent=name,
                records=tuple(records_by_key[(env_id, name)]),
                summary=summarize(records_by_key[(env_id, name)]),
            )
            for env_id, names in plan.items()
            for name in names
        ]
    results: list[AgentResult] = []
    for env_id, names in plan.items():
        for name in names:
            env = make_env(env_id, kwargs)
            try:
                agent = make_named_agent(name, env)
                records = []
                for episode in range(episodes):
                    record = run_episode(env, agent, seed + episode, max_steps_per_episode)
                    records.append(record)
                    if on_episode is not None:
                        on_episode(env_id, name, record)
            finally:
                env.close()
            results.append(
                AgentResult(
                    env_id=env_id, agent=name, records=tuple(records), summary=summarize(records)
                )
            )
    return results


def count_episodes(plan: Mapping[str, Sequence[str]], episodes: int) -> int:
    """Total number of episodes an evaluation of ``plan`` plays."""
    return episodes * sum(len(names) for names in plan.values())


# --------------------------------------------------------------------------------------------
# where a command writes


def _name_part(text: str) -> str:
    """``text`` with every character outside ``[A-Za-z0-9._=+-]`` replaced by ``-``."""
    return re.sub(r"[^A-Za-z0-9._=+-]+", "-", text).strip("-") or "-"


def _env_label(env_id: str) -> str:
    namespace, _, name = env_id.rpartition("/")
    return name if namespace == ENV_NAMESPACE else env_id


def _agent_label(agent: str) -> str:
    if not _looks_like_model(agent):
        return agent
    path = Path(agent)
    run = path.parent.name if path.suffix == ".zip" else path.name
    return f"{run}.{path.stem}" if path.suffix == ".zip" and run else run or path.stem


def output_folder_name(
    env_selection: Sequence[str],
    agents: Sequence[str] | None,
    episodes: int,
    seed: int,
    env_kwargs: Mapping[str, Any] | None = None,
) -> str:
    """The folder name of one evaluation, made of its arguments, so that different commands
    never overwrite each other's results and the same command always writes the same place.

    ``<envs>_<agents>_<episodes>ep_seed<seed>[_<key=value>...]``: envs as given (``all``, or
    ids without the ``SonarGym/`` namespace, joined by ``+``); agents joined by ``+``
    (``all-agents`` when none are named; a saved model as ``<run dir>.<file stem>``); env
    arguments sorted by key. Characters outside ``[A-Za-z0-9._=+-]`` become ``-``; a name
    longer than :data:`MAX_FOLDER_NAME` characters is cut and ends in a hash of the whole.

    >>> output_folder_name(["SonarGym/BeaconScan-v0"], None, 50, 0)
    'BeaconScan-v0_all-agents_50ep_seed0'
    >>> output_folder_name(["all"], ["paper", "random"], 10, 3, {"max_steps": 20})
    'all_paper+random_10ep_seed3_max_steps=20'
    """
    agent_part = (
        "+".join(_name_part(_agent_label(agent)) for agent in agents) if agents else "all-agents"
    )
    return name_from_arguments(
        [env_selection_label(env_selection), agent_part, f"{episodes}ep", f"seed{seed}"],
        env_kwargs,
    )


def env_selection_label(env_selection: Sequence[str]) -> str:
    """Env ids as given (``all``, or ids without the ``SonarGym/`` namespace) joined by ``+``."""
    return "+".join(_name_part(_env_label(env_id)) for env_id in env_selection) or "-"


def name_from_arguments(parts: Sequence[str], env_kwargs: Mapping[str, Any] | None = None) -> str:
    """``parts`` and the sorted ``key=value`` env arguments joined by ``_``, made safe for a
    file name and cut to :data:`MAX_FOLDER_NAME` characters (see :func:`output_folder_name`)."""
    parts = list(parts) + [
        _name_part(f"{key}={json.dumps(value) if not isinstance(value, str) else value}")
        for key, value in sorted((env_kwargs or {}).items())
    ]
    name = "_".join(parts)
    if len(name) > MAX_FOLDER_NAME:
        digest = hashlib.sha1(name.encode()).hexdigest()[:10]
        name = f"{name[: MAX_FOLDER_NAME - 11]}-{digest}"
    return name
