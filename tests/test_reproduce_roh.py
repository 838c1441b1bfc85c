"""``sonar-gym reproduce roh``: Tables II-V beside ours, of the paper's order, and the plots."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from rich.console import Console

from sonar_gym.train.reproduce import roh
from sonar_gym.train.reproduce.common import FLAG


@pytest.fixture(scope="module")
def reproduction(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    out_dir = tmp_path_factory.mktemp("roh")
    console = Console(record=True, width=220)
    roh.run(out_dir, console, n_runs=3)
    return out_dir, console.export_text()


def test_writes_the_plots_and_the_numbers(reproduction: tuple[Path, str]) -> None:
    out_dir, _ = reproduction
    for name in (
        "roh_scene_two_areas.png",
        "roh_scene_three_areas.png",
        "roh_path_error.png",
        "roh_env.png",
    ):
        path = out_dir / name
        assert path.exists() and path.stat().st_size > 10_000
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    numbers = json.loads((out_dir / "roh_results.json").read_text())
    assert numbers["n_runs"] == 3 and set(numbers["tables"]) == {t.name for t in roh.PAPER_TABLES}


def test_prints_the_papers_tables_beside_ours(reproduction: tuple[Path, str]) -> None:
    _, text = reproduction
    assert "σ paper" in text and "σ' ours" in text
    for printed in ("44.4", "30.2", "13.9", "66.9", "14.8", "33.3", "21.9", "46.5", "17.3"):
        assert printed in text
    assert "Parameters the paper does not state" in text
    assert "Differences from the paper" in text


def test_two_area_errors_are_of_the_papers_order(reproduction: tuple[Path, str]) -> None:
    out_dir, _ = reproduction
    two = json.loads((out_dir / "roh_results.json").read_text())["tables"][roh.PAPER_TABLES[0].name]
    average = two["ours_average"]
    assert 33.3 / 3.0 < average["sigma_mm"] < 33.3 * 3.0
    assert 21.9 / 3.0 < average["sigma_prime_mm"] < 21.9 * 3.0
    assert sum(row["successes"] for row in two["rows"]) >= 12  # of 18 runs


def test_three_areas_complete_only_the_rows_a_single_crossing_can_meet(
    reproduction: tuple[Path, str],
) -> None:
    out_dir, text = reproduction
    three = json.loads((out_dir / "roh_results.json").read_text())["tables"][
        roh.PAPER_TABLES[1].name
    ]
    repeated, *rising = three["rows"]
    assert repeated["distances_mm"][3:] == [200.0, 200.0, 200.0]
    # 200 mm is crossed only twice on a single crossing of BD: E never gets three good points
    assert repeated["successes"] == 0
    assert sum(repeated["failures"].values()) == 3
    assert all(key.startswith("E: ") for key in repeated["failures"])
    assert any(row["successes"] > 0 for row in rising)
    for row in rising:
        if row["successes"]:
            assert 17.3 / 4.0 < row["ours_sigma_prime_mm"] < 17.3 * 4.0
    assert roh.NO_RUN in text


def test_ratio_flag_marks_more_than_a_factor_two() -> None:
    assert roh.ratio_flag(20.0, 10.0) == ""
    assert roh.ratio_flag(20.1, 10.0) == FLAG
    assert roh.ratio_flag(5.0, 10.0) == ""
    assert roh.ratio_flag(4.9, 10.0) == FLAG
    assert roh.ratio_flag(float("nan"), 10.0) == roh.NO_RUN
