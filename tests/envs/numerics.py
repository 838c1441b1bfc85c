"""Which family of floating-point results this machine's numpy gives, for the bit-for-bit
rollout fixtures.

numpy picks its float64 ``exp``, ``log``, ``sin``, ``cos``, ``power`` and the like at run time by
the processor's vector extensions: with AVX-512 (x86-64-v4) its own vectorised code, whose last
bits differ from the C library's; without it (x86-64-v3: AVX2 and FMA) the C library's. OpenBLAS
picks its kernels the same way. A seeded rollout is therefore the same bits on every machine
of one family and may differ in the last bits between families (and then diverge). Each
fixture is recorded once per family on the reference tree; the replay compares with its own
family's file, bit for bit.
"""

from __future__ import annotations

import platform
from pathlib import Path

try:
    from numpy._core._multiarray_umath import __cpu_features__ as _CPU_FEATURES
except ImportError:  # numpy 1.x
    from numpy.core._multiarray_umath import __cpu_features__ as _CPU_FEATURES


def numerics_family() -> str:
    """``"x86-64-v4"``, ``"x86-64-v3"``, or ``"<machine>-other"`` for anything else."""
    machine = platform.machine().lower()
    if machine in ("x86_64", "amd64"):
        if _CPU_FEATURES.get("AVX512F") and _CPU_FEATURES.get("AVX512_SKX"):
            return "x86-64-v4"
        if _CPU_FEATURES.get("AVX2") and _CPU_FEATURES.get("FMA3"):
            return "x86-64-v3"
    return f"{machine}-other"


NUMERICS_FAMILY = numerics_family()
"""This machine's family."""


def family_fixture(path: Path, family: str = NUMERICS_FAMILY) -> Path:
    """``name.<family>.json`` beside ``path`` (``name.json``): the fixture of ``family``."""
    return path.with_name(f"{path.stem}.{family}{path.suffix}")


def missing_fixture_message(path: Path) -> str:
    """Why a replay cannot run: no fixture recorded for this family, and how to record one."""
    return (
        f"no reference rollouts for numerics family {NUMERICS_FAMILY!r} ({path.name}): record "
        "them once on this kind of machine from the reference tree (see the recording module's "
        "docstring), never from the code under test"
    )
