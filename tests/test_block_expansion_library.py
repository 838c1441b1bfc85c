"""The library pieces of the BlockExpansion task: the d mapping, route and beacon features."""

from __future__ import annotations

import numpy as np

from sonar_gym.calibration_distances import (
    DECREASING_GAP_M,
    distances_to_fractions,
    fractions_to_distances,
)
from sonar_gym.kept import KeptValue
from sonar_gym.maps import CALIBRATED, SURVEYED, UNUSED, beacon_slot_features
from sonar_gym.routes import PAPER_ROUTE, ParabolicRoute, route_features

RANGE_M = (0.02, 0.8)


def test_free_fractions_map_linearly_onto_the_range_per_boundary() -> None:
    triples = fractions_to_distances(np.array([0.0, 0.5, 1.0, 0.25, 0.25, 0.75]), RANGE_M, "free")
    np.testing.assert_allclose(triples, [(0.02, 0.41, 0.8), (0.215, 0.215, 0.605)])


def test_decreasing_distances_keep_the_gap_and_round_trip() -> None:
    rng = np.random.default_rng(0)
    for _ in range(50):
        u = rng.uniform(0.0, 1.0, 3)
        ((d1, d2, d3),) = fractions_to_distances(u, RANGE_M, "decreasing")
        assert RANGE_M[0] <= d3 <= d2 - DECREASING_GAP_M + 1e-12
        assert d2 <= d1 - DECREASING_GAP_M + 1e-12 and d1 <= RANGE_M[1] + 1e-12
        back = distances_to_fractions(np.array([d1, d2, d3]), RANGE_M, "decreasing")
        np.testing.assert_allclose(back, u, atol=1e-9)


def test_route_features_scale_the_paper_route_into_the_map_frame() -> None:
    features = route_features(PAPER_ROUTE)
    start_y = PAPER_ROUTE.y_at(2.75)
    # Map frame: (p - (2.0, 1.0)) / (2.5, 2.0); curvature / 2 per m.
    expected = [(2.75 - 2.0) / 2.5, (start_y - 1.0) / 2.0, (0.55 - 2.0) / 2.5]
    np.testing.assert_allclose(features[:3], expected)
    np.testing.assert_allclose(features[4:], [(1.6 - 2.0) / 2.5, (1.45 - 1.0) / 2.0, -0.45])
    steep = route_features(ParabolicRoute(2.75, 0.55, (1.6, 1.45), -9.0))
    assert steep[-1] == -1.0


def test_beacon_slots_fill_the_given_beacons_then_mark_unused_slots() -> None:
    features = beacon_slot_features([(2.0, 1.0, 1.25), (9.0, -9.0, 0.0)], [SURVEYED, CALIBRATED], 4)
    slots = features.reshape(4, 4)
    np.testing.assert_array_equal(slots[0], [0.0, 0.0, 0.0, SURVEYED])
    np.testing.assert_array_equal(slots[1], [1.0, -1.0, -1.0, CALIBRATED])
    np.testing.assert_array_equal(slots[2:], [[0.0, 0.0, 0.0, UNUSED]] * 2)


def test_a_kept_value_is_remade_only_when_its_key_changes() -> None:
    kept: KeptValue[list[int]] = KeptValue()
    made: list[int] = []

    def make() -> list[int]:
        made.append(len(made))
        return [len(made)]

    first = kept.get(("A", (1.0, 2.0)), make)
    assert kept.get(("A", (1.0, 2.0)), make) is first  # equal content, not the same object
    second = kept.get(("A", (1.0, 2.5)), make)
    assert second is not first and made == [0, 1]
