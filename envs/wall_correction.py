"""``SonarGym/WallCorrection-v0``: correct drifting odometry with flat walls sensed from the side.

The task of Yamamoto, Maeyama, Ohya & Yuta, *APCS: autonomous position correction system using
ultrasonic sensing*. The robot drives a corridor route leg by leg; before each leg the agent
chooses which side sonars to run, how often to sample and how far from the corridor's centre
line to drive. Inside the legs runs the paper's procedure (Fig. 2) in
:class:`sonar_gym.apcs_route.APCSRoute` and :mod:`sonar_gym.localization.apcs_online`:
estimated reflection points (eqs 1-6), flat-wall detection (sec. 4.2.2-4.2.3), matching to the
map of oriented wall vectors (sec. 4.3) and the maximum-likelihood correction of pose and
covariance (eqs 7-14). This module holds the task: configuration, actions, observation, reward.

:func:`map_wall_vectors`, :class:`WallStream`, :func:`rejection_reason`,
:func:`nearest_facing_walls` and the episode records are re-exported from their homes
(:mod:`sonar_gym.maps`, :mod:`sonar_gym.localization.apcs_online`, :mod:`sonar_gym.apcs_route`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from sonar_gym.apcs_route import (
    REAIM_TOLERANCE_RAD,
    APCSRoute,
    EpisodeTrace,
    LegSummary,
    WallDetection,
    with_wall_obstacles,
)
from sonar_gym.envs.base import SonarEnv, StepOutcome
from sonar_gym.envs.config import (
    build_config,
    check_choice,
    check_number,
    choice_field,
    number_field,
    numbers_field,
    scenario_field,
)
from sonar_gym.localization.apcs import DEFAULT_PARAMETERS
from sonar_gym.localization.apcs_online import (
    SIDE_NAMES,
    APCSTracker,
    ClosedGroup,
    WallStream,
    nearest_facing_walls,
    rejection_reason,
)
from sonar_gym.maps import facing_wall_stretch, map_wall_vectors
from sonar_gym.metrics import heading_error_rad, position_error_m
from sonar_gym.pose import FloatArray, Pose
from sonar_gym.robot import DifferentialDriveRobot, OdometryNoise
from sonar_gym.scenario import Scenario, load_scenario
from sonar_gym.sonar.swept import SideSonars
from sonar_gym.validation import MIN_LENGTH_M, MIN_SCALE, MIN_VARIANCE
from sonar_gym.world import World

ENV_ID = "SonarGym/WallCorrection-v0"

SIDES = ("none", "left", "right", "both")
"""Values of the first action component: which side sonars run during the leg."""

POSITION_STD_SCALE_M = 0.1
"""Standard deviation (metres) that fills the position-uncertainty features of the observation."""
HEADING_STD_SCALE_RAD = math.radians(2.0)
"""Standard deviation (radians) that fills the heading-uncertainty feature."""
COUNT_SCALE = 10.0
"""Wall count that fills a last-leg count feature."""
MAP_PROFILE_STEP_M = 0.02
"""Spacing of the map look-up along a leg for the map-ahead features (metres)."""
STANDOFF_CLEARANCE_M = 0.05
"""Least clearance (metres) between the robot and every mapped surface on every offered stand-off."""


@dataclass(frozen=True)
class WallCorrectionConfig:
    """The ``gym.make`` arguments of ``SonarGym/WallCorrection-v0`` (see the env docstring)."""

    scenario: str | Path = "apcs_corridor"
    n_legs: int = 6
    route_margin_m: float = 0.5
    transition_m: float = 0.5
    standoffs_m: tuple[float, ...] = (-0.4, -0.2, 0.0, 0.2, 0.4)
    sample_spacings_cm: tuple[int, ...] = (3, 6, 9)
    motion_step_cm: int = 3
    reaim_interval_m: float = 0.3
    n_unmapped_obstacles: int = 2
    obstacle_length_range_m: tuple[float, float] = (0.3, 1.0)
    obstacle_depth_range_m: tuple[float, float] = (0.05, 0.35)
    encoder_noise_m_per_sqrt_m: float = 0.0005
    wheel_scale_error_std: float = 0.0005
    slip_probability_per_m: float = 0.005
    slip_fraction_max: float = 0.3
    initial_position_std_m: float = 0.005
    initial_heading_std_deg: float = 0.1
    odometry_variance_per_m: float | None = None
    range_variance_m2: float = 1e-4
    bearing_std_deg: float = 1.0
    measurement_variances: str = "fixed"
    correction_method: str = "paper"
    position_scale_m: float = 0.05
    heading_scale_deg: float = 2.0
    sensing_cost_per_s: float = 0.1
    collision_penalty: float = 5.0
    temperature_c: float = 20.0
    range_noise_std_m: float | None = 0.001
    action_type: str = "multi_discrete"

    def __post_init__(self) -> None:
        scenario_field(self)
        number_field(self, "n_legs", low=1, high=100, integer=True)
        number_field(self, "route_margin_m", low=0.0, high=100.0)
        number_field(self, "transition_m", low=MIN_LENGTH_M, high=100.0)
        numbers_field(self, "standoffs_m", low=-5.0, high=5.0, min_length=1, distinct=True)
        numbers_field(
            self,
            "sample_spacings_cm",
            low=1,
            high=100,
            integer=True,
            min_length=1,
            distinct=True,
        )
        number_field(self, "motion_step_cm", low=1, high=20, integer=True)
        if any(spacing % self.motion_step_cm for spacing in self.sample_spacings_cm):
            raise ValueError(
                "argument 'sample_spacings_cm' must hold multiples of motion_step_cm "
                f"({self.motion_step_cm}); got {self.sample_spacings_cm!r}"
            )
        number_field(self, "reaim_interval_m", low=MIN_LENGTH_M, high=100.0)
        number_field(self, "n_unmapped_obstacles", low=0, high=20, integer=True)
        _range_field(self, "obstacle_length_range_m", low=0.05, high=5.0)
        _range_field(self, "obstacle_depth_range_m", low=0.01, high=1.0)
        number_field(self, "encoder_noise_m_per_sqrt_m", low=0.0, high=0.1)
        number_field(self, "wheel_scale_error_std", low=0.0, high=0.05)
        number_field(self, "slip_probability_per_m", low=0.0, high=1.0)
        number_field(self, "slip_fraction_max", low=0.0, high=1.0)
        number_field(self, "initial_position_std_m", low=0.0, high=1.0)
        number_field(self, "initial_heading_std_deg", low=0.0, high=30.0)
        number_field(self, "odometry_variance_per_m", low=MIN_VARIANCE, high=1.0, optional=True)
        number_field(self, "range_variance_m2", low=MIN_VARIANCE, high=1.0)
        number_field(self, "bearing_std_deg", low=MIN_SCALE, high=45.0)
        choice_field(self, "measurement_variances", ("fixed", "fit"))
        choice_field(self, "correction_method", ("paper", "linear"))
        number_field(self, "position_scale_m", low=MIN_SCALE, high=10.0)
        number_field(self, "heading_scale_deg", low=MIN_SCALE, high=180.0)
        number_field(self, "sensing_cost_per_s", low=0.0, high=100.0)
        number_field(self, "collision_penalty", low=0.0, high=1e4)
        number_field(self, "temperature_c", low=-20.0, high=50.0)
        number_field(self, "range_noise_std_m", low=0.0, high=0.1, optional=True)
        choice_field(self, "action_type", ("multi_discrete", "discrete"))

    @property
    def motion_step_m(self) -> float:
        """Length of one straight drive command, metres."""
        return self.motion_step_cm / 100.0

    @property
    def filter_variance_per_m(self) -> float:
        """Variance per metre rolled of each wheel that the pose filter assumes, m^2/m.

        Default: ``encoder_noise^2 + wheel_scale_error_std^2 * 1 m``, the random encoder error
        plus the wheel-radius error treated as if it were random per metre.
        """
        if self.odometry_variance_per_m is not None:
            return float(self.odometry_variance_per_m)
        return self.encoder_noise_m_per_sqrt_m**2 + self.wheel_scale_error_std**2


def _range_field(config: object, name: str, *, low: float, high: float) -> None:
    """A pair (low, high) with ``low <= high``, both within ``[low, high]``."""
    first, _ = numbers_field(config, name, length=2, low=low, high=high)
    check_number(f"{name}[1]", getattr(config, name)[1], low=first, high=high)


# --------------------------------------------------------------------------------------------
# Episode state and records
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class LegCommand:
    """A decoded action: which sonars, the sampling spacing and the lateral stand-off.

    Attributes:
        side: one of :data:`SIDES`.
        spacing_cm: travel between two samples, centimetres.
        standoff_m: offset of the leg from the route's centre line, metres (positive: left).
    """

    side: str
    spacing_cm: int
    standoff_m: float

    @property
    def active_sides(self) -> tuple[str, ...]:
        """The side sonars that run: ``()``, ``("left",)``, ``("right",)`` or both."""
        return {"none": (), "left": ("left",), "right": ("right",), "both": SIDE_NAMES}[self.side]


@dataclass
class _Episode:
    route: APCSRoute
    collisions: int = 0
    last_leg: LegSummary = field(default_factory=LegSummary)
    totals: LegSummary = field(default_factory=LegSummary)

    @property
    def world(self) -> World:
        return self.route.world

    @property
    def robot(self) -> DifferentialDriveRobot:
        return self.route.robot

    @property
    def leg(self) -> int:
        return self.route.leg

    @property
    def estimate(self) -> Pose:
        return self.route.tracker.estimate

    @property
    def covariance(self) -> FloatArray:
        return self.route.tracker.covariance

    @property
    def sensing_time_s(self) -> float:
        return self.route.sensing_time_s

    @property
    def trace(self) -> EpisodeTrace:
        return self.route.trace

    @property
    def true_pose(self) -> Pose:
        return self.route.true_pose


# --------------------------------------------------------------------------------------------
# The environment
# --------------------------------------------------------------------------------------------


class WallCorrectionEnv(SonarEnv):
    """
    ## Description

    A robot drives a corridor with drifting odometry (Yamamoto, Maeyama, Ohya & Yuta, *APCS:
    autonomous position correction system using ultrasonic sensing*). Its two side-looking
    MA40B8 sonars range the walls; the map holds the corridor's walls and pillars as oriented
    wall vectors, but not wall B (a board standing in front of the left wall) nor the unmapped
    obstacles drawn at random for each episode. The route runs along the room's long axis
    (``+x``) from ``route_margin_m`` after its start to ``route_margin_m`` before its end, cut
    into ``n_legs`` equal legs. Before each leg the agent chooses which side sonars to run, how
    often they sample, and the leg's stand-off from the centre line.

    During a leg the robot drives from its pose estimate, through pymunk, in straight commands
    of ``motion_step_cm`` (a :class:`~sonar_gym.robot.DifferentialDriveRobot` with encoder
    noise, wheel-radius errors drawn per episode and rare slips): first towards the point
    ``transition_m`` into the leg at the new stand-off, then to the leg's end, turning towards
    the target every ``reaim_interval_m``. The estimate and its covariance follow the
    encoder increments (Kim et al. sec. 3.1, :func:`sonar_gym.localization.kim.predict`, each
    wheel's variance growing by ``odometry_variance_per_m`` per metre rolled). Every
    ``spacing`` of travel the active sonars take one reading each. APCS runs on line on each
    side (Fig. 2): ERPs from consecutive readings placed with the estimate (eqs 1-6), grouping
    (100 cm^2, groups of 4 to 8 ERPs), line fit and variance test (sec. 4.2.2-4.2.3); every
    detected wall is matched against the map (+-0.5 deg, inclusion, d1^2 + d2^2 < 200 cm^2;
    sec. 4.3, 6) and, on exactly one match, corrects the estimate and its covariance by
    maximum likelihood (eqs 7-14) with the measurement ``(r, xi)`` of the fitted line. After
    a correction the stored readings and ERPs move with the estimate's frame.

    The paper does not give the variances ``sigma_r`` and ``sigma_xi``; by default they are
    fixed at (1 cm)^2 and (1 deg)^2 (``measurement_variances="fixed"``), and beside them
    ``"fit"`` takes each wall's own least-squares variances (residual variance over the
    spread of its ERPs along the line, and the range variance at the robot's foot on it).
    The sonars' timing jitter defaults to 1 mm instead of the MA40B8 preset's 3 mm: the
    paper's thresholds assume consecutive ERPs within 10 cm at a 3 cm spacing, i.e. range
    differences good to about 2 mm, and with 3 mm of jitter the +-0.5 deg test passes only
    about one wall fit in seven even with a perfect heading (``range_noise_std_m=None``
    restores the preset).

    ## Action Space

    ``action_type="multi_discrete"`` (default): ``MultiDiscrete([4, len(sample_spacings_cm),
    len(standoffs_m)])``:

    | index | meaning | values |
    |---|---|---|
    | 0 | side sonars | 0 none, 1 left, 2 right, 3 both |
    | 1 | sampling spacing | ``sample_spacings_cm`` (default 3, 6, 9 cm of travel) |
    | 2 | stand-off | ``standoffs_m`` (default -0.4, -0.2, 0, 0.2, 0.4 m; positive = left) |

    The spacing is ignored when no sonar runs. ``action_type="discrete"`` flattens the same
    choices into ``Discrete(4 * n_spacings * n_standoffs)`` (side major, stand-off minor).
    Every stand-off keeps the robot at least 5 cm from every *mapped* surface along the legs
    (checked at construction); unmapped obstacles can still be hit.

    ## Observation Space

    ``Box(-1, 1, (22,), float32)``; ``env.unwrapped.observation_layout`` names the slices:

    | slice | meaning | unit / normalisation | bounds |
    |---|---|---|---|
    | progress | legs done / ``n_legs`` | - | [0, 1] |
    | estimate_xy | estimated position | room's extent mapped to [-1, 1] | [-1, 1] |
    | estimate_heading | cos, sin of the estimated heading | - | [-1, 1] |
    | position_std | sqrt of the estimate's variance along x, across (y) | / 0.1 m, clipped | [0, 1] |
    | heading_std | sqrt of the heading variance | / 2 deg, clipped | [0, 1] |
    | map_ahead | per side (left, right): longest stretch of one mapped flat wall facing the next leg / leg length; median distance from the centre line to the mapped wall / 5 m | - | [0, 1] |
    | last_leg_walls | per side: walls detected, matched, rejected during the last leg | / 10, clipped | [0, 1] |
    | last_leg_dropped | ERP groups dropped by the size or variance test in the last leg | / 10, clipped | [0, 1] |
    | collided | whether the last leg touched an obstacle | - | {0, 1} |
    | sensing_time | sensing time so far / the most the episode can use | - | [0, 1] |
    | samples | readings taken in the last leg / the most a leg can take | - | [0, 1] |

    The map-ahead features are zero after the last leg.

    ## Rewards

    After each leg: ``-(E_xy / position_scale_m + E_theta / heading_scale_deg)``, the errors
    of the APCS estimate against the true pose at the end of the leg (Beom & Cho eq. (16);
    defaults 0.05 m and 2 deg, so 5 cm or 2 deg cost 1), minus ``sensing_cost_per_s`` times
    the leg's sensing time, minus ``collision_penalty`` (default 5) when the robot touched an
    obstacle. Sensing time is the time the sonars spend listening: every sampling instant
    costs one MA40B8 listening time (29 ms, for its 5 m range), whether one sonar or both
    run, since the two look in opposite directions, fire together and listen at once.

    ## Starting State

    The robot stands at the route's start on the centre line, heading ``+x``; its estimate
    differs from the truth by ``N(0, initial_position_std_m)`` in x and y and
    ``N(0, initial_heading_std_deg)`` in heading, with that diagonal covariance. Each episode
    draws the ``n_unmapped_obstacles`` boxes (against the corridor's long walls, clear of the
    start and of each other) and the wheels' radius errors ``N(0, wheel_scale_error_std)``.

    ## Episode End

    Terminates after ``n_legs`` legs with status ``"ok"``. No truncation.

    ## Info

    ``position_error_m``, ``heading_error_rad`` (of the estimate), ``sensing_time_s``
    (cumulative), ``status`` (``"running"``, then ``"ok"``), ``n_matched_walls``,
    ``n_rejected_walls``, ``n_detected_walls``, ``n_corrections`` (cumulative), ``leg``,
    ``collisions`` (legs with a contact), ``odometry_position_error_m`` (of plain
    dead reckoning), ``true_pose``, ``estimated_pose``, ``covariance_diagonal``.

    ## Arguments

    | argument | default | meaning |
    |---|---|---|
    | scenario | ``"apcs_corridor"`` | a scenario with a room; the route runs along its x axis |
    | n_legs | 6 | legs of the route |
    | route_margin_m | 0.5 | distance kept from the room's ends, metres |
    | transition_m | 0.5 | travel over which a leg reaches its stand-off, metres |
    | standoffs_m | (-0.4, -0.2, 0, 0.2, 0.4) | offered stand-offs from the centre line, metres |
    | sample_spacings_cm | (3, 6, 9) | offered sampling spacings (sec. 6: 3 cm), centimetres |
    | motion_step_cm | 3 | length of one drive command, centimetres |
    | reaim_interval_m | 0.3 | travel between two steering corrections, metres |
    | n_unmapped_obstacles | 2 | random unmapped boxes per episode (besides wall B) |
    | obstacle_length_range_m | (0.3, 1.0) | their length along the wall, metres |
    | obstacle_depth_range_m | (0.05, 0.35) | how far they stand out from the wall, metres |
    | encoder_noise_m_per_sqrt_m | 0.0005 | random encoder error after 1 m, metres |
    | wheel_scale_error_std | 0.0005 | std of each wheel's radius error (the drift) |
    | slip_probability_per_m | 0.005 | chance that a wheel slips within a metre |
    | slip_fraction_max | 0.3 | largest loss of travel in a slip |
    | initial_position_std_m | 0.005 | start uncertainty, metres |
    | initial_heading_std_deg | 0.1 | start uncertainty, degrees |
    | odometry_variance_per_m | None | filter's wheel variance per metre (None: encoder^2 + scale^2) |
    | range_variance_m2 | 1e-4 | ``sigma_r`` of eqs (13)-(14), a variance (m^2) |
    | bearing_std_deg | 1.0 | ``sqrt(sigma_xi)``, degrees |
    | measurement_variances | ``"fixed"`` | the two above, or ``"fit"``: each wall fit's own variances |
    | correction_method | ``"paper"`` | eqs (11)-(14), or ``"linear"`` (exact linear update) |
    | position_scale_m | 0.05 | position error that costs 1 |
    | heading_scale_deg | 2.0 | heading error that costs 1 |
    | sensing_cost_per_s | 0.1 | cost per second of sonar listening |
    | collision_penalty | 5.0 | cost of a leg with a contact |
    | temperature_c | 20.0 | air temperature (the sonar assumes 20 deg C) |
    | range_noise_std_m | 0.001 | timing jitter of the sonars as range, metres (None: the preset's 3 mm) |
    | action_type | ``"multi_discrete"`` | or ``"discrete"`` (for DQN) |

    ## Version History

    * v0: first release.

    ## Example

    >>> import gymnasium as gym, sonar_gym
    >>> env = gym.make("SonarGym/WallCorrection-v0")
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape, obs.dtype
    ((22,), dtype('float32'))
    >>> action = env.unwrapped.encode_action("left", spacing_cm=3, standoff_m=0.0)
    >>> obs, reward, terminated, truncated, info = env.step(action)
    >>> info["status"], info["leg"], info["n_detected_walls"] > 0
    ('running', 1, True)
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 2}

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        super().__init__(render_mode)
        self.config = build_config(WallCorrectionConfig, kwargs, ENV_ID)
        config = self.config
        self.scenario = load_scenario(config.scenario)
        if self.scenario.room is None:
            raise ValueError(
                f"argument 'scenario': {self.scenario.name!r} has no room; the route runs along a room's x axis"
            )
        self.params = DEFAULT_PARAMETERS
        self.wall_map = map_wall_vectors(self.scenario)
        (x_min, y_min), (x_max, y_max) = self.scenario.room.min, self.scenario.room.max
        self.centre_line_y = 0.5 * (y_min + y_max)
        self.route_start_x = x_min + config.route_margin_m
        route_end_x = x_max - config.route_margin_m
        if route_end_x - self.route_start_x <= 0.0:
            raise ValueError(
                f"argument 'route_margin_m' leaves no route in a room {x_max - x_min:g} m long; got {config.route_margin_m!r}"
            )
        self.leg_length_m = (route_end_x - self.route_start_x) / config.n_legs
        if config.transition_m >= self.leg_length_m:
            raise ValueError(
                f"argument 'transition_m' must be shorter than a leg ({self.leg_length_m:.3f} m); "
                f"got {config.transition_m!r}"
            )
        self.leg_starts_x = self.route_start_x + self.leg_length_m * np.arange(config.n_legs + 1)
        self._check_standoffs()
        self.sonars = _side_sonars(config.range_noise_std_m)
        self._map_ahead = self._map_ahead_features()

        n_spacings, n_standoffs = len(config.sample_spacings_cm), len(config.standoffs_m)
        if config.action_type == "multi_discrete":
            self.action_space = gym.spaces.MultiDiscrete([len(SIDES), n_spacings, n_standoffs])
        else:
            self.action_space = gym.spaces.Discrete(len(SIDES) * n_spacings * n_standoffs)
        self.observation_layout = {
            "progress": slice(0, 1),
            "estimate_xy": slice(1, 3),
            "estimate_heading": slice(3, 5),
            "position_std": slice(5, 7),
            "heading_std": slice(7, 8),
            "map_ahead": slice(8, 12),
            "last_leg_walls": slice(12, 18),
            "last_leg_dropped": slice(18, 19),
            "collided": slice(19, 20),
            "sensing_time": slice(20, 21),
            "samples": slice(21, 22),
        }
        self.observation_space = gym.spaces.Box(-1.0, 1.0, shape=(22,), dtype=np.float32)
        steps_per_leg = math.ceil(self.leg_length_m / config.motion_step_m) + 2
        instants_per_leg = steps_per_leg * config.motion_step_cm // min(config.sample_spacings_cm)
        self._max_samples_per_leg = 2 * instants_per_leg
        self._max_sensing_time_s = (
            config.n_legs * instants_per_leg * self.sonars.transducer.listen_time_s
        )
        self._episode: _Episode | None = None

    # --- set-up checks and static features --------------------------------------------------
    def _check_standoffs(self) -> None:
        """Every stand-off line and transition must clear the mapped surfaces by 5 cm."""
        mapped = dataclasses.replace(
            self.scenario,
            walls=tuple(w for w in self.scenario.walls if w.mapped),
            boxes=tuple(b for b in self.scenario.boxes if b.mapped),
            cylinders=tuple(c for c in self.scenario.cylinders if c.mapped),
        )
        world = World(mapped, temperature_c=self.config.temperature_c)
        radius = mapped.robot.radius + STANDOFF_CLEARANCE_M
        xs = np.arange(self.route_start_x, self.leg_starts_x[-1] + 1e-9, 0.05)
        ends = (self.route_start_x, float(self.leg_starts_x[-1]))
        if not all(world.is_free((x, self.centre_line_y), radius) for x in ends):
            raise ValueError(
                f"argument 'route_margin_m' puts the route's ends within {STANDOFF_CLEARANCE_M:g} m "
                f"of a mapped surface of {self.scenario.name!r}; got {self.config.route_margin_m!r}"
            )
        for offset in self.config.standoffs_m:
            y = self.centre_line_y + offset
            if not all(world.is_free((x, y), radius) for x in xs):
                raise ValueError(
                    f"argument 'standoffs_m': {offset:g} m brings the robot within "
                    f"{STANDOFF_CLEARANCE_M:g} m of a mapped surface of {self.scenario.name!r}; "
                    f"got {self.config.standoffs_m!r}"
                )
        if not world.is_free((self.route_start_x, self.centre_line_y)):
            raise ValueError(f"scenario {self.scenario.name!r}: the route's start is not free")

    def _map_ahead_features(self) -> FloatArray:
        """``(n_legs, 4)``: per leg, per side, continuity and median distance of the mapped wall.

        Along the leg's centre line, every :data:`MAP_PROFILE_STEP_M`, the nearest map vector
        facing the route on each side (a wall whose line the perpendicular from the centre line
        meets, with the free side towards the route) is looked up; continuity is the longest
        run of one vector over the leg's length, the distance its median over the leg.
        """
        max_range = self.sonars.transducer.max_range_m
        features = np.zeros((self.config.n_legs, 4))
        for leg in range(self.config.n_legs):
            xs = np.arange(self.leg_starts_x[leg], self.leg_starts_x[leg + 1], MAP_PROFILE_STEP_M)
            origins = np.column_stack([xs, np.full_like(xs, self.centre_line_y)])
            for side_index, side in enumerate(SIDE_NAMES):
                longest_m, median_m = facing_wall_stretch(
                    self.wall_map, origins, (0.0, _side_sign(side)), MAP_PROFILE_STEP_M
                )
                features[leg, 2 * side_index] = min(longest_m / self.leg_length_m, 1.0)
                features[leg, 2 * side_index + 1] = min(median_m / max_range, 1.0)
        return features

    # --- actions ----------------------------------------------------------------------------
    def encode_action(
        self, side: str, spacing_cm: int = 3, standoff_m: float = 0.0
    ) -> np.ndarray | int:
        """The action for a command; the stand-off snaps to the nearest offered one."""
        check_choice("side", side, SIDES)
        check_choice("spacing_cm", spacing_cm, self.config.sample_spacings_cm)
        check_number("standoff_m", standoff_m, low=-10.0, high=10.0)
        side_index = SIDES.index(side)
        spacing_index = self.config.sample_spacings_cm.index(spacing_cm)
        standoff_index = int(np.argmin(np.abs(np.asarray(self.config.standoffs_m) - standoff_m)))
        if self.config.action_type == "multi_discrete":
            return np.array([side_index, spacing_index, standoff_index], dtype=np.int64)
        n_spacings, n_standoffs = len(self.config.sample_spacings_cm), len(self.config.standoffs_m)
        return (side_index * n_spacings + spacing_index) * n_standoffs + standoff_index

    def decode_action(self, action: Any) -> LegCommand:
        """The command an action stands for."""
        config = self.config
        if config.action_type == "discrete":
            rest, standoff_index = divmod(int(action), len(config.standoffs_m))
            side_index, spacing_index = divmod(rest, len(config.sample_spacings_cm))
        else:
            side_index, spacing_index, standoff_index = (int(v) for v in action)
        return LegCommand(
            SIDES[side_index],
            config.sample_spacings_cm[spacing_index],
            float(config.standoffs_m[standoff_index]),
        )

    # --- episode ----------------------------------------------------------------------------
    def _reset_task(self, options: dict[str, Any] | None) -> dict[str, Any]:
        config = self.config
        rng = self.np_random
        scenario = self._with_random_obstacles(rng)
        start = Pose(self.route_start_x, self.centre_line_y, 0.0)
        world = World(scenario, temperature_c=config.temperature_c, robot_pose=start)
        noise = OdometryNoise(
            encoder_std_m_per_sqrt_m=config.encoder_noise_m_per_sqrt_m,
            scale_error_left=float(
                np.clip(rng.normal(0.0, config.wheel_scale_error_std), -0.4, 0.4)
            ),
            scale_error_right=float(
                np.clip(rng.normal(0.0, config.wheel_scale_error_std), -0.4, 0.4)
            ),
            slip_probability_per_m=config.slip_probability_per_m,
            slip_fraction_max=config.slip_fraction_max,
        )
        heading_std = math.radians(config.initial_heading_std_deg)
        estimate = Pose(
            start.x + rng.normal(0.0, config.initial_position_std_m),
            start.y + rng.normal(0.0, config.initial_position_std_m),
            start.theta + rng.normal(0.0, heading_std),
        )
        covariance = np.diag(
            [
                max(config.initial_position_std_m, 1e-4) ** 2,
                max(config.initial_position_std_m, 1e-4) ** 2,
                max(heading_std, 1e-5) ** 2,
            ]
        )
        motion_rng = np.random.default_rng(int(rng.integers(2**63)))
        sensor_rng = np.random.default_rng(int(rng.integers(2**63)))
        robot = DifferentialDriveRobot(noise, odometry_pose=estimate)
        tracker = APCSTracker(
            self.wall_map,
            estimate,
            covariance,
            wheel_base_m=robot.wheel_base_for(world),
            variance_per_m=config.filter_variance_per_m,
            range_variance_m2=config.range_variance_m2,
            bearing_variance_rad2=math.radians(config.bearing_std_deg) ** 2,
            measurement_variances=config.measurement_variances,
            correction_method=config.correction_method,
            params=self.params,
        )
        route = APCSRoute(world, robot, self.sonars, tracker, motion_rng, sensor_rng, self.timing)
        self._episode = _Episode(route)
        return self._info("running")

    def _with_random_obstacles(self, rng: np.random.Generator) -> Scenario:
        """The scenario plus ``n_unmapped_obstacles`` unmapped boxes against the long walls."""
        config = self.config
        return with_wall_obstacles(
            self.scenario,
            rng,
            config.n_unmapped_obstacles,
            config.obstacle_length_range_m,
            config.obstacle_depth_range_m,
            (self.route_start_x + 0.5, self.leg_starts_x[-1] - 0.2),
        )

    def _apply_action(self, action: Any) -> StepOutcome:
        episode = self._require_episode()
        config = self.config
        route = episode.route
        command = self.decode_action(action)
        summary = LegSummary()
        for side in SIDE_NAMES:
            if side not in command.active_sides:
                route.flush(side, summary)
        start_x = self.leg_starts_x[route.leg]
        end_x = self.leg_starts_x[route.leg + 1]
        y = self.centre_line_y + command.standoff_m
        steps_per_aim = max(1, round(config.reaim_interval_m / config.motion_step_m))
        route.drive_through(
            [np.array((start_x + config.transition_m, y)), np.array((end_x, y))],
            command.active_sides,
            command.spacing_cm // config.motion_step_cm,
            config.motion_step_m,
            steps_per_aim,
            summary,
        )
        route.leg += 1
        done = route.leg >= config.n_legs
        if done:
            for side in SIDE_NAMES:
                route.flush(side, summary)
        episode.last_leg = summary
        episode.totals.add(summary)
        episode.collisions += int(summary.collided)

        truth = episode.true_pose
        pose_loss = position_error_m(
            episode.estimate, truth
        ) / config.position_scale_m + heading_error_rad(episode.estimate, truth) / math.radians(
            config.heading_scale_deg
        )
        reward = -pose_loss - config.sensing_cost_per_s * summary.sensing_time_s
        if summary.collided:
            reward -= config.collision_penalty
        return StepOutcome(reward, terminated=done, info=self._info("ok" if done else "running"))

    # --- observation and info ---------------------------------------------------------------
    def _observe(self) -> np.ndarray:
        episode = self._require_episode()
        config = self.config
        layout = self.observation_layout
        observation = np.zeros(self.observation_space.shape, dtype=np.float32)
        room = self.scenario.room
        assert room is not None
        estimate = episode.estimate
        observation[layout["progress"]] = episode.leg / config.n_legs
        observation[layout["estimate_xy"]] = np.clip(
            [
                2.0 * (estimate.x - room.min[0]) / (room.max[0] - room.min[0]) - 1.0,
                2.0 * (estimate.y - room.min[1]) / (room.max[1] - room.min[1]) - 1.0,
            ],
            -1.0,
            1.0,
        )
        observation[layout["estimate_heading"]] = [
            math.cos(estimate.theta),
            math.sin(estimate.theta),
        ]
        variances = np.maximum(np.diag(episode.covariance), 0.0)
        observation[layout["position_std"]] = np.minimum(
            np.sqrt(variances[:2]) / POSITION_STD_SCALE_M, 1.0
        )
        observation[layout["heading_std"]] = min(
            math.sqrt(variances[2]) / HEADING_STD_SCALE_RAD, 1.0
        )
        if episode.leg < config.n_legs:
            observation[layout["map_ahead"]] = self._map_ahead[episode.leg]
        last = episode.last_leg
        counts = [
            count[side]
            for side in SIDE_NAMES
            for count in (last.detected, last.matched, last.rejected)
        ]
        observation[layout["last_leg_walls"]] = np.minimum(np.asarray(counts) / COUNT_SCALE, 1.0)
        observation[layout["last_leg_dropped"]] = min(last.dropped_groups / COUNT_SCALE, 1.0)
        observation[layout["collided"]] = float(last.collided)
        observation[layout["sensing_time"]] = min(
            episode.sensing_time_s / self._max_sensing_time_s, 1.0
        )
        observation[layout["samples"]] = min(last.samples / self._max_samples_per_leg, 1.0)
        return observation

    def _info(self, status: str) -> dict[str, Any]:
        episode = self._require_episode()
        truth = episode.true_pose
        estimate = episode.estimate
        totals = episode.totals
        odometry = episode.robot.odometry_pose or estimate
        return {
            "position_error_m": position_error_m(estimate, truth),
            "heading_error_rad": heading_error_rad(estimate, truth),
            "sensing_time_s": episode.sensing_time_s,
            "status": status,
            "n_matched_walls": sum(totals.matched.values()),
            "n_rejected_walls": sum(totals.rejected.values()),
            "n_detected_walls": sum(totals.detected.values()),
            "n_corrections": totals.corrections,
            "leg": episode.leg,
            "collisions": episode.collisions,
            "odometry_position_error_m": position_error_m(odometry, truth),
            "true_pose": truth.as_array(),
            "estimated_pose": estimate.as_array(),
            "covariance_diagonal": np.diag(episode.covariance).copy(),
        }

    @property
    def trace(self) -> EpisodeTrace:
        """The current episode's paths, ERPs, detections and corrections."""
        return self._require_episode().trace

    @property
    def true_pose(self) -> Pose:
        """The robot's true pose (for plots and tests; agents see only the observation)."""
        return self._require_episode().true_pose

    @property
    def world_scenario(self) -> Scenario:
        """The current episode's scenario, with its random unmapped obstacles."""
        return self._require_episode().world.scenario

    # --- rendering --------------------------------------------------------------------------
    def _render_frame(self) -> np.ndarray:
        from sonar_gym.render import render_topdown

        episode = self._require_episode()
        trace = episode.trace
        erps = np.array([(x, y) for x, y, _ in trace.erps]).reshape(-1, 2)
        totals = episode.totals
        image = render_topdown(
            episode.world.scenario,
            true_pose=episode.true_pose,
            estimated_pose=episode.estimate,
            scan_points=erps,
            width_px=900,
            title=f"WallCorrection  leg {episode.leg}/{self.config.n_legs}",
            extra={
                "matched walls": sum(totals.matched.values()),
                "rejected walls": sum(totals.rejected.values()),
                "position error m": position_error_m(episode.estimate, episode.true_pose),
            },
        )
        _draw_path(
            image, episode.world.scenario, np.array(trace.odometry_path), (150, 150, 150), 900
        )
        _draw_path(image, episode.world.scenario, np.array(trace.true_path), (20, 120, 20), 900)
        _draw_path(
            image, episode.world.scenario, np.array(trace.estimated_path), (216, 27, 156), 900
        )
        return image

    def _require_episode(self) -> _Episode:
        if self._episode is None:
            raise RuntimeError("WallCorrectionEnv: call reset() first")
        return self._episode


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------


def _side_sonars(range_noise_std_m: float | None) -> SideSonars:
    """The MA40B8 side sonars, with the timing jitter set to ``range_noise_std_m`` if given."""
    sonars = SideSonars.apcs()
    if range_noise_std_m is None:
        return sonars
    transducer = dataclasses.replace(sonars.transducer, range_noise_std_m=float(range_noise_std_m))
    return dataclasses.replace(sonars, transducer=transducer)


def _side_sign(side: str) -> float:
    return 1.0 if side == "left" else -1.0


def _draw_path(
    image: np.ndarray,
    scenario: Scenario,
    path: FloatArray,
    colour: tuple[int, int, int],
    width_px: int,
) -> None:
    """Mark the ``(x, y)`` of each row of ``path`` on ``image`` with a 2x2 dot (in place)."""
    from sonar_gym.render import world_to_pixel

    height, width = image.shape[:2]
    for x, y in path[:, :2]:
        row, col = world_to_pixel(scenario, (x, y), width_px, height)
        if 0 <= row < height - 1 and 0 <= col < width - 1:
            image[row : row + 2, col : col + 2] = colour


__all__ = [
    "ENV_ID",
    "REAIM_TOLERANCE_RAD",
    "SIDES",
    "SIDE_NAMES",
    "ClosedGroup",
    "EpisodeTrace",
    "LegCommand",
    "LegSummary",
    "WallCorrectionConfig",
    "WallCorrectionEnv",
    "WallDetection",
    "WallStream",
    "map_wall_vectors",
    "nearest_facing_walls",
    "rejection_reason",
]
