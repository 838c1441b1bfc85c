"""What every ``sonar-gym reproduce`` module shares: the factor-of-two flag, the table of
parameters a paper leaves unstated, and a picture of one episode of the paper's agent."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from pathlib import Path

import gymnasium as gym
import numpy as np
from rich.markup import escape
from rich.table import Table

from sonar_gym.agents.base import Agent

FLAG = "differs by more than 2x"


def ratio_flag(ours: float, paper: float) -> str:
    """:data:`FLAG` when ``ours / paper`` lies outside [1/2, 2] (or is undefined), else ``""``."""
    if not (math.isfinite(ours) and math.isfinite(paper)) or paper <= 0.0 or ours <= 0.0:
        return FLAG
    ratio = ours / paper
    return FLAG if ratio > 2.0 or ratio < 0.5 else ""


def parameters_table(rows: Iterable[Sequence[str]]) -> Table:
    """The parameters a paper does not state: ``(parameter, our value, where)`` rows."""
    table = Table(
        title="Parameters the paper does not state", title_justify="left", header_style="bold"
    )
    for header in ("parameter", "our value", "where"):
        table.add_column(header)
    for row in rows:
        table.add_row(*(escape(str(cell)) for cell in row))
    return table


def final_frame_png(env: gym.Env, agent: Agent, seed: int, path: Path) -> Path:
    """Play ``agent`` for one episode from ``reset(seed=seed)`` on ``env`` (made with
    ``render_mode="rgb_array"``) and save the last rendered frame as a PNG at ``path``."""
    from sonar_gym.render import save_png

    observation, _ = env.reset(seed=seed)
    done = False
    while not done:
        observation, _, terminated, truncated, _ = env.step(agent.act(observation))
        done = terminated or truncated
    image = env.render()
    env.close()
    return save_png(np.asarray(image), path)
