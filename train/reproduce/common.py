"""What every ``sonar-gym reproduce`` module shares: the factor-of-two flag and the table of
parameters a paper leaves unstated."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

from rich.markup import escape
from rich.table import Table

FLAG = "differs by more than 2x"


def ratio_flag(ours: float, paper: float) -> str:
    """:data:`FLAG` when ``ours / paper`` lies outside [1/2, 2] (or is undefined), else ``""``."""
    if not (math.isfinite(ours) and math.isfinite(paper)) or paper <= 0.0 or ours <= 0.0:
        return FLAG
    ratio = ours / paper
    return FLAG if ratio > 2.0 or ratio < 0.5 else ""


def parameters_table(rows: Iterable[Sequence[str]]) -> Table:
    """The parameters a paper does not state: ``(parameter, our value, where)`` rows."""
    table = Table(
        title="Parameters the paper does not state", title_justify="left", header_style="bold"
    )
    for header in ("parameter", "our value", "where"):
        table.add_column(header)
    for row in rows:
        table.add_row(*(escape(str(cell)) for cell in row))
    return table
