"""``sonar-gym reproduce beom-cho``: Table II from the lab pan, errors along a path with stops."""

from __future__ import annotations

import io
import json
import math
from pathlib import Path
from typing import Any

import pytest
from rich.console import Console

from sonar_gym.pose import angle_difference
from sonar_gym.robot import OdometryNoise
from sonar_gym.scenario import load_scenario
from sonar_gym.train.reproduce import beom_cho
from sonar_gym.train.reproduce.common import FLAG

TABLE_II_AS_PRINTED = (
    "2.8542", "-10.3", "22.0", "0.0027",
    "1.4401", "-78.3", "24.0", "0.0012",
    "1.4612", "-140.3", "18.0", "0.0074",
    "1.8311", "158.7", "0.0021",
)  # fmt: skip
PAPER_POSITION_BOUND_M = 0.03
PAPER_HEADING_BOUND_RAD = math.radians(2.0)
SMALL_BEACON_XY = (2.85, -0.6)
LARGE_BEACON_XY = (0.3, -1.5)


@pytest.fixture(scope="module")
def reproduction(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str, dict[str, Any]]:
    out_dir = tmp_path_factory.mktemp("beom_cho")
    buffer = io.StringIO()
    beom_cho.run(out_dir, Console(file=buffer, width=240), origin_pans=2, path_repeats=1)
    numbers = json.loads((out_dir / "beom_cho_results.json").read_text())
    return out_dir, buffer.getvalue(), numbers


def _position_error(estimate: list[float], truth: list[float]) -> float:
    return math.hypot(estimate[0] - truth[0], estimate[1] - truth[1])


def _heading_error(estimate: list[float], truth: list[float]) -> float:
    return abs(angle_difference(estimate[2], truth[2]))


def test_the_equal_distance_point_is_as_far_from_both_beacons() -> None:
    x = beom_cho.equal_distance_x_m(load_scenario("beom_cho_lab"))
    assert math.dist((x, 0.0), SMALL_BEACON_XY) == pytest.approx(
        math.dist((x, 0.0), LARGE_BEACON_XY), rel=1e-12
    )
    assert 1.0 < x < 1.4  # the paper's slip point (1.2, 0) lies about where the roles cross


def test_the_slip_falls_on_the_move_that_ends_at_1_2_m() -> None:
    assert beom_cho.stop_count(0.2) == 15
    segment = beom_cho.slip_segment(0.2)
    assert beom_cho.PATH_START_X_M + 0.2 * segment == pytest.approx(1.2, abs=1e-12)
    with pytest.raises(ValueError, match="stop_spacing_m"):
        beom_cho.stop_count(0.0)


def test_slipping_noise_lowers_only_the_left_wheel_scale() -> None:
    base = OdometryNoise(slip_probability_per_m=0.0)
    slipping = beom_cho.slipping_noise(base, 0.2)
    assert slipping.scale_error_left == pytest.approx(base.scale_error_left - 0.2, abs=1e-15)
    assert slipping.scale_error_right == base.scale_error_right
    assert slipping.encoder_std_m_per_sqrt_m == base.encoder_std_m_per_sqrt_m


def test_table_ii_rows_lead_eq_7_to_the_papers_pair() -> None:
    # Sec. V.B: RCDs 1 (small beacon, the narrower) and 2 (large beacon) are chosen.
    result = beom_cho.paper_pose_from_table_ii(load_scenario("beom_cho_lab"))
    rows = beom_cho.table_ii_rcds()
    assert result.status == "ok"
    assert result.small_rcd == rows[0]
    assert result.large_rcd == rows[1]


def test_writes_the_plots_and_prints_table_ii_beside_ours(
    reproduction: tuple[Path, str, dict[str, Any]],
) -> None:
    out_dir, text, _ = reproduction
    for name in ("beom_cho_table2_scan.png", "beom_cho_path.png", "beom_cho_errors.png"):
        path = out_dir / name
        assert path.is_file() and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    for value in TABLE_II_AS_PRINTED:
        assert value in text
    for printed_pair_error in ("0.031", "2.049", "0.257"):
        assert printed_pair_error in text
    assert "δ [m]" in text and "E_xy [cm]" in text  # units survive the table markup
    assert FLAG in text
    assert "Parameters the paper does not state" in text


def test_table_ii_pan_chooses_the_two_beacons_and_finds_the_origin(
    reproduction: tuple[Path, str, dict[str, Any]],
) -> None:
    _, _, numbers = reproduction
    paper = numbers["table_ii"]["paper"]
    assert paper["status"] == "ok"
    assert paper["beacons_identified"] is True
    # The chosen RCDs point at the beacons as the geometry of Fig. 7 places them.
    small_bearing = math.atan2(SMALL_BEACON_XY[1], SMALL_BEACON_XY[0])
    large_bearing = math.atan2(LARGE_BEACON_XY[1], LARGE_BEACON_XY[0])
    assert abs(angle_difference(paper["small_rcd_beta_rad"], small_bearing)) < math.radians(1.5)
    assert abs(angle_difference(paper["large_rcd_beta_rad"], large_bearing)) < math.radians(1.5)
    x, y, theta = paper["pose"]
    assert math.hypot(x, y) <= PAPER_POSITION_BOUND_M
    assert abs(theta) <= PAPER_HEADING_BOUND_RAD
    window = numbers["table_ii"]["window"]
    assert 4 <= len(window) <= numbers["table_ii"]["rcds_total"]
    kept = {row["fate"]: row["object"] for row in window if row["fate"].startswith("kept")}
    assert kept == {"kept: small beacon": "small beacon", "kept: large beacon": "large beacon"}
    for row in window:
        assert math.radians(18.0) - 1e-9 <= row["eta_rad"] <= math.radians(26.0) + 1e-9


def test_improved_variant_without_slip_stays_within_the_papers_bound(
    reproduction: tuple[Path, str, dict[str, Any]],
) -> None:
    _, _, numbers = reproduction
    run = numbers["path"]["no_slip"]
    truth = run["true_poses"]
    estimates = run["estimates"]["improved"]
    assert len(truth) == beom_cho.stop_count(beom_cho.STOP_SPACING_M)
    assert all(estimate is not None for estimate in estimates)
    assert max(map(_position_error, estimates, truth)) <= PAPER_POSITION_BOUND_M
    assert max(map(_heading_error, estimates, truth)) <= PAPER_HEADING_BOUND_RAD


def test_with_slip_dead_reckoning_ends_worse_than_the_method(
    reproduction: tuple[Path, str, dict[str, Any]],
) -> None:
    _, _, numbers = reproduction
    run = numbers["path"]["slip"]
    truth = run["true_poses"][-1]
    dead_reckoning = run["dead_reckoning_poses"][-1]
    improved = run["estimates"]["improved"][-1]
    assert _position_error(dead_reckoning, truth) > _position_error(improved, truth)
    assert _heading_error(dead_reckoning, truth) > _heading_error(improved, truth)
    # The turn the slip left behind is what dead reckoning misses.
    assert _heading_error(dead_reckoning, truth) > PAPER_HEADING_BOUND_RAD / 2.0


def test_the_slip_turns_the_robot_by_f_d_over_l_unseen_by_dead_reckoning(
    reproduction: tuple[Path, str, dict[str, Any]],
) -> None:
    _, _, numbers = reproduction
    no_slip, slip = numbers["path"]["no_slip"], numbers["path"]["slip"]
    segment = numbers["slip_segment"]
    expected_turn = numbers["slip_fraction"] * numbers["stop_spacing_m"] / numbers["wheel_base_m"]
    assert expected_turn == pytest.approx(0.2 * 0.2 / 0.5, rel=1e-12)
    assert slip["true_poses"][:segment] == no_slip["true_poses"][:segment]
    turn = angle_difference(slip["true_poses"][segment][2], no_slip["true_poses"][segment][2])
    assert turn == pytest.approx(expected_turn, abs=1e-9)
    assert slip["dead_reckoning_poses"] == no_slip["dead_reckoning_poses"]
