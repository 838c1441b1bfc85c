"""A correction without a unique match writes its message when first read: the text, and the
result's equality, hash, copy, pickle and ``dataclasses`` views, are those of a result made with
the message written at once (Yamamoto et al., Fig. 2)."""

from __future__ import annotations

import copy
import dataclasses
import math
import pickle

import numpy as np
import pytest

from sonar_gym.localization.apcs import (
    AMBIGUOUS,
    MATCHED,
    NO_MATCH,
    CorrectionResult,
    DetectedWall,
    WallMap,
    WallVector,
    correct_with_detected_wall,
)
from sonar_gym.pose import Pose
from tests.localization.apcs_message_reference import unmatched_message_eager


def _room() -> WallMap:
    corners = [(0.0, 0.0), (0.0, 4.0), (6.0, 4.0), (6.0, 0.0)]
    walls = [WallVector(corners[i], corners[(i + 1) % 4], name=f"wall_{i}") for i in range(4)]
    walls += [WallVector((0.05, 0.0), (0.05, 3.0), name="twin"), WallVector((2.0, 1.0), (2.0, 1.5))]
    return WallMap(tuple(walls))


def _detected(rng: np.random.Generator, wall_map: WallMap) -> DetectedWall:
    """Along a map wall, nearly (every condition and both statuses in play), or anywhere."""
    if len(wall_map) and rng.random() < 0.6:
        wall = wall_map[int(rng.integers(len(wall_map)))]
        start = np.array(wall.start) + rng.normal(0.0, float(rng.choice([1e-4, 0.05])), 2)
        direction = np.array(wall.end) - np.array(wall.start)
        end = start + direction * rng.uniform(0.2, 0.9) + rng.normal(0.0, 1e-3, 2)
    else:
        start = rng.uniform(-1.0, 7.0, 2)
        end = start + rng.normal(0.0, 1.0, 2)
    return DetectedWall(tuple(start.tolist()), tuple(end.tolist()), (0, 1, 2, 3), 1e-6)


def test_the_message_of_an_unmatched_wall_is_the_message_written_at_once() -> None:
    rng = np.random.default_rng(20261207)
    covariance = np.diag([1e-2, 2e-2, math.radians(3.0) ** 2])
    statuses = set()
    for wall_map in (_room(), WallMap(())):
        for _ in range(2000):
            x, y = rng.uniform(0.5, 3.5, 2).tolist()
            pose = Pose(x, y, float(rng.uniform(-3.0, 3.0)))
            match, correction = correct_with_detected_wall(
                pose, covariance, _detected(rng, wall_map), wall_map, 1e-4, 1e-3
            )
            statuses.add(match.status)
            if match.matched:
                continue
            eager = CorrectionResult(
                match.status,
                None,
                unmatched_message_eager(match),
                covariance=correction.covariance,
                method=correction.method,
            )
            copied, pickled = copy.deepcopy(correction), pickle.loads(pickle.dumps(correction))
            assert hash(correction) == hash(eager)  # reads the message first
            for result in (correction, copied, pickled):
                assert result.message == eager.message
                assert result == eager and repr(result) == repr(eager)
                assert dataclasses.asdict(result)["message"] == eager.message
            assert correction.covariance is eager.covariance
    assert statuses == {MATCHED, AMBIGUOUS, NO_MATCH}


def test_a_deferred_message_is_written_once_and_stays_read_only() -> None:
    calls: list[None] = []

    def explain() -> str:
        calls.append(None)
        return "no map wall matches (0: orientation)"

    result = CorrectionResult.explained_when_read(NO_MATCH, explain, np.eye(3), "paper")
    assert calls == []
    assert result.message == result.message == "no map wall matches (0: orientation)"
    assert len(calls) == 1
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.message = "changed"  # type: ignore[misc]
    replaced = dataclasses.replace(result, status=AMBIGUOUS)
    assert (replaced.status, replaced.message) == (AMBIGUOUS, result.message)
    assert not result.ok and result.pose is None
