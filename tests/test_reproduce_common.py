"""The flag and table every reproduce module shares."""

from __future__ import annotations

import io
import math

from rich.console import Console

from sonar_gym.train.reproduce.common import FLAG, parameters_table, ratio_flag


def test_ratio_flag_marks_only_factors_beyond_two() -> None:
    assert ratio_flag(2.0, 1.0) == ""
    assert ratio_flag(0.5, 1.0) == ""
    assert ratio_flag(2.01, 1.0) == FLAG
    assert ratio_flag(0.49, 1.0) == FLAG
    assert ratio_flag(math.nan, 1.0) == FLAG
    assert ratio_flag(1.0, 0.0) == FLAG


def test_parameters_table_keeps_bracketed_units_in_cells() -> None:
    buffer = io.StringIO()
    Console(file=buffer, width=120).print(
        parameters_table([("range noise [mm]", "2", "presets.py")])
    )
    assert "range noise [mm]" in buffer.getvalue()
