"""A cheap exact stand-in for ``action_space.contains`` on the step path.

Gymnasium's ``MultiDiscrete.contains`` and ``Discrete.contains`` go through several NumPy
calls and reductions, a noticeable share of a sonar_gym step. :class:`ActionCheck` answers the
common cases (an integer array of the space's own dtype and shape; a Python int or NumPy
scalar of the space's dtype) with plain integer comparisons, and hands every other value to
``space.contains``, so it accepts and rejects exactly what ``space.contains`` does.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np


class ActionCheck:
    """``space.contains`` with fast paths for ``MultiDiscrete`` and ``Discrete`` spaces.

    The space's bounds are read once, at construction; make a new check when the space's
    ``start``, ``nvec`` or ``n`` change (the env rebuilds it whenever ``action_space`` is
    replaced or these arrays are reassigned).
    """

    def __init__(self, space: gym.Space[Any]) -> None:
        self.space = space
        self._start: Any = None
        self._nvec: Any = None
        self._low: list[int] = []
        self._high: list[int] = []
        kind = type(space)
        self._multi_discrete = kind is gym.spaces.MultiDiscrete
        self._discrete = kind is gym.spaces.Discrete and space.dtype == np.int64
        if isinstance(space, gym.spaces.MultiDiscrete) and self._multi_discrete:
            self._start, self._nvec = space.start, space.nvec
            self._low = space.start.ravel().tolist()
            self._high = (space.start + (space.nvec - 1)).ravel().tolist()
        elif isinstance(space, gym.spaces.Discrete) and self._discrete:
            self._start, self._nvec = space.start, space.n
            self._low = [int(space.start)]
            self._high = [int(space.start) + int(space.n) - 1]

    def is_current_for(self, space: gym.Space[Any]) -> bool:
        """Whether this check was built for ``space`` as it is now (same bound arrays)."""
        if space is not self.space:
            return False
        if self._multi_discrete:
            return space.start is self._start and space.nvec is self._nvec  # type: ignore[attr-defined]
        if self._discrete:
            return space.start is self._start and space.n is self._nvec  # type: ignore[attr-defined]
        return True

    def __call__(self, action: Any) -> bool:
        """Whether ``action`` lies in the space; the same answer as ``space.contains``."""
        space = self.space
        if self._multi_discrete:
            if (
                type(action) is np.ndarray
                and action.dtype == space.dtype
                and action.shape == space.shape
            ):
                values = action.ravel().tolist()
                return all(
                    low <= value <= high
                    for low, value, high in zip(self._low, values, self._high, strict=True)
                )
        elif self._discrete and (type(action) is int or type(action) is np.int64):
            return self._low[0] <= int(action) <= self._high[0]
        return bool(space.contains(action))
