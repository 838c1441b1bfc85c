"""Observation features: layouts tile the vector, values stay in their declared ranges."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import sonar_gym  # noqa: F401  (registers the ids)
from sonar_gym.envs.base import unwrap_sonar_env
from sonar_gym.envs.features import (
    FEATURE_TYPES,
    Feature,
    Flag,
    Heading,
    ObservationSpec,
    RangeBins,
    ScaledPosition,
    ScannedBins,
)
from sonar_gym.registration import REGISTRATIONS

VARIANTS = [(env_id, {}) for env_id in REGISTRATIONS] + [
    ("SonarGym/BlockExpansion-v0", {"n_areas": 3}),
    ("SonarGym/BeaconScan-v0", {"n_range_bins": 36}),
    ("SonarGym/SweepLocalization-v0", {"n_range_bins": 7}),
]


def spec_of(env: gym.Env) -> ObservationSpec:
    spec = unwrap_sonar_env(env).observation_spec
    assert isinstance(spec, ObservationSpec)
    return spec


@pytest.mark.parametrize(("env_id", "kwargs"), VARIANTS)
def test_the_layout_tiles_the_observation_vector(env_id: str, kwargs: dict) -> None:
    env = gym.make(env_id, **kwargs)
    spec = spec_of(env)
    layout = unwrap_sonar_env(env).observation_layout
    assert layout == spec.layout
    covered = np.zeros(env.observation_space.shape[0], dtype=int)
    for place in layout.values():
        assert place.step is None and 0 <= place.start < place.stop
        covered[place] += 1
    assert covered.tolist() == [1] * len(covered)
    assert env.observation_space == spec.space


@pytest.mark.parametrize(("env_id", "kwargs"), VARIANTS)
def test_every_feature_stays_in_its_range_over_random_episodes(env_id: str, kwargs: dict) -> None:
    env = gym.make(env_id, **kwargs)
    spec = spec_of(env)
    low, high = spec.feature_bounds()
    for seed in range(3):
        env.action_space.seed(seed)
        observation, _ = env.reset(seed=seed)
        observations = [observation]
        done = False
        while not done:
            observation, _, terminated, truncated, _ = env.step(env.action_space.sample())
            observations.append(observation)
            done = terminated or truncated
        stacked = np.stack(observations)
        outside = (stacked < low) | (stacked > high)
        names = [f.name for f in spec.features for _ in range(f.size)]
        assert not outside.any(), sorted({names[i] for i in np.nonzero(outside)[1]})
        for feature in spec.features:
            if isinstance(feature, Flag):
                values = stacked[:, spec.layout[feature.name]]
                assert set(np.unique(values).tolist()) <= {0.0, 1.0}, feature.name


room_coordinate = st.floats(-50, 50, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(
    st.tuples(room_coordinate, room_coordinate),
    st.tuples(st.floats(0.01, 40), st.floats(0.01, 40)),
    st.tuples(st.floats(-1e6, 1e6), st.floats(-1e6, 1e6)),
)
def test_a_scaled_position_stays_in_minus_one_one(corner, size, position) -> None:
    low = np.array(corner)
    high = low + np.array(size)
    values = ScaledPosition.values(position, low, high)
    assert values.shape == (2,) and np.all(np.abs(values) <= 1.0)
    centred = ScaledPosition.centred_values(position, (low + high) / 2, (high - low) / 2)
    assert np.all(np.abs(centred) <= 1.0)
    # the corners map to the ends, the centre to 0
    np.testing.assert_allclose(ScaledPosition.values(low, low, high), [-1.0, -1.0])
    np.testing.assert_allclose(ScaledPosition.values(high, low, high), [1.0, 1.0])
    np.testing.assert_allclose(ScaledPosition.values((low + high) / 2, low, high), 0, atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(
    st.tuples(room_coordinate, room_coordinate),
    st.tuples(st.floats(0.01, 40), st.floats(0.01, 40)),
    st.tuples(st.floats(-1e6, 1e6) | st.just(math.nan), st.integers(-100, 100)),
    st.sampled_from(["tuple", "array", "list"]),
)
def test_a_scaled_position_is_the_array_formula_bit_for_bit(corner, size, position, form) -> None:
    low = np.array(corner)
    high = low + np.array(size)
    expected = np.clip(
        2.0 * (np.asarray(position, dtype=np.float64) - low) / (high - low) - 1.0, -1.0, 1.0
    )
    given_position = {"tuple": tuple(position), "array": np.array(position), "list": list(position)}
    values = ScaledPosition.values(given_position[form], tuple(low.tolist()), high)
    assert values.dtype == np.float64 and values.tobytes() == expected.tobytes()


@settings(max_examples=100, deadline=None)
@given(st.floats(-1e6, 1e6))
def test_a_heading_is_a_unit_vector(angle: float) -> None:
    cos_value, sin_value = Heading.values(angle)
    assert abs(cos_value) <= 1.0 and abs(sin_value) <= 1.0
    assert math.isclose(math.hypot(cos_value, sin_value), 1.0, rel_tol=1e-12)


def nearest_per_bin_reference(fractions: np.ndarray, n_bins: int) -> list[float]:
    """Bin ``i * n // m`` of ping ``i``, the nearest finite fraction clipped to [0, 1], else 1."""
    bins = [1.0] * n_bins
    for index, value in enumerate(fractions.tolist()):
        if math.isfinite(value):
            b = index * n_bins // len(fractions)
            bins[b] = min(bins[b], min(max(value, 0.0), 1.0))
    return bins


@settings(max_examples=200, deadline=None)
@given(
    st.integers(1, 24),
    arrays(
        np.float64,
        st.integers(0, 100),
        elements=st.floats(-2, 5) | st.just(math.nan) | st.just(math.inf) | st.just(-math.inf),
    ),
)
def test_range_bins_hold_the_nearest_range_per_bin_in_zero_one(n_bins, fractions) -> None:
    feature = RangeBins("ranges", n_bins)
    values = feature.values(fractions)
    assert values.shape == (n_bins,)
    assert np.all((values >= 0.0) & (values <= 1.0))
    expected = nearest_per_bin_reference(fractions, n_bins) if fractions.size else [1.0] * n_bins
    assert values.tolist() == expected
    assert feature.values(None).tolist() == [1.0] * n_bins


@settings(max_examples=100, deadline=None)
@given(st.integers(1, 12), st.integers(1, 8), st.data())
def test_scanned_bins_mark_every_bin_with_a_scanned_slot(n_bins, per_bin, data) -> None:
    scanned = np.array(
        data.draw(st.lists(st.booleans(), min_size=n_bins * per_bin, max_size=n_bins * per_bin))
    )
    values = ScannedBins("scanned", n_bins).values(scanned)
    assert values.tolist() == [
        bool(scanned[b * per_bin : (b + 1) * per_bin].any()) for b in range(n_bins)
    ]


def test_scanned_bins_refuse_slots_that_do_not_divide_into_the_bins() -> None:
    with pytest.raises(ValueError, match="multiple of 4"):
        ScannedBins("scanned", 4).values(np.zeros(10, dtype=bool))


def test_a_spec_lays_features_out_in_order_and_builds_the_symmetric_box() -> None:
    spec = ObservationSpec([Feature("a", 3), Flag("b"), Heading("c")])
    assert spec.layout == {"a": slice(0, 3), "b": slice(3, 4), "c": slice(4, 6)}
    assert spec.space == gym.spaces.Box(-1.0, 1.0, shape=(6,), dtype=np.float32)
    writer = spec.writer()
    writer["c"] = Heading.values(0.0)
    writer.one_hot("a", 2)
    assert writer.vector.tolist() == [0, 0, 1, 0, 1, 0]
    assert writer.vector.dtype == np.float32
    with pytest.raises(IndexError, match="'a'"):
        writer.one_hot("a", 3)
    extended = spec.extended([Flag("d")])
    assert extended.layout["d"] == slice(6, 7) and spec.size == 6


@pytest.mark.parametrize(
    ("features", "match"),
    [
        ([], "at least one"),
        ([Flag("a"), Flag("a")], "repeats"),
    ],
)
def test_a_bad_spec_says_what_is_wrong(features, match) -> None:
    with pytest.raises(ValueError, match=match):
        ObservationSpec(features)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"name": ""}, "name"),
        ({"name": "a", "size": 0}, "size"),
        ({"name": "a", "low": -2.0}, "low"),
        ({"name": "a", "low": 0.5, "high": 0.1}, "low"),
    ],
)
def test_a_bad_feature_names_the_field(kwargs, field) -> None:
    with pytest.raises(ValueError, match=field):
        Feature(**kwargs)


def test_the_feature_types_are_registered_by_their_kind() -> None:
    assert {kind: cls.kind for kind, cls in FEATURE_TYPES.items()} == {
        kind: kind for kind in FEATURE_TYPES
    }
    assert {"scaled_position", "heading", "range_bins", "scanned_bins"} <= set(FEATURE_TYPES)


def test_a_run_of_consecutive_features_is_filled_at_once() -> None:
    spec = ObservationSpec([Feature("a", 2), Feature("b"), Feature("c", 3)])
    run = spec.run(("b", "c"))
    assert run == slice(2, 6)
    observation = spec.writer()
    observation.write_run(run, [0.25, -0.5, 0.5, 1.0])
    assert observation.vector.tolist() == [0.0, 0.0, 0.25, -0.5, 0.5, 1.0]
    with pytest.raises(ValueError, match="a run of 4 entries got 3 values"):
        observation.write_run(run, [0.0] * 3)


@pytest.mark.parametrize(
    ("names", "message"),
    [
        (("a", "c"), "'c' does not follow 'a'"),
        (("c", "b"), "'b' does not follow 'c'"),
        (("b", "z"), r"names no feature of this spec: \['z'\]"),
        ((), "at least one feature"),
    ],
)
def test_a_run_must_name_consecutive_features(names: tuple[str, ...], message: str) -> None:
    spec = ObservationSpec([Feature("a", 2), Feature("b"), Feature("c", 3)])
    with pytest.raises(ValueError, match=message):
        spec.run(names)
