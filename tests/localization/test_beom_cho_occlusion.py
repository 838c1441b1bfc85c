"""Occlusion-aware RCDs beside Beom & Cho: cut beacons rebuilt, merged ones split, roles kept."""

from __future__ import annotations

import ast
import importlib
import math
from pathlib import Path

import numpy as np
import pytest

from sonar_gym.localization.beom_cho import (
    RCD,
    BeomChoParameters,
    extract_rcds,
    filter_beacon_candidates,
    localize_rcds,
    localize_scan,
)
from sonar_gym.localization.beom_cho_occlusion import occlusion_aware_rcds, split_at_other_objects
from sonar_gym.pose import Pose
from sonar_gym.scenario import load_scenario
from sonar_gym.sonar.scan import Scan

EPS_M = 0.02
EXTENTS_RAD = (math.radians(22.0), math.radians(24.0))
MIN_VISIBLE_RAD = math.radians(5.0)
FULL_PAN_DEG = np.arange(-180.0, 180.0, 1.0)


def _pan(segments: list[tuple[float, float, float]]) -> tuple[np.ndarray, np.ndarray]:
    """A full 1-deg pan: NaN everywhere but ``(first_deg, last_deg, range_m)`` segments, later
    ones on top."""
    ranges = np.full(len(FULL_PAN_DEG), np.nan)
    for first, last, range_m in segments:
        ranges[(first <= FULL_PAN_DEG) & (last >= FULL_PAN_DEG)] = range_m
    return np.radians(FULL_PAN_DEG), ranges


def _rebuild(angles: np.ndarray, ranges: np.ndarray) -> list[RCD]:
    return occlusion_aware_rcds(angles, ranges, EPS_M, EXTENTS_RAD, MIN_VISIBLE_RAD)


def test_a_beacon_cut_by_a_nearer_wall_fails_the_papers_filter_but_is_rebuilt() -> None:
    # small beacon at 2.205 m from -11 to +11 deg; a wall 2.2 cm nearer takes over from +7 deg
    angles, ranges = _pan([(-11.0, 11.0, 2.205), (7.0, 35.0, 2.183)])
    assert not [
        rcd
        for rcd in filter_beacon_candidates(extract_rcds(angles, ranges, EPS_M))
        if abs(rcd.delta - 2.205) < 0.01
    ]
    rebuilt = {rcd.role: rcd for rcd in _rebuild(angles, ranges) if rcd.role is not None}
    assert set(rebuilt) == {"small_beacon", "large_beacon"}
    # the free end is at -11 deg: the centre is half an expected extent inside it
    assert math.degrees(rebuilt["small_beacon"].beta) == pytest.approx(0.0, abs=1e-9)
    assert math.degrees(rebuilt["large_beacon"].beta) == pytest.approx(1.0, abs=1e-9)
    assert rebuilt["small_beacon"].delta == pytest.approx(2.205)
    assert rebuilt["small_beacon"].eta == pytest.approx(EXTENTS_RAD[0])


def test_the_rebuilt_centre_mirrors_when_the_cut_is_on_the_other_side() -> None:
    angles, ranges = _pan([(-11.0, 11.0, 2.205), (-40.0, -4.0, 2.150)])
    small = next(rcd for rcd in _rebuild(angles, ranges) if rcd.role == "small_beacon")
    assert math.degrees(small.beta) == pytest.approx(0.0, abs=1e-9)


def test_a_beacon_running_into_a_slightly_farther_wall_is_split_off_whole() -> None:
    # steps of 1.1 and 1.1 cm (each under eps) from the beacon plateau into the wall's
    angles, ranges = _pan([(-11.0, 11.0, 2.270), (12.0, 12.0, 2.281), (13.0, 50.0, 2.292)])
    paper = extract_rcds(angles, ranges, EPS_M)
    assert len(paper) == 1 and math.degrees(paper[0].eta) == pytest.approx(61.0)
    pieces = [rcd for rcd in _rebuild(angles, ranges) if rcd.role is None]
    beacon = next(rcd for rcd in pieces if abs(rcd.delta - 2.270) < 1e-9)
    assert math.degrees(beacon.eta) == pytest.approx(23.0)
    assert math.degrees(beacon.beta) == pytest.approx(0.5)


def test_split_at_a_nearer_object_and_at_a_slow_drift() -> None:
    ranges = np.array([3.400, 3.395, 3.400, 3.384, 3.384, 3.378])
    assert split_at_other_objects(range(6), ranges, EPS_M) == [[0, 1, 2], [3, 4, 5]]
    drifting = np.array([2.00, 2.01, 2.01, 2.015, 2.02, 2.031, 2.035])
    # the piece median is 2.01 m when 2.03 m arrives: 2 cm farther, another object
    assert split_at_other_objects(range(7), drifting, EPS_M) == [[0, 1, 2, 3, 4], [5, 6]]
    steady = np.array([2.00, 2.005, 2.0, 2.011, 2.005])
    assert split_at_other_objects(range(5), steady, EPS_M) == [[0, 1, 2, 3, 4]]


def test_no_beacon_is_rebuilt_from_a_piece_occluded_on_both_sides_or_cut_at_a_pan_end() -> None:
    angles, ranges = _pan([(-11.0, 11.0, 2.205), (-30.0, -6.0, 1.5), (6.0, 30.0, 1.6)])
    assert not [rcd for rcd in _rebuild(angles, ranges) if rcd.role is not None]
    # a sector pan that stops inside the beacon: the far end is unknown, not free
    sector = (FULL_PAN_DEG >= -20.0) & (FULL_PAN_DEG <= 5.0)
    angles, ranges = _pan([(-11.0, 11.0, 2.205), (-30.0, -6.0, 1.5)])
    assert not [rcd for rcd in _rebuild(angles[sector], ranges[sector]) if rcd.role is not None]


def test_too_little_of_a_beacon_or_more_than_a_beacon_is_not_rebuilt() -> None:
    angles, ranges = _pan([(-11.0, 11.0, 2.205), (-7.0, 40.0, 2.150)])  # 4 deg visible
    assert not [rcd for rcd in _rebuild(angles, ranges) if rcd.role is not None]
    angles, ranges = _pan([(-20.0, 20.0, 2.205), (15.0, 40.0, 2.150)])  # 35 deg visible
    assert not [rcd for rcd in _rebuild(angles, ranges) if rcd.role is not None]


def test_a_rebuilt_rcd_pairs_only_in_its_role() -> None:
    small_c, large_c, r_s, r_l = (2.85, -0.6), (0.3, -1.5), 0.0191, 0.07
    sensor = (0.0, 0.0)
    small_range = math.dist(sensor, small_c) - r_s
    large_range = math.dist(sensor, large_c) - r_l
    small_bearing = math.atan2(small_c[1], small_c[0])
    large_bearing = math.atan2(large_c[1], large_c[0])
    both_small = [
        RCD(small_range, small_bearing, EXTENTS_RAD[0], role="small_beacon"),
        RCD(large_range, large_bearing, EXTENTS_RAD[0], role="small_beacon"),
    ]
    assert localize_rcds(both_small, small_c, r_s, large_c, r_l).status == "no_pair"
    small = RCD(small_range, small_bearing, EXTENTS_RAD[0], role="small_beacon")
    large_seen = RCD(large_range, large_bearing, math.radians(22.0))  # extent says "small"
    result = localize_rcds([small, large_seen], small_c, r_s, large_c, r_l)
    assert result.ok and result.small_rcd is small
    assert math.dist((result.pose.x, result.pose.y), sensor) < 1e-9


def test_unknown_role_is_rejected() -> None:
    with pytest.raises(ValueError, match="RCD.role"):
        RCD(1.0, 0.0, 0.3, role="beacon")


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("extraction", "guess"),
        ("expected_extents_rad", (0.4,)),
        ("min_visible_extent_rad", -0.1),
        ("rebuilt_agreement_m", 0.0),
    ],
)
def test_bad_parameters_are_named(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=field):
        BeomChoParameters(**{field: value})


def _lab_scan(board: bool) -> tuple[Scan, Pose]:
    """A noise-free pan of beom_cho_lab, robot at (-0.3, 1.0) facing the small beacon; with
    ``board``, that beacon's RCD is cut on one side by a board 3 cm nearer than the beacon."""
    small_c, large_c, r_s, r_l = (2.85, -0.6), (0.3, -1.5), 0.0191, 0.07
    pose = Pose(-0.3, 1.0, math.atan2(small_c[1] - 1.0, small_c[0] + 0.3))
    ranges = np.full(len(FULL_PAN_DEG), np.nan)
    for center, radius, half_deg in ((small_c, r_s, 11.0), (large_c, r_l, 12.0)):
        bearing = math.degrees(math.atan2(center[1] - pose.y, center[0] - pose.x) - pose.theta)
        offsets = (FULL_PAN_DEG - bearing + 180.0) % 360.0 - 180.0
        beacon_range = math.dist((pose.x, pose.y), center) - radius
        ranges[np.abs(offsets) <= half_deg] = beacon_range
        if board and center == small_c:
            ranges[(offsets > 5.0) & (offsets <= 30.0)] = beacon_range - 0.03
    amplitudes = np.where(np.isfinite(ranges), 1.0, 0.0)
    return Scan(np.radians(FULL_PAN_DEG), ranges, amplitudes, 1.0), pose


def test_the_fallback_localizes_the_lab_pan_the_papers_extraction_gives_up_on() -> None:
    scan, pose = _lab_scan(board=True)
    scenario = load_scenario("beom_cho_lab")
    assert localize_scan(scan, scenario).status == "no_pair"
    result = localize_scan(scan, scenario, BeomChoParameters(extraction="occlusion_aware"))
    assert result.ok
    assert math.dist((result.pose.x, result.pose.y), (pose.x, pose.y)) < 0.02
    assert abs(result.pose.theta - pose.theta) < math.radians(1.0)


def test_the_fallback_leaves_the_papers_answer_alone_when_it_has_one() -> None:
    scan, _ = _lab_scan(board=False)
    scenario = load_scenario("beom_cho_lab")
    paper = localize_scan(scan, scenario)
    aware = localize_scan(scan, scenario, BeomChoParameters(extraction="occlusion_aware"))
    assert paper.ok and aware.ok
    assert aware.pose == paper.pose and aware.small_rcd == paper.small_rcd


def test_pairs_that_disagree_on_the_place_give_no_pose_when_agreement_is_asked() -> None:
    small_c, large_c, r_s, r_l = (2.85, -0.6), (0.3, -1.5), 0.0191, 0.07
    small = RCD(
        math.dist((0, 0), small_c) - r_s, math.atan2(small_c[1], small_c[0]), math.radians(22)
    )
    large = RCD(
        math.dist((0, 0), large_c) - r_l, math.atan2(large_c[1], large_c[0]), math.radians(24)
    )
    # both assignments tried and a loose tolerance: the swapped pair also passes eq. (7)
    loose = {"distance_tolerance": 0.1, "params": BeomChoParameters(assignment="best_fit")}
    chosen = localize_rcds([small, large], small_c, r_s, large_c, r_l, **loose)
    assert chosen.ok and math.dist((chosen.pose.x, chosen.pose.y), (0.0, 0.0)) < 1e-9
    strict = localize_rcds([small, large], small_c, r_s, large_c, r_l, agreement_m=0.1, **loose)
    assert strict.status == "ambiguous_pair" and strict.pose is None
    # with the paper's tolerance only the right assignment passes, and agreement changes nothing
    paper = localize_rcds([small, large], small_c, r_s, large_c, r_l, agreement_m=0.1)
    assert paper.ok and paper.pose == chosen.pose


def _imported_modules(module: str) -> set[str]:
    source = Path(importlib.import_module(module).__file__ or "").read_text(encoding="utf-8")
    found: set[str] = set()
    for node in ast.walk(ast.parse(source)):  # deferred imports inside functions included
        if isinstance(node, ast.ImportFrom) and node.module:
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
    return found


def test_rcd_module_is_shared_without_an_import_cycle() -> None:
    for module in (
        "sonar_gym.localization.beom_cho_rcd",
        "sonar_gym.localization.beom_cho_occlusion",
    ):
        assert "sonar_gym.localization.beom_cho" not in _imported_modules(module)
    assert "sonar_gym.localization.beom_cho_rcd" in _imported_modules(
        "sonar_gym.localization.beom_cho_occlusion"
    )
    from sonar_gym.localization import beom_cho, beom_cho_rcd

    for name in ("RCD", "extract_rcds", "make_rcd", "symmetry_measure", "MIN_RCD_SAMPLES"):
        assert getattr(beom_cho, name) is getattr(beom_cho_rcd, name)
