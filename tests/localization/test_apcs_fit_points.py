"""The verdict of :func:`fit_group_points` on float glue has exactly the bits of the numpy-array
form it replaced and of its float-glue form before the compiled centroid (Yamamoto et al.
sec. 4.2.2-4.2.3, Fig. 6)."""

from __future__ import annotations

import pickle
import warnings

import numpy as np
import pytest

from sonar_gym.localization.apcs_walls import (
    DEFAULT_PARAMETERS,
    GROUP_OK,
    GROUP_TOO_MUCH_VARIANCE,
    GROUP_ZERO_LENGTH,
    APCSParameters,
    WallFit,
    fit_group_points,
)
from sonar_gym.pose import wrap_angles
from tests.localization.apcs_fit_reference import (
    fit_group_points_arrays,
    fit_group_points_numpy_glue,
    fit_group_points_two_sums,
)
from tests.localization.float_bits import canonical


def _bits(fit: WallFit) -> bytes:
    """Every field of the verdict, floats by their bits (``-0.0`` differs from ``0.0``)."""
    wall = fit.wall
    wall_fields = None
    if wall is not None:  # every attribute of the wall and of its segment, in order
        wall_fields = [
            (name, canonical(value))
            for owner in (wall, wall.vector)
            for name, value in owner.__dict__.items()
            if name != "_vector"
        ]
    return pickle.dumps((fit.status, fit.erp_indices, fit.residual_variance_m2, wall_fields))


def _group(rng: np.random.Generator, count: int) -> np.ndarray:
    """ERPs along a wall of any orientation, with noise of any scale and repeated points."""
    kind = rng.integers(5)
    angle = rng.uniform(-np.pi, np.pi)
    along = np.cumsum(rng.choice([0.0, 0.01, 0.05], size=count))
    noise = rng.normal(0.0, [0.0, 1e-6, 0.005, 0.02, 0.3][kind], size=(count, 2))
    points = rng.uniform(-50.0, 50.0, 2) + np.outer(along, [np.cos(angle), np.sin(angle)]) + noise
    if rng.random() < 0.05:
        points[:] = points[0]  # one point repeated: no extent
    if rng.random() < 0.05:
        points[:, rng.integers(2)] = -0.0  # on an axis, with signed zeros
    return points


def _check(members: np.ndarray, directions: np.ndarray | None, params: APCSParameters) -> str:
    indices = tuple(range(len(members)))
    expected = fit_group_points_arrays(members, directions, indices, params)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = fit_group_points(members, directions, indices, params)
    assert _bits(got) == _bits(expected), (members.tolist(), directions)
    glue = fit_group_points_numpy_glue(members, directions, indices, params)
    assert _bits(got) == _bits(glue), (members.tolist(), directions)
    two_sums = fit_group_points_two_sums(members, directions, indices, params)
    assert _bits(got) == _bits(two_sums), (members.tolist(), directions)
    return got.status


@pytest.mark.parametrize("with_directions", [True, False])
def test_fit_group_points_matches_the_array_form_on_random_groups(with_directions: bool) -> None:
    rng = np.random.default_rng(20261203)
    loose = APCSParameters(variance_threshold_m2=1.0)
    statuses = set()
    for _ in range(3000):
        members = _group(rng, int(rng.integers(4, 20)))
        directions = wrap_angles(rng.uniform(-4.0, 4.0, len(members))) if with_directions else None
        params = loose if rng.random() < 0.5 else DEFAULT_PARAMETERS
        statuses.add(_check(members, directions, params))
    assert statuses == {GROUP_OK, GROUP_TOO_MUCH_VARIANCE, GROUP_ZERO_LENGTH}


@pytest.mark.parametrize(
    "members",
    [
        np.zeros((4, 2)),
        np.full((5, 2), -0.0),
        np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]]),
        np.array([[0.0, 0.0], [0.0, 1.0], [0.0, 2.0], [0.0, 3.0]]),
        np.array([[0.0, 3.0], [0.0, 2.0], [0.0, 1.0], [0.0, 0.0]]),
        np.array([[1e-300, 0.0], [2e-300, 0.0], [3e-300, 0.0], [4e-300, 1e-300]]),
        np.array([[1e150, 0.0], [2e150, 1.0], [3e150, 0.0], [4e150, 1.0]]),
        np.array([[0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 0.0]]),
    ],
)
@pytest.mark.parametrize("directions", [None, np.full(8, np.pi / 2), np.zeros(8)])
def test_fit_group_points_matches_the_array_form_on_edge_groups(
    members: np.ndarray, directions: np.ndarray | None
) -> None:
    _check(members, None if directions is None else directions[: len(members)], DEFAULT_PARAMETERS)


def test_fit_group_points_goes_through_eigh_on_an_overflowing_group() -> None:
    members = np.array([[1e200, 0.0], [-1e200, 0.0], [1e200, 1.0], [-1e200, 1.0]])
    indices = (0, 1, 2, 3)
    with warnings.catch_warnings(record=True) as expected_warnings:
        warnings.simplefilter("always")
        expected = fit_group_points_arrays(members, None, indices)
    with warnings.catch_warnings(record=True) as got_warnings:
        warnings.simplefilter("always")
        got = fit_group_points(members, None, indices)
    assert _bits(got) == _bits(expected)
    assert [str(w.message) for w in got_warnings] == [str(w.message) for w in expected_warnings]


def test_one_reduction_along_the_rows_sums_each_row_as_its_own_reduction() -> None:
    """The fit sums the cosines and the sines of a group's directions as one ``(2, n)``
    reduction along the rows: each sum has the bits of ``np.add.reduce`` of that row alone
    (numpy's pairwise summation, for short and long groups)."""
    rng = np.random.default_rng(20261207)
    for _ in range(20000):
        count = int(rng.integers(1, 140))
        directions = rng.uniform(-4.0, 4.0, count) * 10.0 ** float(rng.integers(-6, 2))
        trig = np.empty((2, count))
        np.cos(directions, out=trig[0])
        np.sin(directions, out=trig[1])
        rows = np.add.reduce(trig, axis=1)
        separate = np.array([np.add.reduce(np.cos(directions)), np.add.reduce(np.sin(directions))])
        assert rows.tobytes() == separate.tobytes(), directions.tolist()
