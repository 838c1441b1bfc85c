"""One validator for every number a user gives: ``gym.make`` arguments and scenario fields.

:func:`checked_number` accepts Python and numpy numbers (``np.int64(8)``, ``np.float32(21.0)``)
and returns a plain Python ``int`` or ``float``, so configs stay hashable and comparable. It
refuses, with a ``ValueError`` (or the subclass the caller passes) naming the subject, the
value and what is allowed:

- bools (``True`` is not the number 1 here), strings, complex numbers and other types;
- NaN, infinities and integers too large for a float (``10**400``);
- anything outside ``[low, high]``. ``-0.0`` is read as ``0.0``, so it passes a ``>= 0`` check
  and never reaches numpy as a negative scale.

There is no open "> 0" bound: a quantity that must be positive gets a physically meaningful
floor instead (:data:`MIN_SPEED_MPS`, :data:`MIN_SCALE`, ...), so a denormal such as
``5e-324`` cannot pass and later divide by zero.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

MIN_SCALE = 1e-6
"""Least value of a positive scale, standard deviation, gate or interval, in its own unit."""
MIN_SPEED_MPS = 1e-3
"""Least positive speed, metres (or radians) per second: slower never finishes an episode."""
MIN_LENGTH_M = 1e-3
"""Least positive length in metres (one millimetre)."""
MIN_DURATION_S = 1e-6
"""Least positive duration, interval or time budget, seconds (one microsecond)."""
MIN_TIMER_PERIOD_S = 1e-12
"""Least positive period of a time-of-flight counter, seconds (a 1 THz counter; 0 means no
counter). A period near the float minimum would put ``time / period`` past the float range,
so every reading would overflow to a dropout instead of staying unquantised."""
MIN_VARIANCE = MIN_SCALE**2
"""Least positive variance: the square of :data:`MIN_SCALE` in the variance's unit."""
MAX_SHOWN_CHARS = 60
"""Longest ``repr`` of a refused value quoted in a message (a 400-digit integer is cut)."""


def shown(value: object) -> str:
    """``repr(value)``, cut to :data:`MAX_SHOWN_CHARS` characters for error messages."""
    try:
        text = repr(value)
    except ValueError:  # an int past Python's digit limit for str()
        text = f"<{type(value).__name__} too large to print>"
    if len(text) > MAX_SHOWN_CHARS:
        text = f"{text[: MAX_SHOWN_CHARS - 15]}...({len(text)} chars)"
    return text


def is_bool(value: object) -> bool:
    """Whether ``value`` is a Python or numpy bool."""
    return isinstance(value, (bool, np.bool_))


def checked_number(
    subject: str,
    value: object,
    *,
    low: float | None = None,
    high: float | None = None,
    integer: bool = False,
    error: type[ValueError] = ValueError,
) -> int | float:
    """Return ``value`` as a Python number if it is finite and in ``[low, high]``; else raise.

    Args:
        subject: how the message names the value, e.g. ``"argument 'n_bins'"`` or
            ``"lab.toml: field 'room.min'"``.
        value: the number to check (Python or numpy int/float; bools are refused).
        low, high: inclusive bounds, in the value's unit; ``None`` for none.
        integer: require an integer (a float such as ``8.0`` is refused).
        error: the exception class to raise (a ``ValueError`` subclass).

    Returns:
        ``int`` when ``integer`` is set, else ``float``; ``-0.0`` comes back as ``0.0``.
    """
    if integer:
        kind = "a positive integer" if low is not None and low > 0 else "an integer"
    else:
        kind = "a positive number" if low is not None and low > 0 else "a finite number"
    allowed = kind
    if low is not None or high is not None:
        lower = "-inf" if low is None else f"{low:g}"
        upper = "inf" if high is None else f"{high:g}"
        allowed = f"{kind} in [{lower}, {upper}]"
    wanted: tuple[type, ...] = (numbers.Integral,) if integer else (numbers.Real,)
    if is_bool(value) or not isinstance(value, wanted):
        raise error(f"{subject} must be {allowed}; got {shown(value)}")
    try:
        number: int | float = int(value) if integer else float(value)  # type: ignore[call-overload, arg-type]
        as_float = float(number)
    except (OverflowError, ValueError) as overflow:
        raise error(f"{subject} must be {allowed}; got {shown(value)}") from overflow
    if not math.isfinite(as_float):
        raise error(f"{subject} must be {allowed}; got {shown(value)}")
    if not integer:
        number = as_float + 0.0  # -0.0 + 0.0 == +0.0
    if (low is not None and number < low) or (high is not None and number > high):
        raise error(f"{subject} must be {allowed}; got {shown(value)}")
    return number


def checked_array(
    value: npt.ArrayLike, name: str, shape: tuple[int | None, ...]
) -> npt.NDArray[np.float64]:
    """``value`` as a float64 array of ``shape`` (``None``: any length), all finite; else a
    ``ValueError`` naming argument ``name``."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"argument {name!r} must be a numeric array; got {value!r}") from error
    if array.ndim != len(shape) or any(
        want is not None and got != want for got, want in zip(array.shape, shape, strict=True)
    ):
        wanted = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"argument {name!r} must have shape {wanted}; got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"argument {name!r} must be finite; got {array!r}")
    return array


def checked_positive(value: float, name: str) -> float:
    """``value`` as a float if finite and > 0; else a ``ValueError`` naming argument ``name``."""
    number = float(value)
    if not (math.isfinite(number) and number > 0.0):
        raise ValueError(f"argument {name!r} must be a finite positive number; got {value!r}")
    return number


def checked_sequence(
    subject: str,
    value: object,
    *,
    length: int | None = None,
    min_length: int = 0,
    max_length: int | None = None,
    error: type[ValueError] = ValueError,
) -> tuple[object, ...]:
    """Return a list, tuple or 1-D numpy array as a tuple of its items; else raise.

    Lists are accepted wherever tuples are, since gymnasium's ``EnvSpec.to_json`` turns
    tuples into lists.
    """
    if isinstance(value, np.ndarray) and value.ndim == 1:
        value = value.tolist()
    if length is not None:
        allowed = f"a sequence of {length} items"
    elif max_length is not None:
        allowed = f"a sequence of {min_length} to {max_length} items"
    else:
        allowed = f"a sequence of at least {min_length} items"
    if not isinstance(value, (list, tuple)):
        raise error(f"{subject} must be {allowed}; got {shown(value)}")
    items = tuple(value)
    too_short = len(items) < (length if length is not None else min_length)
    too_long = (length is not None and len(items) > length) or (
        max_length is not None and len(items) > max_length
    )
    if too_short or too_long:
        raise error(f"{subject} must be {allowed}; got {shown(value)}")
    return items


def checked_numbers(
    subject: str,
    value: object,
    *,
    low: float | None = None,
    high: float | None = None,
    integer: bool = False,
    length: int | None = None,
    min_length: int = 0,
    max_length: int | None = None,
    error: type[ValueError] = ValueError,
) -> tuple[int | float, ...]:
    """A sequence of numbers, each checked by :func:`checked_number` as ``subject[i]``."""
    items = checked_sequence(
        subject, value, length=length, min_length=min_length, max_length=max_length, error=error
    )

    def item_subject(i: int) -> str:  # "argument 'x'" -> "argument 'x[0]'"
        return f"{subject[:-1]}[{i}]'" if subject.endswith("'") else f"{subject}[{i}]"

    return tuple(
        checked_number(item_subject(i), item, low=low, high=high, integer=integer, error=error)
        for i, item in enumerate(items)
    )


def checked_bool(subject: str, value: object, *, error: type[ValueError] = ValueError) -> bool:
    """Return a Python or numpy bool as ``bool``; refuse everything else (``1`` included)."""
    if not is_bool(value):
        raise error(f"{subject} must be True or False; got {shown(value)}")
    return bool(value)


def checked_choice(
    subject: str, value: object, allowed: Sequence[object], *, error: type[ValueError] = ValueError
) -> object:
    """Return the member of ``allowed`` equal to ``value`` (so numpy scalars come back plain)."""
    for option in allowed:
        if (
            type(option) is not bool
            and not is_bool(value)
            and isinstance(value, (str, numbers.Number))
            and value == option
        ):
            return option
        if is_bool(option) and is_bool(value) and bool(value) == option:
            return option
    raise error(f"{subject} must be one of {list(allowed)}; got {shown(value)}")
