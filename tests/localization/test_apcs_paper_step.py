"""The single maximum-likelihood step of Yamamoto et al. eqs (11)-(14) gives exactly the bits
of the form with ``np.diag``, ``np.eye`` and per-use trigonometry it replaced."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

from sonar_gym.localization import apcs_correction
from sonar_gym.localization.apcs_correction import (
    HEADING_DEGENERATE,
    NUMERICAL_FAILURE,
    PRIOR_ON_WALL_LINE,
    CorrectionResult,
    _paper_step,
    corrected_pose,
    observed_wall,
    validated_covariance,
)
from sonar_gym.localization.apcs_walls import WallVector
from sonar_gym.localization.result import OK
from sonar_gym.pose import Pose
from tests.localization import apcs_correction_reference
from tests.localization.apcs_correction_reference import (
    corrected_pose_copied,
    observe_wall_arrays,
    paper_step_arrays,
)


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


def _result_bits(result: CorrectionResult) -> bytes:
    covariance = result.covariance
    layout = (covariance.flags.writeable, covariance.flags.c_contiguous, covariance.dtype.str)
    pose = None if result.pose is None else result.pose.as_array().tobytes()
    fields = (result.status, pose, result.message, result.method)
    return pickle.dumps((fields, covariance.tobytes(), layout))


@pytest.mark.parametrize("method", ["paper", "linear"])
def test_corrected_pose_matches_the_copying_form(method: str) -> None:
    rng = np.random.default_rng(3)
    statuses = set()
    for _ in range(2000):
        prior, covariance, wall, r, xi, sigma_r, sigma_xi = _case(rng)
        if rng.random() < 0.05:
            covariance = covariance / np.abs(covariance).max() * 1e308  # overflows
        pose = Pose.from_array(prior)
        with np.errstate(all="ignore"):
            covariance = validated_covariance(covariance)
            covariance.setflags(write=False)
            case = (pose, covariance, wall, r, xi, sigma_r, sigma_xi)
            got = corrected_pose(*case, method=method)  # type: ignore[arg-type]
            expected = corrected_pose_copied(*case, method=method)  # type: ignore[arg-type]
        assert _result_bits(got) == _result_bits(expected)
        statuses.add(got.status)
    assert NUMERICAL_FAILURE in statuses and OK in statuses


def test_observed_wall_matches_the_array_form() -> None:
    rng = np.random.default_rng(5)
    walls = [WallVector((0.0, 0.0), (5.0, 0.0)), WallVector((1.0, -0.0), (1.0, 4.0))]
    walls += [WallVector((-0.0, 2.0), (-3.0, 2.0)), WallVector((1.0, 4.0), (1.0, -2.0))]
    poses = [Pose(0.5, 0.0, 0.0), Pose(1.0, 1.0, -math.pi), Pose(-0.0, 2.0, math.pi / 2)]
    for _ in range(5000):
        prior, _, wall, *_ = _case(rng)
        walls.append(wall)
        poses.append(Pose.from_array(prior))
    for wall, pose in zip(walls, poses[: len(walls)], strict=False):
        got, expected = observed_wall(wall, pose), observe_wall_arrays(wall, pose)
        assert pickle.dumps(got) == pickle.dumps(expected)
    for wall in walls[:4]:
        for pose in poses:
            got, expected = observed_wall(wall, pose), observe_wall_arrays(wall, pose)
            assert pickle.dumps(got) == pickle.dumps(expected)


@pytest.mark.parametrize(
    ("pose_values", "covariance_entry"),
    [
        ((1.0, 2.0, 0.5), math.inf),  # a finite pose, an overflowed covariance
        ((1.0, 2.0, 0.5), math.nan),
        ((1.0, math.inf, 0.5), 0.0),  # an overflowed pose, a finite covariance
        ((math.nan, 2.0, 0.5), 0.0),
        ((1.0, 2.0, -math.inf), 0.0),
        ((1.0, 2.0, 7.0), 0.0),  # finite: the heading wraps as Pose.from_array wraps it
        ((-0.0, 1e308, -math.pi), 0.0),
    ],
)
def test_corrected_pose_screens_a_step_as_the_copying_form(
    pose_values: tuple[float, float, float],
    covariance_entry: float,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Each non-finite value of a step's pose or covariance fails the correction alone."""

    def step(*_: object) -> tuple[str, np.ndarray, np.ndarray, str]:
        covariance = np.diag([1e-4, 2e-4, 3e-5])
        covariance[1, 2] = covariance_entry
        return OK, np.array(pose_values), covariance, ""

    monkeypatch.setattr(apcs_correction, "_paper_step", step)
    monkeypatch.setattr(apcs_correction_reference, "_paper_step", step)
    prior = validated_covariance(np.diag([0.01, 0.02, 0.003]))
    prior.setflags(write=False)
    case = (Pose(0.0, 0.0, 0.0), prior, WallVector((0.0, 1.0), (5.0, 1.0)), 1.0, 0.2, 1e-4, 1e-3)
    got = corrected_pose(*case)
    expected = corrected_pose_copied(*case)
    assert _result_bits(got) == _result_bits(expected)
    finite = all(map(math.isfinite, (*pose_values, covariance_entry)))
    assert got.status == (OK if finite else NUMERICAL_FAILURE)
