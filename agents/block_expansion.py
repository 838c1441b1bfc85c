"""Scripted agents for ``SonarGym/BlockExpansion-v0`` (registered on import).

``paper``: Roh et al.'s choices. d1, d2, d3 = 450, 250, 50 mm (Tables II-III, Figs. 6-7).
Over three areas, d4, d5, d6 = 300, 400, 700 mm: Table IV's second row. Its first row
(200, 200, 200 mm, Figs. 6-7) repeats one distance, which a path that crosses the boundary
once meets only twice (approaching and leaving), so the third point is never saved; the second
row is the first the paper's path can complete. With ``ordering="decreasing"`` the rising
d4..d6 cannot be expressed and the agent repeats 450, 250, 50 mm.

``spread``: beyond the paper. It rebuilds the nominal path from the observation (the parabola's
parameters) and the boundary from the beacons the robot knows (surveyed or calibrated; the rough
prior for a beacon not calibrated yet), replays the three-point extraction of Sec. III.C on
that path for every triple of a grid of d's (30 mm apart over the action's range), and picks
the triple whose three saved positions calibrate the new beacon best. The score is the
dilution of precision of the calibration, ``sqrt(trace((H^T H)^-1))`` with H the unit
vectors from the three positions to the new beacon's known or prior position: how many times
the range error the calibrated position errs (``criterion="condition"`` uses instead the
condition number of the positions, the number
:func:`~sonar_gym.localization.roh.auto_calibrate` reports; it does less well over three
areas). A triple must be met clearly (margins on the distances and the path's end). Before a
boundary that is not the last one, the agent looks one boundary ahead: a triple scores the
worse of its own score and the best score the next boundary can still reach from where this
triple hands over.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
import numpy.typing as npt

from sonar_gym.agents.base import ScriptedAgent
from sonar_gym.envs.block_expansion import BlockExpansionEnv
from sonar_gym.maps import MAP_FRAME_CENTRE_M as FRAME_CENTRE_M
from sonar_gym.maps import MAP_FRAME_HALF_SPAN_M as FRAME_HALF_SPAN_M
from sonar_gym.maps import PRIOR_ONLY, SURVEYED, UNUSED
from sonar_gym.localization.roh import distance_to_segment, parabolic_path
from sonar_gym.pose import FloatArray
from sonar_gym.routes import CURVATURE_SCALE_PER_M, PATH_STEP_M

ENV_ID = "SonarGym/BlockExpansion-v0"

PAPER_FIRST_TRIPLE_M = (0.45, 0.25, 0.05)
"""d1, d2, d3 of Tables II-III and Figs. 6-7, metres."""
PAPER_SECOND_TRIPLE_M = (0.30, 0.40, 0.70)
"""d4, d5, d6 of Table IV's second row, metres (see the module docstring)."""

PRIOR_HYPOTHESIS_SIGMAS = 1.5
"""How far (in prior standard deviations) the spread agent shifts a beacon known only roughly."""

CRITERIA = ("gdop", "condition")
"""Scores the spread agent can rank triples by."""

IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True)
class Beacons:
    """Beacon positions as the robot knows them (metres, {W}), which are rough priors and
    which are surveyed."""

    positions: dict[str, FloatArray]
    uncertain: frozenset[str]
    surveyed: frozenset[str]


def boundary_of(observation: np.ndarray, layout: dict[str, slice]) -> int:
    """Index of the boundary an observation asks a decision for (0 once the episode is over)."""
    one_hot = observation[layout["boundary"]]
    return int(np.argmax(one_hot)) if np.any(one_hot > 0.5) else 0


class PaperAgent(ScriptedAgent[BlockExpansionEnv]):
    """Roh et al.'s d's: 450/250/50 mm, then 300/400/700 mm over a second boundary."""

    name = "paper"

    def __init__(self, env: gym.Env[Any, Any]) -> None:
        super().__init__(env)
        self._triples = [PAPER_FIRST_TRIPLE_M, PAPER_SECOND_TRIPLE_M]
        if self._env.config.ordering == "decreasing":
            self._triples = [PAPER_FIRST_TRIPLE_M, PAPER_FIRST_TRIPLE_M]

    def decide(self, observation: np.ndarray) -> np.ndarray:
        config = self._env.config
        if config.decisions == "all_at_once":
            chosen = [d for triple in self._triples[: config.n_boundaries] for d in triple]
        else:
            chosen = list(self._triples[boundary_of(observation, self._env.observation_layout)])
        return self._env.encode_distances(chosen)


class SpreadAgent(ScriptedAgent[BlockExpansionEnv]):
    """Best-placed calibration positions on the nominal path (see the module docstring).

    Args:
        env: the environment (its ordering, distance range and decision mode are read).
        grid_step_m: spacing of the candidate d's, metres.
        end_margin_m: path length to leave after the last saved position of the last boundary,
            metres, so that the robot's estimated path still crosses it.
        crossing_margin_m: how clearly each d must be crossed on the nominal path, metres
            (see :meth:`_scores`): the robot's estimated path and boundary differ from
            the nominal ones by millimetres to centimetres.
        lookahead_step: path samples between the hand-over indices for which the next
            boundary's best score is computed.
        robust: score a boundary whose end beacon is only roughly known by its worst case over
            shifted priors (see :meth:`_boundary_hypotheses`) instead of the prior alone.
            Default: only when all boundaries are decided at once; deciding boundary by
            boundary, the next decision sees the calibrated beacon anyway.
        criterion: ``"gdop"`` (default) or ``"condition"`` (see the module docstring).
    """

    name = "spread"

    def __init__(
        self,
        env: gym.Env[Any, Any],
        grid_step_m: float = 0.03,
        end_margin_m: float = 0.1,
        crossing_margin_m: float = 0.05,
        lookahead_step: int = 15,
        robust: bool | None = None,
        criterion: str = "gdop",
    ) -> None:
        super().__init__(env)
        config = self._env.config
        low, high = config.distance_range_m
        count = max(int(round((high - low) / grid_step_m)) + 1, 3)
        self.grid_m = np.linspace(low, high, count)
        self.end_margin_samples = int(np.ceil(end_margin_m / PATH_STEP_M))
        self.crossing_margin_m = crossing_margin_m
        self.lookahead_step = lookahead_step
        self.decreasing = config.ordering == "decreasing"
        self.prior_std_m = float(config.beacon_prior_std_m)
        self.robust = config.decisions == "all_at_once" if robust is None else robust
        if criterion not in CRITERIA:
            raise ValueError(f"criterion must be one of {CRITERIA}; got {criterion!r}")
        self.criterion = criterion
        self.sensor_height_m = float(self._env.sensor_height_m)
        self.areas = self._env.areas
        areas = self.areas
        self.slot_names = self._env.slot_names
        self.boundaries = tuple(
            tuple(n for n in areas[k] if n in areas[k + 1]) for k in range(len(areas) - 1)
        )
        g1, g2, g3 = np.meshgrid(*(np.arange(count),) * 3, indexing="ij")
        triples = np.stack([g1.ravel(), g2.ravel(), g3.ravel()], axis=1)
        if self.decreasing:
            triples = triples[(triples[:, 0] > triples[:, 1]) & (triples[:, 1] > triples[:, 2])]
        self._triples: IntArray = triples

    def decide(self, observation: np.ndarray) -> np.ndarray:
        env = self._env
        layout = env.observation_layout
        beacons = self._beacons(observation[layout["beacons"]])
        path = self._path(observation[layout["path"]])
        boundary = boundary_of(observation, layout)
        start = int(round(float(observation[layout["progress"]][0]) * (len(path) - 1)))
        if env.config.decisions == "all_at_once":
            chosen = self.plan(path, beacons, 0, 0, env.config.n_boundaries)
        else:
            chosen = self.plan(path, beacons, boundary, start, 1)
        return env.encode_distances([d for triple in chosen for d in triple])

    # --- planning ----------------------------------------------------------------------------
    def plan(
        self,
        path: FloatArray,
        beacons: Beacons,
        boundary: int,
        start: int,
        count: int,
    ) -> list[tuple[float, float, float]]:
        """d triples (metres) for ``count`` boundaries from ``boundary`` on, the first boundary's
        extraction starting at path index ``start``."""
        chosen: list[tuple[float, float, float]] = []
        for k in range(boundary, boundary + count):
            triple, start = self._best(path, beacons, k, start)
            chosen.append(triple)
        return chosen

    def _best(
        self, path: FloatArray, beacons: Beacons, boundary: int, start: int
    ) -> tuple[tuple[float, float, float], int]:
        """The chosen triple for one boundary and the path index where the next one starts.

        Before the last boundary a triple scores the worse of its own score and the best score
        the next boundary can still reach from where this one hands over; the latter is
        computed for hand-over indices rounded up to a grid of ``lookahead_step`` samples.
        """
        last = boundary == len(self.boundaries) - 1
        scores, saved = self._candidates(path, beacons, boundary, start, last)
        if not np.any(np.isfinite(scores)):
            return self._fallback(), start
        switches = self._switch_indices(path, beacons, boundary, saved[:, 2])
        if last:
            best = int(np.argmin(scores))
            return self._triple(best), int(switches[best])
        n = len(path)
        step = self.lookahead_step
        buckets = np.minimum(-(-switches // step) * step, n - 1)
        following = np.full(len(scores), np.inf)
        usable = np.isfinite(scores)
        for bucket in np.unique(buckets[usable]):
            next_scores, _ = self._candidates(path, beacons, boundary + 1, int(bucket), True)
            following[usable & (buckets == bucket)] = np.min(next_scores)
        scores = np.maximum(scores, following)
        best = int(np.argmin(scores)) if np.any(np.isfinite(scores)) else int(np.argmin(scores))
        return self._triple(best), int(switches[best])

    def _candidates(
        self,
        path: FloatArray,
        beacons: Beacons,
        boundary: int,
        start: int,
        last: bool,
    ) -> tuple[FloatArray, IntArray]:
        """Scores and saved indices ``(triples, 3)`` of the grid for one boundary.

        The score is the worst over the boundary's hypotheses (inf when a triple is not met
        under one of them); the saved indices are those of the nominal boundary.
        """
        worst: FloatArray | None = None
        nominal_saved: IntArray | None = None
        strict = any(name not in beacons.surveyed for name in self.boundaries[boundary])
        new_name = next(n for n in self._area(boundary + 1) if n not in self._area(boundary))
        hypotheses = self._boundary_hypotheses(beacons, boundary)
        if not self.robust:
            hypotheses = hypotheses[:1]
        for a, b in hypotheses:
            distance = distance_to_segment(path, a, b)
            saved = replay_extraction(distance, self.grid_m, self._triples, start)
            scores = self._scores(
                path, distance, saved, start, last, strict, beacons.positions.get(new_name)
            )
            if worst is None:
                worst, nominal_saved = scores, saved
            else:
                worst = np.maximum(worst, scores)
        assert worst is not None and nominal_saved is not None
        return worst, nominal_saved

    def _scores(
        self,
        path: FloatArray,
        distance: FloatArray,
        saved: IntArray,
        start: int,
        last: bool,
        strict: bool,
        new_beacon: FloatArray | None = None,
    ) -> FloatArray:
        """The criterion of each triple's saved positions (smaller is better); inf if unusable.

        Usable: three distinct positions, the last one at least ``end_margin_m`` of path before
        the end (last boundary), and every crossing clear by ``crossing_margin_m``: the
        distance to the boundary where the search for d1 starts lies that far from d1 (later
        searches start just past the previous d, on a side the grid's spacing makes clear),
        and after each crossing the path goes on that far past the d. ``D`` is never negative:
        for a boundary between surveyed beacons (``strict`` false) a d below the margin need
        only be passed half way to zero; a boundary with a calibrated end (``strict``) keeps
        the full margin, because the robot's fixes, made with the calibrated beacon, stay out
        of a band along the calibrated boundary where the range circles do not meet.
        """
        n = len(path)
        limit = n - 1 - (self.end_margin_samples if last else 0)
        usable = (saved[:, 0] < saved[:, 1]) & (saved[:, 1] < saved[:, 2]) & (saved[:, 2] <= limit)
        targets = self.grid_m[self._triples]
        margin = self.crossing_margin_m
        suffix_min = np.minimum.accumulate(distance[::-1])[::-1]
        suffix_max = np.maximum.accumulate(distance[::-1])[::-1]
        previous = np.full(len(saved), distance[min(max(start, 0), n - 1)])
        usable &= np.abs(previous - targets[:, 0]) >= margin
        for k in range(3):
            index = np.minimum(saved[:, k], n - 1)
            downward = previous > targets[:, k]
            below = targets[:, k] - (margin if strict else np.minimum(margin, targets[:, k] / 2))
            usable &= np.where(
                downward, suffix_min[index] <= below, suffix_max[index] >= targets[:, k] + margin
            )
            previous = distance[index]
        scores = np.full(len(saved), np.inf)
        points = path[np.minimum(saved[usable], n - 1)]
        if self.criterion == "gdop" and new_beacon is not None:
            scores[usable] = dilution_of_precision(points, new_beacon, self.sensor_height_m)
        else:
            scores[usable] = condition_number(
                points[:, 1] - points[:, 0], points[:, 2] - points[:, 0]
            )
        return scores

    def _boundary_hypotheses(
        self, beacons: Beacons, boundary: int
    ) -> list[tuple[FloatArray, FloatArray]]:
        """The boundary's end points: nominal first, then with each prior-only end shifted.

        A beacon known only from its rough prior is shifted by 1.5 prior standard deviations
        along +-x and +-y, one shift at a time.
        """
        names = self.boundaries[boundary]
        start, end_point = (beacons.positions[name][:2] for name in names)
        nominal = (start, end_point)
        hypotheses: list[tuple[FloatArray, FloatArray]] = [nominal]
        spread = PRIOR_HYPOTHESIS_SIGMAS * self.prior_std_m
        for end, name in enumerate(names):
            if name not in beacons.uncertain or spread == 0.0:
                continue
            for shift in ((spread, 0.0), (-spread, 0.0), (0.0, spread), (0.0, -spread)):
                moved = list(nominal)
                moved[end] = nominal[end] + np.array(shift)
                hypotheses.append((moved[0], moved[1]))
        return hypotheses

    def _switch_indices(
        self, path: FloatArray, beacons: Beacons, boundary: int, third: IntArray
    ) -> IntArray:
        """The runner's hand-over for each triple: the index after the first fix at or after
        the third saved one that lies past the boundary (``len(path) - 1`` if none)."""
        names = self.boundaries[boundary]
        a, b = (beacons.positions[name][:2] for name in names)
        area = self._area(boundary)
        opposite = next(beacons.positions[n][:2] for n in area if n not in names)
        inner = _side(opposite, a, b)
        sides = _side(path, a, b)
        n = len(path)
        past = np.where((sides != 0.0) & (sides != inner), np.arange(n), n)
        first_past = np.concatenate([np.minimum.accumulate(past[::-1])[::-1], [n]])
        following = first_past[np.minimum(third, n)] + 1
        return np.minimum(following, n - 1).astype(np.int64)

    def _area(self, boundary: int) -> tuple[str, str, str]:
        return self.areas[boundary]

    def _triple(self, index: int) -> tuple[float, float, float]:
        g = self.grid_m[self._triples[index]]
        return float(g[0]), float(g[1]), float(g[2])

    def _fallback(self) -> tuple[float, float, float]:
        return PAPER_FIRST_TRIPLE_M

    # --- reading the observation ---------------------------------------------------------------
    def _beacons(self, slots: np.ndarray) -> Beacons:
        values = np.asarray(slots, dtype=np.float64).reshape(-1, 4)
        positions: dict[str, FloatArray] = {}
        uncertain: set[str] = set()
        surveyed: set[str] = set()
        for name, slot in zip(self.slot_names, values, strict=False):
            if slot[3] != UNUSED:
                positions[name] = slot[:3] * FRAME_HALF_SPAN_M + FRAME_CENTRE_M
            if slot[3] == PRIOR_ONLY:
                uncertain.add(name)
            if slot[3] == SURVEYED:
                surveyed.add(name)
        return Beacons(positions, frozenset(uncertain), frozenset(surveyed))

    @staticmethod
    def _path(values: np.ndarray) -> FloatArray:
        v = np.asarray(values, dtype=np.float64)
        x_start = v[0] * FRAME_HALF_SPAN_M[0] + FRAME_CENTRE_M[0]
        x_end = v[2] * FRAME_HALF_SPAN_M[0] + FRAME_CENTRE_M[0]
        vertex = (
            v[4] * FRAME_HALF_SPAN_M[0] + FRAME_CENTRE_M[0],
            v[5] * FRAME_HALF_SPAN_M[1] + FRAME_CENTRE_M[1],
        )
        return parabolic_path(x_start, x_end, vertex, v[6] * CURVATURE_SCALE_PER_M, PATH_STEP_M)


def replay_extraction(
    distance_m: FloatArray, grid_m: FloatArray, triples: IntArray, start: int
) -> IntArray:
    """Indices the extraction of Sec. III.C saves, for many d triples at once.

    Mirrors :class:`~sonar_gym.localization.roh.ThreePointExtractor` on a known profile
    ``D`` of distances to the boundary: the search for each d starts at the sample where the
    previous one was saved (``start`` for d1) and saves the first later sample on the other
    side of d (the sample itself if it lies exactly on d).

    Args:
        distance_m: ``(n,)`` the profile ``D`` along the path, metres.
        grid_m: ``(m,)`` candidate d's, metres.
        triples: ``(k, 3)`` indices into ``grid_m``.
        start: index where the search for d1 starts.

    Returns:
        ``(k, 3)`` saved indices; ``n`` marks a d never met.
    """
    n = len(distance_m)
    side = np.sign(distance_m[None, :] - grid_m[:, None]).astype(np.int8)
    positions = np.broadcast_to(np.arange(n), side.shape)
    next_at_or_below = _next_index(np.where(side <= 0, positions, n), n)
    next_at_or_above = _next_index(np.where(side >= 0, positions, n), n)
    side = np.concatenate([side, np.zeros((len(grid_m), 1), dtype=np.int8)], axis=1)
    current = np.full(len(triples), min(max(start, 0), n), dtype=np.int64)
    saved = np.empty((len(triples), 3), dtype=np.int64)
    for column in range(3):
        g = triples[:, column]
        here = side[g, current]
        following = np.minimum(current + 1, n)
        crossed = np.where(here > 0, next_at_or_below[g, following], next_at_or_above[g, following])
        current = np.where(current >= n, n, np.where(here == 0, current, crossed))
        saved[:, column] = current
    return saved


def dilution_of_precision(
    points: FloatArray, beacon: FloatArray, sensor_height_m: float
) -> FloatArray:
    """``sqrt(trace((H^T H)^-1))`` of ranging a beacon from three positions, per triple.

    ``points``: ``(k, 3, 2)`` positions at ``sensor_height_m``; row i of H is the unit vector
    from position i to ``beacon`` ``(3,)``. The beacon's error is about this times the range
    error. inf where H is singular.
    """
    offsets = np.asarray(beacon, dtype=np.float64)[None, None, :] - np.concatenate(
        [points, np.full((*points.shape[:2], 1), sensor_height_m)], axis=2
    )
    units = offsets / np.linalg.norm(offsets, axis=2, keepdims=True)
    normal = np.einsum("kij,kil->kjl", units, units)
    det = np.linalg.det(normal)
    result = np.full(len(points), np.inf)
    regular = det > 1e-12
    if np.any(regular):
        result[regular] = np.sqrt(np.trace(np.linalg.inv(normal[regular]), axis1=1, axis2=2))
    return result


def condition_number(u: FloatArray, v: FloatArray) -> FloatArray:
    """Ratio of the singular values of the 2 x 2 matrices with rows ``u``, ``v`` (``(k, 2)`` each).

    With ``f = |u|^2 + |v|^2`` and ``det = u x v``: ``s1^2 s2^2 = det^2`` and
    ``s1^2 + s2^2 = f``, so ``s1 / s2 = (f + sqrt(f^2 - 4 det^2)) / (2 |det|)``; inf when
    ``det = 0``. The same number :func:`~sonar_gym.localization.roh.auto_calibrate` reports
    for positions at one height.
    """
    f = np.einsum("ij,ij->i", u, u) + np.einsum("ij,ij->i", v, v)
    det = np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    root = np.sqrt(np.maximum(f * f - 4.0 * det * det, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(det > 0.0, (f + root) / (2.0 * np.where(det > 0.0, det, 1.0)), np.inf)


def _next_index(candidates: IntArray, n: int) -> IntArray:
    """``(m, n + 1)``: for each start i, the smallest candidate index >= i (``n`` if none)."""
    reversed_min = np.minimum.accumulate(candidates[:, ::-1], axis=1)[:, ::-1]
    return np.concatenate([reversed_min, np.full((len(candidates), 1), n)], axis=1)


def _side(points: Any, a: FloatArray, b: FloatArray) -> Any:
    p = np.asarray(points, dtype=np.float64)
    direction = b - a
    offset = p - a
    return np.sign(direction[0] * offset[..., 1] - direction[1] * offset[..., 0])
