"""numpy ``Generator`` objects handed to compiled loops (numba) by the addresses of their bit
generators, so a call does not pay numba's conversion of the ``Generator`` object.

numba converts a ``Generator`` argument on every call: it types the object, reads its bit
generator's ``ctypes`` interface and casts three of its function pointers through
``ctypes.cast``, which costs tens of microseconds, far more than the draws of a short loop.
The addresses it reads are fixed for the life of a bit generator (its state lives inside the
object; setting ``bit_generator.state`` writes into it), so :func:`generator_handle` reads them
once per bit generator and :func:`handle_generator` rebuilds numba's ``Generator`` from them
inside a compiled loop. The loop then draws with numba's own ``Generator`` methods on the
caller's bit generator, exactly as it does with the converted object: same algorithms, same
numbers, same state afterwards.

The caller keeps the ``Generator`` alive while a loop uses its handle (it holds it to pass it).
"""

from __future__ import annotations

import ctypes
from typing import Any

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

GENERATOR_HANDLE = types.UniTuple(types.uintp, 6)
"""The numba type of a :func:`generator_handle`."""

GeneratorHandle = tuple[int, int, int, int, int, int]
"""The addresses of a bit generator: its state's address, its state, its ``next_uint64``,
``next_uint32`` and ``next_double`` functions and the bit generator struct (in the order of
numba's model of a bit generator)."""

_KEPT = 8
"""How many bit generators :func:`generator_handle` remembers (most recent first)."""

_RECENT: list[tuple[Any, GeneratorHandle]] = []
"""The last bit generators asked of :func:`generator_handle` and their handles; holding each
bit generator keeps its ``id`` from being reused while it is remembered."""


def _read_handle(bit_generator: Any) -> GeneratorHandle:
    """The addresses of ``bit_generator`` as numba's conversion reads them."""
    interface = bit_generator.ctypes

    def address(function: Any) -> int:
        value = ctypes.cast(function, ctypes.c_void_p).value
        return 0 if value is None else int(value)

    state = interface.state.value
    struct = interface.bit_generator.value
    return (
        int(interface.state_address),
        0 if state is None else int(state),
        address(interface.next_uint64),
        address(interface.next_uint32),
        address(interface.next_double),
        0 if struct is None else int(struct),
    )


def generator_handle(rng: np.random.Generator) -> GeneratorHandle:
    """The handle of ``rng``'s bit generator for a compiled loop (:data:`GENERATOR_HANDLE`);
    remembered for the last few bit generators."""
    bit_generator = rng.bit_generator
    for known, handle in _RECENT:
        if known is bit_generator:
            return handle
    handle = _read_handle(bit_generator)
    _RECENT.insert(0, (bit_generator, handle))
    del _RECENT[_KEPT:]
    return handle


_GENERATOR = types.NumPyRandomGeneratorType("NumPyRandomGeneratorType")
_BIT_GENERATOR = types.NumPyRandomBitGeneratorType("bit_generator")
_HANDLE_FIELDS = (
    "state_address",
    "state",
    "fnptr_next_uint64",
    "fnptr_next_uint32",
    "fnptr_next_double",
    "bit_generator",
)


def _handle_generator(typing_context: Any, handle: Any) -> Any:
    """numba's ``Generator`` on the bit generator of ``handle``, built in place."""
    if handle != GENERATOR_HANDLE:
        return None
    signature = _GENERATOR(GENERATOR_HANDLE)

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        bit_generator = cgutils.create_struct_proxy(_BIT_GENERATOR)(context, builder)
        for index, name in enumerate(_HANDLE_FIELDS):
            setattr(bit_generator, name, builder.extract_value(args[0], index))
        null = ir.Constant(ir.IntType(8).as_pointer(), None)
        bit_generator.parent = null
        generator = cgutils.create_struct_proxy(_GENERATOR)(context, builder)
        generator.bit_generator = bit_generator._getvalue()
        generator.meminfo = null
        generator.parent = null
        return generator._getvalue()

    return signature, codegen


handle_generator: Any = intrinsic(_handle_generator)
"""``handle_generator(handle)`` inside a compiled loop: numba's ``Generator`` on the bit
generator of ``handle`` (:func:`generator_handle`), with no Python object behind it (it is
never returned)."""

__all__ = ["GENERATOR_HANDLE", "GeneratorHandle", "generator_handle", "handle_generator"]
