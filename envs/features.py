"""Observation features: what each slice of a task's observation vector holds.

A task declares its observation as a list of features (HighwayEnv's observation types, kept
as plain data): each :class:`Feature` has a name, a size and the range its values stay in.
:class:`ObservationSpec` turns the list into the Gymnasium ``Box`` (always
``Box(-1, 1, (n,), float32)``, the symmetric normalised range SB3's checker asks for), the
``observation_layout`` (name -> slice, in declaration order, covering the vector without a
gap or overlap) and a writer that fills a fresh vector by feature name.

The feature types that compute their own values live here too, so that each mapping has one
home: :class:`ScaledPosition` (a position scaled from the room's bounds to [-1, 1]),
:class:`Heading` (cos, sin of an angle), :class:`RangeBins` (the nearest sonar range per
angular bin, as a fraction of the maximum range) and :class:`ScannedBins` (which bins a pan has
covered). :data:`FEATURE_TYPES` lists them by name.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import ClassVar, TypeGuard

import gymnasium as gym
import numpy as np
import numpy.typing as npt
from numba import types

from sonar_gym.compiled import NUMBERS, compiled
from sonar_gym.pose import FloatArray

OBSERVATION_LOW, OBSERVATION_HIGH = -1.0, 1.0
"""The bounds of every observation vector (each feature's range lies inside them)."""


@dataclass(frozen=True)
class Feature:
    """One named slice of an observation vector.

    Attributes:
        name: the key in ``observation_layout``.
        size: how many entries it takes.
        low, high: the range its values stay in (inside [-1, 1]).
    """

    name: str
    size: int = 1
    low: float = OBSERVATION_LOW
    high: float = OBSERVATION_HIGH
    kind: ClassVar[str] = "value"

    def __post_init__(self) -> None:
        if not self.name:
            raise ValueError("field 'name' of a Feature must be a non-empty string; got ''")
        if isinstance(self.size, bool) or not isinstance(self.size, int) or self.size < 1:
            raise ValueError(
                f"field 'size' of feature {self.name!r} must be an integer >= 1; got {self.size!r}"
            )
        if not OBSERVATION_LOW <= self.low <= self.high <= OBSERVATION_HIGH:
            raise ValueError(
                f"fields 'low' and 'high' of feature {self.name!r} must satisfy "
                f"-1 <= low <= high <= 1; got {self.low!r} and {self.high!r}"
            )


@dataclass(frozen=True)
class Flag(Feature):
    """Values in {0, 1} (a yes/no, or a one-hot group)."""

    low: float = 0.0
    kind: ClassVar[str] = "flag"


@dataclass(frozen=True)
class Fraction(Feature):
    """Values in [0, 1] (a share, or a non-negative quantity over its scale, capped)."""

    low: float = 0.0
    kind: ClassVar[str] = "fraction"


@dataclass(frozen=True)
class ScaledPosition(Feature):
    """A position, each coordinate mapped from the room's ``[low, high]`` to [-1, 1], clipped."""

    size: int = 2
    kind: ClassVar[str] = "scaled_position"

    @staticmethod
    def values(position: npt.ArrayLike, low: npt.ArrayLike, high: npt.ArrayLike) -> np.ndarray:
        """``2 (p - low) / (high - low) - 1`` per coordinate, clipped to [-1, 1] (float64).

        Args:
            position, low, high: ``(size,)`` in the same frame and unit (metres in {W}).
        """
        return np.array(ScaledPosition.float_values(position, low, high), dtype=np.float64)

    @staticmethod
    def float_values(
        position: npt.ArrayLike, low: npt.ArrayLike, high: npt.ArrayLike
    ) -> list[float]:
        """:meth:`values` as Python floats."""
        # On Python floats: numpy's six calls on two coordinates cost more than the arithmetic,
        # which rounds the same, step by step; clipped as np.clip does (NaN stays).
        if _is_float_pair(position) and _is_float_pair(low) and _is_float_pair(high):
            # how tasks pass a point and the room's corners: the same arithmetic, unrolled
            (x, y), (low_x, low_y), (high_x, high_y) = position, low, high
            return [
                clipped(2.0 * (x - low_x) / (high_x - low_x) - 1.0, -1.0, 1.0),
                clipped(2.0 * (y - low_y) / (high_y - low_y) - 1.0, -1.0, 1.0),
            ]
        return [
            clipped(2.0 * (p - lo) / (hi - lo) - 1.0, -1.0, 1.0)
            for p, lo, hi in zip(_floats(position), _floats(low), _floats(high), strict=True)
        ]

    @staticmethod
    def centred_values(
        position: npt.ArrayLike, centre: npt.ArrayLike, half_size: npt.ArrayLike
    ) -> np.ndarray:
        """``(p - centre) / half_size``, clipped to [-1, 1] (float64): the same map written
        from the room's centre (it differs from :meth:`values` in the last bits)."""
        offset = np.asarray(position, dtype=np.float64) - np.asarray(centre, dtype=np.float64)
        return np.clip(offset / np.asarray(half_size, dtype=np.float64), -1.0, 1.0)


@dataclass(frozen=True)
class Heading(Feature):
    """An angle as its cosine and sine (radians in; no wrap-around jump)."""

    size: int = 2
    kind: ClassVar[str] = "heading"

    @staticmethod
    def values(angle_rad: float) -> tuple[float, float]:
        """``(cos, sin)`` of ``angle_rad``."""
        return math.cos(angle_rad), math.sin(angle_rad)


@dataclass(frozen=True)
class RangeBins(Feature):
    """The nearest range per angular bin of a scan, as a fraction of the maximum range; a bin
    without an echo (or without a ping) reads 1. ``size`` is the number of bins."""

    low: float = 0.0
    kind: ClassVar[str] = "range_bins"

    def values(self, range_fractions: npt.ArrayLike | None) -> np.ndarray:
        """Nearest of ``range_fractions`` (ranges / max range, NaN for a dropout) per bin of
        consecutive pings (float64, ``(size,)``); ping ``i`` of ``m`` falls in bin
        ``i * size // m``."""
        if range_fractions is None:
            return np.ones(self.size)
        fractions = np.asarray(range_fractions, dtype=np.float64)
        if fractions.size == 0:
            return np.ones(self.size)
        if fractions.ndim != 1:
            fractions = fractions.reshape(-1)
        return _nearest_per_bin(fractions, self.size)  # type: ignore[no-any-return]


def clipped(value: float, low: float, high: float) -> float:
    """``min(max(value, low), high)`` for ``low <= high``: ``max`` keeps ``value`` unless
    ``low > value``, ``min`` keeps that unless ``high < value``; so NaN stays, as in np.clip.
    Two comparisons cost less than the two builtin calls."""
    return low if low > value else high if high < value else value


def _is_float_pair(values: object) -> TypeGuard[tuple[float, float]]:
    """Whether ``values`` is a tuple of two Python floats (a point as tasks pass it)."""
    return (
        type(values) is tuple
        and len(values) == 2
        and type(values[0]) is float
        and type(values[1]) is float
    )


def _floats(values: npt.ArrayLike) -> Sequence[float]:
    """``values`` as a flat sequence of Python floats (a tuple of floats as it is)."""
    if type(values) is tuple and all(type(value) is float for value in values):
        return values
    return np.asarray(values, dtype=np.float64).reshape(-1).tolist()  # type: ignore[no-any-return]


@compiled(types.Array(types.float64, 1, "C"), NUMBERS, types.int64)  # type: ignore[misc]
def _nearest_per_bin(fractions: FloatArray, bins: int) -> FloatArray:
    """:meth:`RangeBins.values` of ``fractions``: each clipped to [0, 1] (1 where not finite),
    the smallest per bin (ping ``i`` of ``m`` in bin ``i * bins // m``), 1 in an empty bin."""
    nearest = np.ones(bins)
    pings = fractions.shape[0]
    for ping in range(pings):
        fraction = fractions[ping]
        value = min(max(fraction, 0.0), 1.0) if math.isfinite(fraction) else 1.0
        slot = ping * bins // pings
        if value < nearest[slot]:
            nearest[slot] = value
    return nearest


@dataclass(frozen=True)
class ScannedBins(Feature):
    """1 where a pan has covered any slot of the bin, else 0. ``size`` is the number of bins;
    the slots divide evenly into them."""

    low: float = 0.0
    kind: ClassVar[str] = "scanned_bins"

    def values(self, scanned: npt.ArrayLike) -> np.ndarray:
        """Whether any of ``scanned`` (booleans per slot) is set, per bin (bool, ``(size,)``)."""
        slots = np.asarray(scanned, dtype=bool)
        if slots.size % self.size:
            raise ValueError(
                f"argument 'scanned' must hold a multiple of {self.size} slots; got {slots.size}"
            )
        return np.logical_or.reduce(slots.reshape(self.size, -1), axis=1)


FEATURE_TYPES: dict[str, type[Feature]] = {
    kind.kind: kind
    for kind in (Feature, Flag, Fraction, ScaledPosition, Heading, RangeBins, ScannedBins)
}
"""The feature types by name."""


class ObservationSpec:
    """A task's observation: its features in order, the space, the layout and a writer.

    Attributes:
        features: the features in vector order.
        layout: feature name -> its slice of the vector (shared; :meth:`observation_layout`
            gives a copy to hand out).
        size: the vector's length.
        space: ``Box(-1, 1, (size,), float32)``.
    """

    def __init__(self, features: Sequence[Feature]) -> None:
        if not features:
            raise ValueError("argument 'features' must hold at least one Feature; got none")
        names = [feature.name for feature in features]
        repeated = sorted({name for name in names if names.count(name) > 1})
        if repeated:
            raise ValueError(f"argument 'features' repeats the name(s) {repeated}")
        self.features = tuple(features)
        self.layout: dict[str, slice] = {}
        start = 0
        for feature in self.features:
            self.layout[feature.name] = slice(start, start + feature.size)
            start += feature.size
        self.size = start
        self.space = gym.spaces.Box(
            OBSERVATION_LOW, OBSERVATION_HIGH, shape=(self.size,), dtype=np.float32
        )

    def __iter__(self) -> Iterator[Feature]:
        return iter(self.features)

    def __getitem__(self, name: str) -> Feature:
        for feature in self.features:
            if feature.name == name:
                return feature
        raise KeyError(name)

    def observation_layout(self) -> dict[str, slice]:
        """A copy of the layout (what a task hands out as ``observation_layout``)."""
        return dict(self.layout)

    def extended(self, features: Sequence[Feature]) -> ObservationSpec:
        """This spec with ``features`` appended (a task that observes more than its base)."""
        return ObservationSpec((*self.features, *features))

    def run(self, names: Sequence[str]) -> slice:
        """The slice of the vector that the features ``names`` fill, which must follow each
        other in this order (:meth:`ObservationWriter.write_run` fills it at once)."""
        if not names:
            raise ValueError("argument 'names' must name at least one feature; got none")
        unknown = [name for name in names if name not in self.layout]
        if unknown:
            raise ValueError(f"argument 'names' names no feature of this spec: {unknown}")
        places = [self.layout[name] for name in names]
        for before, after, name in zip(places, places[1:], names[1:], strict=False):
            if after.start != before.stop:
                raise ValueError(
                    f"argument 'names' must list consecutive features; {name!r} does not "
                    f"follow {names[names.index(name) - 1]!r}"
                )
        return slice(places[0].start, places[-1].stop)

    def writer(self) -> ObservationWriter:
        """A writer over a fresh zero vector."""
        return ObservationWriter(self)

    def vector_of(self, values: Sequence[float]) -> np.ndarray:
        """A fresh observation vector from every entry, in vector order: each of ``values``
        clipped to [-1, 1] (NaN stays), as float32.

        The same vector as writing ``values`` through :meth:`writer` and clipping its float32
        vector: rounding to float32 keeps order and -1 and 1 are float32 numbers, so clipping
        before rounding gives the same bits as clipping after.
        """
        if len(values) != self.size:
            raise ValueError(f"an observation of {self.size} entries got {len(values)} values")
        low, high = OBSERVATION_LOW, OBSERVATION_HIGH
        # clipped(value, low, high), written out: a call per entry costs more than its work
        return np.array(
            [low if low > value else high if high < value else value for value in values],
            dtype=np.float32,
        )

    def feature_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(low, high)`` per entry of the vector, from each feature's range."""
        low = np.concatenate([np.full(f.size, f.low) for f in self.features])
        high = np.concatenate([np.full(f.size, f.high) for f in self.features])
        return low, high


class ObservationWriter:
    """Fills one observation vector (float32 zeros to start) feature by feature."""

    __slots__ = ("_layout", "vector")

    def __init__(self, spec: ObservationSpec) -> None:
        self._layout = spec.layout
        self.vector = np.zeros(spec.size, dtype=np.float32)

    def __setitem__(self, name: str, values: npt.ArrayLike | float) -> None:
        self.vector[self._layout[name]] = values

    def write_run(self, run: slice, values: Sequence[float]) -> None:
        """Fill a run of consecutive features (:meth:`ObservationSpec.run`) in one assignment,
        ``values`` in the features' order."""
        size = run.stop - run.start
        if len(values) != size:
            raise ValueError(f"a run of {size} entries got {len(values)} values")
        self.vector[run] = values

    def one_hot(self, name: str, index: int) -> None:
        """Set entry ``index`` of feature ``name`` to 1 (a one-hot group)."""
        place = self._layout[name]
        if not 0 <= index < place.stop - place.start:
            raise IndexError(
                f"index {index} is outside feature {name!r} of size {place.stop - place.start}"
            )
        self.vector[place.start + index] = 1.0
