"""Validated, frozen environment configurations.

Every environment takes its ``gym.make`` keyword arguments into a frozen dataclass checked in
``__init__``: a misspelt key or a value outside its range fails at once with a message that
names the argument, the value and what is allowed, instead of being ignored.

The checks are the shared ones of :mod:`sonar_gym.validation` (the scenario loader uses the
same): numpy scalars are accepted and stored as Python numbers, lists are accepted where
tuples are (``EnvSpec.to_json`` turns tuples into lists) and stored as tuples, so a config
always hashes. The ``*_field`` helpers check a field of a frozen dataclass and store the
converted value back.

Renamed arguments: one concept has one argument name across the environments. A config class
lists the names it used to accept in a ``RENAMED_ARGUMENTS`` class table (old name -> new
name); :func:`build_config` still accepts an old name, with a ``DeprecationWarning`` that
names the new one, and refuses the old and the new name given together.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import warnings
from collections.abc import Iterable, Mapping
from pathlib import Path
from types import FrameType
from typing import Any, TypeVar

import gymnasium

from sonar_gym.validation import (
    MIN_SCALE,
    checked_bool,
    checked_choice,
    checked_number,
    checked_numbers,
    shown,
)

ConfigT = TypeVar("ConfigT")
MAX_SCENARIO_ARGUMENT_CHARS = 4096
"""Longest ``scenario`` argument accepted (a path longer than this is not a path)."""


RENAMED_ARGUMENTS_ATTRIBUTE = "RENAMED_ARGUMENTS"
"""The class attribute of a config that maps its deprecated argument names to the new ones."""


def renamed_arguments(config_type: type) -> Mapping[str, str]:
    """The deprecated argument names of ``config_type`` -> their new names (may be empty)."""
    table: Mapping[str, str] = getattr(config_type, RENAMED_ARGUMENTS_ATTRIBUTE, {})
    return table


def build_config(config_type: type[ConfigT], kwargs: Mapping[str, Any], env_name: str) -> ConfigT:
    """Instantiate ``config_type`` from ``kwargs``, rejecting unknown keys by name.

    A deprecated name of the config's ``RENAMED_ARGUMENTS`` is accepted for its new name with a
    ``DeprecationWarning``; giving both raises ``ValueError`` naming both.
    """
    allowed = [f.name for f in dataclasses.fields(config_type)]  # type: ignore[arg-type]
    arguments = _with_new_names(renamed_arguments(config_type), kwargs, env_name)
    unknown = sorted(set(arguments) - set(allowed))
    if unknown:
        raise ValueError(
            f"{env_name}: unknown argument(s) {unknown}; allowed arguments are {sorted(allowed)}"
        )
    return config_type(**arguments)


def _with_new_names(
    renamed: Mapping[str, str], kwargs: Mapping[str, Any], env_name: str
) -> dict[str, Any]:
    """``kwargs`` with every deprecated name replaced by its new one (warning once per name)."""
    arguments = dict(kwargs)
    for old, new in renamed.items():
        if old not in arguments:
            continue
        if new in arguments:
            raise ValueError(
                f"{env_name}: arguments {old!r} and {new!r} are the same setting ({old!r} is "
                f"the deprecated name of {new!r}); give only {new!r}"
            )
        warnings.warn(
            f"{env_name}: argument {old!r} is deprecated; use {new!r} (same meaning and units)",
            DeprecationWarning,
            stacklevel=_stacklevel_outside_library(),
        )
        arguments[new] = arguments.pop(old)
    return arguments


def _stacklevel_outside_library() -> int:
    """The ``warnings.warn`` stack level of the first caller outside sonar_gym and gymnasium,
    so the warning points at the user's ``gym.make`` (or config construction) line."""
    module_files = (__file__, gymnasium.__file__, sys.modules["sonar_gym"].__file__)
    library_dirs = tuple(
        {str(Path(f).resolve().parent) + os.sep for f in module_files if f is not None}
        | {str(Path(__file__).parent) + os.sep}
    )
    frame: FrameType | None = sys._getframe(1)  # the caller: _with_new_names
    level = 1
    while frame is not None:
        path = frame.f_code.co_filename
        resolved = path if path.startswith("<") else str(Path(path).resolve())
        if not resolved.startswith(library_dirs) and not path.startswith(library_dirs):
            return level
        frame = frame.f_back
        level += 1
    return level


def check_number(
    name: str,
    value: object,
    *,
    low: float | None = None,
    high: float | None = None,
    low_inclusive: bool = True,
    integer: bool = False,
) -> int | float:
    """Return ``value`` as a Python number if finite and in range; else raise ``ValueError``.

    ``low_inclusive=False`` is read as "at least :data:`~sonar_gym.validation.MIN_SCALE`
    above ``low``", never as an open bound a denormal could slip through; prefer an explicit
    physical floor as ``low``.
    """
    if not low_inclusive and low is not None:
        low = low + MIN_SCALE * max(1.0, abs(low))
    return checked_number(f"argument {name!r}", value, low=low, high=high, integer=integer)


def check_choice(name: str, value: object, allowed: Iterable[object]) -> Any:
    """Return the member of ``allowed`` equal to ``value``; else raise ``ValueError``."""
    return checked_choice(f"argument {name!r}", value, list(allowed))


def check_bool(name: str, value: object) -> bool:
    """Return a Python or numpy bool as ``bool``; else raise ``ValueError``."""
    return checked_bool(f"argument {name!r}", value)


def _store(config: object, name: str, value: object) -> None:
    object.__setattr__(config, name, value)


def number_field(
    config: object,
    name: str,
    *,
    low: float | None = None,
    high: float | None = None,
    integer: bool = False,
    optional: bool = False,
) -> None:
    """Check the number field ``name`` of a frozen config and store it as a Python number.

    ``optional``: ``None`` is also allowed (and kept).
    """
    value = getattr(config, name)
    if optional and value is None:
        return
    _store(config, name, check_number(name, value, low=low, high=high, integer=integer))


def numbers_field(
    config: object,
    name: str,
    *,
    low: float | None = None,
    high: float | None = None,
    integer: bool = False,
    length: int | None = None,
    min_length: int = 0,
    max_length: int | None = None,
    distinct: bool = False,
) -> tuple[int | float, ...]:
    """Check a tuple-of-numbers field (lists accepted), store it as a tuple and return it."""
    values = checked_numbers(
        f"argument {name!r}",
        getattr(config, name),
        low=low,
        high=high,
        integer=integer,
        length=length,
        min_length=min_length,
        max_length=max_length,
    )
    if distinct and len(set(values)) != len(values):
        raise ValueError(f"argument {name!r} must hold distinct values; got {values!r}")
    _store(config, name, values)
    return values


def choice_field(config: object, name: str, allowed: Iterable[object]) -> None:
    """Check a field against its allowed values and store the plain allowed value."""
    _store(config, name, check_choice(name, getattr(config, name), allowed))


def bool_field(config: object, name: str) -> None:
    """Check a bool field (numpy bools accepted) and store it as ``bool``."""
    _store(config, name, check_bool(name, getattr(config, name)))


def scenario_field(config: object, name: str = "scenario", extra: str = "") -> None:
    """Check a scenario argument: a non-empty name or path of at most 4096 characters.

    Whether the name or file exists is the loader's question
    (:func:`sonar_gym.scenario.load_scenario`), which answers with a ``ScenarioError``.
    ``extra`` describes further accepted values for the message (e.g. ``", or 'random'"``).
    """
    value = getattr(config, name)
    text = str(value) if isinstance(value, (str, Path)) else None
    if text is None or not text.strip() or len(text) > MAX_SCENARIO_ARGUMENT_CHARS:
        raise ValueError(
            f"argument {name!r} must be a built-in scenario name or a path to a .toml or .json "
            f"file (a non-empty string of at most {MAX_SCENARIO_ARGUMENT_CHARS} characters)"
            f"{extra}; got {shown(value)}"
        )
