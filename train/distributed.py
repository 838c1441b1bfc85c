"""Evaluation spread over a Ray cluster: ``sonar-gym evaluate --ray [--address ADDR]``.

Scripted baselines over thousands of seeds are embarrassingly parallel: every episode is
``agent.reset(seed)``, ``env.reset(seed)`` and a loop of ``act``/``step``, independent of every
other. This module cuts an evaluation plan into chunks of consecutive seeds, runs each chunk
as a Ray task (which builds its own env and agent, exactly as the local run does) and puts the
episode records back in seed order, so the numbers equal the local run's for the same seeds.

A saved model given as an agent must be readable at the same path on every node of the
cluster (a shared file system, or the same checkout everywhere).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from sonar_gym.train.rllib_backend import init_ray, require_ray

if TYPE_CHECKING:
    from sonar_gym.train.evaluation import EpisodeRecord

DEFAULT_CHUNK_EPISODES = 16
"""Episodes per Ray task: large enough that a task outweighs its scheduling, small enough
that a few thousand seeds spread over every core."""

EpisodeCallback = Callable[[str, str, "EpisodeRecord"], None]
ChunkPlayer = Callable[[str, str, Mapping[str, Any], Sequence[int], int], "list[EpisodeRecord]"]
"""Plays the episodes of some seeds with a fresh env and agent: (env id, agent name, env
arguments, seeds, step guard) -> records. It runs inside a Ray worker, so it must be a
module-level function (Ray ships it by reference)."""


def chunk_seeds(first_seed: int, episodes: int, chunk_episodes: int) -> list[list[int]]:
    """Seeds ``first_seed .. first_seed + episodes - 1`` cut into runs of ``chunk_episodes``."""
    if chunk_episodes < 1:
        raise ValueError(f"chunk_episodes must be at least 1, got {chunk_episodes}")
    seeds = list(range(first_seed, first_seed + episodes))
    return [seeds[i : i + chunk_episodes] for i in range(0, len(seeds), chunk_episodes)]


def evaluate_plan_on_ray(
    plan: Mapping[str, Sequence[str]],
    episodes: int,
    seed: int,
    env_kwargs: Mapping[str, Any],
    max_steps: int,
    play: ChunkPlayer,
    *,
    address: str | None = None,
    chunk_episodes: int = DEFAULT_CHUNK_EPISODES,
    on_episode: EpisodeCallback | None = None,
) -> dict[tuple[str, str], list[EpisodeRecord]]:
    """Records per (env id, agent) of ``plan``, computed as Ray tasks, in seed order.

    Args:
        plan: env id -> agent names (already checked by the caller).
        episodes: episodes per (env, agent); episode ``i`` has seed ``seed + i``.
        seed: seed of the first episode.
        env_kwargs: ``gym.make`` arguments for every env.
        max_steps: the per-episode step guard of the local run.
        play: what a task runs (:func:`sonar_gym.train.evaluation.play_seeds`).
        address: a running cluster (``"auto"``, ``"ray://host:10001"``); None starts a local one.
        chunk_episodes: episodes per task.
        on_episode: called for every record as its chunk comes back (progress display).
    """
    ray = require_ray()
    init_ray(address)
    remote_chunk = ray.remote(play)
    pending: dict[Any, tuple[str, str, int]] = {}
    for env_id, names in plan.items():
        for name in names:
            for index, seeds in enumerate(chunk_seeds(seed, episodes, chunk_episodes)):
                reference = remote_chunk.remote(env_id, name, dict(env_kwargs), seeds, max_steps)
                pending[reference] = (env_id, name, index)
    chunks: dict[tuple[str, str], dict[int, list[EpisodeRecord]]] = {}
    waiting = list(pending)
    while waiting:
        done, waiting = ray.wait(waiting, num_returns=1)
        env_id, name, index = pending[done[0]]
        records = ray.get(done[0])
        chunks.setdefault((env_id, name), {})[index] = records
        if on_episode is not None:
            for record in records:
                on_episode(env_id, name, record)
    return {
        key: [record for index in sorted(parts) for record in parts[index]]
        for key, parts in chunks.items()
    }
