"""The records of APCS's wall handling built unchecked are those their constructors build: the
same fields, equality, representation and pickle (Yamamoto et al., Fig. 2)."""

from __future__ import annotations

import pickle

import numpy as np

from sonar_gym.apcs_route import WallDetection
from sonar_gym.localization.apcs import (
    CorrectionResult,
    DetectedWall,
    MatchResult,
    WallFit,
    match_wall,
)
from sonar_gym.localization.apcs_online import ClosedGroup, WallHandling
from sonar_gym.localization.apcs_walls import GROUP_OK, WallVector
from sonar_gym.pose import Pose


def _parts() -> tuple[DetectedWall, ClosedGroup, MatchResult, CorrectionResult]:
    wall = DetectedWall((1.0, 1.01), (1.2, 1.012), (0, 1, 2, 3), 1e-6)
    points = np.array([[1.0, 1.01], [1.1, 1.011], [1.15, 1.0115], [1.2, 1.012]])
    group = ClosedGroup(WallFit(GROUP_OK, (0, 1, 2, 3), 1e-6, wall), points)
    match = match_wall(wall, (WallVector((-1.0, 1.0), (10.0, 1.0)),))
    correction = CorrectionResult("ok", Pose(1.0, 0.0, 0.1), covariance=np.eye(3))
    return wall, group, match, correction


def _same(got: object, expected: object) -> None:
    assert type(got) is type(expected)
    assert vars(got).keys() == vars(expected).keys()  # the fields, in their order
    assert got == expected and repr(got) == repr(expected)
    assert pickle.dumps(got) == pickle.dumps(expected)


def test_an_unchecked_wall_handling_is_the_constructed_one() -> None:
    _, group, match, correction = _parts()
    before, after = Pose(1.0, 0.02, 0.1), Pose(1.0, 0.0, 0.1)
    fields = ("left", group, match, None, correction, before, after, 7)
    _same(WallHandling.unchecked(*fields), WallHandling(*fields))


def test_an_unchecked_wall_detection_is_the_constructed_one() -> None:
    wall, group, match, _ = _parts()
    before, after, truth = Pose(1.0, 0.02, 0.1), Pose(1.0, 0.0, 0.1), Pose(1.0, 0.0, 0.1)
    fields = (3, "right", wall, group.points, match, "distance", "ok", before, after, truth)
    _same(WallDetection.unchecked(*fields), WallDetection(*fields))
