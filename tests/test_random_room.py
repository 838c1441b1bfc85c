"""Random rooms: determinism, validity, beacon placement and visibility."""

from __future__ import annotations

import re

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.random_room import (
    LARGE_BEACON_RADIUS_M,
    SMALL_BEACON_RADIUS_M,
    random_scenario,
    visibility_fraction,
)
from sonar_gym.scenario import RobotSpec
from sonar_gym.world import World


def test_same_seed_gives_an_equal_scenario() -> None:
    a = random_scenario(np.random.default_rng(123))
    b = random_scenario(np.random.default_rng(123))
    assert a == b
    assert random_scenario(np.random.default_rng(124)) != a


def test_scenarios_are_plain_python_floats() -> None:
    scenario = random_scenario(np.random.default_rng(1))
    assert scenario.room is not None
    assert all(type(v) is float for v in scenario.room.min + scenario.room.max)
    assert all(type(v) is float for c in scenario.cylinders for v in (*c.center, c.radius))


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_random_rooms_respect_their_parameters(seed: int) -> None:
    scenario = random_scenario(np.random.default_rng(seed))
    assert scenario.room is not None
    width, height = scenario.room.size
    assert 4.0 <= width <= 7.0 and 3.5 <= height <= 6.0
    assert scenario.room.min == (-width / 2, -height / 2)
    assert len(scenario.boxes) <= 6
    clutter = [c for c in scenario.cylinders if c.role == "clutter"]
    assert len(clutter) <= 4
    assert all(0.02 <= c.radius <= 0.05 for c in clutter)
    small, large = scenario.beacon("small_beacon"), scenario.beacon("large_beacon")
    assert small.radius == pytest.approx(0.0382 / 2) and large.radius == pytest.approx(0.14 / 2)
    assert math.dist(small.center, large.center) >= 1.5
    for box in scenario.boxes:
        for corner in box.corners:
            assert scenario.room.min[0] <= corner[0] <= scenario.room.max[0]
            assert scenario.room.min[1] <= corner[1] <= scenario.room.max[1]
    without_cylinders = World(replace(scenario, cylinders=()))
    for cylinder in scenario.cylinders:  # no cylinder touches a box or a wall
        assert without_cylinders.is_free(cylinder.center, radius=cylinder.radius)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_both_beacons_are_visible_from_most_free_poses(seed: int) -> None:
    """An independent estimate with many more poses than the generator used."""
    scenario = random_scenario(np.random.default_rng(seed))
    fraction = visibility_fraction(scenario, np.random.default_rng(10_000 + seed), n_samples=600)
    # The generator accepts on 100 poses at >= 0.7; allow the sampling error of that check.
    assert fraction >= 0.6


def test_visibility_fraction_counts_occlusion() -> None:
    from sonar_gym.scenario import scenario_from_dict

    open_room = scenario_from_dict(
        {
            "room": {"min": [-2, -2], "max": [2, 2]},
            "cylinders": [
                {"center": [-1.0, 0.0], "radius": SMALL_BEACON_RADIUS_M, "role": "small_beacon"},
                {"center": [1.0, 0.0], "radius": LARGE_BEACON_RADIUS_M, "role": "large_beacon"},
            ],
        }
    )
    walled = scenario_from_dict(
        {
            "room": {"min": [-2, -2], "max": [2, 2]},
            "walls": [{"a": [0, -2], "b": [0, 2]}],
            "cylinders": [
                {"center": [-1.0, 0.0], "radius": SMALL_BEACON_RADIUS_M, "role": "small_beacon"},
                {"center": [1.0, 0.0], "radius": LARGE_BEACON_RADIUS_M, "role": "large_beacon"},
            ],
        }
    )
    # In a 4 m room everything is within 4 m: nearly every pose sees both beacons.
    assert visibility_fraction(open_room, np.random.default_rng(0), 300) > 0.9
    # A wall splitting the room hides one beacon from every pose.
    assert visibility_fraction(walled, np.random.default_rng(0), 300) == 0.0


def test_generator_parameters_are_honoured() -> None:
    scenario = random_scenario(
        np.random.default_rng(5),
        size_range=((5.0, 5.0), (4.0, 4.0)),
        n_boxes=(0, 0),
        n_clutter_cylinders=(3, 3),
        robot=RobotSpec(radius=0.2),
        name="fixed",
    )
    assert scenario.room is not None and scenario.room.size == pytest.approx((5.0, 4.0))
    assert scenario.boxes == ()
    assert sum(c.role == "clutter" for c in scenario.cylinders) == 3
    assert scenario.robot.radius == 0.2 and scenario.name == "fixed"


@pytest.mark.parametrize(
    ("kwargs", "argument"),
    [
        ({"size_range": ((4.0, 3.0), (3.5, 6.0))}, "size_range"),
        ({"size_range": (4.0, 7.0)}, "size_range"),
        ({"n_boxes": (3, 1)}, "n_boxes"),
        ({"n_clutter_cylinders": (-1, 2)}, "n_clutter_cylinders"),
        ({"clutter_radius_range_m": (0.0, 0.05)}, "clutter_radius_range_m"),
        ({"beacon_separation_min_m": -1.0}, "beacon_separation_min_m"),
        ({"visibility_min_fraction": 1.5}, "visibility_min_fraction"),
        ({"n_visibility_samples": 0}, "n_visibility_samples"),
        ({"sensor_min_range_m": 5.0}, "sensor_min_range_m"),
    ],
)
def test_bad_arguments_name_themselves(kwargs: dict, argument: str) -> None:
    with pytest.raises(ValueError, match=argument):
        random_scenario(np.random.default_rng(0), **kwargs)


def test_rng_must_be_a_generator() -> None:
    with pytest.raises(ValueError, match="rng"):
        random_scenario(0)  # type: ignore[arg-type]


def test_impossible_requests_fail_clearly() -> None:
    with pytest.raises(RuntimeError, match="random_scenario"):
        random_scenario(np.random.default_rng(0), beacon_separation_min_m=20.0, max_rooms=2)


@pytest.mark.parametrize(
    ("kwargs", "argument"),
    [
        ({"clutter_radius_range_m": (5e-324, 0.05)}, "clutter_radius_range_m[0]"),
        ({"clutter_radius_range_m": (-0.0, 0.05)}, "clutter_radius_range_m[0]"),
        ({"beacon_separation_min_m": 10**400}, "beacon_separation_min_m"),
        ({"visibility_min_fraction": float("nan")}, "visibility_min_fraction"),
        ({"sensor_max_range_m": 10**400}, "sensor_max_range_m"),
        ({"n_boxes": (1, 2.0)}, "n_boxes[1]"),
    ],
)
def test_denormal_overflowing_and_non_integer_arguments_name_themselves(
    kwargs: dict, argument: str
) -> None:
    with pytest.raises(ValueError, match=re.escape(argument)):
        random_scenario(np.random.default_rng(0), **kwargs)


def test_numpy_integers_and_lists_are_accepted() -> None:
    scenario = random_scenario(
        np.random.default_rng(0),
        size_range=[[4.0, 5.0], [4.0, 5.0]],
        n_boxes=(np.int64(1), np.int64(2)),
    )
    assert scenario.has_beacons()
