"""``sonar-gym reproduce kim`` runs, prints the paper beside ours, lands on the paper's order."""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console

from sonar_gym.localization.kim import TABLE_1_ESTIMATED_POSITIONS_M, TABLE_1_TRUE_POSITIONS_M
from sonar_gym.train.reproduce import kim

TABLE_1_ERRORS_M = np.linalg.norm(TABLE_1_ESTIMATED_POSITIONS_M - TABLE_1_TRUE_POSITIONS_M, axis=1)


def test_reproduction_writes_plots_and_numbers_of_the_paper_order(tmp_path: Path) -> None:
    buffer = io.StringIO()
    kim.run(tmp_path, Console(file=buffer, width=200), table1_seeds=4, sweep_seeds=3)
    text = buffer.getvalue()
    for name in ("kim_table1.png", "kim_error_vs_sweeps.png", "kim_scene.png"):
        path = tmp_path / name
        assert path.is_file() and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # The paper's Table 1 is printed beside ours (its first row, in cm), with the 2x flags.
    assert "2.50, 10.00" in text and "3.02, 10.57" in text
    assert "Parameters the paper does not state" in text
    numbers = json.loads((tmp_path / "kim_results.json").read_text())
    np.testing.assert_allclose(
        numbers["paper_table1_error_per_point_m"], TABLE_1_ERRORS_M, rtol=1e-12
    )
    summary = numbers["summary"]
    assert summary["paper_table_mean_m"] == np.mean(TABLE_1_ERRORS_M)
    # Of the paper's order: within 2x of Table 1's mean, below the text's "typical 10 cm".
    for key in ("ours_mean_m", "beside_mean_m"):
        assert (
            0.5 * summary["paper_table_mean_m"]
            <= summary[key]
            <= 2.0 * summary["paper_table_mean_m"]
        )
        assert summary[key] < 0.10
    sweeps = {(row["n_sweeps"], row["anchor"]): row for row in numbers["sweeps"]}
    assert set(sweeps) == {(n, a) for n in (1, 2, 3, 4) for a in ("cell_center", "obstacle_point")}
    for row in sweeps.values():
        assert 0.005 < row["fix_position_error_mean_m"] < 0.10
        assert row["sensing_time_per_decision_s"] == pytest.approx(
            1.25 * row["n_sweeps"], rel=1e-12
        )
    # Sec. 3.3: more sweeps (up to four) localize better.
    for anchor in ("cell_center", "obstacle_point"):
        assert (
            sweeps[(4, anchor)]["fix_position_error_mean_m"]
            < sweeps[(1, anchor)]["fix_position_error_mean_m"]
        )
