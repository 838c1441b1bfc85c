"""Frozen dataclass instances made without running their ``__init__``.

A frozen dataclass sets each field through ``object.__setattr__`` and then runs its
``__post_init__`` checks and conversions, a few microseconds an instance. Inner loops that make
many instances from values already checked and converted (floats from a fit, poses from an
integrator) set the attributes directly instead; each caller's docstring says why its values
need no checks.
"""

from __future__ import annotations

from typing import Any, TypeVar

InstanceT = TypeVar("InstanceT")


def unchecked_instance(cls: type[InstanceT], /, **attributes: Any) -> InstanceT:
    """An instance of the frozen dataclass ``cls`` holding ``attributes`` (its fields, and any
    attributes its ``__post_init__`` derives), as its constructor would set them from values
    that pass its checks, without running the constructor."""
    instance = object.__new__(cls)
    instance.__dict__.update(attributes)
    return instance
