"""Shared settings and strategies of the property-based (fuzz) tests.

Every fuzz test runs a fixed number of examples, derandomized and without an example database,
so CI sees the same inputs every run. ``SONAR_GYM_FUZZ_SCALE=10`` multiplies the number of
examples for a deeper run by hand; ``pytest --hypothesis-show-statistics`` then prints how
often each outcome (``hypothesis.event``) occurred.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np
from hypothesis import HealthCheck, Phase, settings
from hypothesis import strategies as st

FUZZ_SCALE = int(os.environ.get("SONAR_GYM_FUZZ_SCALE", "1"))
"""Multiplier of every fuzz test's example count (1 in the default run)."""


def fuzz_settings(examples: int = 300, *, shrink: bool = True) -> settings:
    """``examples * FUZZ_SCALE`` derandomized examples, no deadline, no database.

    ``shrink=False`` for tests marked ``xfail`` (a known failure need not be minimised on
    every run).
    """
    phases = list(Phase) if shrink else [Phase.explicit, Phase.reuse, Phase.generate]
    return settings(
        max_examples=examples * FUZZ_SCALE,
        phases=phases,
        deadline=None,
        derandomize=True,
        database=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
    )


EDGE_NUMBERS: list[Any] = [
    -0.0,
    0.0,
    5e-324,
    -5e-324,
    1e-300,
    1e-9,
    1e-6,
    1.0,
    -1.0,
    math.nan,
    math.inf,
    -math.inf,
    10**400,
    -(10**400),
    2**63,
    1e300,
]
"""Numbers that broke argument checks before: signed zero, denormals, overflow, non-finite."""


def numpy_scalar(value: float | int) -> Any:
    """``value`` as a numpy scalar (int64 or float64); integers past int64 stay Python ints."""
    if isinstance(value, int):
        return np.int64(value) if abs(value) < 2**62 else value
    return np.float64(value)


def nasty_number() -> st.SearchStrategy[Any]:
    """Edge numbers, any float, any int, and numpy scalars of them."""
    plain = st.one_of(
        st.sampled_from(EDGE_NUMBERS),
        st.floats(allow_nan=True, allow_infinity=True),
        st.integers(min_value=-(10**6), max_value=10**6),
    )
    return st.one_of(plain, plain.map(numpy_scalar))


def near(default: float | int) -> st.SearchStrategy[Any]:
    """Values around a valid default: scaled by [0, 3], shifted by a little, or its numpy twin."""
    if isinstance(default, bool):
        return st.sampled_from([default, np.bool_(default)])
    if isinstance(default, int):
        return st.one_of(
            st.integers(min_value=default - 3, max_value=default * 3 + 3),
            st.integers(min_value=default - 3, max_value=default * 3 + 3).map(np.int64),
        )
    return st.one_of(
        st.floats(min_value=0.0, max_value=3.0).map(lambda k: default * k),
        st.floats(min_value=-1.0, max_value=1.0).map(lambda d: default + d),
        st.just(np.float32(default)),
    )


def wrong_type() -> st.SearchStrategy[Any]:
    """Values of the wrong kind for any argument."""
    return st.one_of(
        st.none(),
        st.booleans(),
        st.text(max_size=6),
        st.lists(st.floats(allow_nan=False), max_size=3),
        st.just(1j),
        st.just({"a": 1}),
        st.just(np.array([[1.0, 2.0]])),
    )


def value_like(default: Any) -> st.SearchStrategy[Any]:
    """Arguments a user might pass where ``default`` is the valid default."""
    if isinstance(default, bool):
        return st.one_of(near(default), st.integers(0, 1), wrong_type())
    if isinstance(default, (int, float)):
        return st.one_of(near(default), nasty_number(), wrong_type())
    if isinstance(default, tuple):
        element = (
            st.one_of(*(near(v) for v in default[:1]), nasty_number())
            if default
            else (nasty_number())
        )
        return st.one_of(
            st.just(list(default)),
            st.permutations(list(default)).map(tuple),
            st.lists(element, max_size=max(len(default) + 1, 2)),
            st.lists(element, max_size=4).map(tuple),
            st.just(np.asarray(default)),
            wrong_type(),
        )
    if isinstance(default, str):
        return st.one_of(
            st.just(default),
            st.just(default.upper()),
            st.text(max_size=8),
            st.sampled_from(["", "   ", "x" * 5000, "/", "random"]),
            wrong_type(),
        )
    return st.one_of(st.just(default), nasty_number(), wrong_type())
