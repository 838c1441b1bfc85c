"""Reset cost in a large room: a built-in scenario with many extra walls, made and reset.

An episode must only place the robot and draw noise and temperatures; the static world
(pymunk shapes, the geometry cache, the corner analysis) is built once per scenario. This
measures that promise: the wall time of ``gym.make`` and of a few resets in
``beom_cho_lab`` with ``extra_walls`` short wall pieces added along its long walls.
"""

from __future__ import annotations

import json
import tempfile
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from sonar_gym.scenario import BUILTIN_DIR

ROOM_ENV_ID = "SonarGym/BeaconScan-v0"
ROOM_SCENARIO = "beom_cho_lab"
DEFAULT_EXTRA_WALLS = 1500
DEFAULT_RESETS = 4
PIECE_LENGTH_M = 0.01
"""Length of each extra wall piece, metres."""
PIECE_INSET_M = 0.01
"""How far inside the room's long walls the pieces lie, metres."""


@dataclass(frozen=True)
class RoomReset:
    """Wall time of building and resetting an env in a room with many walls.

    Attributes:
        env_id: the env made.
        walls: wall segments in the scenario, the extra pieces included.
        extra_walls: the pieces added to the built-in scenario.
        make_seconds: wall time of ``gym.make``, seconds.
        reset_seconds: wall time of all ``resets`` resets (seeds 0, 1, ...), seconds.
        resets: how many resets were timed.
    """

    env_id: str
    walls: int
    extra_walls: int
    make_seconds: float
    reset_seconds: float
    resets: int

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict."""
        return dict(vars(self))


def scenario_with_extra_walls(extra_walls: int, seed: int = 0) -> dict[str, Any]:
    """``beom_cho_lab`` as a scenario dict with ``extra_walls`` pieces of
    :data:`PIECE_LENGTH_M` at seeded random places just inside its top and bottom walls."""
    if extra_walls < 0:
        raise ValueError(f"argument 'extra_walls' must be >= 0, got {extra_walls}")
    scenario = tomllib.loads((BUILTIN_DIR / f"{ROOM_SCENARIO}.toml").read_text())
    (x_min, y_min), (x_max, y_max) = scenario["room"]["min"], scenario["room"]["max"]
    rng = np.random.default_rng(seed)
    starts = rng.uniform(x_min + 0.1, x_max - 0.1 - PIECE_LENGTH_M, size=extra_walls)
    pieces = [
        {
            "a": [float(x), y_max - PIECE_INSET_M if index % 2 else y_min + PIECE_INSET_M],
            "b": [
                float(x) + PIECE_LENGTH_M,
                y_max - PIECE_INSET_M if index % 2 else y_min + PIECE_INSET_M,
            ],
        }
        for index, x in enumerate(starts)
    ]
    scenario["walls"] = list(scenario.get("walls", [])) + pieces
    scenario["meta"]["name"] = f"{ROOM_SCENARIO}_plus_{extra_walls}_walls"
    return scenario


def room_reset(extra_walls: int = DEFAULT_EXTRA_WALLS, resets: int = DEFAULT_RESETS) -> RoomReset:
    """Time ``gym.make`` and ``resets`` resets of :data:`ROOM_ENV_ID` in the large room."""
    if resets < 1:
        raise ValueError(f"argument 'resets' must be >= 1, got {resets}")
    scenario = scenario_with_extra_walls(extra_walls)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "room.json"
        path.write_text(json.dumps(scenario))
        start = time.perf_counter()
        env = gym.make(ROOM_ENV_ID, scenario=str(path))
        made = time.perf_counter()
        try:
            for seed in range(resets):
                env.reset(seed=seed)
            reset_seconds = time.perf_counter() - made
        finally:
            env.close()
    return RoomReset(
        ROOM_ENV_ID, len(scenario["walls"]), extra_walls, made - start, reset_seconds, resets
    )
