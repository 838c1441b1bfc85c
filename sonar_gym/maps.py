"""Scenario-to-map conversions: what a localizer's map holds of a scenario.

Each conversion is a separate function, named after the map it builds.
"""

from __future__ import annotations

from sonar_gym.localization.apcs import WallVector
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


__all__ = ["map_wall_vectors"]
