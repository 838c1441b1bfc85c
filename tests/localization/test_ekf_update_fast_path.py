"""``ekf_update_unchecked`` on floats gives the bits of its original array form."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonar_gym.localization.ekf import ekf_update_unchecked
from sonar_gym.pose import Pose
from tests.localization.ekf_update_reference import ekf_update_reference


def _covariance(rng: np.random.Generator, size: int, kind: str) -> np.ndarray:
    """A symmetric ``size`` x ``size`` covariance: dense, diagonal, zero or rank-deficient."""
    if kind == "zero":
        return np.zeros((size, size))
    if kind == "diagonal":
        return np.diag(rng.uniform(0.0, 1e-2, size))
    factor = rng.normal(0.0, 0.05, (size, size if kind == "dense" else 1))
    matrix = factor @ factor.T
    return 0.5 * (matrix + matrix.T)


def _pose(rng: np.random.Generator) -> Pose:
    return Pose(*rng.uniform(-3.0, 3.0, 2), rng.uniform(-math.pi, math.pi))


@pytest.mark.parametrize("joseph_form", [False, True])
@pytest.mark.parametrize("rows", [3, 2])
def test_ekf_update_matches_reference_bit_for_bit(rows: int, joseph_form: bool) -> None:
    rng = np.random.default_rng(20 + rows + 10 * joseph_form)
    kinds = ("dense", "diagonal", "zero", "rank_one")
    for trial in range(1500):
        prior = _covariance(rng, 3, kinds[trial % 4])
        noise = _covariance(rng, rows, kinds[(trial // 4) % 4])
        estimate, fix = _pose(rng), _pose(rng)
        if trial % 7 == 0:  # heading innovations at the wrap
            fix = Pose(fix.x, fix.y, estimate.theta + math.pi)
        _assert_same_update(estimate, prior, fix, noise, joseph_form)


def _assert_same_update(
    estimate: Pose, prior: np.ndarray, fix: Pose, noise: np.ndarray, joseph_form: bool
) -> None:
    """The update gives the reference's pose and covariance bit for bit (signed zeros too)."""
    got_pose, got = ekf_update_unchecked(estimate, prior, fix, noise, joseph_form)
    want_pose, want = ekf_update_reference(estimate, prior, fix, noise, joseph_form)
    assert (got_pose.x, got_pose.y, got_pose.theta) == (want_pose.x, want_pose.y, want_pose.theta)
    assert got.tobytes() == want.tobytes()


def _layouts(prior: np.ndarray) -> list[np.ndarray]:
    """``prior`` in C order, in Fortran order and as a strided view."""
    padded = np.zeros((6, 6))
    padded[::2, ::2] = prior
    return [np.ascontiguousarray(prior), np.asfortranarray(prior), padded[::2, ::2]]


@pytest.mark.parametrize("joseph_form", [False, True])
def test_ekf_update_matches_reference_for_signed_zeros_and_layouts(joseph_form: bool) -> None:
    rng = np.random.default_rng(5 + joseph_form)
    for trial in range(400):
        factor = rng.normal(0.0, 0.05, (3, 3))
        prior = factor @ factor.T
        prior = 0.5 * (prior + prior.T)
        if trial % 3 == 0:  # zeros of either sign off the diagonal
            sign = -1.0 if trial % 2 else 1.0
            prior[0, 1] = prior[1, 0] = sign * 0.0
        if trial % 5 == 0:
            prior[1, 2] = prior[2, 1] = -0.0
        if trial % 11 == 0:  # entries of the smallest and largest magnitudes
            prior[0, 2] = prior[2, 0] = 5e-324 if trial % 2 else 1e300
        noise = np.diag(rng.uniform(1e-5, 1e-2, 3))
        if trial % 4 == 0:
            noise[0, 1] = noise[1, 0] = -0.0
        estimate, fix = _pose(rng), _pose(rng)
        for layout in _layouts(prior):
            _assert_same_update(estimate, layout, fix, noise, joseph_form)
