"""``sonar-gym reproduce apcs`` runs, prints the paper beside ours, lands on the paper's order."""

from __future__ import annotations

import io
import json
from pathlib import Path

from rich.console import Console

from sonar_gym.train.reproduce import apcs


def test_reproduction_writes_plots_and_numbers_of_the_paper_order(tmp_path: Path) -> None:
    buffer = io.StringIO()
    apcs.run(tmp_path, Console(file=buffer, width=220), n_runs=3)
    text = buffer.getvalue()
    for name in ("apcs_walls.png", "apcs_paths.png"):
        path = tmp_path / name
        assert path.is_file() and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # The paper's statements are printed beside ours.
    assert "100 cm^2" in text and "200 cm^2" in text and "+-0.5 deg" in text
    assert "Parameters the paper does not state" in text
    numbers = json.loads((tmp_path / "apcs_results.json").read_text())
    assert numbers["paper_vectors_on_long_wall"] == 5
    # Sec. 6: "a long flat wall is divided to 5 detected wall vectors": ours within 2x.
    assert 2.5 <= numbers["vectors_on_long_wall"] <= 10.0
    # Figs 13-14: wall B is detected in every run and every vector on it is rejected.
    assert numbers["wall_b_detected_share"] == 1.0
    assert numbers["wall_b_rejected_share"] == 1.0
    assert set(numbers["wall_b_reasons"]) <= {"distance", "orientation", "inclusion"}
    # The mapped walls give matches, and corrections reduce the lateral error (Fig. 15).
    assert numbers["matched_share_on_mapped_walls"] > 0.2
    assert (
        numbers["correction_lateral_error_after_m"] < numbers["correction_lateral_error_before_m"]
    )
    assert numbers["final_error_apcs_m"] < numbers["final_error_odometry_m"]
