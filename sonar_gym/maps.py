"""Scenario-to-map conversions: what a localizer's map holds of a scenario.

Each conversion is a separate function, named after the map it builds.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from sonar_gym.localization.apcs import WallVector
from sonar_gym.localization.apcs_online import nearest_facing_walls
from sonar_gym.scenario import Scenario


def map_wall_vectors(scenario: Scenario) -> tuple[WallVector, ...]:
    """The mapped flat surfaces of ``scenario`` as APCS wall vectors (sec. 4.1, Fig. 3).

    Each vector has the occupied side on its left:

    - the room's walls: the room is free inside, so its counter-clockwise edges are reversed;
    - free walls with ``mapped = true``: ``a -> b`` as listed, the convention of the scenario
      files (the occupied side of ``a -> b`` on the left, see ``apcs_corridor.toml``);
    - mapped boxes: their counter-clockwise edges as they are (the inside is occupied).

    Cylinders are not flat and unmapped objects are not in the map; neither appears.
    """
    vectors: list[WallVector] = []
    if scenario.room is not None:
        corners = scenario.room.corners
        for index in range(4):
            start, end = corners[(index + 1) % 4], corners[index]
            vectors.append(WallVector(start, end, name=f"room_{index}"))
    for index, wall in enumerate(scenario.walls):
        if wall.mapped:
            vectors.append(WallVector(wall.a, wall.b, name=f"wall_{index}"))
    for index, box in enumerate(scenario.boxes):
        if box.mapped:
            corners = box.corners
            for side in range(4):
                vectors.append(
                    WallVector(corners[side], corners[(side + 1) % 4], name=f"box_{index}_{side}")
                )
    return tuple(vectors)


def facing_wall_stretch(
    wall_map: Sequence[WallVector],
    origins: npt.ArrayLike,
    direction: npt.ArrayLike,
    spacing_m: float,
) -> tuple[float, float]:
    """How long and how far one mapped wall faces a row of points, looking along ``direction``.

    For each of ``origins`` (``(n, 2)``, metres in {W}, ``spacing_m`` apart along a line) the
    nearest wall vector the ray along ``direction`` meets face on is looked up
    (:func:`~sonar_gym.localization.apcs_online.nearest_facing_walls`).

    Returns:
        ``(longest_m, median_m)``: the longest run of consecutive points facing one wall, times
        ``spacing_m`` (metres), and the median distance to the walls met (metres; inf when no
        ray meets a wall).
    """
    wall_ids, distances = nearest_facing_walls(
        wall_map, origins, np.asarray(direction, dtype=np.float64)
    )
    seen = distances[wall_ids >= 0]
    median = float(np.median(seen)) if seen.size else math.inf
    return longest_run(wall_ids.tolist()) * spacing_m, median


def map_ahead_features(
    wall_map: Sequence[WallVector],
    leg_starts_x: Sequence[float] | npt.NDArray[np.floating[Any]],
    leg_length_m: float,
    centre_line_y: float,
    spacing_m: float,
    max_range_m: float,
) -> npt.NDArray[np.float64]:
    """``(n_legs, 4)``: per leg of a route along ``+x``, per side, how well a mapped wall faces it.

    Along leg ``i``'s centre line (``x`` from ``leg_starts_x[i]`` to ``leg_starts_x[i + 1]``,
    ``leg_length_m`` long, at ``y = centre_line_y``; metres in {W}), every ``spacing_m`` the
    nearest map vector facing the route on each side (left: ``+y``, right: ``-y``) is looked
    up (:func:`facing_wall_stretch`). Columns: left continuity, left distance, right
    continuity, right distance; continuity is the longest run of one vector over the leg's
    length, the distance its median over ``max_range_m``, each clipped to 1.
    """
    n_legs = len(leg_starts_x) - 1
    features = np.zeros((n_legs, 4))
    for leg in range(n_legs):
        xs = np.arange(leg_starts_x[leg], leg_starts_x[leg + 1], spacing_m)
        origins = np.column_stack([xs, np.full_like(xs, centre_line_y)])
        for side_index, sign in enumerate((1.0, -1.0)):
            longest_m, median_m = facing_wall_stretch(wall_map, origins, (0.0, sign), spacing_m)
            features[leg, 2 * side_index] = min(longest_m / leg_length_m, 1.0)
            features[leg, 2 * side_index + 1] = min(median_m / max_range_m, 1.0)
    return features


def longest_run(ids: Sequence[int]) -> int:
    """Length of the longest run of one non-negative id (negative ids break runs)."""
    longest = current = 0
    previous = -1
    for wall_id in ids:
        current = (
            current + 1 if wall_id == previous and wall_id >= 0 else (1 if wall_id >= 0 else 0)
        )
        previous = wall_id
        longest = max(longest, current)
    return longest


__all__ = ["facing_wall_stretch", "longest_run", "map_ahead_features", "map_wall_vectors"]
