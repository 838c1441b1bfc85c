"""Wall-clock time per named phase (``sensing``, ``localization``, ...), added up in a dict."""

from __future__ import annotations

import time


class PhaseTimer:
    """A context that adds the wall-clock time of its block to ``timing[phase]`` (seconds).

    A plain class rather than a generator-based context: it costs several times less per
    block, and hot loops time many blocks.
    """

    __slots__ = ("phase", "start", "timing")

    def __init__(self, timing: dict[str, float], phase: str) -> None:
        self.timing = timing
        self.phase = phase
        self.start = 0.0

    def __enter__(self) -> None:
        self.start = time.perf_counter()

    def __exit__(self, *exc_info: object) -> None:
        timing = self.timing
        timing[self.phase] = timing.get(self.phase, 0.0) + time.perf_counter() - self.start
