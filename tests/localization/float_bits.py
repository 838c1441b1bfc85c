"""Values compared by their bits: ``-0.0`` apart from ``0.0``, NaN equal to itself."""

from __future__ import annotations

import struct


def canonical(value: object) -> object:
    """``value`` as new tuples of plain values, every float by its type and bits."""
    if isinstance(value, float):
        return (type(value).__name__, struct.pack("<d", value))
    if isinstance(value, tuple):
        return tuple(canonical(item) for item in value)
    return (type(value).__name__, value)
