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
        got_pose, got = ekf_update_unchecked(estimate, prior, fix, noise, joseph_form)
        want_pose, want = ekf_update_reference(estimate, prior, fix, noise, joseph_form)
        assert (got_pose.x, got_pose.y, got_pose.theta) == (
            want_pose.x,
            want_pose.y,
            want_pose.theta,
        )
        assert got.tobytes() == want.tobytes()  # signed zeros too
