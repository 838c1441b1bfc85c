"""Validated, frozen environment configurations.

Every environment takes its ``gym.make`` keyword arguments into a frozen dataclass checked in
``__init__``: a misspelt key or a value outside its range fails at once with a message that
names the argument and what is allowed, instead of being ignored.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping
from typing import Any, TypeVar

ConfigT = TypeVar("ConfigT")


def build_config(config_type: type[ConfigT], kwargs: Mapping[str, Any], env_name: str) -> ConfigT:
    """Instantiate ``config_type`` from ``kwargs``, rejecting unknown keys by name."""
    allowed = [f.name for f in dataclasses.fields(config_type)]  # type: ignore[arg-type]
    unknown = sorted(set(kwargs) - set(allowed))
    if unknown:
        raise ValueError(
            f"{env_name}: unknown argument(s) {unknown}; allowed arguments are {sorted(allowed)}"
        )
    return config_type(**kwargs)


def check_number(
    name: str,
    value: object,
    *,
    low: float | None = None,
    high: float | None = None,
    low_inclusive: bool = True,
    integer: bool = False,
) -> None:
    """Raise ``ValueError`` unless ``value`` is a finite number in the given range."""
    kind = "an integer" if integer else "a finite number"
    valid_type = isinstance(value, int) if integer else isinstance(value, (int, float))
    if isinstance(value, bool) or not valid_type or not math.isfinite(float(value)):  # type: ignore[arg-type]
        raise ValueError(f"argument {name!r} must be {kind}; got {value!r}")
    number = float(value)  # type: ignore[arg-type]
    too_low = low is not None and (number < low if low_inclusive else number <= low)
    too_high = high is not None and number > high
    if too_low or too_high:
        lower = "-inf" if low is None else f"{low:g}"
        upper = "inf" if high is None else f"{high:g}"
        bracket = "[" if low_inclusive else "("
        raise ValueError(f"argument {name!r} must be in {bracket}{lower}, {upper}]; got {value!r}")


def check_choice(name: str, value: object, allowed: Iterable[object]) -> None:
    """Raise ``ValueError`` unless ``value`` is one of ``allowed``."""
    options = list(allowed)
    if value not in options:
        raise ValueError(f"argument {name!r} must be one of {options}; got {value!r}")


def check_bool(name: str, value: object) -> None:
    """Raise ``ValueError`` unless ``value`` is a bool."""
    if not isinstance(value, bool):
        raise ValueError(f"argument {name!r} must be True or False; got {value!r}")
