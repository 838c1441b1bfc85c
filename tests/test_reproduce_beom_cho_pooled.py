"""The pooled path table of the Beom & Cho reproduction reports every run's last stop."""

from __future__ import annotations

import math

import numpy as np
from rich.console import Console

from sonar_gym.train.reproduce.beom_cho import DEAD_RECKONING, ErrorSummary, path_table


class FakeRun:
    """Stands in for a PathRun: position and heading errors per stop (metres, radians)."""

    def __init__(self, final_position_m: float, final_heading_rad: float) -> None:
        self.position = np.array([0.01, final_position_m])
        self.heading = np.array([0.001, final_heading_rad])

    def errors(self, estimator: str) -> tuple[np.ndarray, np.ndarray]:
        return self.position, self.heading


def summary_with_final(position_m: float, heading_rad: float) -> ErrorSummary:
    return ErrorSummary(
        fixes=2,
        stops=2,
        wrong_pair=0,
        max_position_m=0.05,
        mean_position_m=0.02,
        max_heading_rad=0.01,
        mean_heading_rad=0.005,
        max_position_right_m=0.05,
        max_heading_right_rad=0.01,
        final_position_m=position_m,
        final_heading_rad=heading_rad,
    )


def rendered(table) -> str:
    console = Console(width=400, record=True, file=None)
    with console.capture() as capture:
        console.print(table)
    return capture.get()


def test_pooled_table_gives_the_largest_final_error_over_the_runs() -> None:
    runs = [FakeRun(0.011, math.radians(0.5)), FakeRun(0.042, math.radians(1.25))]
    summaries = {DEAD_RECKONING: summary_with_final(0.011, math.radians(0.5))}  # run 0's
    pooled = rendered(path_table("pooled", summaries, runs))
    assert "max final E_xy / E_θ" in pooled
    assert "4.20 / 1.25" in pooled and "1.10 / 0.50" not in pooled


def test_single_run_table_keeps_the_runs_final_error() -> None:
    summaries = {DEAD_RECKONING: summary_with_final(0.011, math.radians(0.5))}
    single = rendered(path_table("run", summaries))
    assert "1.10 / 0.50" in single and "max final" not in single
