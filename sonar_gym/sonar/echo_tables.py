"""Per-geometry constant tables that make :func:`~sonar_gym.sonar.echoes.echo_candidates` cheap.

Almost everything the echo search needs is *affine* in the sensor position ``p = (px, py)``:
the vector from ``p`` to a wall's foot of the perpendicular (``-n n^T (p - a)``), to a vertex
(``v - p``) and to a cylinder's centre (``c - p``); where the foot falls along the wall; the
signed distance of ``p`` from each wall's line; the two wedge tests of
:meth:`~sonar_gym.geometry.StaticGeometry.is_concave_from`; and every pairwise quantity the
occlusion test needs (``rel x d``, ``(a - p) x d``, ``(a - p) x rel``, ``(c - p) . rel``,
written as a matrix acting on ``(rel_x, rel_y, 1)``). So each of them is a row of a constant
matrix, and one matrix-vector product per sensor position evaluates them all.

The tables are built once per :class:`~sonar_gym.geometry.StaticGeometry` and cached (weakly:
a rebuilt geometry gets new tables).
"""

from __future__ import annotations

import functools
import weakref
from dataclasses import dataclass, field

import numpy as np

from sonar_gym.geometry import StaticGeometry
from sonar_gym.pose import FloatArray
from sonar_gym.sonar.loop_kernels import closer_than, solid_sides
from sonar_gym.sonar.table_kernels import linear_maps

PATH_END_TOLERANCE = 1e-9
"""Fraction of a path, at its far end, in which a crossing does not count as an occlusion."""
LOOP_TOLERANCE_M = 1e-9
"""End points closer than this are the same point (closing polygons, pairing T-junctions)."""


@dataclass(frozen=True, eq=False)
class EchoTables:
    """Constant tables of one geometry.

    Candidates are numbered planes (one per segment, ``S``), then cylinders (``C``), then
    vertices (``V``; those that can be concave corners first, ``W`` of them).

    Attributes:
        position_map: ``(3 (S+C+V) + 2 S + 2 W, 3)``; times ``(px, py, 1)`` it gives, in order,
            ``(rel_x, rel_y, 1)`` of every candidate (``rel`` = echo point - ``p``; for a
            cylinder its centre - ``p``), the foot position along each segment (0 at its
            start, 1 at its end), the signed distance of ``p`` from each segment's line (left
            positive), and the two wedge tests of each possibly-concave vertex.
        occlusion_map: ``((3 S + C) 3, 3)``; times ``(px, py, 1)`` and reshaped to
            ``(3 S + C, 3)`` it is the matrix ``N`` such that ``N @ (rel_x, rel_y, 1)`` gives,
            for every segment, ``rel x d``, then for every segment ``(a - p) x d``, then
            ``(a - p) x rel``, then for every circle ``(c - p) . rel``.
        position_and_occlusion_map: both maps stacked, so that one product with
            ``(px, py, 1)`` evaluates them together.
        n_position_rows: the number of rows of ``position_map``.
        n_segments, n_circles, n_vertices, n_wedges: the counts ``S, C, V, W``.
        radius, radius_sq: ``(C,)`` cylinder radii and their squares.
        radius_padded: ``(S+C+V,)`` the radius of every candidate (0 but for cylinders).
        solid_side: ``(S,)`` +1 when the solid lies left of the segment, -1 right, 0 for open
            chains (see :func:`convex_loops`).
        encloses: ``(S,)`` whether the segment belongs to an enclosure (the room).
        twin: ``(W,)`` the other vertex at the same point (a T-junction), else the vertex
            itself; ``twin_comes_first``: whether that twin has the lower index, and
            ``twin_comes_last`` its complement.
        kinds_template: ``(S+C+V,)`` EchoKind codes with every vertex an edge.
        has_t_junctions: whether any wedge vertex has a twin (else every wedge passes its
            T-junction test whatever its concavity).
        rel_rows, along_rows, distance_rows, wedge_a_rows, wedge_b_rows, occlusion_rows: the
            slices of the product of ``position_and_occlusion_map`` with ``(px, py, 1)`` that
            hold each quantity.
        search_map: ``position_and_occlusion_map`` followed by the rows of the per-candidate
            tests of the echo search, ``N = S+C+V`` each: the foot position along the
            candidate's segment, its negative, the signed distance of ``p`` from the segment's
            line times minus the solid side (zeros for other candidates), then two blocks of
            zeros where the search writes the candidates' ranges and amplitudes, then ``S + C``
            occluder rows (a segment that is not part of an enclosure occludes when seen from
            its open side: its facing row; enclosure segments and circles: zeros). Its product
            with ``(px, py, 1)`` from row ``first_test_row`` on is compared with bounds: the
            first ``2 N`` strictly (``>``, :attr:`strict_bounds`), the rest inclusively
            (``>=``, :meth:`inclusive_bounds`).
        first_test_row, ranges_rows, amplitudes_rows: where the tests start and where the
            search writes the ranges and amplitudes.
        strict_bounds: ``(2 N,)`` 0 and -1 for segments (foot strictly inside the segment:
            ``along > 0`` and ``-along > -1``), -1 for the other candidates.
        occluder_bounds: ``(S + C,)`` 0 for segments that may occlude, 1 for enclosure
            segments (never), -1 for circles (always).
        kind_codes: the EchoKind codes of a plane, a cylinder and an edge.
        n_candidates, n_picks: ``N = S + C + V``, and ``N + S + C`` (the picks of the echo
            search's tests: the indices of the candidates that pass, then the occluders).

    What only the pan's echo search reads (``position_and_occlusion_map``, ``radius_padded``,
    ``twin_comes_last``, ``kinds_template``, ``has_t_junctions``, ``search_map``,
    ``strict_bounds``, ``occluder_bounds``, ``n_candidates``, ``n_picks``) is built on first
    use, once per geometry: the side sonars, whose geometry changes every episode in an env
    with random obstacles, never ask.
    """

    position_map: FloatArray
    occlusion_map: FloatArray
    n_position_rows: int
    n_segments: int
    n_circles: int
    n_vertices: int
    n_wedges: int
    radius: FloatArray
    radius_sq: FloatArray
    solid_side: FloatArray
    encloses: np.ndarray
    twin: np.ndarray
    twin_comes_first: np.ndarray
    rel_rows: slice
    along_rows: slice
    distance_rows: slice
    wedge_a_rows: slice
    wedge_b_rows: slice
    occlusion_rows: slice
    first_test_row: int
    ranges_rows: slice
    amplitudes_rows: slice
    kind_codes: tuple[int, int, int] = field(repr=False)
    _inclusive_bounds: dict[tuple[float, float], FloatArray] = field(
        default_factory=dict, repr=False
    )

    # The members below serve the pan's echo search (sonar_gym.sonar.echoes) only; the side
    # sonars never read them, so each is built on first use, once per geometry.

    @functools.cached_property
    def position_and_occlusion_map(self) -> FloatArray:
        """Both maps stacked, so that one product with ``(px, py, 1)`` evaluates them together."""
        return np.concatenate([self.position_map, self.occlusion_map])

    @functools.cached_property
    def radius_padded(self) -> FloatArray:
        """``(S+C+V,)`` the radius of every candidate (0 but for cylinders)."""
        return np.concatenate([np.zeros(self.n_segments), self.radius, np.zeros(self.n_vertices)])

    @functools.cached_property
    def twin_comes_last(self) -> np.ndarray:
        """``(W,)`` whether each wedge vertex's twin has its index or a higher one."""
        return self.twin >= np.arange(self.n_wedges)

    @functools.cached_property
    def kinds_template(self) -> np.ndarray:
        """``(S+C+V,)`` EchoKind codes with every vertex an edge."""
        plane, cylinder, edge = self.kind_codes
        return np.concatenate(
            [
                np.full(self.n_segments, plane, dtype=np.int8),
                np.full(self.n_circles, cylinder, dtype=np.int8),
                np.full(self.n_vertices, edge, dtype=np.int8),
            ]
        )

    @functools.cached_property
    def has_t_junctions(self) -> bool:
        """Whether any wedge vertex has a twin."""
        return bool(np.any(self.twin != np.arange(self.n_wedges)))

    @functools.cached_property
    def search_map(self) -> FloatArray:
        """``position_and_occlusion_map`` followed by the test rows of the echo search."""
        n_segments, n_candidates = (
            self.n_segments,
            self.n_segments + self.n_circles + self.n_vertices,
        )
        distance = self.position_map[self.distance_rows]
        # The per-candidate test rows (zeros but for segments; see the class docstring).
        along_all = np.zeros((n_candidates, 3))
        along_all[:n_segments] = self.position_map[self.along_rows]
        facing_all = np.zeros((n_candidates, 3))
        facing_all[:n_segments] = -self.solid_side[:, None] * distance
        occluder_rows = np.zeros((n_segments + self.n_circles, 3))
        occluder_rows[:n_segments] = np.where(self.encloses[:, None], 0.0, facing_all[:n_segments])
        search_map = np.concatenate(
            [
                self.position_and_occlusion_map,
                along_all,
                -along_all,
                facing_all,
                np.zeros((2 * n_candidates, 3)),  # the ranges and amplitudes go here
                occluder_rows,
            ]
        )
        search_map.flags.writeable = False
        return search_map

    @functools.cached_property
    def strict_bounds(self) -> FloatArray:
        """``(2 N,)`` the bounds of the strict tests of the echo search."""
        n_candidates = self.n_segments + self.n_circles + self.n_vertices
        strict_bounds = np.concatenate(
            [np.zeros(self.n_segments), np.full(2 * n_candidates - self.n_segments, -1.0)]
        )
        strict_bounds.flags.writeable = False
        return strict_bounds

    @functools.cached_property
    def occluder_bounds(self) -> FloatArray:
        """``(S + C,)`` the bounds of the occluder tests of the echo search."""
        occluder_bounds = np.concatenate(
            [np.where(self.encloses, 1.0, 0.0), np.full(self.n_circles, -1.0)]
        )
        occluder_bounds.flags.writeable = False
        return occluder_bounds

    @functools.cached_property
    def n_candidates(self) -> int:
        """``N = S + C + V``, the number of echo candidates."""
        return self.n_segments + self.n_circles + self.n_vertices

    @functools.cached_property
    def n_picks(self) -> int:
        """``N + S + C``: the length of the picks of
        :func:`sonar_gym.sonar.kernels.audible_paths` (the indices of at most every candidate,
        then one occluder flag per segment and circle)."""
        return self.n_candidates + self.n_segments + self.n_circles

    @functools.cached_property
    def search_layout(self) -> np.ndarray:
        """``(S, C, W, V, first ranges row, first rows of the wedge sides a and b)`` as int64:
        what :func:`sonar_gym.sonar.kernels.on_axis_echoes` reads of these tables."""
        layout = np.array(
            (
                self.n_segments,
                self.n_circles,
                self.n_wedges,
                self.n_vertices,
                self.ranges_rows.start,
                self.wedge_a_rows.start,
                self.wedge_b_rows.start,
            ),
            dtype=np.int64,
        )
        layout.flags.writeable = False
        return layout

    def inclusive_bounds(self, min_range_m: float, detection_threshold: float) -> FloatArray:
        """``(3 N + S + C,)`` the bounds of the inclusive tests (``>=``) of the echo search: 0
        for the facing test (a segment not seen from its solid side; 0 for other candidates),
        ``min_range_m`` for the ranges, ``detection_threshold`` for the amplitudes, then the
        occluder bounds (remembered per pair: a sonar asks with the same two everywhere)."""
        key = (min_range_m, detection_threshold)
        bounds = self._inclusive_bounds.get(key)
        if bounds is None:
            n = self.n_segments + self.n_circles + self.n_vertices
            bounds = np.concatenate(
                [
                    np.zeros(n),
                    np.full(n, min_range_m),
                    np.full(n, detection_threshold),
                    self.occluder_bounds,
                ]
            )
            bounds.flags.writeable = False
            self._inclusive_bounds[key] = bounds
        return bounds


_CACHE: weakref.WeakKeyDictionary[StaticGeometry, EchoTables] = weakref.WeakKeyDictionary()
_LAST: list[tuple[weakref.ref[StaticGeometry], EchoTables]] = []
"""The last geometry asked for and its tables (spares the weak dictionary's lookup)."""


def echo_tables(geometry: StaticGeometry, plane: int, cylinder: int, edge: int) -> EchoTables:
    """The (cached) tables of ``geometry``; ``plane``, ``cylinder``, ``edge`` are the kind codes."""
    if _LAST and _LAST[0][0]() is geometry:
        return _LAST[0][1]
    cached = _CACHE.get(geometry)
    if cached is None:
        cached = _build(geometry, plane, cylinder, edge)
        _CACHE[geometry] = cached
    _LAST[:] = [(weakref.ref(geometry), cached)]
    return cached


def _build(geometry: StaticGeometry, plane: int, cylinder: int, edge: int) -> EchoTables:
    a = geometry.segment_starts
    d = geometry.segment_ends - a
    n_segments, n_circles = geometry.n_segments, geometry.n_circles
    arm_a, arm_b = geometry.vertex_arms[:, 0], geometry.vertex_arms[:, 1]
    length = np.hypot(d[:, 0], d[:, 1])
    position_map, occlusion_map, order, n_wedges = linear_maps(
        a, d, length, geometry.circles, geometry.vertices, arm_a, arm_b
    )
    vertices = geometry.vertices[order]
    n_vertices = len(vertices)
    n_candidates = n_segments + n_circles + n_vertices
    n_rows = 3 * n_segments + n_circles

    wedge_points = vertices[:n_wedges]
    same_point = _closer_than(wedge_points, wedge_points, LOOP_TOLERANCE_M)
    np.fill_diagonal(same_point, False)
    # The first other vertex at the same point, else the vertex itself.
    twin = np.arange(n_wedges)
    if n_wedges:  # (argmax refuses an empty axis)
        twin = np.where(same_point.any(axis=1), same_point.argmax(axis=1), twin)
    solid_side, encloses = convex_loops(a, geometry.segment_ends, geometry.circles[:, :2])
    n_rel = 3 * n_candidates
    n_position_rows = len(position_map)
    n_occlusion_rows = 3 * n_rows
    first_test_row = n_position_rows + n_occlusion_rows
    ranges_start = first_test_row + 3 * n_candidates
    return EchoTables(
        position_map=position_map,
        occlusion_map=occlusion_map,
        n_position_rows=n_position_rows,
        n_segments=n_segments,
        n_circles=n_circles,
        n_vertices=n_vertices,
        n_wedges=n_wedges,
        radius=geometry.circles[:, 2].copy(),
        radius_sq=geometry.circles[:, 2] ** 2,
        solid_side=solid_side,
        encloses=encloses,
        twin=twin,
        twin_comes_first=twin < np.arange(n_wedges),
        rel_rows=slice(0, n_rel),
        along_rows=slice(n_rel, n_rel + n_segments),
        distance_rows=slice(n_rel + n_segments, n_rel + 2 * n_segments),
        wedge_a_rows=slice(n_rel + 2 * n_segments, n_rel + 2 * n_segments + n_wedges),
        wedge_b_rows=slice(n_rel + 2 * n_segments + n_wedges, n_position_rows),
        occlusion_rows=slice(n_position_rows, first_test_row),
        first_test_row=first_test_row,
        ranges_rows=slice(ranges_start, ranges_start + n_candidates),
        amplitudes_rows=slice(ranges_start + n_candidates, ranges_start + 2 * n_candidates),
        kind_codes=(plane, cylinder, edge),
    )


def convex_loops(
    starts: FloatArray, ends: FloatArray, centres: FloatArray
) -> tuple[FloatArray, np.ndarray]:
    """Per segment: the side of its solid and whether it belongs to an enclosure.

    Segments chained end to start into a closed convex polygon are either an *enclosure* (the
    polygon contains every end point and centre of the geometry: a room, solid outside) or an
    obstacle (a box, solid inside). ``solid_side`` is +1 when the solid lies on the segment's
    left, -1 on its right, and 0 for segments of open chains (free walls), which reflect on
    both sides. Which end meets which start is measured here (numpy's ``hypot``); the chains
    and verdicts are a compiled loop (:func:`~sonar_gym.sonar.loop_kernels.solid_sides`).
    """
    joins = _closer_than(ends, starts, LOOP_TOLERANCE_M)  # [i, j]: end i meets start j
    return solid_sides(starts, ends, centres, joins, LOOP_TOLERANCE_M)  # type: ignore[no-any-return]


def _closer_than(from_points: FloatArray, to_points: FloatArray, tolerance_m: float) -> np.ndarray:
    """``_pairwise_distances(from_points, to_points) < tolerance_m``, decided by a compiled
    loop (:func:`~sonar_gym.sonar.loop_kernels.closer_than`) unless a pair lies at a hair from
    the tolerance, when numpy measures them all."""
    closer, undecided = closer_than(from_points, to_points, tolerance_m)
    if undecided:
        closer = _pairwise_distances(from_points, to_points) < tolerance_m
    return closer  # type: ignore[no-any-return]


def _pairwise_distances(from_points: FloatArray, to_points: FloatArray) -> FloatArray:
    """``[i, j]``: the distance from ``from_points[i]`` to ``to_points[j]`` (metres)."""
    return np.hypot(
        to_points[None, :, 0] - from_points[:, None, 0],
        to_points[None, :, 1] - from_points[:, None, 1],
    )
