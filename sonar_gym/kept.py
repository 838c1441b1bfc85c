"""A one-entry store for values that depend only on a key and are costly to rebuild.

Environments rebuild some things per episode from inputs that often repeat (the same beacon
layout, the same path): :class:`KeptValue` keeps the value made for the last key, compared
by equality (content), and makes a new one only when the key changes.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

ValueT = TypeVar("ValueT")


class KeptValue(Generic[ValueT]):
    """The value made for the last key (see the module docstring); pickles with its owner."""

    def __init__(self) -> None:
        self._entry: tuple[Hashable, ValueT] | None = None

    def get(self, key: Hashable, make: Callable[[], ValueT]) -> ValueT:
        """The kept value if ``key`` equals the last key, else ``make()`` (then kept)."""
        if self._entry is None or self._entry[0] != key:
            self._entry = (key, make())
        return self._entry[1]
