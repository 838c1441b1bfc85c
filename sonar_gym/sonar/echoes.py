"""Echo candidates: where a pulse-echo sonar at one position can receive echoes from.

Specular reflectors return an echo from a point that depends on where the sensor *is*, not on
where it points (DESIGN sec. 3): the foot of the perpendicular on a wall, the point of a
cylinder on the line to its centre, a corner or an edge itself. So for a sensor position ``p``
({W}, metres) this module finds every such point once, with its one-way path length ``r`` and
its on-axis echo amplitude; a ping then only multiplies by the two-way beam pattern ``D^2``
of its off-axis angle (:mod:`sonar_gym.sonar.pulse_echo`).

Amplitudes are pressures relative to the pressure the transducer radiates at 1 m on its axis
(units 1/m, "the units of the echo model"); a detection threshold is in the same units.

=========  ======================================  =============================================
kind        echo point                              on-axis amplitude (before air absorption)
=========  ======================================  =============================================
plane       foot of the perpendicular from ``p``,   ``1 / (2 r)``: the image source at ``2 r``
            when it lies inside the segment
cylinder    the point on the line to the centre,    ``1/(2 r) sqrt(rho / (r + rho))``: ray optics
            ``r = |c - p| - rho``                   of a convex mirror (horizontal radius ``rho``,
                                                    vertically flat); for ``rho << r`` this is
                                                    DESIGN's ``sqrt(rho/2) / r^1.5`` times
                                                    ``1/sqrt(2)``, a constant the calibrated
                                                    threshold absorbs
corner      a vertex seen from inside its wedge     ``1 / (2 r)``: a right-angle dihedral is a
            (opening < 180 deg)                     retro-reflector, image source at ``2 r``
edge        any other vertex (convex corners of     weak: ``s / r^2``, a point-like diffractor
            boxes and walls, free wall ends)        (default, ``edge_law="weak"``, see below);
                                                    or ``G / (2 sqrt(pi k) r^1.5)``, Keller's
                                                    geometrical theory of diffraction for an
                                                    infinite rigid right-angle wedge seen along
                                                    its bisector, ``G = 0.770``
                                                    (``edge_law="gtd"``)
=========  ======================================  =============================================

Edges. Beom & Cho: "the edges produce weak echo", and in their Table II scan no edge survives
the 18-26 deg angular-extent filter. The ideal wedge of the GTD is only about 20 dB below the
1.9 cm beacon at the same range; with the sensitivity the beacon calibration implies (the
small beacon heard to 11.5 deg off axis, 44 dB down its main lobe) it would give every box
corner a beacon-like RCD of about 20 deg out to several metres. Real edges (table tops,
monitor bezels, rounded cabinet corners) are short and blunt, so the default is an empirical
point-diffractor law with strength :data:`EDGE_ECHO_STRENGTH_M`, chosen so that the Polaroid
threshold with a constant receiver gain hears an edge on its axis only within about 0.75 m,
and an edge's RCD spans under 18 deg (the lower bound of Beom & Cho's filter) even at the
0.3 m minimum range. Through the Polaroid preset's gain ramp (:mod:`sonar_gym.sonar.receiver`),
which is low at short range, an edge stays over 20 dB below the threshold at any range: the
preset hears no edge. ``edge_law="gtd"`` gives the ideal-wedge law instead.

Air absorption multiplies every amplitude by ``10^(-alpha 2 r / 20)``. A receiver with a
time-varying gain (:mod:`sonar_gym.sonar.receiver`) then multiplies it by its gain ``G(r)``:
the amplitudes are what the comparator sees, in the units of the threshold.

An echo is kept only if its path ``p -> echo point`` crosses no segment and enters no circle
before reaching the echo point (the reflector's own primitives touch the path only at its end,
which is excluded with a relative tolerance of 1e-9), if ``r`` is at least the transducer's
minimum range (echoes during the ring-down are not heard), if the echo point is outside the
robot's footprint, and, when a threshold is given, if its on-axis amplitude reaches the
threshold (no off-axis angle can make it louder). A box face seen from inside the box, or a
room wall from outside the room, returns nothing. A T-junction (a free wall ending on another
wall) is one vertex: a corner from whichever side is concave.

The work is array arithmetic over all primitives at once, with per-geometry constant tables
(:mod:`sonar_gym.sonar.echo_tables`) and the occlusion test as one ``(primitives x
candidates)`` product, whose interval tests a compiled loop runs
(:mod:`sonar_gym.sonar.kernels`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np
import numpy.typing as npt

from sonar_gym.frozen import unchecked_instance
from sonar_gym.geometry import StaticGeometry
from sonar_gym.pose import FloatArray
from sonar_gym.sonar import kernels
from sonar_gym.sonar.echo_tables import PATH_END_TOLERANCE, EchoTables, echo_tables
from sonar_gym.sonar.receiver import TimeVaryingGain

EDGE_DIFFRACTION_COEFFICIENT = (4.0 / 3.0) * math.sin(2.0 * math.pi / 3.0) / 1.5
"""``|D| sqrt(2 pi k)`` of Keller's diffraction coefficient for backscatter from a rigid wedge of
exterior angle 270 deg (``n = 3/2``) seen along its bisector:
``sin(pi/n) / n * |1 / (cos(pi/n) - 1) + 1 / (cos(pi/n) + 1)| = 0.770``."""
EDGE_ECHO_STRENGTH_M = 2.0e-5
"""Strength ``s`` (metres) of the default edge echo ``s / r^2`` (chosen, see the module docs)."""
EDGE_LAWS = ("weak", "gtd")


class EchoKind(IntEnum):
    """Kind of reflector an echo candidate comes from."""

    PLANE = 0
    CYLINDER = 1
    CORNER = 2
    EDGE = 3


_PLANE, _CYLINDER, _EDGE = int(EchoKind.PLANE), int(EchoKind.CYLINDER), int(EchoKind.EDGE)
_LN10 = math.log(10.0)


def plane_echo_amplitude(range_m: npt.ArrayLike) -> FloatArray:
    """On-axis echo of a plane at normal incidence, ``1 / (2 r)`` (r in metres)."""
    return 0.5 / np.asarray(range_m, dtype=np.float64)


def cylinder_echo_amplitude(range_m: npt.ArrayLike, radius_m: npt.ArrayLike) -> FloatArray:
    """On-axis echo of a vertical cylinder, ``1/(2 r) sqrt(rho / (r + rho))`` (metres)."""
    r = np.asarray(range_m, dtype=np.float64)
    rho = np.asarray(radius_m, dtype=np.float64)
    return 0.5 / r * np.sqrt(rho / (r + rho))


def corner_echo_amplitude(range_m: npt.ArrayLike) -> FloatArray:
    """On-axis echo of a concave right-angle corner (a retro-reflector), ``1 / (2 r)``."""
    return plane_echo_amplitude(range_m)


def edge_echo_amplitude(
    range_m: npt.ArrayLike, wavenumber: float, edge_law: str = "weak"
) -> FloatArray:
    """On-axis echo of a convex edge: ``s / r^2`` (``"weak"``) or ``G / (2 sqrt(pi k) r^1.5)``
    (``"gtd"``); ``r`` in metres, ``k`` in rad/m."""
    r = np.asarray(range_m, dtype=np.float64)
    weak, constant = edge_law_constants(edge_law, wavenumber).tolist()
    return constant / (r * r) if weak else constant / (r * np.sqrt(r))


@functools.lru_cache(maxsize=16)
def edge_law_constants(edge_law: str, wavenumber: float) -> np.ndarray:
    """``(1, s)`` for the weak edge law, ``(0, G / (2 sqrt(pi k)))`` for the GTD law."""
    if edge_law == "weak":
        law = np.array((1.0, EDGE_ECHO_STRENGTH_M))
    elif edge_law == "gtd":
        law = np.array(
            (0.0, EDGE_DIFFRACTION_COEFFICIENT / (2.0 * math.sqrt(math.pi * wavenumber)))
        )
    else:
        raise ValueError(f"argument 'edge_law' must be one of {list(EDGE_LAWS)}; got {edge_law!r}")
    law.flags.writeable = False
    return law


@dataclass(frozen=True)
class EchoCandidates:
    """Every echo a sensor at ``position`` can receive, sorted by path length (nearest first).

    Attributes:
        position: the sensor position in {W}, metres, shape ``(2,)``.
        directions: ``(K, 2)`` unit vectors from ``position`` towards each echo point.
        path_lengths: ``(K,)`` one-way path lengths ``r``, metres.
        amplitudes: ``(K,)`` on-axis echo amplitudes including air absorption and the
            receiver's gain, if any (1/m, the units of the threshold).
        kinds: ``(K,)`` :class:`EchoKind` codes (computed on first use).
        threshold: the detection threshold they were searched with (1/m): every amplitude
            reaches it.
    """

    position: FloatArray
    directions: FloatArray
    path_lengths: FloatArray
    amplitudes: FloatArray
    _primitive_indices: np.ndarray = field(repr=False)
    _concave: np.ndarray = field(repr=False)
    _tables: EchoTables = field(repr=False)
    threshold: float = 0.0

    @classmethod
    def unchecked(
        cls,
        position: FloatArray,
        directions: FloatArray,
        path_lengths: FloatArray,
        amplitudes: FloatArray,
        primitive_indices: np.ndarray,
        concave: np.ndarray,
        tables: EchoTables,
        threshold: float,
    ) -> EchoCandidates:
        """The candidates of these fields, in the order of the attributes, set as the frozen
        dataclass's constructor sets them (it has no checks) at a fraction of its cost: for
        :func:`echo_candidates`, which runs once per sensor position."""
        return unchecked_instance(
            cls,
            position=position,
            directions=directions,
            path_lengths=path_lengths,
            amplitudes=amplitudes,
            _primitive_indices=primitive_indices,
            _concave=concave,
            _tables=tables,
            threshold=threshold,
        )

    def __len__(self) -> int:
        return len(self.path_lengths)

    @functools.cached_property
    def kinds(self) -> np.ndarray:
        """``(K,)`` :class:`EchoKind` codes."""
        tables = self._tables
        kinds = tables.kinds_template.copy()
        corners = tables.n_segments + tables.n_circles + np.flatnonzero(self._concave)
        kinds[corners] = EchoKind.CORNER
        return kinds[self._primitive_indices]

    @property
    def points(self) -> FloatArray:
        """``(K, 2)`` echo points in {W}, metres."""
        return self.position + self.directions * self.path_lengths[:, None]


_PATH_CENTRE = (1.0 - PATH_END_TOLERANCE) / 2.0
"""The middle and half width of ``[0, 1 - tol]``, where ``u`` and ``u*`` block a path."""


def echo_candidates(
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
    """Find the echo candidates of a sensor at ``position`` (see the module docstring); their
    directions, path lengths and amplitudes are read-only.

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
    n_circles, n_candidates = tables.n_circles, tables.n_candidates

    # The map's product holds every quantity affine in the position, and gets the ranges and
    # amplitudes written into its rows for them: from first_test_row on it is then every
    # per-candidate test, two comparisons in all.
    sensor = np.array((px, py, 1.0))
    mapped = np.dot(tables.search_map, sensor)
    # Ranges (planes and vertices |rel|, a cylinder its centre distance minus its radius,
    # written into the map's ranges rows), the cylinders' offsets moved to their echo points,
    # and the on-axis laws of the module docstring (written into the map's amplitudes rows),
    # candidate by candidate; then the exponents of air absorption.
    concave = np.empty(tables.n_wedges, dtype=np.bool_)
    distances = kernels.echo_ranges(
        mapped,
        tables.search_layout,
        tables.radius_padded,
        tables.radius,
        edge_law_constants(edge_law, wavenumber),
        -absorption_db_per_m * _LN10 / 10.0,
        concave,
    )
    # Air absorption 10^(-alpha 2 r / 20) = exp(-alpha ln(10) r / 10) and the receiver's gain
    # as factors here; the amplitudes, their products, are written by the tests' loop below.
    absorption = (
        np.exp(distances[n_circles + n_candidates :]) if absorption_db_per_m > 0.0 else _NO_FACTORS
    )
    gain = (
        _NO_FACTORS
        if receiver_gain is None
        else receiver_gain.gain(distances[n_circles : n_circles + n_candidates])
    )

    # The tests, as rows of `mapped` against bounds: strictly, the foot inside the segment
    # (along > 0, -along > -1); inclusively, the segment not seen from its solid side, the
    # minimum range and the threshold (a candidate is valid if it passes all five), then
    # which segments and circles may occlude; then the robot's footprint.
    footprint = _NO_FOOTPRINT  # (sensor - centre, radius), {W}, metres
    if footprint_center is not None and footprint_radius_m > 0.0:
        fx, fy = float(footprint_center[0]), float(footprint_center[1])
        if footprint_radius_m > min_range_m - math.hypot(px - fx, py - fy):
            footprint = (px - fx, py - fy, footprint_radius_m)
    picks = np.empty(tables.n_picks, dtype=np.int64)
    kept = kernels.audible_paths(
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
        *footprint,
        picks,
    )
    keep, directions, path_lengths, kept_amplitudes = _unoccluded_nearest_first(
        tables, mapped, picks, kept, distances
    )
    return EchoCandidates.unchecked(
        sensor[:2],
        directions,
        path_lengths,
        kept_amplitudes,
        keep,
        concave,
        tables,
        max(detection_threshold, 0.0),
    )


def _unoccluded_nearest_first(
    tables: EchoTables,
    mapped: FloatArray,
    picks: np.ndarray,
    kept: FloatArray,
    distances: FloatArray,
) -> tuple[np.ndarray, FloatArray, FloatArray, FloatArray]:
    """The candidates :func:`~sonar_gym.sonar.kernels.audible_paths` picked whose paths
    ``p -> p + rel`` cross no occluding segment and enter no circle before their end, nearest
    first: ``(indices, (K, 2) unit directions, path lengths, amplitudes)``.

    Segments: ``p + u rel = a + v d`` gives ``u = ((a - p) x d) / (rel x d)`` and
    ``v = ((a - p) x rel) / (rel x d)``; a crossing with ``0 <= u <= 1 - tol`` and
    ``0 <= v <= 1`` blocks (a segment that may not occlude is skipped). Circles: the point of
    the path's line nearest the centre, ``u* = (c - p).rel / |rel|^2``, blocks if it lies on
    the path (``0 <= u* <= 1 - tol``) and inside the circle. (Beyond the path's end the nearest
    point of the path is its end, an echo point on another surface, never inside a circle; the
    reflecting cylinder itself has ``u* > 1``.) The products are numpy's; the tests and the
    ordering run path by path in :func:`sonar_gym.sonar.kernels.clear_paths_nearest_first`,
    whose one array of floats the directions, path lengths and amplitudes are read-only views
    of.

    Args:
        mapped: the search map's product at the sensor, its ranges and amplitudes rows written.
        picks: ``(N + S + C,)`` the indices of the ``P`` candidates that passed the tests, then
            whether each segment may occlude and 1 for every circle (last ``S + C`` entries).
        kept: ``(P, 3)`` their rows ``(rel_x, rel_y, 1)``.
        distances: :func:`~sonar_gym.sonar.kernels.echo_ranges`' distances, the first ``C``
            from ``p`` to every circle centre.
    """
    matrix = mapped[tables.occlusion_rows].reshape(-1, 3)  # the occlusion map at the sensor
    indices, floats = kernels.clear_paths_nearest_first(
        np.dot(matrix, kept.T),  # (3 S + C, P)
        picks,
        kept,
        mapped,
        distances,
        tables.search_layout,
        tables.radius_sq,
        _PATH_CENTRE,
    )
    n_kept = len(indices)
    floats.setflags(write=False)  # and so every view of it
    return (
        indices,
        floats[: 2 * n_kept].reshape(n_kept, 2),
        floats[2 * n_kept : 3 * n_kept],
        floats[3 * n_kept :],
    )


_NO_FACTORS = np.empty(0)
"""No absorption or gain factors: the amplitudes are the on-axis ones."""
_NO_FACTORS.flags.writeable = False
_NO_FOOTPRINT = (0.0, 0.0, 0.0)
"""No footprint test: a radius of 0 (:func:`sonar_gym.sonar.kernels.audible_paths`)."""
