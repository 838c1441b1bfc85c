"""The compiled echo search (:func:`~sonar_gym.sonar.kernels.audible_candidates`, then
:func:`~sonar_gym.sonar.kernels.clear_nearest_first`) against the numpy steps it replaced
(:mod:`tests.sonar.echo_candidates_reference`): the same candidates, bit for bit, over every
built-in scenario and a cluttered room, at random positions (inside obstacles and outside the
room too), with and without air absorption, receiver gain and footprint, both edge laws."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from sonar_gym.scenario import load_scenario
from sonar_gym.sonar.echoes import EchoCandidates, echo_candidates
from sonar_gym.sonar.presets import preset
from sonar_gym.world import World
from tests.sonar.echo_candidates_reference import echo_candidates_reference
from tests.sonar.worlds import cluttered_room

SCENARIOS = ("beom_cho_lab", "kim_arena", "apcs_corridor", "roh_beacons", "wu_tsai_room")


def _assert_same(got: EchoCandidates, want: EchoCandidates) -> None:
    for name in ("position", "directions", "path_lengths", "amplitudes", "kinds"):
        a, b = getattr(got, name), getattr(want, name)
        assert a.dtype == b.dtype and a.shape == b.shape, name
        assert np.array_equal(a, b, equal_nan=True), name
    assert np.array_equal(got._primitive_indices, want._primitive_indices)
    assert np.array_equal(got._concave, want._concave)
    assert got.threshold == want.threshold


def _options(rng: np.random.Generator) -> dict[str, Any]:
    """Search options drawn at random: every branch of the search, and its presets' values."""
    transducer = preset(str(rng.choice(["srf04", "polaroid-6500", "ma40b8"])))
    options: dict[str, Any] = {
        "wavenumber": float(rng.uniform(300.0, 1000.0)),
        "absorption_db_per_m": float(rng.choice([0.0, transducer.absorption_db_per_m, 2.5])),
        "min_range_m": float(rng.choice([0.0, transducer.min_range_m, 0.3])),
        "detection_threshold": float(rng.choice([0.0, transducer.detection_threshold, 0.5])),
        "edge_law": str(rng.choice(["weak", "gtd"])),
        "receiver_gain": transducer.time_varying_gain if rng.random() < 0.5 else None,
    }
    if rng.random() < 0.8:
        options["footprint_center"] = tuple(rng.uniform(-0.3, 0.3, 2))
        options["footprint_radius_m"] = float(rng.choice([0.0, 0.1, 0.25, 1.0]))
    return options


def assert_search_finds_what(
    reference: Callable[..., EchoCandidates],
    world_name: str,
    seed: int,
    assert_same: Callable[[EchoCandidates, EchoCandidates], None] = _assert_same,
) -> None:
    """:func:`echo_candidates` against ``reference`` at 150 random positions in and around the
    world, each with random options (:func:`_options`), compared by ``assert_same``."""
    rng = np.random.default_rng(seed)
    world: Any = (
        cluttered_room() if world_name == "cluttered_room" else World(load_scenario(world_name))
    )
    geometry = world.geometry
    low = geometry.segment_starts.min(axis=0) - 0.5
    high = geometry.segment_starts.max(axis=0) + 0.5
    found = 0
    for _ in range(150):
        position = rng.uniform(low, high)
        options = _options(rng)
        if "footprint_center" in options and rng.random() < 0.7:
            # the robot's body around the sensor, as the sonars search
            offset = rng.uniform(-0.1, 0.1, 2)
            options["footprint_center"] = (position[0] + offset[0], position[1] + offset[1])
        got = echo_candidates(geometry, position, **options)
        want = reference(geometry, position, **options)
        assert_same(got, want)
        found += len(want)
    assert found > 0


@pytest.mark.parametrize("world_name", [*SCENARIOS, "cluttered_room"])
def test_compiled_echo_search_finds_what_the_numpy_steps_find(world_name: str) -> None:
    assert_search_finds_what(echo_candidates_reference, world_name, 23)


def test_compiled_echo_search_at_vertices_and_on_walls() -> None:
    """Edge positions: exactly on segment ends and on walls, where tests sit on their bounds."""
    world = World(load_scenario("kim_arena"))
    geometry = world.geometry
    starts, ends = geometry.segment_starts, geometry.segment_ends
    positions = [*starts, *ends, *((starts + ends) / 2.0), *(0.25 * starts + 0.75 * ends)]
    rng = np.random.default_rng(5)
    for position in positions:
        options = _options(rng)
        _assert_same(
            echo_candidates(geometry, position, **options),
            echo_candidates_reference(geometry, position, **options),
        )
