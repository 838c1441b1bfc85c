"""The start-pose test on floats answers as its array form, pose by pose."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.beacon_visibility import beacons_visible
from sonar_gym.pose import Pose
from sonar_gym.random_room import random_scenario
from sonar_gym.scenario import load_scenario
from sonar_gym.sonar.rotating import RotatingSonar
from sonar_gym.world import World
from tests.beacon_visibility_reference import reference_beacons_visible


@pytest.mark.parametrize("seed", range(3))
def test_beacons_visible_matches_the_array_form(seed: int) -> None:
    rng = np.random.default_rng(seed)
    scenarios = [load_scenario("beom_cho_lab"), *(random_scenario(rng) for _ in range(3))]
    sonar = RotatingSonar.preset("polaroid-6500")
    for scenario in scenarios:
        world = World(scenario)
        (x0, y0), (x1, y1) = scenario.bounds
        answers = []
        for _ in range(400):
            pose = Pose(
                float(rng.uniform(x0, x1)),
                float(rng.uniform(y0, y1)),
                float(rng.uniform(-math.pi, math.pi)),
            )
            answer = beacons_visible(world, sonar, pose)
            assert answer is reference_beacons_visible(world, sonar, pose)
            answers.append(answer)
        if scenario.name == "beom_cho_lab":
            assert any(answers) and not all(answers)
