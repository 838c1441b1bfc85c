"""The echo search of :func:`sonar_gym.sonar.echoes.echo_candidates` with its amplitudes, tests,
footprint and occlusion as separate numpy steps and compiled loops, which
:func:`sonar_gym.sonar.kernels.audible_candidates` and
:func:`sonar_gym.sonar.kernels.clear_nearest_first` replaced, kept as the tests' reference."""

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
    _PATH_CENTRE,
    _PLANE,
    EchoCandidates,
    edge_law_constants,
)
from sonar_gym.sonar.receiver import TimeVaryingGain
from tests.sonar.echo_search_kernels_reference import on_axis_echoes_reference


def echo_candidates_reference(
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
    """:func:`~sonar_gym.sonar.echoes.echo_candidates` as it was before its tests, footprint,
    occlusion and ordering ran in two compiled loops (same arguments).

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
    n_specular = tables.n_segments + tables.n_circles

    # The map's product holds every quantity affine in the position, and gets the ranges and
    # amplitudes written into its rows for them: from first_test_row on it is then every
    # per-candidate test, two comparisons in all.
    mapped = np.dot(tables.search_map, np.array((px, py, 1.0)))
    rel = mapped[tables.rel_rows].reshape(-1, 3)  # (rel_x, rel_y, 1) per candidate
    # Ranges (planes and vertices |rel|, a cylinder its centre distance minus its radius,
    # written into the map's ranges rows), the cylinders' offsets moved to their echo points,
    # and the on-axis laws of the module docstring, candidate by candidate.
    concave, centre_distance, safe, on_axis = on_axis_echoes_reference(
        mapped,
        tables.search_layout,
        tables.radius_padded,
        tables.radius,
        edge_law_constants(edge_law, wavenumber),
    )
    ranges = mapped[tables.ranges_rows]
    amplitudes = mapped[tables.amplitudes_rows]
    absorbs = absorption_db_per_m > 0.0
    if not absorbs and receiver_gain is None:
        amplitudes[:] = on_axis
    else:
        if absorbs:
            # 10^(-alpha 2 r / 20) = exp(-alpha ln(10) r / 10)
            absorption = np.exp((-absorption_db_per_m * _LN10 / 10.0) * safe)
            if receiver_gain is None:
                np.multiply(on_axis, absorption, out=amplitudes)
            else:
                on_axis = on_axis * absorption
        if receiver_gain is not None:
            np.multiply(on_axis, receiver_gain.gain(safe), out=amplitudes)

    # The tests, as rows of `mapped` against bounds: strictly, the foot inside the segment
    # (along > 0, -along > -1); inclusively, the segment not seen from its solid side, the
    # minimum range and the threshold (a candidate is valid if it passes all five), then
    # which segments and circles may occlude.
    keep, occluders = kernels.passing_candidates(
        mapped[tables.first_test_row :],
        tables.strict_bounds,
        tables.inclusive_bounds(max(min_range_m, 1e-9), detection_threshold),
        concave,
        tables.twin,
        tables.twin_comes_last,
        n_specular,
        tables.has_t_junctions,
    )
    kept = rel.take(keep, axis=0)  # the rows of rel at keep, gathered once as keep narrows
    if footprint_center is not None and footprint_radius_m > 0.0:
        fx, fy = float(footprint_center[0]), float(footprint_center[1])
        if footprint_radius_m > min_range_m - math.hypot(px - fx, py - fy):
            outside = np.hypot(kept[:, 0] + (px - fx), kept[:, 1] + (py - fy)) >= footprint_radius_m
            keep, kept = keep[outside], kept[outside]
    clear = _unoccluded(
        tables,
        mapped[tables.occlusion_rows].reshape(-1, 3),
        kept,
        ranges.take(keep),
        centre_distance,
        occluders,
    )
    keep, directions, path_lengths, kept_amplitudes = kernels.nearest_first(
        keep, clear, kept, ranges, amplitudes
    )
    return EchoCandidates(
        position=np.array((px, py)),
        directions=directions,
        path_lengths=path_lengths,
        amplitudes=kept_amplitudes,
        _primitive_indices=keep,
        _concave=concave,
        _tables=tables,
        threshold=max(detection_threshold, 0.0),
    )


def _unoccluded(
    tables: EchoTables,
    matrix: FloatArray,
    rel: FloatArray,
    ranges: FloatArray,
    centre_distance: FloatArray,
    occluders: np.ndarray,
) -> np.ndarray:
    """Which paths ``p -> p + rel`` cross no occluding segment and enter no circle before their end.

    Segments: ``p + u rel = a + v d`` gives ``u = ((a - p) x d) / (rel x d)`` and
    ``v = ((a - p) x rel) / (rel x d)``; a crossing with ``0 <= u <= 1 - tol`` and
    ``0 <= v <= 1`` blocks (a segment that may not occlude is skipped). Circles: the point of
    the path's line nearest the centre, ``u* = (c - p).rel / |rel|^2``, blocks if it lies on
    the path (``0 <= u* <= 1 - tol``) and inside the circle. (Beyond the path's end the nearest
    point of the path is its end, an echo point on another surface, never inside a circle; the
    reflecting cylinder itself has ``u* > 1``.) The products are numpy's; the tests run path
    by path in :func:`sonar_gym.sonar.kernels.unoccluded`.

    Args:
        matrix: ``(3 S + C, 3)``, the occlusion map of ``tables`` at the sensor position
            (:class:`~sonar_gym.sonar.echo_tables.EchoTables`).
        rel: ``(K, 3)`` rows ``(rel_x, rel_y, 1)``.
        ranges: ``(K,)`` path lengths ``|rel|``.
        centre_distance: ``(C,)`` distance from ``p`` to every circle centre.
        occluders: ``(S + C,)`` which segments may occlude, then True for every circle.
    """
    if len(rel) == 0:
        return np.zeros(0, dtype=bool)
    products = np.dot(matrix, rel.T)  # (3 S + C, K)
    return kernels.unoccluded(
        products, ranges, centre_distance, tables.radius_sq, occluders, _PATH_CENTRE
    )
