"""Action types: how a task's choices become a Gymnasium space and back (HighwayEnv's
``action_factory`` idea, with a checked registry in place of an unchecked config dict).

A discrete task describes its choices once, as :class:`DiscreteChoices`: a ``kind`` index
followed by parameter indices (a pan's centre, width and increment; a leg's spacing and
stand-off). An action type turns that description into a space and converts between the space's
elements and the *index tuple* ``(kind, parameter, ...)`` the task works with:

* ``"multi_discrete"`` (:class:`MultiDiscreteActions`): ``MultiDiscrete(sizes)``, the index
  tuple as an int64 vector (PPO, A2C);
* ``"discrete"`` (:class:`FlatDiscreteActions`): the same choices flattened into one
  ``Discrete`` (DQN). Kinds without parameters take one code each, first; every other kind
  takes one block of codes, one code per combination of its parameters, in row-major order;
* ``"box"`` (:class:`BoxActions`): a continuous task's values in ``[low, high]``, scaled to the
  symmetric ``Box(-1, 1)`` that SB3's checker asks for (SAC, PPO).

Envs pick theirs with :func:`make_action_type` from :data:`ACTION_TYPES`, never with if/else.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
import numpy.typing as npt

from sonar_gym.validation import shown


@dataclass(frozen=True)
class DiscreteChoices:
    """What a discrete task lets its agent choose.

    Attributes:
        sizes: the number of options of each index, the kind first (``sizes[0]`` kinds), then
            each parameter.
        parameterless_kinds: kinds whose parameters are ignored (calibrate, localize); in the
            flattened form each takes a single code, in this order, before the other kinds.
    """

    sizes: tuple[int, ...]
    parameterless_kinds: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        if not self.sizes or any(int(size) < 1 for size in self.sizes):
            raise ValueError(
                f"field 'sizes' must hold at least one size, each >= 1; got {self.sizes!r}"
            )
        kinds = self.sizes[0]
        if len(set(self.parameterless_kinds)) != len(self.parameterless_kinds) or any(
            not 0 <= kind < kinds for kind in self.parameterless_kinds
        ):
            raise ValueError(
                f"field 'parameterless_kinds' must hold distinct kinds in [0, {kinds - 1}]; "
                f"got {self.parameterless_kinds!r}"
            )

    @property
    def parameter_sizes(self) -> tuple[int, ...]:
        """The sizes of the parameter indices (everything after the kind)."""
        return self.sizes[1:]


@dataclass(frozen=True)
class ContinuousRange:
    """What a continuous task lets its agent choose: one value per component in
    ``[low, high]`` (the task's own units, e.g. fractions of a distance range)."""

    low: tuple[float, ...]
    high: tuple[float, ...]

    def __post_init__(self) -> None:
        if len(self.low) != len(self.high) or not self.low:
            raise ValueError(
                f"fields 'low' and 'high' must have the same length >= 1; got {self.low!r} "
                f"and {self.high!r}"
            )
        if not all(
            math.isfinite(lo) and math.isfinite(hi) and lo < hi
            for lo, hi in zip(self.low, self.high, strict=True)
        ):
            raise ValueError(
                f"fields 'low' and 'high' must be finite with low < high in every component; "
                f"got {self.low!r} and {self.high!r}"
            )

    @classmethod
    def unit(cls, size: int) -> ContinuousRange:
        """``size`` components in ``[0, 1]``."""
        return cls((0.0,) * size, (1.0,) * size)


class ActionType(ABC):
    """One way of presenting a task's choices to an agent: a space and its codec.

    Attributes:
        name: the registry name (the value of a config's ``action_type``).
        space: the Gymnasium action space.
    """

    name: ClassVar[str]
    space: gym.Space[Any]

    @abstractmethod
    def encode(self, choice: Any) -> Any:
        """The element of ``space`` that stands for ``choice``."""

    @abstractmethod
    def decode(self, action: Any) -> Any:
        """The choice an element of ``space`` stands for (``action`` unchecked: see
        :meth:`check`)."""

    @abstractmethod
    def allowed(self) -> str:
        """What the elements of ``space`` are, in words, for error messages."""

    def check(self, action: Any) -> None:
        """Refuse an ``action`` outside ``space`` (what an env's ``decode_action`` calls before
        :meth:`decode`; ``step`` checks with its own fast path).

        Raises:
            ValueError: ``action`` is not an element of ``space``; the message names it and
                what is allowed.
        """
        if not self._contains(action):
            raise ValueError(
                f"argument 'action' must be an element of the action space {self.space}: "
                f"{self.allowed()}; got {shown(action)}"
            )

    def _contains(self, action: Any) -> bool:
        try:
            return bool(self.space.contains(action))
        except (TypeError, ValueError):  # e.g. a ragged nested list
            return False


class _DiscreteActionType(ActionType):
    """A discrete type over :class:`DiscreteChoices`; choices are index tuples."""

    def __init__(self, choices: DiscreteChoices) -> None:
        if not isinstance(choices, DiscreteChoices):
            raise ValueError(
                f"action type {self.name!r} needs DiscreteChoices; got {type(choices).__name__}"
            )
        self.choices = choices

    @abstractmethod
    def encode(self, choice: Sequence[int]) -> Any:
        """The action for the index tuple ``(kind, parameter, ...)``."""

    @abstractmethod
    def decode(self, action: Any) -> tuple[int, ...]:
        """The index tuple ``(kind, parameter, ...)`` of an action (parameters 0 where the
        kind ignores them)."""


class MultiDiscreteActions(_DiscreteActionType):
    """``MultiDiscrete(sizes)``: the index tuple itself, as an int64 vector."""

    name = "multi_discrete"
    space: gym.spaces.MultiDiscrete

    def __init__(self, choices: DiscreteChoices) -> None:
        super().__init__(choices)
        self.space = gym.spaces.MultiDiscrete(list(choices.sizes))

    def encode(self, choice: Sequence[int]) -> np.ndarray:
        return np.array(choice, dtype=np.int64)

    def allowed(self) -> str:
        ranges = ", ".join(f"[0, {size - 1}]" for size in self.choices.sizes)
        return f"{len(self.choices.sizes)} integers, in {ranges}"

    def decode(self, action: Any) -> tuple[int, ...]:
        if type(action) is np.ndarray and action.dtype.kind in "iu":
            return tuple(action.tolist())
        return tuple(int(value) for value in action)


class FlatDiscreteActions(_DiscreteActionType):
    """``Discrete(n)``: every choice one code (see the module docstring for the order)."""

    name = "discrete"
    space: gym.spaces.Discrete

    def __init__(self, choices: DiscreteChoices) -> None:
        super().__init__(choices)
        self._parameterless = choices.parameterless_kinds
        self._kinds_with_parameters = tuple(
            kind for kind in range(choices.sizes[0]) if kind not in self._parameterless
        )
        self._block = math.prod(choices.parameter_sizes)
        self.space = gym.spaces.Discrete(
            len(self._parameterless) + len(self._kinds_with_parameters) * self._block
        )

    def encode(self, choice: Sequence[int]) -> int:
        kind, *parameters = (int(index) for index in choice)
        if kind in self._parameterless:
            return self._parameterless.index(kind)
        code = 0
        for index, size in zip(parameters, self.choices.parameter_sizes, strict=True):
            code = code * size + index
        block = self._kinds_with_parameters.index(kind)
        return len(self._parameterless) + block * self._block + code

    def allowed(self) -> str:
        return f"an integer in [0, {self.space.n - 1}]"

    def decode(self, action: Any) -> tuple[int, ...]:
        code = int(action)
        n_parameterless = len(self._parameterless)
        sizes = self.choices.parameter_sizes
        if code < n_parameterless:
            return (self._parameterless[code], *(0 for _ in sizes))
        block, rest = divmod(code - n_parameterless, self._block)
        parameters = []
        for size in reversed(sizes):
            rest, index = divmod(rest, size)
            parameters.append(index)
        return (self._kinds_with_parameters[block], *reversed(parameters))


class BoxActions(ActionType):
    """``Box(-1, 1, (n,), float32)`` over :class:`ContinuousRange`: ``-1`` is ``low``, ``1``
    is ``high``; a decoded value is clipped into the range first (for an action :meth:`check`
    accepts, that moves only a value float32 rounds to -1 or 1)."""

    name = "box"
    space: gym.spaces.Box

    def __init__(self, choices: ContinuousRange) -> None:
        if not isinstance(choices, ContinuousRange):
            raise ValueError(
                f"action type {self.name!r} needs a ContinuousRange; got {type(choices).__name__}"
            )
        self.choices = choices
        self._low = np.asarray(choices.low, dtype=np.float64)
        self._span = np.asarray(choices.high, dtype=np.float64) - self._low
        self.space = gym.spaces.Box(-1.0, 1.0, shape=(len(choices.low),), dtype=np.float32)

    def encode(self, choice: npt.ArrayLike) -> np.ndarray:
        """The action for values in the range (float32, in ``[-1, 1]`` for values inside it)."""
        values = np.asarray(choice, dtype=np.float64)
        return (2.0 * ((values - self._low) / self._span) - 1.0).astype(np.float32)

    def allowed(self) -> str:
        return f"{self.space.shape[0]} finite numbers in [-1, 1]"

    def _contains(self, action: Any) -> bool:
        """Finite values of the space's shape that lie in ``[-1, 1]`` once in float32, as
        ``step`` takes them (any float dtype: a helper need not insist on float32)."""
        try:
            values = np.asarray(action, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            return False
        if values.shape != self.space.shape or not np.isfinite(values).all():
            return False
        with np.errstate(over="ignore"):  # past float32's range: inf, outside the bounds
            as_space = values.astype(self.space.dtype)
        return bool(np.all(as_space >= self.space.low) and np.all(as_space <= self.space.high))

    def decode(self, action: npt.ArrayLike) -> np.ndarray:
        """The values (float64) an action stands for."""
        values = np.asarray(action, dtype=np.float64).reshape(-1)
        if values.shape != self.space.shape:
            raise ValueError(f"action must have shape {self.space.shape}; got {values.shape}")
        return self._low + (np.clip(values, -1.0, 1.0) + 1.0) / 2.0 * self._span


ACTION_TYPES: dict[str, type[ActionType]] = {
    kind.name: kind for kind in (MultiDiscreteActions, FlatDiscreteActions, BoxActions)
}
"""The registered action types by name."""


def make_action_type(name: str, choices: DiscreteChoices | ContinuousRange) -> ActionType:
    """The action type registered as ``name`` over ``choices``.

    Raises:
        ValueError: ``name`` is not registered (the message lists the names), or ``choices``
            is not what that type takes.
    """
    try:
        kind = ACTION_TYPES[name]
    except (KeyError, TypeError):
        raise ValueError(
            f"argument 'action_type' must be one of {sorted(ACTION_TYPES)}; got {name!r}"
        ) from None
    return kind(choices)  # type: ignore[call-arg]
