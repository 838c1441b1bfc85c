"""How the compiled loops are compiled (numba): one signature each, cached, numpy's arithmetic.

Every loop is compiled for one signature whose arrays are read-only and of any layout, so
writable, read-only and strided inputs share one compiled loop, cached beside its module
(``cache=True``); it is loaded, not recompiled, by every later process. Division by zero gives
inf or NaN as in numpy (``error_model="numpy"``), and no ``fastmath``: numba then fuses no
multiply-add, so every elementwise step rounds as numpy's does.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

NUMBERS = types.Array(types.float64, 1, "A", readonly=True)
"""A read-only 1-d float64 array of any layout."""
FLAGS = types.Array(types.boolean, 1, "A", readonly=True)
"""A read-only 1-d bool array of any layout."""
INDICES = types.Array(types.int64, 1, "A", readonly=True)
"""A read-only 1-d int64 array of any layout."""
TABLE = types.Array(types.float64, 2, "A", readonly=True)
"""A read-only 2-d float64 array of any layout."""
INDEX_TABLE = types.Array(types.int64, 2, "A", readonly=True)
"""A read-only 2-d int64 array of any layout."""


def compiled(
    result: Any, *arguments: Any, inline: bool = False
) -> Callable[[Callable[..., Any]], Any]:
    """Decorator: compile a loop for ``result(*arguments)`` (numba types), cached.

    ``inline``: a helper that other loops call per element, inlined into each of them (a call
    per element costs more than the helper's arithmetic).
    """
    return numba.njit(  # type: ignore[no-any-return]
        result(*arguments),
        cache=True,
        error_model="numpy",
        nogil=True,
        inline="always" if inline else "never",
    )


def _nan_min(a: float, b: float) -> float:
    """``np.minimum`` of two floats: NaN if either is NaN."""
    if a != a:
        return a
    if b != b:
        return b
    return a if a <= b else b


def _nan_max(a: float, b: float) -> float:
    """``np.maximum`` of two floats: NaN if either is NaN."""
    if a != a:
        return a
    if b != b:
        return b
    return a if a >= b else b


nan_min = compiled(types.float64, types.float64, types.float64)(_nan_min)
"""``np.minimum`` of two floats inside a compiled loop (Python's ``min`` drops a NaN)."""
nan_max = compiled(types.float64, types.float64, types.float64)(_nan_max)
"""``np.maximum`` of two floats inside a compiled loop (Python's ``max`` drops a NaN)."""


def _fused_multiply_add(typing_context: Any, a: Any, b: Any, c: Any) -> Any:
    """``a * b + c`` with one rounding (LLVM's ``llvm.fma.f64``)."""
    signature = types.float64(types.float64, types.float64, types.float64)

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        double = ir.DoubleType()
        function = builder.module.declare_intrinsic(
            "llvm.fma", [double], ir.FunctionType(double, [double, double, double])
        )
        return builder.call(function, args)

    return signature, codegen


fused_multiply_add: Any = intrinsic(_fused_multiply_add)
"""``fused_multiply_add(a, b, c)``: ``a * b + c`` rounded once, inside a compiled loop. numpy's
BLAS products round so: OpenBLAS's ``gemm`` sums ``a_0 b_0``, then adds each further term with
one fused multiply-add."""


def _remainder(x: float, y: float) -> float:
    """IEEE 754 ``remainder(x, y)`` of finite floats, ``y != 0``: exact, so the bits of
    Python's ``math.remainder`` (whose algorithm this is: ``fmod`` is exact too)."""
    absx, absy = abs(x), abs(y)
    m = np.fmod(absx, absy)
    c = absy - m
    if m < c:
        r = m
    elif m > c:
        r = -c
    else:  # half way: the even multiple
        r = m - 2.0 * np.fmod(0.5 * (absx - m), absy)
    return math.copysign(1.0, x) * r


remainder = compiled(types.float64, types.float64, types.float64, inline=True)(_remainder)
"""``math.remainder`` of two finite floats inside a compiled loop."""


def _wrap_angle(angle_rad: float) -> float:
    wrapped = remainder(angle_rad, 2.0 * math.pi)
    return math.pi if wrapped == -math.pi else wrapped


wrap_angle = compiled(types.float64, types.float64, inline=True)(_wrap_angle)
""":func:`sonar_gym.pose.wrap_angle` of a finite angle (radians) inside a compiled loop."""


def _floor_remainder(x: float, y: float) -> float:
    """``np.remainder(x, y)`` of floats, ``y != 0``: numpy's ``npy_divmod`` (``fmod``, exact,
    moved to the sign of ``y``; a zero takes the sign of ``y``)."""
    mod = np.fmod(x, y)
    if mod != 0.0:
        if (y < 0.0) != (mod < 0.0):
            mod += y
    else:
        mod = math.copysign(0.0, y)
    return mod  # type: ignore[no-any-return]


floor_remainder = compiled(types.float64, types.float64, types.float64, inline=True)(
    _floor_remainder
)
"""``np.remainder`` of two floats (divisor not zero) inside a compiled loop."""


def _wrap_to_pi(angle_rad: float) -> float:
    wrapped = floor_remainder(angle_rad + np.pi, 2.0 * np.pi) - np.pi
    return np.pi if wrapped <= -np.pi else wrapped


wrap_to_pi = compiled(types.float64, types.float64, inline=True)(_wrap_to_pi)
""":func:`sonar_gym.pose.wrap_angles` of one finite angle (radians) inside a compiled loop: its
``np.remainder(angle + pi, 2 pi) - pi``, then ``pi`` for ``-pi``."""

_PAIRWISE_BLOCK = 128
"""numpy's ``PW_BLOCKSIZE``: the longest run its pairwise sum adds with eight accumulators."""


@compiled(types.float64, NUMBERS, types.int64, types.int64)  # type: ignore[misc]
def _pairwise(values: Any, start: int, count: int) -> float:
    """numpy's ``pairwise_sum`` of ``values[start : start + count]``."""
    if count < 8:
        total = -0.0
        for index in range(start, start + count):
            total += values[index]
        return total  # type: ignore[no-any-return]
    if count <= _PAIRWISE_BLOCK:
        r0, r1, r2, r3 = values[start], values[start + 1], values[start + 2], values[start + 3]
        r4, r5, r6, r7 = values[start + 4], values[start + 5], values[start + 6], values[start + 7]
        index = start + 8
        stop = start + count - count % 8
        while index < stop:
            r0 += values[index]
            r1 += values[index + 1]
            r2 += values[index + 2]
            r3 += values[index + 3]
            r4 += values[index + 4]
            r5 += values[index + 5]
            r6 += values[index + 6]
            r7 += values[index + 7]
            index += 8
        total = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while index < start + count:
            total += values[index]
            index += 1
        return total  # type: ignore[no-any-return]
    half = count // 2
    half -= half % 8
    return _pairwise(values, start, half) + _pairwise(  # type: ignore[no-any-return]
        values, start + half, count - half
    )


def _pairwise_sum(values: Any) -> float:
    return 0.0 + _pairwise(values, 0, values.size)  # type: ignore[no-any-return]


pairwise_sum = compiled(types.float64, NUMBERS)(_pairwise_sum)
"""``values.sum()`` of a 1-d float64 array inside a compiled loop, bit for bit: numpy's pairwise
summation (eight accumulators over runs of up to 128, halves above) of the whole array (a
float64 array needs no cast, so numpy's reduction does not buffer it), added to the identity
``0.0``."""
