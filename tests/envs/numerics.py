"""Which family of floating-point results this machine's numpy gives, for the bit-for-bit
rollout fixtures.

Two run-time choices set the last bits of a float64 result, and a seeded rollout diverges as
soon as one bit differs:

- **numpy's own loops.** numpy picks its ``exp``, ``log``, ``sin``, ``cos``, ``power`` and the
  like by the processor's vector extensions: with AVX-512 (x86-64-v4) its own vectorised code,
  whose last bits differ from the C library's; without it (x86-64-v3: AVX2 and FMA) the C
  library's.
- **OpenBLAS's kernels** (matrix products, ``inv``, ``solve``, ``eigh``). OpenBLAS picks a
  kernel family by processor, and ``OPENBLAS_CORETYPE`` overrides the choice: ``SkylakeX``,
  ``Cooperlake`` and ``SapphireRapids`` are AVX-512 kernels, ``Haswell`` and ``Zen`` AVX2 ones.
  Some machines set ``OPENBLAS_CORETYPE=Haswell`` on an AVX-512 processor, so numpy's loops
  and OpenBLAS's kernels need not be of one level.

A family is therefore the pair: ``"x86-64-v4"`` and ``"x86-64-v3"`` where both are of that
level (the machines the first fixtures came from), ``"<level>-blas-<kernels>"`` where they
differ (e.g. ``"x86-64-v4-blas-v3"``: AVX-512 numpy, AVX2 OpenBLAS), ``"<machine>-other"``
elsewhere. Each fixture is recorded once per family on the reference tree; the replay compares
with its own family's file, bit for bit.
"""

from __future__ import annotations

import platform
from pathlib import Path

from threadpoolctl import threadpool_info

try:
    from numpy._core._multiarray_umath import __cpu_features__ as _CPU_FEATURES
except ImportError:  # numpy 1.x
    from numpy.core._multiarray_umath import __cpu_features__ as _CPU_FEATURES

BLAS_KERNEL_LEVELS = {
    "skylakex": "v4",
    "cooperlake": "v4",
    "sapphirerapids": "v4",
    "haswell": "v3",
    "zen": "v3",
}
"""OpenBLAS's kernel families (as ``openblas_get_corename`` names them, lower case) by the
x86-64 level of the instructions they use."""


def numpy_level() -> str:
    """``"x86-64-v4"``, ``"x86-64-v3"``, or ``"<machine>-other"``: numpy's own loops."""
    machine = platform.machine().lower()
    if machine in ("x86_64", "amd64"):
        if _CPU_FEATURES.get("AVX512F") and _CPU_FEATURES.get("AVX512_SKX"):
            return "x86-64-v4"
        if _CPU_FEATURES.get("AVX2") and _CPU_FEATURES.get("FMA3"):
            return "x86-64-v3"
    return f"{machine}-other"


def blas_level() -> str:
    """The level of numpy's BLAS kernels: ``"v4"`` or ``"v3"`` for OpenBLAS's x86-64 kernel
    families, else the kernel or library name as ``threadpoolctl`` reports it (lower case)."""
    blas = [entry for entry in threadpool_info() if entry.get("user_api") == "blas"]
    if not blas:
        return "none"
    entry = blas[0]
    if entry.get("internal_api") != "openblas":
        return str(entry.get("internal_api", "unknown")).lower()
    kernels = str(entry.get("architecture") or "unknown").lower()
    return BLAS_KERNEL_LEVELS.get(kernels, kernels)


def numerics_family(level: str | None = None, blas: str | None = None) -> str:
    """The family of numpy's loops at ``level`` with BLAS kernels at ``blas`` (default: this
    machine's): the level alone when the kernels are of it, else ``"<level>-blas-<blas>"``."""
    level = numpy_level() if level is None else level
    blas = blas_level() if blas is None else blas
    if level.startswith("x86-64-") and level.removeprefix("x86-64-") == blas:
        return level
    return f"{level}-blas-{blas}"


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
