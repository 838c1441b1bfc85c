"""The single maximum-likelihood step of Yamamoto et al. eqs (11)-(14) gives exactly the bits
of the form with ``np.diag``, ``np.eye`` and per-use trigonometry it replaced."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

from sonar_gym.localization.apcs_correction import (
    HEADING_DEGENERATE,
    PRIOR_ON_WALL_LINE,
    _paper_step,
)
from sonar_gym.localization.apcs_walls import WallVector
from sonar_gym.localization.result import OK
from tests.localization.apcs_correction_reference import paper_step_arrays


def _case(rng: np.random.Generator) -> tuple:
    """A prior near a wall of any orientation, a positive definite covariance and a reading."""
    start = rng.uniform(-20.0, 20.0, 2)
    angle = rng.uniform(-math.pi, math.pi)
    end = start + rng.uniform(0.1, 10.0) * np.array([math.cos(angle), math.sin(angle)])
    wall = WallVector(tuple(start), tuple(end))
    normal = np.array([math.sin(angle), -math.cos(angle)])
    kind = rng.integers(4)
    offset = [rng.uniform(0.05, 3.0), 0.0, rng.uniform(-3.0, 3.0), 1e-10][kind]
    position = start + rng.uniform(-1.0, 2.0) * (end - start) + offset * normal
    theta = rng.uniform(-math.pi, math.pi)
    prior = np.array([position[0], position[1], theta])
    root = rng.normal(0.0, rng.choice([1e-4, 0.05, 1.0]), (3, 3))
    covariance = root @ root.T + np.diag(rng.uniform(1e-8, 0.1, 3))
    r = rng.uniform(0.05, 3.0)
    xi = rng.uniform(-math.pi, math.pi) if rng.random() < 0.8 else -math.pi / 2
    if rng.random() < 0.1:
        xi = angle - theta  # theta + xi along the wall
    sigma_r, sigma_xi = rng.uniform(1e-6, 0.1, 2)
    return prior, covariance, wall, r, xi, float(sigma_r), float(sigma_xi)


def _bits(step: tuple) -> bytes:
    status, corrected, covariance, message = step
    return pickle.dumps((status, corrected.tobytes(), covariance.tobytes(), message))


def test_paper_step_matches_the_array_form_on_random_corrections() -> None:
    rng = np.random.default_rng(20261203)
    statuses = set()
    for _ in range(5000):
        case = _case(rng)
        got = _paper_step(*case)
        assert _bits(got) == _bits(paper_step_arrays(*case)), case
        statuses.add(got[0])
    assert statuses == {OK, PRIOR_ON_WALL_LINE, HEADING_DEGENERATE}


@pytest.mark.parametrize("theta", [0.0, -0.0, math.pi, -math.pi / 2, 1e-300])
@pytest.mark.parametrize("xi", [0.0, math.pi / 2, -math.pi / 2, math.pi])
def test_paper_step_matches_the_array_form_on_axis_walls(theta: float, xi: float) -> None:
    covariance = np.diag([0.01, 0.02, 0.003])
    for wall in (WallVector((0.0, 0.0), (5.0, 0.0)), WallVector((1.0, -2.0), (1.0, 4.0))):
        for position in ((0.5, 1.0), (0.5, -0.0), (1.0, 0.5), (-2.0, 3.0)):
            case = (np.array([*position, theta]), covariance, wall, 1.0, xi, 1e-4, 1e-3)
            assert _bits(_paper_step(*case)) == _bits(paper_step_arrays(*case))
