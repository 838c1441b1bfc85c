"""``sonar-gym reproduce beom-cho-map``: outcome of Beom & Cho's method by robot position."""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console

from sonar_gym.pose import Pose
from sonar_gym.scenario import load_scenario
from sonar_gym.sonar.rotating import RotatingSonar
from sonar_gym.world import World
from sonar_gym.train.reproduce import beom_cho_map
from sonar_gym.train.reproduce.beom_cho_map import (
    NO_INTERSECTION,
    NO_PAIR,
    NOT_VISIBLE,
    OUTCOMES,
    OUTSIDE_BOUNDS,
    WITHIN_BOUNDS,
    WRONG_POSE,
    outcome_of,
)


@pytest.mark.parametrize(
    ("status", "estimate", "expected"),
    [
        ("no_intersection", None, NO_INTERSECTION),
        ("no_pair", None, NO_PAIR),
        ("no_candidates", None, NO_PAIR),
        ("ok", Pose(1.01, 2.0, 0.01), WITHIN_BOUNDS),
        ("ok", Pose(1.05, 2.0, 0.0), OUTSIDE_BOUNDS),
        ("ok", Pose(1.0, 2.0, math.radians(3.0)), OUTSIDE_BOUNDS),
        ("ok", Pose(1.0, 2.2, 0.0), WRONG_POSE),
    ],
)
def test_outcome_of_a_localization(status: str, estimate: Pose | None, expected: str) -> None:
    assert outcome_of(status, estimate, Pose(1.0, 2.0, 0.0)) == expected


def _trial(pose: Pose, seed: int = 0) -> dict[str, str]:
    scenario = load_scenario("beom_cho_lab")
    world = World(scenario, temperature_c=20.0)
    probe = RotatingSonar.preset("polaroid-6500")
    return beom_cho_map.cell_outcomes(world, scenario, probe, pose, np.random.default_rng(seed))


def test_the_origin_of_table_ii_is_within_bounds_and_a_box_is_no_trial() -> None:
    assert set(_trial(Pose(0.0, 0.0, 0.3)).values()) == {WITHIN_BOUNDS}
    assert set(_trial(Pose(-1.25, -0.2, 0.0)).values()) == {""}  # inside the hexahedral object
    assert set(_trial(Pose(-2.3, 1.2, 0.0)).values()) == {NOT_VISIBLE}  # small beacon 5.4 m away


def test_on_the_line_through_the_beacons_no_pose_is_within_bounds() -> None:
    # between the beacons the two circles of eqs (8)-(9) touch: D of eq. (12) is about 0
    for seed, heading in enumerate((0.0, 1.0, 2.0, -2.0)):
        x = 1.8
        y = -1.5 + (x - 0.3) * (0.9 / 2.55)
        assert WITHIN_BOUNDS not in _trial(Pose(x, y, heading), seed).values()


def test_the_map_run_writes_a_plot_and_shares_that_add_up(tmp_path: Path) -> None:
    buffer = io.StringIO()
    numbers = beom_cho_map.run(tmp_path, Console(file=buffer, width=200), spacing_m=0.4)
    assert (tmp_path / "beom_cho_map.png").stat().st_size > 10_000
    saved = json.loads((tmp_path / "beom_cho_map.json").read_text())
    assert saved["trials"] == numbers["trials"] >= 20
    for shares in saved["shares"].values():
        assert set(shares) == set(OUTCOMES)
        assert sum(shares.values()) == pytest.approx(1.0)
    paper, aware = saved["shares"]["paper"], saved["shares"]["occlusion_aware"]
    assert paper[WITHIN_BOUNDS] >= 0.6
    assert aware[NO_PAIR] <= paper[NO_PAIR]
    assert "occlusion-aware retry" in buffer.getvalue()


def test_a_grid_finer_than_2_cm_is_refused() -> None:
    with pytest.raises(ValueError, match="spacing_m"):
        beom_cho_map.outcome_map(0, 0.01)
