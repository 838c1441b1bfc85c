"""``SonarGym/SweepLocalization-v0``: how many servo sweeps, and where, along a route.

The task of Kim, Lee & Jeong (*Self localization of mobile robot using sonar sensing and map
building*): a small robot drives a route in the 2 m arena with drifting dead reckoning; at each
decision point the agent chooses how many sweeps of the servo-mounted SRF04 to take (0 to
``max_sweeps``) and toward which sector. The sweeps, taken between short moves along the route
and combined through dead reckoning, feed the voting localization on the known occupancy grid
(sec. 3.3), whose fix corrects the EKF (secs. 3.1-3.2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from sonar_gym.envs.action_types import DiscreteChoices, make_action_type
from sonar_gym.envs.base import INFO_KEYS, SonarEnv, StepOutcome
from sonar_gym.envs.features import (
    Flag,
    Fraction,
    Heading,
    ObservationSpec,
    RangeBins,
    ScaledPosition,
    clipped,
)
from sonar_gym.envs.config import (
    build_config,
    check_choice,
    check_number,
    choice_field,
    number_field,
    scenario_field,
)
from sonar_gym.localization.kim_fix import fix_covariance, gated_ekf_update, vote_around_estimate
from sonar_gym.localization.kim_grid import (
    PAPER_CELL_SIZE_M,
    occupancy_grid_of,
    sweep_end_points,
)
from sonar_gym.localization.kim import (
    TABLE_1_TRUE_POSITIONS_M,
    Sweep,
)
from sonar_gym.metrics import heading_error_rad, position_error_m
from sonar_gym.odometry import OdometryConfig
from sonar_gym.polyline import Route, draw_free_route, draw_polyline, follow_route
from sonar_gym.pose import Pose, wrap_angle
from sonar_gym.robot import DifferentialDriveRobot
from sonar_gym.scenario import Scenario, load_scenario
from sonar_gym.sonar.swept import SweptSonar
from sonar_gym.validation import MIN_SCALE, MIN_VARIANCE
from sonar_gym.world import World

POSITION_UNIT_M = 0.1
"""Position error worth one unit of loss: the "typical" error of Kim et al. sec. 4.1 (10 cm)."""
HEADING_UNIT_RAD = math.radians(5.0)
"""Heading error worth one unit of loss (5 deg: one heading step of the vote at 1 m range is
about the cell size, 5 cm, i.e. ~3 deg, and 5 deg is where a fix is clearly needed)."""
SECTOR_NAMES = ("front", "left", "right", "back")
SECTOR_CENTRES_RAD = (0.0, math.pi / 2.0, -math.pi / 2.0, math.pi)
"""Sector centres in the robot frame {R} (0 = forward, counter-clockwise positive)."""
SLIP_FRACTION_MAX = 0.1
"""A slipping wheel loses up to this fraction of the command's ground travel."""
POSITION_STD_SCALE_M = 0.25
"""Covariance features: ``sqrt(P_xx) / 0.25 m`` (clipped to 1)."""
HEADING_STD_SCALE_RAD = math.radians(15.0)
"""Covariance feature: ``sqrt(P_thth) / 15 deg`` (clipped to 1)."""
DISTANCE_SCALE_M = 2.0
"""Feature: distance driven since the last accepted fix / 2 m (clipped to 1)."""
_STD_SCALES = (POSITION_STD_SCALE_M, POSITION_STD_SCALE_M, HEADING_STD_SCALE_RAD)
"""The scales of ``sqrt(P_xx)``, ``sqrt(P_yy)``, ``sqrt(P_thth)`` in the observation."""
MAX_MAP_CELLS = 4_000_000
"""Largest voting map the env builds: cells of the scenario's bounds (100 m x 100 m of 5 cm)."""
_RUNNING = "running"
_OBSERVATION_ORDER = (
    "estimate_xy",
    "estimate_heading",
    "estimate_std",
    "distance_since_fix",
    "route_progress",
    "last_sweep_ranges",
    "last_sweep_sector",
    "last_fix_ok",
    "route_heading",
    "steps_remaining",
)
"""The observation's features in vector order."""


@dataclass(frozen=True)
class SweepLocalizationConfig:
    """The ``gym.make`` arguments of ``SonarGym/SweepLocalization-v0`` (see the env docstring)."""

    RENAMED_ARGUMENTS: ClassVar[dict[str, str]] = {
        "encoder_noise_std_m_per_sqrt_m": "encoder_std_m_per_sqrt_m",
        "wheel_scale_error": "wheel_scale_error_bound",
    }

    scenario: str = "kim_arena"
    route: str = "table1"
    route_length_m: float = 3.2
    decision_points: str = "spacing"
    decision_spacing_m: float = 0.4
    sweep_spacing_m: float = 0.1
    max_sweeps: int = 4
    sweep_width_deg: int = 90
    sweep_step_deg: float = 5.0
    anchor: str = "obstacle_point"
    heading_step_deg: float = 1.0
    sensing_cost_per_s: float = 0.1
    max_error_loss: float = 20.0
    encoder_std_m_per_sqrt_m: float = 0.005
    wheel_scale_error_bound: float = 0.01
    slip_probability_per_m: float = 0.02
    initial_position_std_m: float = 0.02
    initial_heading_std_deg: float = 2.0
    fix_position_std_m: float = 0.03
    fix_heading_std_deg: float = 4.0
    innovation_gate: float | None = None
    temperature_c: float = 20.0
    n_range_bins: int = 9

    def __post_init__(self) -> None:
        scenario_field(self)
        choice_field(self, "route", ("table1", "random"))
        number_field(self, "route_length_m", low=0.5, high=50.0)
        choice_field(self, "decision_points", ("spacing", "waypoints"))
        number_field(self, "decision_spacing_m", low=0.05, high=5.0)
        number_field(self, "sweep_spacing_m", low=0.0, high=1.0)
        number_field(self, "max_sweeps", low=4, high=12, integer=True)
        choice_field(self, "sweep_width_deg", (90, 180))
        number_field(self, "sweep_step_deg", low=0.5, high=15.0)
        choice_field(self, "anchor", ("obstacle_point", "cell_center"))
        number_field(self, "heading_step_deg", low=0.25, high=5.0)
        number_field(self, "sensing_cost_per_s", low=0.0, high=100.0)
        number_field(self, "max_error_loss", low=MIN_SCALE, high=1e4)
        number_field(self, "encoder_std_m_per_sqrt_m", low=0.0, high=0.1)
        number_field(self, "wheel_scale_error_bound", low=0.0, high=0.1)
        number_field(self, "slip_probability_per_m", low=0.0, high=1.0)
        number_field(self, "initial_position_std_m", low=0.0, high=0.5)
        number_field(self, "initial_heading_std_deg", low=0.0, high=30.0)
        number_field(self, "fix_position_std_m", low=0.001, high=1.0)
        number_field(self, "fix_heading_std_deg", low=0.05, high=45.0)
        # a squared Mahalanobis distance, so its floor is that of a variance
        number_field(self, "innovation_gate", low=MIN_VARIANCE, high=1e6, optional=True)
        number_field(self, "temperature_c", low=-20.0, high=50.0)
        number_field(self, "n_range_bins", low=1, high=64, integer=True)

    @property
    def ekf_variance_per_m(self) -> float:
        """``V(k)`` of the EKF, m^2 per metre rolled by a wheel (sec. 3.1; the paper gives none).

        The encoder's random variance plus the variance of a wheel scale error uniform in
        ``+-wheel_scale_error_bound`` (``e^2 / 3``, taken over one metre of travel). Wheel slips are
        left out of the filter's model: they are the rare "other errors" ``w(k)`` of sec. 3.1
        that the encoders cannot see, and only a fix corrects them.
        """
        return self.encoder_std_m_per_sqrt_m**2 + self.wheel_scale_error_bound**2 / 3.0


PAPER_SENSOR_PRESET = "srf04"
"""Kim et al.'s ranger, used unless the scenario's ``[sensor]`` chooses another preset."""


@dataclass
class _Episode:
    world: World
    robot: DifferentialDriveRobot
    route: Route
    decision_stations_m: np.ndarray
    estimate: Pose
    covariance: np.ndarray
    progress_m: float = 0.0
    decisions: int = 0
    sensing_time_s: float = 0.0
    distance_since_fix_m: float = 0.0
    last_ranges: np.ndarray | None = None
    last_sector: int = 0
    last_fix_ok: bool = False
    true_track: list[tuple[float, float]] = field(default_factory=list)
    """The true positions after each drive ({W}, metres; for rendering)."""
    estimate_track: list[tuple[float, float]] = field(default_factory=list)
    """The EKF positions after each drive ({W}, metres; for rendering)."""
    scanned: tuple[tuple[Sweep, Pose], ...] = ()
    """The last decision's sweeps with the true poses they were taken at (for rendering)."""

    def scan_points(self) -> np.ndarray | None:
        """End points ({W}) of the last decision's echoes, or None before any sweep."""
        if not self.scanned:
            return None
        return np.concatenate([sweep_end_points(sweep, pose)[1] for sweep, pose in self.scanned])


class SweepLocalizationEnv(SonarEnv):
    """
    ## Description

    A small differential-drive robot (12 x 18 cm, wheel base 0.15 m) follows a route through
    the 2 m arena of Kim, Lee & Jeong (scenario ``kim_arena``). Its dead reckoning drifts:
    encoder noise, a wheel scale error drawn per episode and occasional wheel slip. It knows
    the arena's map as an occupancy grid of 5 cm cells (sec. 2.2, 4.1), rasterised from the
    mapped geometry (``OccupancyGrid.from_segments``). At each decision point along the route
    the agent chooses how many servo sweeps of the SRF04 to take and toward which sector.
    The first sweep is taken where the robot stands; the robot then moves ``sweep_spacing_m``
    along the route before each further sweep (never past the next decision point; sweeps
    with no route left are taken in place). The sweeps are combined through dead reckoning
    (``Sweep.odometry``) and the voting localization of sec. 3.3 runs on them, restricted to
    a circle around the EKF estimate (``search_radius = 3 sqrt(lambda_max(P_xy)) + cell``,
    clipped to [0.1, 0.6] m) and to headings within ``3 sqrt(P_thth) + 1 step`` (clipped to
    [3, 30] deg) of it. Its fix of the last sweep's pose corrects the EKF (sec. 3.2, with the
    gain's missing inverse restored). The EKF predicts with the encoder increments of every
    move (sec. 3.1, ``V(k)`` = ``config.ekf_variance_per_m`` per metre rolled). Then the robot
    drives on to the next decision point.

    Measurement covariance ``G = diag(s^2, s^2, h^2)`` with ``s = fix_position_std_m``
    (3 cm) and ``h = fix_heading_std_deg`` (4 deg), the measured spread of the fixes: over
    random routes in ``kim_arena`` with 1-4 forward sweeps, the vote's error is 2.5-3.3 cm RMS
    per axis (a fix is quantised to the 5 cm cell, ``5 / sqrt(12) = 1.4`` cm, and the SRF04's
    40 deg beam smears each wall into an arc) and 3.4-4.4 deg RMS in heading (a wall seen
    at normal incidence reads the same over the whole beam, so only the ends of the arcs,
    corners and edges fix the heading). With ``innovation_gate`` a fix whose squared
    Mahalanobis innovation ``nu^T (P + G)^-1 nu`` exceeds it is rejected.

    ## Action Space

    ``MultiDiscrete([max_sweeps + 1, 4])``:

    | index | meaning | values |
    |---|---|---|
    | 0 | number of sweeps | 0 .. ``max_sweeps`` (0: no sensing, just drive on) |
    | 1 | sector centre in {R} | 0 front (0 deg), 1 left (+90), 2 right (-90), 3 back (180) |

    Each sweep covers ``sweep_width_deg`` (90: the paper's +-45 deg; 180: the 180 deg
    variant of sec. 2.2) about the sector centre, one ping every ``sweep_step_deg``.
    ``env.unwrapped.encode_action(n_sweeps, sector)`` builds an action from a sector name.

    ## Observation Space

    ``Box(-1, 1, (15 + n_range_bins,), float32)``:

    | slice | meaning | range |
    |---|---|---|
    | ``estimate_xy`` (2) | EKF position scaled to the scenario bounds | [-1, 1] |
    | ``estimate_heading`` (2) | cos, sin of the EKF heading | [-1, 1] |
    | ``estimate_std`` (3) | sqrt of ``P_xx``, ``P_yy`` / 0.25 m; of ``P_thth`` / 15 deg | [0, 1] |
    | ``distance_since_fix`` (1) | metres driven since the last accepted fix / 2 m | [0, 1] |
    | ``route_progress`` (1) | route length covered / route length | [0, 1] |
    | ``last_sweep_ranges`` (n) | last sweep, nearest range per bin (right to left) / 3 m | [0, 1] |
    | ``last_sweep_sector`` (2) | cos, sin of the last sweep's sector centre in {R} | [-1, 1] |
    | ``last_fix_ok`` (1) | 1 if the last decision's sweeps gave an accepted fix | {0, 1} |
    | ``route_heading`` (2) | cos, sin of the bearing of the next decision point in {R} | [-1, 1] |
    | ``steps_remaining`` (1) | decisions left / decisions of the episode | [0, 1] |

    Features are clipped to their range; ``n = n_range_bins``; a bin without an echo (or
    before the first sweep) reads 1; {R} is the frame of the EKF estimate.

    ``env.unwrapped.observation_layout`` maps these names to slices.

    ## Rewards

    At every decision, after the robot reaches the next decision point:
    ``-min(E_xy / 0.1 m + E_theta / 5 deg, max_error_loss) - sensing_cost_per_s * T_sweeps``,
    with ``E_xy``, ``E_theta`` the error of the EKF estimate (Beom & Cho eq. (16) metrics),
    10 cm the typical error Kim et al. report (sec. 4.1), and ``T_sweeps`` the servo and
    listening time of this decision's sweeps (1.25 s per 90 deg sweep at 5 deg).
    ``info["rewards"]`` holds the two terms, ``pose_error`` and ``sensing_cost``.

    ## Starting State

    ``route="table1"``: the polyline through the seven positions of Kim et al. Table 1
    (3.27 m); ``"random"``: free waypoints joined by collision-free legs (at least 0.3 m) up
    to ``route_length_m``. The robot starts at the route's start facing along it; the EKF
    starts at the truth plus Gaussian noise (``initial_position_std_m``,
    ``initial_heading_std_deg``) with that covariance ("the precise initial position of the
    mobile robot is known", sec. 3.1). Wheel scale errors are drawn uniformly in
    ``+-wheel_scale_error_bound`` per wheel per episode.

    ## Episode End

    Terminates when the robot has covered the route (``decision_points="spacing"``: one
    decision every ``decision_spacing_m``; ``"waypoints"``: one at each route vertex, the last
    one at the route's end). No truncation.

    ## Info

    ``position_error_m``, ``heading_error_rad`` (EKF estimate against the truth),
    ``sensing_time_s`` (cumulative), ``status`` (``"running"``, ``"ok"`` at the end),
    ``n_sweeps``, ``sector``, ``step_sensing_time_s``, ``fix_status`` (``"none"`` without
    sweeps, the voting status, or ``"gated"``), ``fix_position_error_m`` and
    ``fix_heading_error_rad`` (the vote's pose of the first sweep against the truth there,
    only after a fix), ``fix_true_pose`` / ``fix_estimated_pose`` (``[x, y, theta]``, same
    condition), ``fix_measured_pose`` (the last sweep's pose from the vote and dead reckoning:
    the measurement fed to the EKF), ``true_pose``, ``estimated_pose``, ``covariance_diagonal``.

    ## Arguments

    | argument | default | meaning |
    |---|---|---|
    | scenario | ``"kim_arena"`` | built-in name or path; the sonar: its ``[sensor]`` preset |
    | | | if set, else the SRF04 |
    | route | ``"table1"`` | or ``"random"`` |
    | route_length_m | 3.2 | length of a random route, m |
    | decision_points | ``"spacing"`` | or ``"waypoints"`` (one decision per route vertex) |
    | decision_spacing_m | 0.4 | route length between decision points, m |
    | sweep_spacing_m | 0.1 | short move between the sweeps of one decision, m |
    | max_sweeps | 4 | largest number of sweeps per decision (4..12) |
    | sweep_width_deg | 90 | 90 (the paper's +-45 deg) or 180 |
    | sweep_step_deg | 5 | angle between pings, deg (the paper gives none) |
    | anchor | ``"obstacle_point"`` | voting anchor; ``"cell_center"`` is the paper's reading |
    | heading_step_deg | 1 | heading candidates of the vote, deg |
    | sensing_cost_per_s | 0.1 | reward per second of sweeping |
    | max_error_loss | 20 | cap of the error term per decision (a cap only: no failure charge) |
    | encoder_std_m_per_sqrt_m | 0.005 | encoder noise, m after 1 m |
    | wheel_scale_error_bound | 0.01 | per-wheel scale error bound (uniform, per episode) |
    | slip_probability_per_m | 0.02 | wheel-slip probability per metre (loss up to 10 %) |
    | initial_position_std_m / initial_heading_std_deg | 0.02 / 2 | initial EKF error |
    | fix_position_std_m / fix_heading_std_deg | 0.03 / 4 | measurement covariance ``G`` |
    | innovation_gate | None | squared Mahalanobis distance above which a fix is rejected |
    | temperature_c | 20 | air temperature (the sensor assumes 20 deg C) |
    | n_range_bins | 9 | bins of the last-sweep summary |

    ## Version History

    * v0: first release. Later, with every default episode unchanged, renamed arguments (the
      old names still work, with a ``DeprecationWarning``): ``encoder_noise_std_m_per_sqrt_m``
      -> ``encoder_std_m_per_sqrt_m``, ``wheel_scale_error`` -> ``wheel_scale_error_bound``.

    ## Example

    >>> import gymnasium as gym, sonar_gym
    >>> env = gym.make("SonarGym/SweepLocalization-v0")
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape, env.action_space
    ((24,), MultiDiscrete([5 4]))
    >>> obs, reward, terminated, truncated, info = env.step(env.unwrapped.encode_action(3, "front"))
    >>> info["n_sweeps"], info["fix_status"], info["position_error_m"] < 0.1
    (3, 'ok', True)
    """

    required_info_keys = INFO_KEYS

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        super().__init__(render_mode)
        self.config = build_config(SweepLocalizationConfig, kwargs, "SonarGym/SweepLocalization-v0")
        config = self.config
        try:
            self._scenario: Scenario = load_scenario(config.scenario)
        except (OSError, ValueError) as error:
            raise ValueError(f"argument 'scenario': {error}") from error
        (x_min, y_min), (x_max, y_max) = self._scenario.bounds
        cells = ((x_max - x_min) / PAPER_CELL_SIZE_M) * ((y_max - y_min) / PAPER_CELL_SIZE_M)
        if cells > MAX_MAP_CELLS:
            raise ValueError(
                f"argument 'scenario': {self._scenario.name!r} spans "
                f"{x_max - x_min:g} m x {y_max - y_min:g} m, {cells:.3g} cells of "
                f"{PAPER_CELL_SIZE_M * 100:g} cm in the voting map; at most {MAX_MAP_CELLS:,} "
                "(e.g. 100 m x 100 m) are allowed, as the map and its free-distance table "
                "grow with the area"
            )
        self.grid = occupancy_grid_of(self._scenario)
        self._bounds = self._scenario.bounds  # (min, max) corners; the scenario never changes
        self._fix_covariance = fix_covariance(
            config.fix_position_std_m, math.radians(config.fix_heading_std_deg)
        )
        self._fix_covariance.setflags(write=False)  # G of every fix, shared
        self.sonar = SweptSonar.kim(
            wide=config.sweep_width_deg == 180,
            preset=self._scenario.sensor.preset_or(PAPER_SENSOR_PRESET),
            step_rad=math.radians(config.sweep_step_deg),
        )
        self._use_action_type(
            make_action_type(
                "multi_discrete", DiscreteChoices((config.max_sweeps + 1, len(SECTOR_NAMES)))
            )
        )
        self._sweep_bins = RangeBins("last_sweep_ranges", config.n_range_bins)
        self._use_observation_spec(
            ObservationSpec(
                [
                    ScaledPosition("estimate_xy"),
                    Heading("estimate_heading"),
                    Fraction("estimate_std", 3),
                    Fraction("distance_since_fix"),
                    Fraction("route_progress"),
                    self._sweep_bins,
                    Heading("last_sweep_sector"),
                    Flag("last_fix_ok"),
                    Heading("route_heading"),
                    Fraction("steps_remaining"),
                ]
            )
        )
        if self.observation_spec.run(_OBSERVATION_ORDER) != slice(0, self.observation_spec.size):
            raise AssertionError("_OBSERVATION_ORDER must list every feature in vector order")
        self._table1_route = Route.through(TABLE_1_TRUE_POSITIONS_M)
        # One world for every episode: ``World.reset_episode`` keeps its static geometry.
        self._world = World(self._scenario, temperature_c=config.temperature_c)
        if config.route == "table1":
            blocked = [
                (float(x), float(y))
                for x, y in TABLE_1_TRUE_POSITIONS_M
                if not self._world.is_free((x, y))
            ]
            if blocked:
                raise ValueError(
                    f"argument 'route': 'table1' needs the Table 1 positions free in scenario "
                    f"{self._scenario.name!r}; blocked: {blocked}; use route='random'"
                )
        self._episode: _Episode | None = None

    @property
    def scenario(self) -> Scenario:
        """The scenario (the agents may read the map; never the episode's hidden state)."""
        return self._scenario

    # --- actions -----------------------------------------------------------------------
    def encode_action(self, n_sweeps: int, sector: str | int = "front") -> np.ndarray:
        """The action for ``n_sweeps`` sweeps toward ``sector`` (a name or an index)."""
        check_number("n_sweeps", n_sweeps, low=0, high=self.config.max_sweeps, integer=True)
        if isinstance(sector, str):
            check_choice("sector", sector, SECTOR_NAMES)
            sector = SECTOR_NAMES.index(sector)
        check_number("sector", sector, low=0, high=len(SECTOR_NAMES) - 1, integer=True)
        return self.action_type.encode((n_sweeps, sector))

    # --- episode -----------------------------------------------------------------------
    def _reset_task(self, options: dict[str, Any] | None) -> dict[str, Any]:
        config = self.config
        rng = self.np_random
        world = self._world
        world.reset_episode(config.temperature_c)
        route = (
            self._table1_route
            if config.route == "table1"
            else draw_free_route(world, rng, config.route_length_m)
        )
        start = Pose(
            float(route.vertices[0, 0]), float(route.vertices[0, 1]), route.heading_at_start()
        )
        world.set_robot_pose(start)
        scale_left, scale_right = rng.uniform(
            -config.wheel_scale_error_bound, config.wheel_scale_error_bound, 2
        )
        noise = OdometryConfig(
            encoder_std_m_per_sqrt_m=config.encoder_std_m_per_sqrt_m,
            scale_error_left=float(scale_left),
            scale_error_right=float(scale_right),
            slip_probability_per_m=config.slip_probability_per_m,
            slip_fraction_max=SLIP_FRACTION_MAX,
        )
        position_std = config.initial_position_std_m
        heading_std = math.radians(config.initial_heading_std_deg)
        offsets = rng.normal(0.0, 1.0, 3) * np.array([position_std, position_std, heading_std])
        estimate = Pose(start.x + offsets[0], start.y + offsets[1], start.theta + offsets[2])
        covariance = np.diag([position_std**2, position_std**2, heading_std**2])
        if config.decision_points == "spacing":
            count = max(1, math.ceil(route.length_m / config.decision_spacing_m - 1e-9))
            stations = config.decision_spacing_m * np.arange(count, dtype=np.float64)
        else:
            stations = route.cumulative_m.copy()
        self._episode = _Episode(
            world=world,
            robot=DifferentialDriveRobot(noise, odometry_pose=estimate),
            route=route,
            decision_stations_m=stations,
            estimate=estimate,
            covariance=covariance,
        )
        self._episode.true_track.append((start.x, start.y))
        self._episode.estimate_track.append((estimate.x, estimate.y))
        return self._info(_RUNNING)

    def _apply_action(self, action: Any) -> StepOutcome:
        episode = self._require_episode()
        config = self.config
        n_sweeps, sector = self.action_type.decode(action)
        stations = episode.decision_stations_m
        next_station = (
            float(stations[episode.decisions + 1])
            if episode.decisions + 1 < len(stations)
            else episode.route.length_m
        )
        episode.decisions += 1
        step_sensing_s = 0.0
        fix_info: dict[str, Any] = {"fix_status": "none"}
        if n_sweeps > 0:
            step_sensing_s, fix_info = self._sense_and_fix(episode, n_sweeps, sector, next_station)
        self._drive_to(episode, next_station)
        episode.sensing_time_s += step_sensing_s
        done = episode.decisions >= len(stations)
        info = self._info("ok" if done else _RUNNING, episode.world.robot_pose)
        # the errors of the EKF estimate against the truth, as the info reports them
        error_loss = (
            info["position_error_m"] / POSITION_UNIT_M
            + info["heading_error_rad"] / HEADING_UNIT_RAD
        )
        terms = {
            "pose_error": -min(error_loss, config.max_error_loss),
            "sensing_cost": -(config.sensing_cost_per_s * step_sensing_s),
        }
        info.update(fix_info)
        info.update(
            n_sweeps=n_sweeps, sector=SECTOR_NAMES[sector], step_sensing_time_s=step_sensing_s
        )
        return StepOutcome(reward_terms=terms, terminated=done, info=info)

    def _sense_and_fix(
        self,
        episode: _Episode,
        n_sweeps: int,
        sector: int,
        next_station_m: float,
    ) -> tuple[float, dict[str, Any]]:
        """Take the sweeps between short moves, localize, correct the EKF."""
        config = self.config
        # the filter's arrays are replaced, never written in place: no copy needed
        first_estimate, first_covariance = episode.estimate, episode.covariance
        first_truth = episode.world.robot_pose
        sweeps: list[Sweep] = []
        scanned: list[tuple[Sweep, Pose]] = []
        duration_s = 0.0
        offset = episode.world.scenario.robot.sensor_offset
        grid = self.sonar.sweep_grid(SECTOR_CENTRES_RAD[sector])
        for index in range(n_sweeps):
            if index > 0 and episode.progress_m < next_station_m:
                self._drive_to(
                    episode, min(episode.progress_m + config.sweep_spacing_m, next_station_m)
                )
            # the first sweep is taken where the robot stood at the decision
            true_pose = first_truth if index == 0 else episode.world.robot_pose
            with self._timed("sensing"):
                angles, ranges, _, sweep_duration_s = self.sonar.sweep_readings(
                    episode.world, true_pose, self.np_random, grid
                )
            duration_s += sweep_duration_s
            odometry = _relative_pose(first_estimate, episode.estimate)
            # the grid's read-only angles and the sweep's fresh ranges: no copies needed
            sweeps.append(Sweep.handed_over(angles, ranges, offset, odometry))
            scanned.append((sweeps[-1], true_pose))
        episode.last_ranges = sweeps[-1].ranges / self.sonar.transducer.max_range_m
        episode.last_sector = sector
        episode.scanned = tuple(scanned)
        with self._timed("localization"):
            result = vote_around_estimate(
                self.grid,
                sweeps,
                first_estimate,
                first_covariance,
                heading_step_rad=math.radians(config.heading_step_deg),
                max_range_m=self.sonar.transducer.max_range_m,
                anchor=config.anchor,  # type: ignore[arg-type]
            )
        info: dict[str, Any] = {"fix_status": result.status}
        episode.last_fix_ok = False
        if result.ok and result.pose is not None and result.last_sweep_pose is not None:
            info.update(
                fix_position_error_m=position_error_m(result.pose, first_truth),
                fix_heading_error_rad=heading_error_rad(result.pose, first_truth),
                fix_true_pose=first_truth.as_array(),
                fix_estimated_pose=result.pose.as_array(),
                fix_measured_pose=result.last_sweep_pose.as_array(),
            )
            corrected = gated_ekf_update(
                episode.estimate,
                episode.covariance,
                result.last_sweep_pose,
                self._fix_covariance,
                config.innovation_gate,
            )
            if corrected is not None:
                episode.estimate, episode.covariance = corrected
                episode.distance_since_fix_m = 0.0
                episode.last_fix_ok = True
            else:
                info["fix_status"] = "gated"
        return duration_s, info

    def _drive_to(self, episode: _Episode, station_m: float) -> None:
        """Drive along the route to ``station_m``, steering from the EKF estimate."""
        if station_m <= episode.progress_m:
            return
        leg = follow_route(
            episode.robot,
            episode.world,
            episode.route,
            (episode.progress_m, station_m),
            episode.estimate,
            episode.covariance,
            self.config.ekf_variance_per_m,
            self.np_random,
        )
        episode.estimate, episode.covariance = leg.estimate, leg.covariance
        episode.distance_since_fix_m = sum((episode.distance_since_fix_m, *leg.rolled_m))
        episode.progress_m = station_m
        truth, estimate = episode.world.robot_pose, episode.estimate
        episode.true_track.append((truth.x, truth.y))
        episode.estimate_track.append((estimate.x, estimate.y))

    # --- observation and info ---------------------------------------------------------
    def _observe(self) -> np.ndarray:
        episode = self._require_episode()
        estimate = episode.estimate
        low, high = self._bounds
        variances = episode.covariance.diagonal().tolist()
        station_x, station_y = self._next_station_point(episode)
        ahead_x, ahead_y = station_x - estimate.x, station_y - estimate.y
        bearing = (
            wrap_angle(math.atan2(ahead_y, ahead_x) - estimate.theta)
            if ahead_x != 0.0 or ahead_y != 0.0
            else 0.0
        )
        decisions = len(episode.decision_stations_m)
        # every entry in the order of _OBSERVATION_ORDER, made a float32 vector in one go
        return self.observation_spec.vector_of(
            [
                *ScaledPosition.float_values((estimate.x, estimate.y), low, high),
                *Heading.values(estimate.theta),
                *[
                    clipped(math.sqrt(0.0 if variance < 0.0 else variance) / scale, 0.0, 1.0)
                    for variance, scale in zip(variances, _STD_SCALES, strict=True)
                ],
                min(episode.distance_since_fix_m / DISTANCE_SCALE_M, 1.0),
                min(episode.progress_m / max(episode.route.length_m, 1e-9), 1.0),
                *self._sweep_bins.values(episode.last_ranges).tolist(),
                *Heading.values(SECTOR_CENTRES_RAD[episode.last_sector]),
                float(episode.last_fix_ok),
                *Heading.values(bearing),
                (decisions - episode.decisions) / decisions,
            ]
        )

    def _next_station_point(self, episode: _Episode) -> tuple[float, float]:
        stations = episode.decision_stations_m
        following = episode.decisions + 1
        station = (
            float(stations[following]) if following < len(stations) else episode.route.length_m
        )
        return episode.route.xy_at(station)

    def _info(self, status: str, truth: Pose | None = None) -> dict[str, Any]:
        """The info dict; ``truth`` is the robot's true pose if the caller has just read it."""
        episode = self._require_episode()
        if truth is None:
            truth = episode.world.robot_pose
        return {
            "position_error_m": position_error_m(episode.estimate, truth),
            "heading_error_rad": heading_error_rad(episode.estimate, truth),
            "sensing_time_s": episode.sensing_time_s,
            "status": status,
            "true_pose": truth.as_array(),
            "estimated_pose": episode.estimate.as_array(),
            "covariance_diagonal": episode.covariance.diagonal().copy(),
            "distance_since_fix_m": episode.distance_since_fix_m,
        }

    # --- rendering ----------------------------------------------------------------------
    def _render_frame(self) -> np.ndarray:
        from sonar_gym.render import render_topdown, world_to_pixel

        episode = self._require_episode()
        truth = episode.world.robot_pose
        stations = episode.decision_stations_m
        image = render_topdown(
            self._scenario,
            true_pose=truth,
            estimated_pose=episode.estimate,
            scan_points=episode.scan_points(),
            title=f"SweepLocalization  decision {episode.decisions}/{len(stations)}",
            extra={
                "E_xy [m]": position_error_m(episode.estimate, truth),
                "sensing [s]": episode.sensing_time_s,
            },
        ).copy()

        def to_pixel(xy: np.ndarray) -> tuple[int, int]:
            return world_to_pixel(self._scenario, xy)

        draw_polyline(image, episode.route.vertices, to_pixel, (120, 120, 255))
        draw_polyline(image, np.array(episode.true_track), to_pixel, (40, 160, 40))
        draw_polyline(image, np.array(episode.estimate_track), to_pixel, (216, 27, 156))
        return image

    def _require_episode(self) -> _Episode:
        if self._episode is None:
            raise RuntimeError("SweepLocalizationEnv: call reset() first")
        return self._episode


def _relative_pose(reference: Pose, pose: Pose) -> Pose:
    """``pose`` expressed in the frame of ``reference`` (both in {W})."""
    dx, dy = pose.x - reference.x, pose.y - reference.y
    c, s = math.cos(reference.theta), math.sin(reference.theta)
    return Pose.unchecked(c * dx + s * dy, -s * dx + c * dy, pose.theta - reference.theta)


__all__ = ["SECTOR_CENTRES_RAD", "SECTOR_NAMES", "SweepLocalizationConfig", "SweepLocalizationEnv"]
