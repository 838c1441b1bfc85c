"""The echo search of :func:`sonar_gym.sonar.echoes.echo_candidates` as it was when its compiled
loops (:func:`sonar_gym.sonar.kernels.on_axis_echoes`,
:func:`sonar_gym.sonar.kernels.audible_candidates`,
:func:`sonar_gym.sonar.kernels.clear_nearest_first`) handed back nine arrays per search and the
exponent of air absorption was numpy's product, kept verbatim as the tests' reference for the
form that calls :func:`sonar_gym.sonar.kernels.echo_ranges`,
:func:`sonar_gym.sonar.kernels.audible_paths` and
:func:`sonar_gym.sonar.kernels.clear_paths_nearest_first`."""

from __future__ import annotations

import math

import numpy as np

from sonar_gym.geometry import StaticGeometry
from sonar_gym.pose import FloatArray
from sonar_gym.sonar import kernels
from sonar_gym.sonar.echo_tables import EchoTables, echo_tables
from sonar_gym.sonar.echoes import (
    _CYLINDER,
    _EDGE,
    _LN10,
    _NO_FACTORS,
    _PATH_CENTRE,
    _PLANE,
    EchoCandidates,
    edge_law_constants,
)
from sonar_gym.sonar.receiver import TimeVaryingGain

_NO_FOOTPRINT = np.empty(0)
"""No footprint test (:func:`sonar_gym.sonar.kernels.audible_candidates`)."""
_NO_FOOTPRINT.flags.writeable = False


def echo_candidates_unpacked_reference(
    geometry: StaticGeometry,
    position: tuple[float, float] | FloatArray,
    *,
    wavenumber: float,
    absorption_db_per_m: float = 0.0,
    min_range_m: float = 0.0,
    detection_threshold: float = 0.0,
    footprint_center: tuple[float, float] | FloatArray | None = None,
    footprint_radius_m: float = 0.0,
    edge_law: str = "weak",
    receiver_gain: TimeVaryingGain | None = None,
) -> EchoCandidates:
    """Find the echo candidates of a sensor at ``position`` (see the module docstring).

    Args:
        geometry: the static reflectors ({W}, metres).
        position: sensor position ``(x, y)`` in {W}, metres.
        wavenumber: acoustic wavenumber ``k`` in rad/m (for the GTD edge law).
        absorption_db_per_m: air absorption in dB per metre of path (0 disables it).
        min_range_m: echoes from nearer than this (one way, metres) are dropped.
        detection_threshold: echoes whose on-axis amplitude is below this are dropped.
        footprint_center, footprint_radius_m: echo points inside this circle (the robot's
            body, {W}, metres) are dropped.
        edge_law: ``"weak"`` (default) or ``"gtd"``, the edge echo of the module docstring.
        receiver_gain: the receiver's time-varying gain, applied to every amplitude before the
            threshold test (None: a constant gain of 1).
    """
    tables = echo_tables(geometry, _PLANE, _CYLINDER, _EDGE)
    px, py = float(position[0]), float(position[1])

    # The map's product holds every quantity affine in the position, and gets the ranges and
    # amplitudes written into its rows for them: from first_test_row on it is then every
    # per-candidate test, two comparisons in all.
    mapped = np.dot(tables.search_map, np.array((px, py, 1.0)))
    # Ranges (planes and vertices |rel|, a cylinder its centre distance minus its radius,
    # written into the map's ranges rows), the cylinders' offsets moved to their echo points,
    # and the on-axis laws of the module docstring (written into the map's amplitudes rows),
    # candidate by candidate.
    concave, distances = kernels.on_axis_echoes(
        mapped,
        tables.search_layout,
        tables.radius_padded,
        tables.radius,
        edge_law_constants(edge_law, wavenumber),
    )
    centre_distance, safe = distances[: tables.n_circles], distances[tables.n_circles :]
    # Air absorption 10^(-alpha 2 r / 20) = exp(-alpha ln(10) r / 10) and the receiver's gain
    # as factors here; the amplitudes, their products, are written by the tests' loop below.
    absorption = (
        np.exp((-absorption_db_per_m * _LN10 / 10.0) * safe)
        if absorption_db_per_m > 0.0
        else _NO_FACTORS
    )
    gain = _NO_FACTORS if receiver_gain is None else receiver_gain.gain(safe)

    # The tests, as rows of `mapped` against bounds: strictly, the foot inside the segment
    # (along > 0, -along > -1); inclusively, the segment not seen from its solid side, the
    # minimum range and the threshold (a candidate is valid if it passes all five), then
    # which segments and circles may occlude; then the robot's footprint.
    footprint = _NO_FOOTPRINT
    if footprint_center is not None and footprint_radius_m > 0.0:
        fx, fy = float(footprint_center[0]), float(footprint_center[1])
        if footprint_radius_m > min_range_m - math.hypot(px - fx, py - fy):
            footprint = np.array((px - fx, py - fy, footprint_radius_m))
    keep, kept, occluders = kernels.audible_candidates(
        mapped,
        tables.search_layout,
        absorption,
        gain,
        tables.strict_bounds,
        tables.inclusive_bounds(max(min_range_m, 1e-9), detection_threshold),
        concave,
        tables.twin,
        tables.twin_comes_last,
        tables.has_t_junctions,
        footprint,
    )
    keep, directions, path_lengths, kept_amplitudes = _unoccluded_nearest_first_reference(
        tables, mapped, keep, kept, centre_distance, occluders
    )
    return EchoCandidates.unchecked(
        np.array((px, py)),
        directions,
        path_lengths,
        kept_amplitudes,
        keep,
        concave,
        tables,
        max(detection_threshold, 0.0),
    )


def _unoccluded_nearest_first_reference(
    tables: EchoTables,
    mapped: FloatArray,
    keep: np.ndarray,
    kept: FloatArray,
    centre_distance: FloatArray,
    occluders: np.ndarray,
) -> tuple[np.ndarray, FloatArray, FloatArray, FloatArray]:
    """The candidates ``keep`` whose paths ``p -> p + rel`` cross no occluding segment and
    enter no circle before their end, nearest first: ``(indices, (K, 2) unit directions, path
    lengths, amplitudes)``.

    Segments: ``p + u rel = a + v d`` gives ``u = ((a - p) x d) / (rel x d)`` and
    ``v = ((a - p) x rel) / (rel x d)``; a crossing with ``0 <= u <= 1 - tol`` and
    ``0 <= v <= 1`` blocks (a segment that may not occlude is skipped). Circles: the point of
    the path's line nearest the centre, ``u* = (c - p).rel / |rel|^2``, blocks if it lies on
    the path (``0 <= u* <= 1 - tol``) and inside the circle. (Beyond the path's end the nearest
    point of the path is its end, an echo point on another surface, never inside a circle; the
    reflecting cylinder itself has ``u* > 1``.) The products are numpy's; the tests and the
    ordering run path by path in :func:`sonar_gym.sonar.kernels.clear_nearest_first`.

    Args:
        mapped: the search map's product at the sensor, its ranges and amplitudes rows written.
        keep: ``(K,)`` candidate indices; ``kept``: ``(K, 3)`` their rows ``(rel_x, rel_y, 1)``.
        centre_distance: ``(C,)`` distance from ``p`` to every circle centre.
        occluders: ``(S + C,)`` which segments may occlude, then True for every circle.
    """
    matrix = mapped[tables.occlusion_rows].reshape(-1, 3)  # the occlusion map at the sensor
    return kernels.clear_nearest_first(  # type: ignore[no-any-return]
        np.dot(matrix, kept.T),  # (3 S + C, K)
        keep,
        kept,
        mapped[tables.ranges_rows],
        mapped[tables.amplitudes_rows],
        centre_distance,
        tables.radius_sq,
        occluders,
        _PATH_CENTRE,
    )
