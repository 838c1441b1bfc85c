"""``SonarGym/BlockExpansion-v0``: choose the calibration distances of Roh et al.'s block expansion.

Roh et al., *Development of new block expansion algorithm for indoor mobile robot
localization* (see the env's Description). The method runs unchanged
(:class:`sonar_gym.localization.roh.BlockExpansion`) on a distance table that the one-way
ranging sensor :class:`sonar_gym.sonar.ranging.BeaconRanger` measures along the whole path at
reset (:func:`sonar_gym.routes.range_along_route`); the agent chooses the d's.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np
import numpy.typing as npt

from sonar_gym.block_expansion_view import render_drive
from sonar_gym.calibration_distances import (
    DECREASING_GAP_M,
    distances_to_fractions,
    fractions_to_distances,
)
from sonar_gym.envs.action_types import ContinuousRange, make_action_type
from sonar_gym.envs.base import INFO_KEYS, SonarEnv, StepOutcome
from sonar_gym.envs.features import Feature, Flag, Fraction, ObservationSpec
from sonar_gym.envs.config import (
    build_config,
    check_number,
    choice_field,
    number_field,
    numbers_field,
)
from sonar_gym.kept import KeptValue
from sonar_gym.localization.result import OK
from sonar_gym.localization.roh import (
    PAPER_THREE_AREAS,
    PAPER_TWO_AREAS,
    TRILATERATION_METHODS,
    BlockExpansion,
    BlockExpansionConfig,
    BlockExpansionResult,
    TruePath,
)
from sonar_gym.localization.roh_outcomes import (
    calibrated_positions,
    calibration_features,
    calibration_summaries,
    final_status,
)
from sonar_gym.maps import (
    CALIBRATED,
    PRIOR_ONLY,
    SURVEYED,
    beacon_slot_features,
    new_beacons_of_areas,
)
from sonar_gym.pose import FloatArray
from sonar_gym.routes import (
    PAPER_ROUTE,
    ParabolicRoute,
    draw_beacons_and_route,
    range_along_route,
    route_features,
)
from sonar_gym.scenario import Emitter, Scenario, load_scenario
from sonar_gym.sonar.acoustics import speed_of_sound_mps
from sonar_gym.sonar.ranging import BeaconRanger, RangingWorld, RouteGeometry
from sonar_gym.validation import MIN_SCALE
from sonar_gym.world import World

ENV_ID = "SonarGym/BlockExpansion-v0"
SCENARIO_NAME = "roh_beacons"
"""The Table I beacons A-E as a scenario (``sonar_gym/scenarios/roh_beacons.toml``)."""

TEMPERATURE_C = 20.0
"""Air temperature, deg C; the ranger converts with the speed of sound at this temperature too."""

FIRING_INTERVAL_S = 0.008
"""Not in the paper (chosen): time between two beacons' firings, seconds; a round of all five
beacons takes the paper's 40 ms localization period."""

PAPER_PATH_X_END_M = {2: 1.3, 3: 0.55}
"""x where the paper-like parabola (:func:`parabolic_path` defaults) ends: inside Area 2 of the
two-area run (Sec. IV.B), inside Area 3 of the three-area run (Sec. IV.D)."""

MAX_BEACON_SLOTS = 5
LAYOUT_JITTER_XY_M = 0.25
"""``layout="random"``: each Table I beacon moves uniformly within +-0.25 m in x and y ..."""
LAYOUT_JITTER_Z_M = 0.15
"""... and within +-0.15 m in height."""
RANDOM_CURVATURE_PER_M = (-1.3, -0.5)
"""``path="random"``: range of the parabola's coefficient ``a``, 1/m (the paper-like path: -0.9)."""
MAX_LAYOUT_TRIES = 200
MIN_BEACON_CLEARANCE_M = 0.3
"""Every beacon stands at least this far above the receiver, metres."""
BOUNDARY_END_MARGIN_M = 0.1
"""A path must cross each boundary at least this far from the boundary's end beacons, metres."""

# Normalisation of the observation (positions use the beacon map's frame, sonar_gym.maps).
NOISE_SCALE_M = 0.01
TIMER_SCALE_S = 1e-4

STATUS_RUNNING = "running"
OBSERVATION = ObservationSpec(
    [
        Feature("beacons", 4 * MAX_BEACON_SLOTS),
        Feature("path", 7),
        Flag("boundary", 2),
        Flag("three_areas"),
        Fraction("progress"),
        Feature("previous_calibration", 3),
        Fraction("sensor", 2),
    ]
)
"""The observation's features (see the env docstring, Observation Space)."""


@dataclass(frozen=True)
class BlockExpansionEnvConfig:
    """The ``gym.make`` arguments of ``SonarGym/BlockExpansion-v0`` (see the env docstring)."""

    n_areas: int = 2
    layout: str = "table_i"
    path: str = "paper"
    decisions: str = "per_boundary"
    ordering: str = "free"
    distance_range_m: tuple[float, float] = (0.02, 0.8)
    range_noise_std_m: float = 0.001
    timer_period_s: float = 1e-6
    max_range_m: float = 5.0
    beacon_prior_std_m: float = 0.2
    sigma_scale_m: float = 0.03
    failure_penalty: float = 10.0
    sensing_cost_per_s: float = 0.0
    trilateration_method: str = "paper"

    def __post_init__(self) -> None:
        number_field(self, "n_areas", low=2, high=3, integer=True)
        choice_field(self, "layout", ("table_i", "random"))
        choice_field(self, "path", ("paper", "random"))
        choice_field(self, "decisions", ("per_boundary", "all_at_once"))
        choice_field(self, "ordering", ("free", "decreasing"))
        low, high = numbers_field(self, "distance_range_m", length=2)
        check_number("distance_range_m[0]", low, low=0.0, high=2.0)
        check_number("distance_range_m[1]", high, low=low + 4 * DECREASING_GAP_M, high=3.0)
        number_field(self, "range_noise_std_m", low=0.0, high=NOISE_SCALE_M)
        number_field(self, "timer_period_s", low=0.0, high=TIMER_SCALE_S)
        number_field(self, "max_range_m", low=0.5, high=50.0)
        number_field(self, "beacon_prior_std_m", low=0.0, high=1.0)
        number_field(self, "sigma_scale_m", low=MIN_SCALE, high=10.0)
        number_field(self, "failure_penalty", low=0.0, high=1e4)
        number_field(self, "sensing_cost_per_s", low=0.0, high=100.0)
        choice_field(self, "trilateration_method", TRILATERATION_METHODS)

    @property
    def n_boundaries(self) -> int:
        """Area boundaries crossed, each with one (d1, d2, d3)."""
        return self.n_areas - 1


PathParameters = ParabolicRoute
PAPER_PATH = PAPER_ROUTE
"""The paper-like parabola (ending at :data:`PAPER_PATH_X_END_M` per area count)."""


def make_ranger(config: BlockExpansionEnvConfig, sensor_height_m: float) -> BeaconRanger:
    """The task's one-way ranging sensor: the config's noise, timer and range, one firing every
    :data:`FIRING_INTERVAL_S`, converting with the speed of sound at :data:`TEMPERATURE_C`."""
    return BeaconRanger(
        height_m=sensor_height_m,
        timer_period_s=config.timer_period_s,
        range_noise_std_m=config.range_noise_std_m,
        max_range_m=config.max_range_m,
        assumed_speed_of_sound_mps=speed_of_sound_mps(TEMPERATURE_C),
        firing_interval_s=FIRING_INTERVAL_S,
    )


@dataclass
class _Episode:
    """Everything one episode holds; pickles with the env."""

    world: RangingWorld
    scenario: Scenario
    beacons_m: dict[str, tuple[float, float, float]]
    prior_m: dict[str, FloatArray]
    path_parameters: PathParameters
    path: FloatArray
    ranges: FloatArray
    round_durations_s: FloatArray
    chosen: list[tuple[float, float, float]] = field(default_factory=list)
    result: BlockExpansionResult | None = None
    evaluated_until: int = 0
    sensing_time_s: float = 0.0
    done: bool = False
    status: str = STATUS_RUNNING


class BlockExpansionEnv(SonarEnv):
    """
    ## Description

    Roh et al.'s robot drives a parabola across two (Sec. IV.B) or three (Sec. IV.D) triangular
    areas of ultrasonic beacons: A, B, C form Area 1, B, C, D Area 2 and B, D, E Area 3
    (Table I; see :mod:`sonar_gym.localization.roh_block_expansion` for the reading of Fig. 3).
    Only A, B and C are surveyed. Every 40 ms a :class:`~sonar_gym.sonar.ranging.BeaconRanger`
    round ranges all beacons (one-way time of flight: Gaussian jitter, a timer counter,
    dropouts out of range), and the robot trilaterates with its area's beacons (Sec. III.A).
    Approaching a boundary it saves its estimated positions where its distance to the
    boundary crosses d1, d2, d3 (Sec. III.C), auto-calibrates the next area's beacon from the
    ranges measured there (Sec. III.B) and switches to it past the boundary. The agent chooses
    the d's. The whole path is then scored with the paper's sigma' (Sec. IV.B).

    ## Action Space

    ``Box(-1, 1, (3,), float32)``: (d1, d2, d3) for the next boundary
    (``decisions="per_boundary"``, default), or ``Box(-1, 1, (3 * (n_areas - 1),), float32)``:
    (d1, ..., d6) for every boundary at once (``decisions="all_at_once"``). With
    ``(low, high) = distance_range_m`` (default 0.02-0.8 m, which holds every d of
    Tables II-V) and ``u = (a + 1) / 2``:

    * ``ordering="free"`` (default): ``d_i = low + u_i (high - low)`` independently. The order
      is not forced, because the paper does not keep d1 > d2 > d3 either (Table IV's d4..d6
      grow: 300/400/700 mm). The extraction gives every order a meaning (``D`` is the unsigned
      distance to the boundary): a d smaller than the previous one is met approaching the
      boundary, a larger one after crossing it. A rise then a fall (d1 < d2 > d3) is never met
      on a path that crosses the boundary once and ends the boundary as ``"not_reached"``.
    * ``ordering="decreasing"``: the d's are mapped to strictly decreasing values, all met
      approaching the boundary (Tables II-III):
      ``d1 = low + 2 g + u1 (high - low - 2 g)``, ``d2 = low + g + u2 (d1 - low - 2 g)``,
      ``d3 = low + u3 (d2 - low - g)``, with the gap ``g = 0.01 m``.

    ``env.unwrapped.encode_distances(d_m)`` and ``decode_action(action)`` convert.

    ## Observation Space

    ``Box(-1, 1, (36,), float32)``. Positions ``(x, y, z)`` are scaled as
    ``(p - (2.0, 1.0, 1.25) m) / (2.5, 2.0, 1.25) m`` and clipped.

    | slice | meaning | range |
    |---|---|---|
    | ``[0, 20)`` | 5 beacon slots (Area 1's three, then the new ones): x, y, z, status | [-1, 1] |
    | ``[20, 27)`` | path: x, y of start, end, vertex (scaled), curvature a / 2 per m | [-1, 1] |
    | ``[27, 29)`` | one-hot: the boundary the action is for (see below) | {0, 1} |
    | ``29`` | 1 for three areas, 0 for two | {0, 1} |
    | ``30`` | fraction of the path already driven when this boundary's extraction starts | [0, 1] |
    | ``[31, 34)`` | previous calibration: outcome, log10(condition) / 4, area / 0.1 m^2 | [-1, 1] |
    | ``[34, 36)`` | ranging: noise std / 0.01 m, timer period / 1e-4 s | [0, 1] |

    The boundary one-hot marks the first boundary when all d's are chosen at once and is all
    zeros at the end. The calibration outcome is 1 ok, -1 failed, 0 none yet.

    A slot's status is 1 for a surveyed beacon (exact), 0.5 for one the robot has calibrated
    (its calibrated position), 0 for one not yet calibrated (a rough prior: the true position
    plus Gaussian noise of ``beacon_prior_std_m`` per coordinate, drawn per episode) and -1
    for an unused slot (zeros). ``env.unwrapped.observation_layout`` maps names to slices.

    ## Rewards

    At the end of the episode, in units of ``sigma_scale_m`` (default 0.03 m, the order of the
    paper's sigma'), with ``P = failure_penalty`` (default 10) and ``f`` the fraction of fixes
    that failed: ``-[(1 - f) min(sigma' / sigma_scale_m, P) + f P]`` (a failed fix counts as the
    capped loss), minus ``P * (boundaries not calibrated and passed) / (boundaries)``.
    sigma' is the mean distance from the successful fixes of the whole path to the true path
    (Sec. IV.B). Every step also costs ``sensing_cost_per_s`` per second of ranging (default 0:
    the robot ranges every 40 ms whatever the d's, so time does not depend on the choice).
    Intermediate steps (the first of two per-boundary decisions) give only that cost.
    ``info["rewards"]`` holds the terms ``sensing_cost`` and ``path_loss`` (the bracket above
    with the boundary part, one number: split further it would no longer add up to the same
    float).

    ## Starting State

    The Table I beacons (``layout="table_i"``) or each of them moved uniformly within
    +-0.25 m horizontally and +-0.15 m vertically (``layout="random"``); the paper-like
    parabola (``path="paper"``: :func:`~sonar_gym.localization.roh.parabolic_path`, ending at
    x = 1.3 m for two areas, 0.55 m for three) or a random one (``path="random"``: coefficient
    uniform in [-1.3, -0.5] 1/m, start, vertex and end jittered). Random layouts and paths are
    redrawn until the path starts in Area 1, crosses each boundary once, in order, at least
    0.1 m from its end beacons, and ends in the last area. The ranging of the whole drive is
    simulated at reset (it does not depend on the actions).

    ## Episode End

    ``decisions="per_boundary"``: after the last boundary's decision (one step for two areas,
    two for three), or after the first step if the first calibration failed.
    ``decisions="all_at_once"``: after one step. No truncation.

    ## Info

    ``position_error_m``: sigma' of the fixes so far, metres (the fixes before the second
    boundary's extraction after an intermediate step, the whole path at the end, 0.0 at
    reset); ``sigma_m``, ``sigma_prime_m`` (Sec. IV.B, metres; when no fix succeeded both
    equal ``failure_penalty * sigma_scale_m``); ``calibration_errors_m`` (new beacon name ->
    distance between calibrated and true position, metres, calibrated beacons only);
    ``calibration_statuses``; ``calibration_conditions`` (condition numbers of the three saved
    positions, finite ones only); ``distances_m`` (the d triples chosen so far, metres);
    ``failed_fix_fraction``; ``sensing_time_s`` (ranging time of the path so far, seconds);
    ``status``: ``"running"``, ``"ok"``, the first failed boundary's status
    (``"not_reached"``, ``"no_intersection"``, ``"collinear_positions"``,
    ``"missing_distance"``) or ``"localization_failed"``. ``heading_error_rad`` is 0.0:
    trilateration gives no heading (``unestimated_info_keys`` names it, so summaries omit it).

    ## Arguments

    | argument | default | meaning |
    |---|---|---|
    | n_areas | 2 | 2 (Sec. IV.B) or 3 (Sec. IV.D) |
    | layout | ``"table_i"`` | or ``"random"`` (jittered Table I) |
    | path | ``"paper"`` | or ``"random"`` (random curvature and end points) |
    | decisions | ``"per_boundary"`` | or ``"all_at_once"`` |
    | ordering | ``"free"`` | or ``"decreasing"`` (see Action Space) |
    | distance_range_m | (0.02, 0.8) | range of the d's, metres |
    | range_noise_std_m | 0.001 | ranging jitter as a distance, metres |
    | timer_period_s | 1e-6 | time-of-flight counter period, seconds (0 = exact, else >= 1e-12) |
    | max_range_m | 5.0 | beacons farther away drop out, metres |
    | beacon_prior_std_m | 0.2 | noise of the rough new-beacon positions in the observation |
    | sigma_scale_m | 0.03 | sigma' that costs one unit of reward, metres |
    | failure_penalty | 10 | loss of a failed calibration; also caps the path loss |
    | sensing_cost_per_s | 0 | reward per second of ranging |
    | trilateration_method | ``"paper"`` | or ``"least_squares"`` (beside the paper's) |

    ## Version History

    * v0: first release.

    ## Example

    >>> import gymnasium as gym, sonar_gym
    >>> env = gym.make("SonarGym/BlockExpansion-v0")
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape, env.action_space.shape
    ((36,), (3,))
    >>> action = env.unwrapped.encode_distances([0.45, 0.25, 0.05])
    >>> obs, reward, terminated, truncated, info = env.step(action)
    >>> terminated, info["status"], info["sigma_prime_m"] < 0.1
    (True, 'ok', True)
    """

    required_info_keys = INFO_KEYS
    unestimated_info_keys = ("heading_error_rad",)

    metadata = {"render_modes": ["rgb_array"], "render_fps": 2}
    action_space: gym.spaces.Box  # d1..d3 (per boundary, or all at once) scaled to [-1, 1]

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        super().__init__(render_mode)
        self.config = build_config(BlockExpansionEnvConfig, kwargs, ENV_ID)
        config = self.config
        self._base_scenario = load_scenario(SCENARIO_NAME)
        self._areas = PAPER_TWO_AREAS if config.n_areas == 2 else PAPER_THREE_AREAS
        self._slot_names = (*self._areas[0], *new_beacons_of_areas(self._areas))
        self._new_beacons = self._slot_names[3:]
        self._static_world = World(self._base_scenario, temperature_c=TEMPERATURE_C)
        # The Table I positions of the slots' beacons and the room's bounds: the base
        # scenario is frozen, so they are read once.
        self._table_i = {
            name: self._base_scenario.emitter(name).position for name in self._slot_names
        }
        self._bounds = self._base_scenario.bounds
        self._paper_path = dataclasses.replace(
            PAPER_PATH, x_end_m=PAPER_PATH_X_END_M[config.n_areas]
        )
        # The paper path's samples, shared by its episodes (read-only).
        self._paper_path_samples = self._paper_path.sample()
        self._paper_path_samples.flags.writeable = False
        # Kept between episodes while their inputs repeat (Table I, the paper path).
        self._true_path: KeptValue[TruePath] = KeptValue()
        self._features_of_route: KeptValue[FloatArray] = KeptValue()
        self._world_of_beacons: KeptValue[RangingWorld] = KeptValue()
        self._route_geometry: KeptValue[RouteGeometry] = KeptValue()
        self.sensor_height_m = self._base_scenario.robot.sensor_height
        self.ranger = make_ranger(config, self.sensor_height_m)
        per_step = 3 if config.decisions == "per_boundary" else 3 * config.n_boundaries
        self._use_action_type(make_action_type("box", ContinuousRange.unit(per_step)))
        self._use_observation_spec(OBSERVATION)
        self._episode: _Episode | None = None

    @property
    def areas(self) -> tuple[tuple[str, str, str], ...]:
        """The chain of triangular areas, as beacon names (Sec. II, Fig. 3)."""
        return self._areas

    @property
    def slot_names(self) -> tuple[str, ...]:
        """Beacon names in the order of the observation's beacon slots."""
        return self._slot_names

    # --- what an episode holds (for analysis and plots; agents read only observations) ------
    @property
    def path_m(self) -> FloatArray:
        """``(n, 2)`` the true receiver positions of the episode's path, metres (a copy)."""
        return self._require_episode().path.copy()

    @property
    def measured_ranges_m(self) -> FloatArray:
        """``(n, beacons)`` the ranges the sensor measured along the path, metres, NaN for a
        dropout; columns in the order of the beacon slots (a copy)."""
        return self._require_episode().ranges.copy()

    @property
    def beacons_m(self) -> dict[str, tuple[float, float, float]]:
        """The episode's true beacon positions ``name -> (x, y, z)``, metres."""
        return dict(self._require_episode().beacons_m)

    @property
    def result(self) -> BlockExpansionResult | None:
        """The block expansion run behind the last step (None before the first step)."""
        return self._require_episode().result

    # --- actions ---------------------------------------------------------------------------
    def decode_action(self, action: npt.ArrayLike) -> tuple[tuple[float, float, float], ...]:
        """The (d1, d2, d3) triples, metres, an action stands for (one per boundary it covers).

        Raises:
            ValueError: ``action`` is not in the action space: not finite, the wrong shape, or
                outside ``[-1, 1]`` (the message says what is allowed).
        """
        self.action_type.check(action)
        return self._distances(action)

    def _distances(self, action: npt.ArrayLike) -> tuple[tuple[float, float, float], ...]:
        """:meth:`decode_action` of an action already checked (``step`` checks it)."""
        fractions = self.action_type.decode(action)
        return fractions_to_distances(fractions, self.config.distance_range_m, self.config.ordering)

    def encode_distances(self, distances_m: npt.ArrayLike) -> np.ndarray:
        """The action for d's in metres (3 per boundary the action covers).

        A d outside what the action can express is moved to the nearest value it can: into
        ``distance_range_m``, and with ``ordering="decreasing"`` below the previous d by the
        gap :data:`DECREASING_GAP_M`.
        """
        values = np.asarray(distances_m, dtype=np.float64).reshape(-1)
        per_step = self.action_space.shape[0]
        if values.shape != (per_step,) or not np.all(np.isfinite(values)):
            raise ValueError(
                f"distances_m must hold {per_step} finite metres "
                f"(d1, d2, d3 per boundary); got {distances_m!r}"
            )
        fractions = distances_to_fractions(
            values, self.config.distance_range_m, self.config.ordering
        )
        return self.action_type.encode(fractions)

    # --- episode ---------------------------------------------------------------------------
    def _reset_task(self, options: dict[str, Any] | None) -> dict[str, Any]:
        config = self.config
        rng = self.np_random
        beacons_m, path_parameters, samples = draw_beacons_and_route(
            rng,
            dict(self._table_i),
            self._paper_path,
            self._areas,
            self._bounds,
            jitter_m=(LAYOUT_JITTER_XY_M, LAYOUT_JITTER_Z_M) if config.layout == "random" else None,
            route_x_end_m=PAPER_PATH_X_END_M[config.n_areas] if config.path == "random" else None,
            curvature_range_per_m=RANDOM_CURVATURE_PER_M,
            min_beacon_height_m=self.sensor_height_m + MIN_BEACON_CLEARANCE_M,
            end_margin_m=BOUNDARY_END_MARGIN_M,
            max_tries=MAX_LAYOUT_TRIES,
        )
        prior_m = {
            name: np.array(beacons_m[name])
            + (rng.normal(0.0, config.beacon_prior_std_m, 3) if name in self._new_beacons else 0.0)
            for name in self._slot_names
        }
        world = self._ranging_world(beacons_m)
        path = samples if samples is not None else self._paper_path_samples
        with self._timed("sensing"):
            geometry = self._route_geometry.get(
                (path_parameters, tuple(beacons_m.items())),
                lambda: self.ranger.route_geometry(world, path, tuple(beacons_m)),
            )
            ranges, durations_s = range_along_route(
                self.ranger, world, path, tuple(beacons_m), rng, geometry
            )
        self._episode = _Episode(
            world=world,
            scenario=world.scenario,
            beacons_m=beacons_m,
            prior_m=prior_m,
            path_parameters=path_parameters,
            path=path,
            ranges=ranges,
            round_durations_s=durations_s,
        )
        return self._info(position_error_m=0.0)

    def _ranging_world(self, beacons_m: dict[str, tuple[float, float, float]]) -> RangingWorld:
        """The room with the episode's beacons, kept while they stay the same (Table I); only
        the beacons move between episodes, so the room's geometry is built once."""

        def make() -> RangingWorld:
            emitters = tuple(Emitter(name, beacons_m[name]) for name in self._slot_names)
            scenario = dataclasses.replace(self._base_scenario, emitters=emitters)
            return RangingWorld(self._static_world.geometry, TEMPERATURE_C, scenario)

        return self._world_of_beacons.get(tuple(beacons_m.items()), make)

    def _runner_config(
        self,
        beacons_m: dict[str, tuple[float, float, float]],
        triples: tuple[tuple[float, float, float], ...],
    ) -> BlockExpansionConfig:
        """The runner's setup; missing triples (decisions still to come) are placeholders."""
        filled = list(triples) + [(0.45, 0.25, 0.05)] * (self.config.n_boundaries - len(triples))
        return BlockExpansionConfig(
            beacons_m=beacons_m,
            areas=self._areas,
            calibration_distances_m=tuple(filled),
            sensor_height_m=self.sensor_height_m,
            range_noise_std_m=0.0,
            trilateration_method=self.config.trilateration_method,
        )

    def _apply_action(self, action: Any) -> StepOutcome:
        episode = self._require_episode()
        config = self.config
        episode.chosen.extend(self._distances(action))
        with self._timed("localization"):
            result = BlockExpansion(
                self._runner_config(episode.beacons_m, tuple(episode.chosen))
            ).run(episode.path, distance_table=episode.ranges)
        episode.result = result
        decided = len(episode.chosen)
        calibration = result.calibrations[decided - 1]
        previous_until = episode.evaluated_until
        final = decided >= config.n_boundaries or calibration.status != OK
        if final:
            episode.evaluated_until = len(episode.path)
        else:
            assert calibration.switch_index is not None
            episode.evaluated_until = calibration.switch_index
        rounds = episode.round_durations_s[previous_until : episode.evaluated_until]
        step_time_s = float(np.sum(rounds))
        episode.sensing_time_s += step_time_s
        terms = {"sensing_cost": -config.sensing_cost_per_s * step_time_s, "path_loss": 0.0}
        if not final:
            errors = self._errors(result, episode.evaluated_until)
            return StepOutcome(
                reward_terms=terms, info=self._info(position_error_m=errors[1], errors=errors)
            )
        episode.done = True
        episode.status = final_status(result)
        errors = self._errors(result, len(episode.path))
        terms["path_loss"] = -self._loss(result, errors[1])
        return StepOutcome(
            reward_terms=terms,
            terminated=True,
            info=self._info(position_error_m=errors[1], errors=errors),
        )

    def _errors(self, result: BlockExpansionResult, until: int) -> tuple[float, float]:
        """``(sigma, sigma')`` of the successful fixes before path index ``until``, metres."""
        episode = self._require_episode()
        indices = result.estimated_indices
        if len(indices) == 0 or indices[0] >= until:
            capped = self.config.failure_penalty * self.config.sigma_scale_m
            return capped, capped
        true_path = self._true_path.get(episode.path_parameters, lambda: TruePath(episode.path))
        # The fix indices ascend: the fixes before ``until`` are a leading run of them.
        count = len(indices) if indices[-1] < until else int(np.searchsorted(indices, until))
        return true_path.errors(result.estimated_xy[:count])

    def _loss(self, result: BlockExpansionResult, sigma_prime_m: float) -> float:
        """The episode's loss (see Rewards), without the sensing cost."""
        config = self.config
        episode = self._require_episode()
        failed_fixes = 1.0 - len(result.estimated_indices) / len(episode.path)
        path_loss = min(sigma_prime_m / config.sigma_scale_m, config.failure_penalty)
        failed_boundaries = sum(c.status != OK for c in result.calibrations)
        return (
            (1.0 - failed_fixes) * path_loss
            + failed_fixes * config.failure_penalty
            + config.failure_penalty * failed_boundaries / config.n_boundaries
        )

    # --- observation and info ----------------------------------------------------------------
    def _observe(self) -> np.ndarray:
        episode = self._require_episode()
        config = self.config
        observation = OBSERVATION.writer()
        calibrated = self._calibrated_positions(episode)
        slots: list[tuple[npt.ArrayLike, float]] = []
        for index, name in enumerate(self._slot_names):
            if index < 3:
                slots.append((episode.beacons_m[name], SURVEYED))
            elif name in calibrated:
                slots.append((calibrated[name], CALIBRATED))
            else:
                slots.append((episode.prior_m[name], PRIOR_ONLY))
        positions, statuses = zip(*slots, strict=True)
        observation["beacons"] = beacon_slot_features(positions, statuses, MAX_BEACON_SLOTS)
        route = episode.path_parameters
        observation["path"] = self._features_of_route.get(route, lambda: route_features(route))
        decided = len(episode.chosen)
        observation["three_areas"] = float(config.n_areas == 3)
        if not episode.done:
            observation.one_hot("boundary", decided)
            observation["progress"] = episode.evaluated_until / max(len(episode.path) - 1, 1)
        if episode.result is not None and decided > 0:
            last = episode.result.calibrations[decided - 1]
            observation["previous_calibration"] = calibration_features(last)
        observation["sensor"] = [
            config.range_noise_std_m / NOISE_SCALE_M,
            config.timer_period_s / TIMER_SCALE_S,
        ]
        return observation.vector

    def _calibrated_positions(self, episode: _Episode) -> dict[str, FloatArray]:
        """New beacons calibrated in the boundaries decided so far."""
        if episode.result is None:
            return {}
        return calibrated_positions(episode.result.calibrations[: len(episode.chosen)])

    def _info(
        self, position_error_m: float, errors: tuple[float, float] | None = None
    ) -> dict[str, Any]:
        episode = self._require_episode()
        sigma_m, sigma_prime_m = errors if errors is not None else (0.0, 0.0)
        info: dict[str, Any] = {
            "position_error_m": float(position_error_m),
            "heading_error_rad": 0.0,  # Roh et al. estimate positions only (see Info)
            "sigma_m": float(sigma_m),
            "sigma_prime_m": float(sigma_prime_m),
            **calibration_summaries(()),
            "distances_m": [list(triple) for triple in episode.chosen],
            "failed_fix_fraction": 0.0,
            "sensing_time_s": float(episode.sensing_time_s),
            "status": episode.status,
        }
        result = episode.result
        if result is None:
            return info
        info.update(calibration_summaries(result.calibrations[: len(episode.chosen)]))
        fixes = np.count_nonzero(result.estimated_indices < episode.evaluated_until)
        info["failed_fix_fraction"] = float(1.0 - fixes / max(episode.evaluated_until, 1))
        return info

    # --- rendering ----------------------------------------------------------------------------
    def _render_frame(self) -> np.ndarray:
        episode = self._require_episode()
        result = episode.result
        shown = max(episode.evaluated_until, 1)
        fixes = None if result is None else result.estimated_xy[result.estimated_indices < shown]
        errors_m = {
            name: float(np.linalg.norm(position - np.asarray(episode.beacons_m[name])))
            for name, position in self._calibrated_positions(episode).items()
        }
        title = f"BlockExpansion  {self.config.n_areas} areas"
        drive = (episode.scenario, episode.path, shown, fixes, episode.chosen, episode.status)
        return render_drive(*drive, errors_m, title)

    def _require_episode(self) -> _Episode:
        if self._episode is None:
            raise RuntimeError("BlockExpansionEnv: call reset() first")
        return self._episode
