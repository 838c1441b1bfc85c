"""The sonar's memory of the last sensor position's echo candidates: hits only on a true match.

Every check compares against a search made with the memory emptied, so a stale entry (another
position, robot, temperature, geometry or transducer) would show.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from sonar_gym.pose import Pose
from sonar_gym.sonar import pulse_echo
from sonar_gym.sonar.echoes import EchoCandidates
from sonar_gym.sonar.presets import polaroid_6500
from sonar_gym.sonar.rotating import RotatingSonar
from tests.sonar.worlds import beom_cho_room, cluttered_room

SONAR = RotatingSonar.preset("polaroid-6500")
FULL_PAN = (-math.pi, math.pi, math.radians(1.0))


def _fresh(sonar: RotatingSonar, world: object, pose: Pose) -> EchoCandidates:
    pulse_echo._LAST_CANDIDATES.clear()
    return sonar.candidates(world, pose, pose.position)  # type: ignore[arg-type]


def _assert_same(a: EchoCandidates, b: EchoCandidates) -> None:
    np.testing.assert_array_equal(a.path_lengths, b.path_lengths)
    np.testing.assert_array_equal(a.directions, b.directions)
    np.testing.assert_array_equal(a.amplitudes, b.amplitudes)


def test_a_second_pan_from_one_pose_reuses_the_candidates_and_reads_the_same() -> None:
    room, pose = cluttered_room(), Pose(1.2, 1.1, 0.3)
    pulse_echo._LAST_CANDIDATES.clear()
    first = SONAR.candidates(room, pose, pose.position)  # type: ignore[arg-type]
    assert SONAR.candidates(room, pose, pose.position) is first  # type: ignore[arg-type]
    calibrated = SONAR.with_assumed_speed(340.0)  # same transducer: the memory answers
    remembered = [
        sonar.pan(room, pose, *FULL_PAN, np.random.default_rng(5)) for sonar in (SONAR, calibrated)
    ]  # type: ignore[arg-type]
    for sonar, scan in zip((SONAR, calibrated), remembered, strict=True):
        pulse_echo._LAST_CANDIDATES.clear()
        fresh = sonar.pan(room, pose, *FULL_PAN, np.random.default_rng(5))  # type: ignore[arg-type]
        np.testing.assert_array_equal(scan.ranges, fresh.ranges)
        np.testing.assert_array_equal(scan.amplitudes, fresh.amplitudes)


@pytest.mark.parametrize(
    "change",
    ["position", "heading only", "temperature", "geometry", "transducer", "edge law"],
)
def test_the_memory_never_answers_for_another_situation(change: str) -> None:
    room, pose, sonar = cluttered_room(), Pose(1.2, 1.1, 0.3), SONAR
    if change == "temperature":  # edges heard, and the GTD edge echo depends on k
        sonar = RotatingSonar(polaroid_6500(time_varying_gain=False), edge_law="gtd")
    sonar.candidates(room, pose, pose.position)  # type: ignore[arg-type]
    if change == "position":
        pose = Pose(1.5, 0.9, 0.3)
    elif change == "heading only":  # same sensor position: the candidates must not change
        pose = Pose(1.2, 1.1, 2.0)
    elif change == "temperature":
        geometry = room.geometry
        room = dataclasses.replace(room, temperature_c=35.0)
        room.geometry = geometry  # the very same geometry object, only warmer air
    elif change == "geometry":
        room = beom_cho_room()
        pose = Pose(1.2, 1.1, 0.3)
    elif change == "transducer":
        sonar = RotatingSonar(polaroid_6500(time_varying_gain=False))
    elif change == "edge law":
        sonar = dataclasses.replace(sonar, edge_law="gtd")
    remembered = sonar.candidates(room, pose, pose.position)  # type: ignore[arg-type]
    _assert_same(remembered, _fresh(sonar, room, pose))


def test_remembered_candidates_are_read_only() -> None:
    room, pose = cluttered_room(), Pose(1.2, 1.1, 0.3)
    candidates = SONAR.candidates(room, pose, pose.position)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="read-only"):
        candidates.path_lengths[0] = 0.0
