"""A vectorised, read-only copy of a scenario's static geometry, for the sensors.

pymunk is the single source of truth for collisions (see :mod:`sonar_gym.world`); the sonar
works on these flat numpy arrays instead, so a whole pan is array arithmetic. Everything is in
metres in the world frame {W}.

Primitives:
    segments: every straight reflecting surface: the room's four walls, free walls and the four
        sides of every box. Plane reflectors.
    circles: cylinders, ``[x, y, radius]``.
    vertices: every segment end point, merged where segments meet. Each vertex keeps the two
        unit directions along its segments (``vertex_arms``); the vertex is a *concave corner*
        (a strong retro-reflector) when seen from inside the wedge between its arms with an
        opening below 180 deg, and a *convex edge* (a weak diffractor) otherwise. A free wall
        end has both arms equal, so it is always an edge.
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from sonar_gym.geometry_kernels import ALONG_COSINE, corner_arms
from sonar_gym.pose import FloatArray
from sonar_gym.scenario import Room, Scenario, Vec2, Wall

_MERGE_TOLERANCE_M = 1e-6
_FLUSH_TOLERANCE_M = 1e-3
GEOMETRY_CACHE_SIZE = 32
"""How many scenarios' geometries :func:`static_geometry` keeps."""
_ALL_PAIRS_MAX = 1024
"""Up to this many (point, segment) pairs, :meth:`_SegmentIndex.near_pairs` tests every pair
instead of asking the k-d tree (cheaper for a room's few walls and a few boxes)."""


@dataclass(frozen=True, eq=False)
class StaticGeometry:
    """Flat arrays of the static reflectors of a scenario (metres, {W}).

    Attributes:
        segment_starts, segment_ends: ``(S, 2)`` end points of every plane reflector.
        segment_mapped: ``(S,)`` whether each segment is in the localizer's map.
        circles: ``(C, 3)`` cylinders as ``[x, y, radius]``.
        circle_mapped: ``(C,)`` whether each cylinder is in the localizer's map.
        vertices: ``(V, 2)`` merged segment end points.
        vertex_arms: ``(V, 2, 2)`` unit vectors from each vertex along its (up to) two segments.
    """

    segment_starts: FloatArray
    segment_ends: FloatArray
    segment_mapped: np.ndarray
    circles: FloatArray
    circle_mapped: np.ndarray
    vertices: FloatArray
    vertex_arms: FloatArray

    @property
    def segments(self) -> FloatArray:
        """``(S, 2, 2)`` segments as ``[[ax, ay], [bx, by]]``."""
        return np.stack([self.segment_starts, self.segment_ends], axis=1)

    @property
    def n_segments(self) -> int:
        return len(self.segment_starts)

    @property
    def n_circles(self) -> int:
        return len(self.circles)

    def is_concave_from(self, point: FloatArray) -> np.ndarray:
        """``(V,)`` whether each vertex acts as a concave corner seen from ``point`` (metres, {W}).

        True when the two arms open by less than 180 deg and ``point`` lies strictly inside the
        wedge between them: there the two faces form a retro-reflector.
        """
        arm_a, arm_b = self.vertex_arms[:, 0], self.vertex_arms[:, 1]
        to_point = np.asarray(point, dtype=np.float64)[None, :] - self.vertices
        cross_ab = arm_a[:, 0] * arm_b[:, 1] - arm_a[:, 1] * arm_b[:, 0]
        cross_ap = arm_a[:, 0] * to_point[:, 1] - arm_a[:, 1] * to_point[:, 0]
        cross_pb = to_point[:, 0] * arm_b[:, 1] - to_point[:, 1] * arm_b[:, 0]
        # For a convex wedge (opening < 180 deg) the point is inside when it is on the same
        # side of both arms as the other arm.
        sign = np.sign(cross_ab)
        return (np.abs(cross_ab) > 1e-9) & (sign * cross_ap > 0) & (sign * cross_pb > 0)


def build_static_geometry(scenario: Scenario) -> StaticGeometry:
    """Flatten a scenario's room, walls, boxes and cylinders into :class:`StaticGeometry`.

    The corner analysis finds coincident end points and segments through a point with k-d
    trees (:class:`_SegmentIndex`), so the build takes O(n log n) in the number of segments.
    """
    walls = _wall_corners(scenario.room, scenario.walls)
    box_starts = np.array([box.corners for box in scenario.boxes], dtype=np.float64)
    box_starts = box_starts.reshape(-1, 4, 2)
    box_ends = ring_shift(box_starts, 1, axis=1)
    box_mapped = np.array([box.mapped for box in scenario.boxes], dtype=bool)
    segment_starts = np.concatenate([walls.index.starts, box_starts.reshape(-1, 2)])
    segment_ends = np.concatenate([walls.index.ends, box_ends.reshape(-1, 2)])
    mapped = np.concatenate([walls.mapped, np.repeat(box_mapped, 4)])
    box_corners, box_arms = _box_corner_arms(box_starts, walls.index)
    vertices = np.concatenate([walls.vertices, box_corners])
    arms = np.concatenate([walls.arms, box_arms])
    circles = np.array(
        [[c.center[0], c.center[1], c.radius] for c in scenario.cylinders], dtype=np.float64
    ).reshape(-1, 3)
    geometry = StaticGeometry(
        segment_starts=segment_starts,
        segment_ends=segment_ends,
        segment_mapped=mapped,
        circles=circles,
        circle_mapped=np.array([c.mapped for c in scenario.cylinders], dtype=bool),
        vertices=vertices,
        vertex_arms=arms,
    )
    for array in vars(geometry).values():
        array.setflags(write=False)  # shared between worlds by static_geometry()
    return geometry


@functools.lru_cache(maxsize=GEOMETRY_CACHE_SIZE)
def static_geometry(scenario: Scenario) -> StaticGeometry:
    """The :class:`StaticGeometry` of ``scenario``, built once per scenario content.

    Equal scenarios (frozen dataclasses, compared by value) share one read-only geometry, so
    the sonar's per-geometry tables (:mod:`sonar_gym.sonar.echo_tables`) are reused too. The
    last :data:`GEOMETRY_CACHE_SIZE` scenarios are kept.
    """
    return build_static_geometry(scenario)


def _room_and_wall_segments(
    room: Room | None, walls: tuple[Wall, ...]
) -> tuple[list[Vec2], list[Vec2], list[bool]]:
    """Start points, end points and map flags of the room's four walls (counter-clockwise
    from ``room.min``) then of the free walls, in scenario order."""
    starts: list[Vec2] = []
    ends: list[Vec2] = []
    mapped: list[bool] = []
    if room is not None:
        corners = room.corners
        for i, corner in enumerate(corners):
            starts.append(corner)
            ends.append(corners[(i + 1) % len(corners)])
            mapped.append(True)
    for wall in walls:
        starts.append(wall.a)
        ends.append(wall.b)
        mapped.append(wall.mapped)
    return starts, ends, mapped


@dataclass(frozen=True, eq=False)
class _WallCorners:
    """The room's and free walls' segments, indexed, with their map flags, merged vertices and
    arms."""

    index: _SegmentIndex
    mapped: np.ndarray
    vertices: FloatArray
    arms: FloatArray


@functools.lru_cache(maxsize=GEOMETRY_CACHE_SIZE)
def _wall_corners(room: Room | None, walls: tuple[Wall, ...]) -> _WallCorners:
    """The corner analysis of the room and the free walls alone (:func:`_merge_vertices`).

    It does not depend on the boxes and cylinders, so scenarios that differ only in those (an
    env that draws new obstacles every episode) share it: built once per room and walls.
    """
    starts, ends, mapped = _room_and_wall_segments(room, walls)
    index = _SegmentIndex(
        np.array(starts, dtype=np.float64).reshape(-1, 2),
        np.array(ends, dtype=np.float64).reshape(-1, 2),
    )
    vertices, arms = _merge_vertices(index)
    wall_mapped = np.array(mapped, dtype=bool)
    for array in (
        index.starts,
        index.ends,
        index.spans,
        index.lengths,
        wall_mapped,
        vertices,
        arms,
    ):
        array.setflags(write=False)
    return _WallCorners(index, wall_mapped, vertices, arms)


class _SegmentIndex:
    """Segments looked up by the points near them, in O(log n) per query.

    A k-d tree holds points sampled along every segment at most ``spacing`` apart, so a point
    within ``tolerance`` of a segment lies within ``spacing / 2 + tolerance`` of one of its
    samples. ``spacing`` is the median segment length, but never so short that the samples
    outnumber eight per segment on average.
    """

    def __init__(self, starts: FloatArray, ends: FloatArray) -> None:
        self.starts, self.ends = starts, ends
        self.spans = ends - starts
        self.lengths = _norms(self.spans)
        n = self.n_segments = len(starts)
        self._all_pairs: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # per number of points
        if n == 0:
            self._tree: cKDTree | None = None
            return
        spacing = max(float(np.median(self.lengths)), float(self.lengths.sum()) / (8 * n))
        pieces = np.maximum(np.ceil(self.lengths / spacing).astype(np.int64), 1)
        per_segment = pieces + 1
        owner = np.repeat(np.arange(n), per_segment)
        self._owner_array = owner  # the segment of each sample, read by near_pairs()
        self._owner: list[int] = owner.tolist()  # the same, read by near()
        first = np.repeat(np.cumsum(per_segment) - per_segment, per_segment)
        fraction = (np.arange(len(owner)) - first) / np.repeat(pieces, per_segment)
        samples = starts[owner] + self.spans[owner] * fraction[:, None]
        self._tree = cKDTree(samples)
        self._reach = float(np.max(self.lengths / pieces)) / 2.0 * (1.0 + 1e-9) + 1e-12

    def near(self, points: FloatArray, tolerance_m: float) -> list[list[int]]:
        """Per point, the ascending indices of the segments that may pass within ``tolerance_m``."""
        if self._tree is None or len(points) == 0:
            return [[] for _ in range(len(points))]
        hits = self._tree.query_ball_point(points, self._reach + tolerance_m)
        owner = self._owner
        return [sorted({owner[sample] for sample in h}) for h in hits]

    def near_pairs(self, points: FloatArray, tolerance_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Pairs ``(point index, segment index)``, two int64 arrays in no particular order (a
        pair may repeat), that hold every pair of :meth:`near`.

        With few segments and points (at most :data:`_ALL_PAIRS_MAX` pairs) that is every pair,
        a superset that passes the same segments: a segment passing within ``tolerance_m`` of
        a point (ends included, as :func:`_segments_containing` tests) lies within
        ``sqrt(2) tolerance_m`` of its nearest end sample, or ``sqrt(reach^2 + tolerance_m^2)``
        of its nearest sample, so the tree's radius ``reach + tolerance_m`` finds it when
        ``reach >= tolerance_m``; only then are all pairs used.
        """
        if self._tree is None or len(points) == 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        n_points = len(points)
        if n_points * self.n_segments <= _ALL_PAIRS_MAX and self._reach >= tolerance_m:
            pairs = self._all_pairs.get(n_points)
            if pairs is None:
                pairs = (
                    np.repeat(np.arange(n_points), self.n_segments),
                    np.tile(np.arange(self.n_segments), n_points),
                )
                for array in pairs:
                    array.setflags(write=False)
                self._all_pairs[n_points] = pairs
            return pairs
        hits = self._tree.query_ball_point(points, self._reach + tolerance_m)
        counts = [len(h) for h in hits]
        samples = np.fromiter(itertools.chain.from_iterable(hits), np.int64, sum(counts))
        point_index = np.repeat(np.arange(len(points)), counts)
        return point_index, self._owner_array[samples]


def _box_corner_arms(
    box_corners: FloatArray, walls: _SegmentIndex
) -> tuple[FloatArray, FloatArray]:
    """Corners of every box with their arms; ``box_corners`` is ``(B, 4, 2)``, counter-clockwise.

    A free-standing box corner faces free space with an opening of 270 deg: always a convex
    edge, which equal arms encode. A corner standing on a wall (a table pushed against it)
    is hidden; instead the box's side leaving the wall and the wall form a concave 90 deg
    dihedral there, which the arms ``(side away from the wall, wall away from the box)``
    encode. A compiled loop decides the corners (:func:`~sonar_gym.geometry_kernels.corner_arms`);
    those it leaves undecided, at a hair from a threshold, are tested here as numpy rounds.
    """
    points = box_corners.reshape(-1, 2)
    to_next = (ring_shift(box_corners, 1, axis=1) - box_corners).reshape(-1, 2)
    to_previous = (ring_shift(box_corners, -1, axis=1) - box_corners).reshape(-1, 2)
    to_next /= _norms(to_next)[:, None]
    to_previous /= _norms(to_previous)[:, None]
    point_index, segment = walls.near_pairs(points, _FLUSH_TOLERANCE_M)
    arms, undecided = corner_arms(
        points,
        to_next,
        to_previous,
        walls.starts,
        walls.spans,
        walls.lengths,
        point_index,
        segment,
        _FLUSH_TOLERANCE_M,
    )
    for k in np.flatnonzero(undecided).tolist():
        arms[k] = _one_corner_arms(points[k], to_next[k], to_previous[k], walls)
    return points.copy(), arms


def _one_corner_arms(
    point: FloatArray, to_next: FloatArray, to_previous: FloatArray, walls: _SegmentIndex
) -> FloatArray:
    """``(2, 2)`` arms of one box corner (see :func:`_box_corner_arms`), tested with numpy."""
    [candidates] = walls.near(point[None, :], _FLUSH_TOLERANCE_M)
    wall = _segment_containing(point, walls, candidates, _FLUSH_TOLERANCE_M)
    if wall is None:
        return np.stack([to_next, to_next])
    along_wall_next = abs(float(wall @ to_next)) > ALONG_COSINE
    leaving = to_previous if along_wall_next else to_next
    flush_side = to_next if along_wall_next else to_previous
    return np.stack([leaving, -flush_side])


def _segment_containing(
    point: FloatArray, walls: _SegmentIndex, candidates: list[int], tolerance_m: float
) -> FloatArray | None:
    """Unit direction of the first segment passing within ``tolerance_m`` of ``point`` (ends
    included), among the ascending ``candidates``."""
    for i in candidates:
        span, length = walls.spans[i], walls.lengths[i]
        t = float((point - walls.starts[i]) @ span) / length
        if -tolerance_m <= t <= length + tolerance_m:
            offset = point - (walls.starts[i] + span * t / length)
            if np.sqrt(offset.dot(offset)) <= tolerance_m:  # np.linalg.norm's arithmetic
                return span / length
    return None


def _merge_vertices(walls: _SegmentIndex) -> tuple[FloatArray, FloatArray]:
    """Merge coincident segment end points; keep up to two arms per vertex.

    End points are taken in order (start then end of each segment); each joins the earliest
    vertex closer than the merge tolerance, else starts a new vertex. A vertex with one arm
    is a free end, or a T-junction when it lies inside another segment.
    """
    n = len(walls.starts)
    points = np.stack([walls.starts, walls.ends], axis=1).reshape(-1, 2)
    directions = walls.spans / walls.lengths[:, None]
    point_arms = np.stack([directions, -directions], axis=1).reshape(-1, 2)
    earlier: dict[int, list[int]] = {}
    if n:
        pairs = cKDTree(points).query_pairs(_MERGE_TOLERANCE_M, output_type="ndarray")
        if len(pairs):
            gap = np.linalg.norm(points[pairs[:, 0]] - points[pairs[:, 1]], axis=1)
            for i, j in np.sort(pairs[gap < _MERGE_TOLERANCE_M], axis=1):
                earlier.setdefault(int(j), []).append(int(i))
    owner = list(range(2 * n))
    for j, before in sorted(earlier.items()):
        joinable = [i for i in before if owner[i] == i]
        if joinable:
            owner[j] = min(joinable)
    members: dict[int, list[int]] = {k: [] for k in range(2 * n) if owner[k] == k}
    for k, root in enumerate(owner):
        members[root].append(k)
    lonely = [r for r in members if len(members[r]) == 1]
    hosts = dict(zip(lonely, walls.near(points[lonely], _MERGE_TOLERANCE_M), strict=True))
    vertex_points: list[FloatArray] = []
    vertex_arms: list[list[FloatArray]] = []
    for root, joined in members.items():
        point = points[root]
        if len(joined) > 1:
            vertex_points.append(point)
            vertex_arms.append([point_arms[joined[0]], point_arms[joined[1]]])
            continue
        arm = point_arms[root]
        host = _segment_through_interior(point, walls, hosts[root])
        if host is None:  # a free end: an edge from every side
            vertex_points.append(point)
            vertex_arms.append([arm, arm])
        else:  # a T-junction: two concave corners, one on each side of the free wall
            for along in (host, -host):
                vertex_points.append(point)
                vertex_arms.append([arm, along])
    return (
        np.array(vertex_points, dtype=np.float64).reshape(-1, 2),
        np.array(vertex_arms, dtype=np.float64).reshape(-1, 2, 2),
    )


def _segment_through_interior(
    point: FloatArray, walls: _SegmentIndex, candidates: list[int]
) -> FloatArray | None:
    """Unit direction of the first of the ascending ``candidates`` with ``point`` inside it."""
    for i in candidates:
        start, span = walls.starts[i], walls.spans[i]
        length_sq = float(span @ span)
        t = float((point - start) @ span) / length_sq
        if _MERGE_TOLERANCE_M < t * np.sqrt(length_sq) < np.sqrt(length_sq) - _MERGE_TOLERANCE_M:
            foot = start + t * span
            if np.linalg.norm(point - foot) < _MERGE_TOLERANCE_M:
                return span / np.sqrt(length_sq)
    return None


def ring_shift(values: np.ndarray, step: int, axis: int = 0) -> np.ndarray:
    """``np.roll(values, -step, axis)``: along ``axis``, the element ``step`` places after each
    one, wrapping round (``step = 1`` the next corner of a polygon, ``-1`` the previous one).

    Two slices joined: ``np.roll``'s general bookkeeping costs several times this move on the
    few corners of a room's polygons.
    """
    after, before = [slice(None)] * values.ndim, [slice(None)] * values.ndim
    after[axis], before[axis] = slice(step, None), slice(None, step)
    return np.concatenate((values[tuple(after)], values[tuple(before)]), axis=axis)


def _dots(first: FloatArray, second: FloatArray) -> FloatArray:
    """``(N,)`` dot products of the rows of two ``(N, 2)`` arrays, each rounded as ``a @ b``
    of the two rows (the batched product takes the same dot product per row)."""
    return np.matmul(first[:, None, :], second[:, :, None])[:, 0, 0]


def _norms(vectors: FloatArray) -> FloatArray:
    """``(N,)`` Euclidean lengths of ``(N, 2)`` vectors, rounded as ``np.linalg.norm`` of each.

    A batched matrix product rounds like the dot product ``np.linalg.norm`` uses, so the
    geometry stays bit-identical to a per-vector build.
    """
    return np.sqrt(_dots(vectors, vectors))
