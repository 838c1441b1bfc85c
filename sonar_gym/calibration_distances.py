"""Roh et al.'s calibration distances (d1, d2, d3) as fractions of a range, and back.

Before each area boundary the robot saves its positions where its distance to the boundary
crosses d1, d2, d3 (Sec. III.C); the user chooses the d's (Sec. IV.E). An agent chooses them
as fractions ``u`` in [0, 1] of the range ``(low, high)``, metres:

* ``ordering="free"``: ``d_i = low + u_i (high - low)`` independently (the paper does not
  keep d1 > d2 > d3 either: Table IV's d4..d6 grow).
* ``ordering="decreasing"``: strictly decreasing d's, all met approaching the boundary
  (Tables II-III): ``d1 = low + 2 g + u1 (high - low - 2 g)``,
  ``d2 = low + g + u2 (d1 - low - 2 g)``, ``d3 = low + u3 (d2 - low - g)``, with the gap
  ``g =`` :data:`DECREASING_GAP_M`.
"""

from __future__ import annotations

import numpy as np

from sonar_gym.pose import FloatArray

DECREASING_GAP_M = 0.01
"""With ``ordering="decreasing"`` consecutive d's differ by at least this much, metres, so each
one is crossed after the previous one was saved (two and a half path steps)."""


def fractions_to_distances(
    u: FloatArray, distance_range_m: tuple[float, float], ordering: str
) -> tuple[tuple[float, float, float], ...]:
    """The (d1, d2, d3) triples, metres, that fractions ``u`` in [0, 1] stand for (three per
    boundary, ``(3 k,)``)."""
    return tuple(
        _triple_of_fractions(u[i : i + 3], distance_range_m, ordering) for i in range(0, len(u), 3)
    )


def distances_to_fractions(
    d: FloatArray, distance_range_m: tuple[float, float], ordering: str
) -> FloatArray:
    """The fractions in [0, 1] nearest to standing for the d's ``(3 k,)``, metres (the inverse
    of :func:`fractions_to_distances` where it can express them)."""
    return np.concatenate(
        [
            _fractions_of_triple(d[i : i + 3], distance_range_m, ordering)
            for i in range(0, len(d), 3)
        ]
    )


def _triple_of_fractions(
    u: FloatArray, distance_range_m: tuple[float, float], ordering: str
) -> tuple[float, float, float]:
    low, high = distance_range_m
    if ordering == "free":
        d = low + u * (high - low)
        return float(d[0]), float(d[1]), float(d[2])
    gap = DECREASING_GAP_M
    d1 = low + 2 * gap + u[0] * (high - low - 2 * gap)
    d2 = low + gap + u[1] * (d1 - low - 2 * gap)
    d3 = low + u[2] * (d2 - low - gap)
    return float(d1), float(d2), float(d3)


def _fractions_of_triple(
    d: FloatArray, distance_range_m: tuple[float, float], ordering: str
) -> FloatArray:
    low, high = distance_range_m
    if ordering == "free":
        return np.clip((d - low) / (high - low), 0.0, 1.0)
    gap = DECREASING_GAP_M
    u1 = _unit_fraction(d[0] - low - 2 * gap, high - low - 2 * gap)
    d1 = low + 2 * gap + u1 * (high - low - 2 * gap)
    u2 = _unit_fraction(d[1] - low - gap, d1 - low - 2 * gap)
    d2 = low + gap + u2 * (d1 - low - 2 * gap)
    u3 = _unit_fraction(d[2] - low, d2 - low - gap)
    return np.array([u1, u2, u3])


def _unit_fraction(numerator: float, denominator: float) -> float:
    """``numerator / denominator`` clipped to [0, 1]; 0 for an empty interval."""
    if denominator <= 0.0:
        return 0.0
    return float(np.clip(numerator / denominator, 0.0, 1.0))
