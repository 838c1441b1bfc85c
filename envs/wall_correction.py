"""``SonarGym/WallCorrection-v0``: correct drifting odometry with flat walls sensed from the side.

The task of Yamamoto, Maeyama, Ohya & Yuta, *APCS: autonomous position correction system using
ultrasonic sensing*. The robot drives a corridor route leg by leg; before each leg the agent
chooses which side sonars to run, how often to sample and how far from the corridor's centre
line to drive. Inside the legs runs the paper's procedure (Fig. 2) in
:class:`sonar_gym.apcs_route.APCSRoute` and :mod:`sonar_gym.localization.apcs_online`:
estimated reflection points (eqs 1-6), flat-wall detection (sec. 4.2.2-4.2.3), matching to the
map of oriented wall vectors (sec. 4.3) and the maximum-likelihood correction of pose and
covariance (eqs 7-14). This module holds the task: configuration, actions, observation, reward;
the map, stream, verdict and record names it re-exports live in :mod:`sonar_gym.maps`,
:mod:`sonar_gym.localization.apcs_online` and :mod:`sonar_gym.apcs_route`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from sonar_gym.apcs_route import (
    REAIM_TOLERANCE_RAD,
    APCSRoute,
    EpisodeTrace,
    LegCommand,
    LegSummary,
    WallDetection,
    check_route_clearance,
    render_route,
    with_wall_obstacles,
)
from sonar_gym.envs.action_types import DiscreteChoices, make_action_type
from sonar_gym.envs.base import INFO_KEYS, SonarEnv, StepOutcome
from sonar_gym.envs.features import Flag, Fraction, Heading, ObservationSpec, ScaledPosition
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
from sonar_gym.localization.apcs_walls import WallMap
from sonar_gym.localization.apcs_online import (
    SIDE_NAMES,
    APCSTracker,
    ClosedGroup,
    WallStream,
    nearest_facing_walls,
    rejection_reason,
)
from sonar_gym.maps import map_ahead_features, map_wall_vectors
from sonar_gym.metrics import heading_error_rad, position_error_m
from sonar_gym.pose import Pose
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
OBSERVATION = ObservationSpec(
    [
        Fraction("progress"),
        ScaledPosition("estimate_xy"),
        Heading("estimate_heading"),
        Fraction("position_std", 2),
        Fraction("heading_std"),
        Fraction("map_ahead", 4),
        Fraction("last_leg_walls", 6),
        Fraction("last_leg_dropped"),
        Flag("collided"),
        Fraction("sensing_time"),
        Fraction("samples"),
    ]
)
"""The observation's features (see the env docstring, Observation Space)."""
MAP_PROFILE_STEP_M = 0.02
"""Spacing of the map look-up along a leg for the map-ahead features (metres)."""
STANDOFF_CLEARANCE_M = 0.05
"""Least clearance (metres) between the robot and the mapped surfaces on every offered stand-off."""


@dataclass(frozen=True)
class WallCorrectionConfig:
    """The ``gym.make`` arguments of ``SonarGym/WallCorrection-v0`` (see the env docstring)."""

    RENAMED_ARGUMENTS: ClassVar[dict[str, str]] = {
        "encoder_noise_m_per_sqrt_m": "encoder_std_m_per_sqrt_m",
    }

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
    encoder_std_m_per_sqrt_m: float = 0.0005
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
        number_field(self, "encoder_std_m_per_sqrt_m", low=0.0, high=0.1)
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

        Default: ``encoder_std^2 + wheel_scale_error_std^2 * 1 m``, the random encoder error
        plus the wheel-radius error treated as if it were random per metre.
        """
        if self.odometry_variance_per_m is not None:
            return float(self.odometry_variance_per_m)
        return self.encoder_std_m_per_sqrt_m**2 + self.wheel_scale_error_std**2


PAPER_SENSOR_PRESET = "ma40b8"
"""The APCS robot's side sonars, used unless the scenario's ``[sensor]`` chooses a preset."""


def _range_field(config: object, name: str, *, low: float, high: float) -> None:
    """A pair (low, high) with ``low <= high``, both within ``[low, high]``."""
    first, _ = numbers_field(config, name, length=2, low=low, high=high)
    check_number(f"{name}[1]", getattr(config, name)[1], low=first, high=high)


# --------------------------------------------------------------------------------------------
# The environment
# --------------------------------------------------------------------------------------------


class WallCorrectionEnv(SonarEnv):
    """
    ## Description

    A robot drives a corridor with drifting odometry (Yamamoto, Maeyama, Ohya & Yuta, *APCS:
    autonomous position correction system using ultrasonic sensing*). Two side-looking MA40B8
    sonars range the walls; the map holds the corridor's walls and pillars as oriented wall
    vectors, but not wall B (a board before the left wall) nor the unmapped obstacles drawn at
    random per episode. The route runs along the room's ``+x`` axis, ``route_margin_m`` from
    its ends, in ``n_legs`` equal legs. Before each leg the agent chooses which side sonars
    run, how often they sample, and the leg's stand-off from the centre line.

    During a leg the robot drives from its estimate, through pymunk, in straight commands of
    ``motion_step_cm`` (a :class:`~sonar_gym.robot.DifferentialDriveRobot` with encoder noise,
    per-episode wheel-radius errors and rare slips): to the point ``transition_m`` into the
    leg at the new stand-off, then to the leg's end, re-aiming every ``reaim_interval_m``. The
    estimate and covariance follow the encoders (Kim et al. sec. 3.1, each wheel's variance
    growing by ``odometry_variance_per_m`` per metre). Every ``spacing`` of travel the active
    sonars read once each, and APCS runs on line per side (Fig. 2): ERPs from consecutive
    readings (eqs 1-6), grouping (100 cm^2, 4 to 8 ERPs), line fit and variance test (sec.
    4.2.2-4.2.3), matching to the map (+-0.5 deg, inclusion, d1^2 + d2^2 < 200 cm^2; sec. 4.3,
    6) and, on exactly one match, the maximum-likelihood correction of pose and covariance
    (eqs 7-14) with the fitted line's ``(r, xi)``; stored readings and ERPs move with it.

    The paper gives no ``sigma_r``, ``sigma_xi``: by default (1 cm)^2 and (1 deg)^2
    (``measurement_variances="fixed"``), or ``"fit"``, each wall fit's own least-squares
    variances. The sonars' timing jitter defaults to 1 mm, not the preset's 3 mm: the paper's
    thresholds (consecutive ERPs within 10 cm at 3 cm spacing) need range differences good to
    about 2 mm, and at 3 mm the +-0.5 deg test passes about one fit in seven even with a
    perfect heading (``range_noise_std_m=None`` restores the preset).

    ## Action Space

    ``action_type="multi_discrete"`` (default): ``MultiDiscrete([4, len(sample_spacings_cm),
    len(standoffs_m)])``: index 0 the side sonars (0 none, 1 left, 2 right, 3 both), 1 the
    sampling spacing (``sample_spacings_cm``, default 3, 6, 9 cm of travel; ignored when no
    sonar runs), 2 the stand-off (``standoffs_m``, default -0.4 to 0.4 m, positive = left).
    ``action_type="discrete"`` flattens them into ``Discrete(4 * n_spacings * n_standoffs)``
    (side major, stand-off minor). Every stand-off keeps the robot 5 cm from every *mapped*
    surface along the legs (checked at construction); unmapped obstacles can still be hit.

    ## Observation Space

    ``Box(-1, 1, (22,), float32)``; ``env.unwrapped.observation_layout`` names the slices:

    | slice | meaning | normalisation | bounds |
    |---|---|---|---|
    | progress | legs done / ``n_legs`` | - | [0, 1] |
    | estimate_xy | estimated position | room's extent to [-1, 1] | [-1, 1] |
    | estimate_heading | cos, sin of the estimated heading | - | [-1, 1] |
    | position_std | sqrt of the variance along x and y | / 0.1 m, clipped | [0, 1] |
    | heading_std | sqrt of the heading variance | / 2 deg, clipped | [0, 1] |
    | map_ahead | per side: longest mapped flat stretch along the next leg | / leg | [0, 1] |
    | | and median distance of the mapped wall from the centre line | / 5 m | |
    | last_leg_walls | per side: walls detected, matched, rejected in the last leg | / 10 | [0, 1] |
    | last_leg_dropped | ERP groups failing the size or variance test, last leg | / 10 | [0, 1] |
    | collided | whether the last leg touched an obstacle | - | {0, 1} |
    | sensing_time | sensing time so far / the most the episode can use | - | [0, 1] |
    | samples | readings in the last leg / the most a leg can take | - | [0, 1] |

    The map-ahead features are zero after the last leg.

    ## Rewards

    After each leg: ``-(E_xy / position_scale_m + E_theta / heading_scale_deg)``, the errors
    of the estimate against the truth at the leg's end (Beom & Cho eq. (16); 5 cm or 2 deg
    cost 1), minus ``sensing_cost_per_s`` times the leg's sensing time, minus
    ``collision_penalty`` after a contact. Sensing time is listening time: one MA40B8
    listening time (29 ms, for 5 m) per sampling instant, one sonar or both (they face apart,
    fire together and listen at once). ``info["rewards"]`` holds the terms ``pose_error``,
    ``sensing_cost`` and ``collision``.

    ## Starting State

    The robot stands at the route's start on the centre line, heading ``+x``; its estimate is
    off by ``N(0, initial_position_std_m)`` in x, y and ``N(0, initial_heading_std_deg)`` in
    heading, with that diagonal covariance. Each episode draws the ``n_unmapped_obstacles``
    boxes (on the long walls, clear of the start and each other) and the wheels' radius
    errors ``N(0, wheel_scale_error_std)``.

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
    | scenario | ``"apcs_corridor"`` | a scenario with a room; the route runs along its x axis; |
    | | | the sonars: its ``[sensor]`` preset if set, else the MA40B8 |
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
    | encoder_std_m_per_sqrt_m | 0.0005 | random encoder error after 1 m, metres |
    | wheel_scale_error_std | 0.0005 | std of each wheel's radius error (the drift) |
    | slip_probability_per_m | 0.005 | chance that a wheel slips within a metre |
    | slip_fraction_max | 0.3 | largest loss of travel in a slip |
    | initial_position_std_m | 0.005 | start uncertainty, metres |
    | initial_heading_std_deg | 0.1 | start uncertainty, degrees |
    | odometry_variance_per_m | None | filter's wheel variance per metre (None: enc.^2 + scale^2) |
    | range_variance_m2 | 1e-4 | ``sigma_r`` of eqs (13)-(14), a variance (m^2) |
    | bearing_std_deg | 1.0 | ``sqrt(sigma_xi)``, degrees |
    | measurement_variances | ``"fixed"`` | the two above, or ``"fit"``: each fit's own variances |
    | correction_method | ``"paper"`` | eqs (11)-(14), or ``"linear"`` (exact linear update) |
    | position_scale_m | 0.05 | position error that costs 1 |
    | heading_scale_deg | 2.0 | heading error that costs 1 |
    | sensing_cost_per_s | 0.1 | cost per second of sonar listening |
    | collision_penalty | 5.0 | cost of a leg with a contact |
    | temperature_c | 20.0 | air temperature (the sonar assumes 20 deg C) |
    | range_noise_std_m | 0.001 | sonar timing jitter as range, metres (None: preset's 3 mm) |
    | action_type | ``"multi_discrete"`` | or ``"discrete"`` (for DQN) |

    ## Version History

    * v0: first release. Later, without changing any default episode:
      ``encoder_noise_m_per_sqrt_m`` renamed ``encoder_std_m_per_sqrt_m`` (the name of
      :class:`~sonar_gym.odometry.OdometryConfig`); the old name still works, with a
      ``DeprecationWarning``.

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

    required_info_keys = INFO_KEYS

    metadata = {"render_modes": ["rgb_array"], "render_fps": 2}

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        super().__init__(render_mode)
        self.config = build_config(WallCorrectionConfig, kwargs, ENV_ID)
        config = self.config
        self.scenario = load_scenario(config.scenario)
        if self.scenario.room is None:
            raise ValueError(
                f"argument 'scenario': {self.scenario.name!r} has no room; "
                "the route runs along a room's x axis"
            )
        self.params = DEFAULT_PARAMETERS
        self.wall_map = map_wall_vectors(self.scenario)
        self._wall_table_map = WallMap(tuple(self.wall_map))  # read-only: shared by episodes
        (x_min, y_min), (x_max, y_max) = self.scenario.room.min, self.scenario.room.max
        self.centre_line_y = 0.5 * (y_min + y_max)
        self.route_start_x = x_min + config.route_margin_m
        route_end_x = x_max - config.route_margin_m
        if route_end_x - self.route_start_x <= 0.0:
            raise ValueError(
                f"argument 'route_margin_m' leaves no route in a room {x_max - x_min:g} m long; "
                f"got {config.route_margin_m!r}"
            )
        self.leg_length_m = (route_end_x - self.route_start_x) / config.n_legs
        if config.transition_m >= self.leg_length_m:
            raise ValueError(
                f"argument 'transition_m' must be shorter than a leg ({self.leg_length_m:.3f} m); "
                f"got {config.transition_m!r}"
            )
        self.leg_starts_x = self.route_start_x + self.leg_length_m * np.arange(config.n_legs + 1)
        check_route_clearance(
            self.scenario,
            (self.route_start_x, self.leg_starts_x[-1]),
            self.centre_line_y,
            config.standoffs_m,
            STANDOFF_CLEARANCE_M,
            config.temperature_c,
            route_margin_m=config.route_margin_m,
        )
        self.sonars = SideSonars.apcs(
            config.range_noise_std_m, preset=self.scenario.sensor.preset_or(PAPER_SENSOR_PRESET)
        )
        self._map_ahead = map_ahead_features(
            self.wall_map,
            self.leg_starts_x,
            self.leg_length_m,
            self.centre_line_y,
            MAP_PROFILE_STEP_M,
            self.sonars.transducer.max_range_m,
        )

        self._use_action_type(
            make_action_type(
                config.action_type,
                DiscreteChoices(
                    (len(SIDES), len(config.sample_spacings_cm), len(config.standoffs_m))
                ),
            )
        )
        self._use_observation_spec(OBSERVATION)
        steps_per_leg = math.ceil(self.leg_length_m / config.motion_step_m) + 2
        instants_per_leg = steps_per_leg * config.motion_step_cm // min(config.sample_spacings_cm)
        self._max_samples_per_leg = 2 * instants_per_leg
        self._max_sensing_time_s = (
            config.n_legs * instants_per_leg * self.sonars.transducer.listen_time_s
        )
        self._episode: APCSRoute | None = None

    # --- actions ----------------------------------------------------------------------------
    def encode_action(
        self, side: str, spacing_cm: int = 3, standoff_m: float = 0.0
    ) -> np.ndarray | int:
        """The action for a command; the stand-off snaps to the nearest offered one."""
        check_choice("side", side, SIDES)
        check_choice("spacing_cm", spacing_cm, self.config.sample_spacings_cm)
        check_number("standoff_m", standoff_m, low=-10.0, high=10.0)
        spacing_index = self.config.sample_spacings_cm.index(spacing_cm)
        standoff_index = int(np.argmin(np.abs(np.asarray(self.config.standoffs_m) - standoff_m)))
        return self.action_type.encode((SIDES.index(side), spacing_index, standoff_index))

    def decode_action(self, action: Any) -> LegCommand:
        """The command an action stands for.

        Raises:
            ValueError: ``action`` is not in the action space (the message says what is).
        """
        self.action_type.check(action)
        return self._command(action)

    def _command(self, action: Any) -> LegCommand:
        """:meth:`decode_action` of an action already checked (``step`` checks it)."""
        config = self.config
        side_index, spacing_index, standoff_index = self.action_type.decode(action)
        return LegCommand(
            SIDES[side_index],
            config.sample_spacings_cm[spacing_index],
            float(config.standoffs_m[standoff_index]),
        )

    # --- episode ----------------------------------------------------------------------------
    def _reset_task(self, options: dict[str, Any] | None) -> dict[str, Any]:
        config = self.config
        rng = self.np_random
        scenario = with_wall_obstacles(  # unmapped boxes against the long walls
            self.scenario,
            rng,
            config.n_unmapped_obstacles,
            config.obstacle_length_range_m,
            config.obstacle_depth_range_m,
            (self.route_start_x + 0.5, self.leg_starts_x[-1] - 0.2),
        )
        start = Pose(self.route_start_x, self.centre_line_y, 0.0)
        world = World(scenario, temperature_c=config.temperature_c, robot_pose=start)

        def scale_error() -> float:
            return min(max(float(rng.normal(0.0, config.wheel_scale_error_std)), -0.4), 0.4)

        noise = OdometryNoise(
            encoder_std_m_per_sqrt_m=config.encoder_std_m_per_sqrt_m,
            scale_error_left=scale_error(),
            scale_error_right=scale_error(),
            slip_probability_per_m=config.slip_probability_per_m,
            slip_fraction_max=config.slip_fraction_max,
        )
        heading_std = math.radians(config.initial_heading_std_deg)
        estimate = Pose(
            start.x + rng.normal(0.0, config.initial_position_std_m),
            start.y + rng.normal(0.0, config.initial_position_std_m),
            start.theta + rng.normal(0.0, heading_std),
        )
        position_variance = max(config.initial_position_std_m, 1e-4) ** 2
        covariance = np.diag([position_variance, position_variance, max(heading_std, 1e-5) ** 2])
        motion_rng = np.random.default_rng(int(rng.integers(2**63)))
        sensor_rng = np.random.default_rng(int(rng.integers(2**63)))
        robot = DifferentialDriveRobot(noise, odometry_pose=estimate)
        tracker = APCSTracker.unchecked(  # the config and draws above are valid
            self._wall_table_map,
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
        self._episode = APCSRoute(
            world, robot, self.sonars, tracker, motion_rng, sensor_rng, self.timing
        )
        return self._info("running")

    def _apply_action(self, action: Any) -> StepOutcome:
        route = self._require_episode()
        config = self.config
        command = self._command(action)
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
        done = route.leg + 1 >= config.n_legs
        if done:
            for side in SIDE_NAMES:
                route.flush(side, summary)
        route.end_leg(summary)

        truth, estimate = route.true_pose, route.tracker.estimate
        pose_loss = position_error_m(estimate, truth) / config.position_scale_m + heading_error_rad(
            estimate, truth
        ) / math.radians(config.heading_scale_deg)
        terms = {
            "pose_error": -pose_loss,
            "sensing_cost": -(config.sensing_cost_per_s * summary.sensing_time_s),
            "collision": -config.collision_penalty if summary.collided else 0.0,
        }
        return StepOutcome(
            reward_terms=terms, terminated=done, info=self._info("ok" if done else "running")
        )

    # --- observation and info ---------------------------------------------------------------
    def _observe(self) -> np.ndarray:
        route = self._require_episode()
        config = self.config
        observation = OBSERVATION.writer()
        room = self.scenario.room
        assert room is not None
        estimate = route.tracker.estimate
        observation["progress"] = route.leg / config.n_legs
        observation["estimate_xy"] = ScaledPosition.float_values(
            (estimate.x, estimate.y), room.min, room.max
        )
        observation["estimate_heading"] = Heading.values(estimate.theta)
        # On Python floats, rounding as numpy's maximum, sqrt and minimum of the diagonal do.
        variance_x, variance_y, variance_theta = (
            _non_negative(variance) for variance in np.diag(route.tracker.covariance).tolist()
        )
        observation["position_std"] = [
            min(math.sqrt(variance_x) / POSITION_STD_SCALE_M, 1.0),
            min(math.sqrt(variance_y) / POSITION_STD_SCALE_M, 1.0),
        ]
        observation["heading_std"] = min(math.sqrt(variance_theta) / HEADING_STD_SCALE_RAD, 1.0)
        if route.leg < config.n_legs:
            observation["map_ahead"] = self._map_ahead[route.leg]
        last = route.last_leg
        tallies = (last.detected, last.matched, last.rejected)
        observation["last_leg_walls"] = [
            min(tally[side] / COUNT_SCALE, 1.0) for side in SIDE_NAMES for tally in tallies
        ]
        observation["last_leg_dropped"] = min(last.dropped_groups / COUNT_SCALE, 1.0)
        observation["collided"] = float(last.collided)
        sensing_fraction = route.sensing_time_s / self._max_sensing_time_s
        observation["sensing_time"] = min(sensing_fraction, 1.0)
        observation["samples"] = min(last.samples / self._max_samples_per_leg, 1.0)
        return observation.vector

    def _info(self, status: str) -> dict[str, Any]:
        route = self._require_episode()
        truth, estimate = route.true_pose, route.tracker.estimate
        totals = route.totals
        odometry = route.robot.odometry_pose or estimate
        return {
            "position_error_m": position_error_m(estimate, truth),
            "heading_error_rad": heading_error_rad(estimate, truth),
            "sensing_time_s": route.sensing_time_s,
            "status": status,
            "n_matched_walls": sum(totals.matched.values()),
            "n_rejected_walls": sum(totals.rejected.values()),
            "n_detected_walls": sum(totals.detected.values()),
            "n_corrections": totals.corrections,
            "leg": route.leg,
            "collisions": route.collisions,
            "odometry_position_error_m": position_error_m(odometry, truth),
            "true_pose": truth.as_array(),
            "estimated_pose": estimate.as_array(),
            "covariance_diagonal": np.diag(route.tracker.covariance).copy(),
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
        route = self._require_episode()
        totals = route.totals
        return render_route(
            route,
            f"WallCorrection  leg {route.leg}/{self.config.n_legs}",
            {
                "matched walls": sum(totals.matched.values()),
                "rejected walls": sum(totals.rejected.values()),
                "position error m": position_error_m(route.tracker.estimate, route.true_pose),
            },
        )

    def _require_episode(self) -> APCSRoute:
        if self._episode is None:
            raise RuntimeError("WallCorrectionEnv: call reset() first")
        return self._episode


def _non_negative(value: float) -> float:
    """``np.maximum(value, 0.0)`` of a float: NaN stays NaN and a signed zero gives ``0.0``."""
    return value if value > 0.0 or value != value else 0.0


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
