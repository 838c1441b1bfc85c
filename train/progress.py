"""Progress bars for long runs (rich), kept apart from the code that does the work."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from sonar_gym.train.evaluation import EpisodeCallback, EpisodeRecord


@contextmanager
def episode_progress(console: Console, total: int) -> Iterator[EpisodeCallback]:
    """A progress bar over ``total`` episodes; yields the callback that advances it.

    The bar's label names the env and agent of the episode that just finished.
    """
    progress = Progress(
        TextColumn("[progress.description]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TextColumn("eta"),
        TimeRemainingColumn(),
        console=console,
        transient=True,
    )
    task = progress.add_task("episodes", total=total)

    def advance(env_id: str, agent: str, record: EpisodeRecord) -> None:
        progress.update(task, advance=1, description=f"{env_id} · {agent}")

    with progress:
        yield advance


@contextmanager
def task_progress(description: str, total: int) -> Iterator[Callable[[], None]]:
    """A progress bar over ``total`` steps of one task; yields the function that advances it."""
    progress = Progress(
        TextColumn(description),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TextColumn("eta"),
        TimeRemainingColumn(),
        transient=True,
    )
    task = progress.add_task(description, total=total)
    with progress:
        yield lambda: progress.advance(task)
