"""``SonarGym/Trilateration-v0``: how many repeated ultrasonic fixes to take along a route.

The task of Wu & Tsai (J. Intelligent and Robotic Systems, 2001): three ceiling transmitters
and two receivers on the robot give position, height and heading in closed form (eqs (2)-(9),
Theorem 2); ``n`` repeated fixes are averaged (eqs (12)-(16), with the circular mean of
headings). The robot crosses the room by dead reckoning; at each decision point the agent
chooses ``n`` (0 keeps dead reckoning), trading pose error against measurement time.

The models that describe a fix's uncertainty to the agent and weight it in the optional
covariance-weighted correction (:func:`quantised_range_error`,
:func:`predicted_fix_covariance`, :class:`TransmitterFrame`) live in
:mod:`sonar_gym.localization.wu_tsai_models`; they are re-exported here. The episode state,
the observation's features and the ``info`` dict are in
:mod:`sonar_gym.envs.trilateration_observation`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from sonar_gym.envs.action_types import DiscreteChoices, make_action_type
from sonar_gym.envs.base import INFO_KEYS, SonarEnv, StepOutcome
from sonar_gym.envs.config import (
    build_config,
    check_choice,
    choice_field,
    number_field,
    numbers_field,
    scenario_field,
)
from sonar_gym.envs.trilateration_observation import (
    OBSERVATION,
    TIME_SINCE_FIX_SCALE_S,
    FeatureScales,
    TrilaterationEpisode,
    episode_info,
    trilateration_observation,
)
from sonar_gym.localization.ekf import ekf_update
from sonar_gym.localization.wu_tsai_models import (
    RangeErrorModel,
    TransmitterFrame,
    predicted_fix_covariance,
    quantised_range_error,
    rotate_covariance,
)
from sonar_gym.localization.wu_tsai import (
    PAPER_COUNTER_RATE_HZ,
    PAPER_REPEATED_FIXES,
    PAPER_TEMPERATURE_C,
    localize_repeated,
)
from sonar_gym.metrics import heading_error_rad, position_error_m
from sonar_gym.odometry import OdometryConfig
from sonar_gym.polyline import densify, draw_equal_legs, drive_leg_dead_reckoned
from sonar_gym.pose import FloatArray, Pose
from sonar_gym.robot import DifferentialDriveRobot
from sonar_gym.scenario import load_scenario
from sonar_gym.sonar.acoustics import speed_of_sound_mps
from sonar_gym.sonar.ranging import BeaconRanger
from sonar_gym.validation import MIN_DURATION_S, MIN_SCALE, MIN_SPEED_MPS
from sonar_gym.world import World

ENV_ID = "SonarGym/Trilateration-v0"
DEFAULT_FIX_COUNTS: tuple[int, ...] = (0, 1, 2, 3, 5, 10, 20)
STATUS_RUNNING = "running"
STATUS_OK = "ok"
NO_FIX = "no_fix"


# --------------------------------------------------------------------------------------------
# Configuration
# --------------------------------------------------------------------------------------------


MIN_ROUTE_LENGTH_M = 0.01
"""Shortest route, metres: one centimetre, so every leg stays longer than a denormal."""


@dataclass(frozen=True)
class TrilaterationConfig:
    """The ``gym.make`` arguments of ``SonarGym/Trilateration-v0`` (see the env docstring)."""

    RENAMED_ARGUMENTS: ClassVar[dict[str, str]] = {
        "measurement_cost_per_s": "sensing_cost_per_s",
        "max_error_score": "max_error_loss",
    }

    scenario: str | Path = "wu_tsai_room"
    fix_counts: tuple[int, ...] = DEFAULT_FIX_COUNTS
    route_length_m: float = 8.0
    n_decision_points: int = 16
    correction: str = "replace"
    sensing_cost_per_s: float = 0.2
    position_scale_m: float = 0.05
    heading_scale_deg: float = 3.0
    max_error_loss: float = 50.0
    temperature_c: float = PAPER_TEMPERATURE_C
    counter_rate_hz: float = PAPER_COUNTER_RATE_HZ
    range_noise_std_m: float = 0.002
    firing_interval_s: float = 0.05
    encoder_std_m_per_sqrt_m: float = 0.005
    wheel_scale_error_std: float = 0.002
    slip_probability_per_m: float = 0.01
    slip_fraction_max: float = 0.3
    initial_position_std_m: float = 0.0
    initial_heading_std_deg: float = 0.0
    wall_clearance_m: float = 0.3
    robot_speed_mps: float = 0.3
    turn_rate_rad_s: float = 1.0

    def __post_init__(self) -> None:
        scenario_field(self)
        try:
            numbers_field(
                self, "fix_counts", low=0, high=200, integer=True, min_length=1, distinct=True
            )
        except ValueError as error:
            raise ValueError(
                "argument 'fix_counts' must be a non-empty sequence of distinct integers in "
                f"[0, 200] (numbers of repeated fixes); {error}"
            ) from error
        number_field(self, "route_length_m", low=MIN_ROUTE_LENGTH_M, high=100.0)
        number_field(self, "n_decision_points", low=1, high=200, integer=True)
        choice_field(self, "correction", ("replace", "fuse"))
        number_field(self, "sensing_cost_per_s", low=0.0, high=100.0)
        number_field(self, "position_scale_m", low=MIN_SCALE, high=10.0)
        number_field(self, "heading_scale_deg", low=MIN_SCALE, high=180.0)
        number_field(self, "max_error_loss", low=MIN_SCALE, high=1e6)
        number_field(self, "temperature_c", low=-20.0, high=50.0)
        number_field(self, "counter_rate_hz", low=1e3, high=1e9)
        number_field(self, "range_noise_std_m", low=0.0, high=0.5)
        number_field(self, "firing_interval_s", low=MIN_DURATION_S, high=10.0)
        number_field(self, "encoder_std_m_per_sqrt_m", low=0.0, high=0.5)
        number_field(self, "wheel_scale_error_std", low=0.0, high=0.1)
        number_field(self, "slip_probability_per_m", low=0.0, high=1.0)
        number_field(self, "slip_fraction_max", low=0.0, high=1.0)
        number_field(self, "initial_position_std_m", low=0.0, high=1.0)
        number_field(self, "initial_heading_std_deg", low=0.0, high=90.0)
        number_field(self, "wall_clearance_m", low=0.0, high=5.0)
        number_field(self, "robot_speed_mps", low=MIN_SPEED_MPS, high=10.0)
        number_field(self, "turn_rate_rad_s", low=MIN_SPEED_MPS, high=100.0)

    @property
    def heading_scale_rad(self) -> float:
        """``heading_scale_deg`` in radians."""
        return math.radians(self.heading_scale_deg)

    @property
    def leg_length_m(self) -> float:
        """Straight-line length of each leg of the route, metres."""
        return self.route_length_m / self.n_decision_points


# --------------------------------------------------------------------------------------------
# The environment
# --------------------------------------------------------------------------------------------


class TrilaterationEnv(SonarEnv):
    """
    ## Description

    A differential-drive robot crosses a room under three ceiling transmitters (Wu & Tsai,
    *Localization of an autonomous mobile robot based on ultrasonic sensory information*,
    J. Intelligent and Robotic Systems, 2001). Two receivers on the robot, at ``(0, +-0.2) m``
    in the robot frame, time one-way pulses from each transmitter: the ranger of
    :mod:`sonar_gym.sonar.ranging` (eq. (11), a 50 kHz counter that truncates the time of
    flight to 20 us, i.e. 6.9 mm of range, and 2 mm of timing jitter, by default). A fix is
    the paper's closed form (eqs (2)-(9), Theorem 2): each receiver's ``(x, y, z)``, and the
    heading from the two receivers. ``n`` repeated fixes are averaged by eqs (12)-(16), the
    heading by its circular mean (eq. (16) read as the mean direction).

    Each episode draws a random route across the room: ``n_decision_points`` legs of
    ``route_length_m / n_decision_points`` metres in random directions, kept
    ``wall_clearance_m`` from the walls. The robot drives each leg by dead reckoning (turn,
    then straight, planned from its estimated pose) and its odometry drifts: encoder noise,
    wheel-radius errors drawn per episode, occasional wheel slip
    (:class:`~sonar_gym.odometry.OdometryConfig`). At the end of each leg, a decision point, the
    agent chooses how many fixes to take. Why the choice matters: dead reckoning drifts
    between decision points; one fix is noisy (counter quantisation, jitter) and noisier away
    from below the transmitters (eqs (7)-(8) multiply range errors by about ``d / a``); each
    fix costs measurement time (three firings, ``firing_interval_s`` apart); averaging helps,
    but only down to the quantisation error that repeats at a fixed pose. With the defaults
    (a decision point every 0.5 m) the paper's n = 10 is the best *fixed* n, and choosing n
    from the state does better (see ``sonar_gym.agents.trilateration``).

    How the averaged fix corrects the pose (``correction``):

    * ``"replace"`` (default, the paper's use: the ultrasonic estimate *is* the robot's pose):
      the averaged fix replaces position and heading, and the robot continues from it.
    * ``"fuse"`` (not in the paper): a Kalman update (the EKF of Kim et al. sec. 3.2 with
      ``H = I``) of the dead-reckoning pose and its covariance with the averaged fix and its
      predicted covariance (below). Heading still comes from the two receivers.

    The covariances: dead reckoning propagates ``P`` through each motion with the odometry
    model of Kim et al. sec. 3.1 (:func:`sonar_gym.odometry.predict_step`), encoder
    variance ``encoder_std^2 |d|`` plus ``wheel_scale_error_std^2 d^2`` per wheel and command
    (slip is not modelled: it is what a fix is for). A fix's covariance is
    :func:`predicted_fix_covariance` at the estimated pose with the range variance of
    :func:`quantised_range_error`, shrunk for ``n`` fixes by
    :meth:`RangeErrorModel.averaging_factor`. These drive the observation's uncertainty
    features and the ``"fuse"`` update; the reward uses the true errors.

    ``render_mode="rgb_array"`` draws the room and transmitters, the planned route (dots),
    the true positions at the decision points and the averaged fixes (dots), the true pose
    (green) and the estimate (magenta).

    ## Action Space

    ``Discrete(len(fix_counts))``: action ``k`` takes ``fix_counts[k]`` repeated fixes; the
    default ``fix_counts = (0, 1, 2, 3, 5, 10, 20)``. ``0`` keeps the dead-reckoning pose. The
    paper takes ``n = 10``. :meth:`action_for` and :meth:`fix_count` convert.

    ## Observation Space

    ``Box(-1, 1, (15,), float32)``; slices by name in ``observation_layout``. A predicted
    spread ``s`` is mapped to ``s / (s + scale)`` (0 for none, 0.5 at the scale, below 1), with
    ``P = position_scale_m`` and ``H = heading_scale_deg``; "half size" is half the room.

    | index | name | meaning | mapping | bounds |
    |---|---|---|---|---|
    | 0-1 | estimated_xy | estimated position | (p - room centre) / half size | [-1, 1] |
    | 2-3 | estimated_heading | cos, sin of the estimated heading | - | [-1, 1] |
    | 4 | time_since_fix | driving time since the last fix (or start) | t / (t + 10 s) | [0, 1) |
    | 5 | distance_since_fix | distance driven since then | d / route_length_m, clipped | [0, 1] |
    | 6 | dead_reckoning_position_std | estimate's predicted RMS position error | s/(s+P) | [0, 1) |
    | 7 | dead_reckoning_heading_std | estimate's predicted heading std | s/(s+H) | [0, 1) |
    | 8-9 | transmitter_offset | estimate - transmitters' centroid | / half size, clip | [-1, 1] |
    | 10 | transmitter_distance | its length | / half diagonal, clipped | [0, 1] |
    | 11 | fix_position_std | predicted RMS position error of ONE fix here | s/(s+P) | [0, 1) |
    | 12 | fix_heading_std | predicted heading std of ONE fix here | s/(s+H) | [0, 1) |
    | 13 | progress | decision points already passed / n_decision_points | - | [0, 1) |
    | 14 | steps_remaining | decisions left, this one included / n_decision_points | - | (0, 1] |

    ## Rewards

    At each decision point, after the chosen fixes have corrected the estimate:

    ``r = -min(E_xy / position_scale_m + E_theta / heading_scale, max_error_loss)
    - sensing_cost_per_s * n * 3 * firing_interval_s``

    with ``E_xy`` (metres) and ``E_theta`` (radians) the errors of the estimate against the
    true pose (Beom & Cho eq. (16), :mod:`sonar_gym.metrics`). Defaults: 0.05 m and 3 deg
    (the paper's position estimates are within a few cm, its headings within 1-3 deg, Tables
    I-II), so 5 cm of position error, 3 deg of heading error and 5 s of measuring (33 fixes)
    each cost 1; ``sensing_cost_per_s = 0.2``. The cap on the error part
    (``max_error_loss``, 50) keeps a lost robot's reward bounded; there is no separate
    failure charge (a failed fix leaves the dead-reckoned estimate, whose error is scored).
    ``info["rewards"]`` holds the two terms, ``pose_error`` and ``sensing_cost``.

    ## Starting State

    The robot stands at the start of a random route, facing its first leg. Its estimate is
    the true pose plus Gaussian errors of ``initial_position_std_m`` per axis and
    ``initial_heading_std_deg`` (default 0: a known start). It then drives the first leg; the
    first observation is taken at the first decision point.

    ## Episode End

    Terminates after the decision at the last of the ``n_decision_points`` decision points
    (status ``"ok"``). There is no truncation; nothing ends an episode early.

    ## Info

    Every ``reset`` and ``step`` returns ``position_error_m`` and ``heading_error_rad`` (of the
    current estimate), ``sensing_time_s`` (cumulative measurement time, seconds), ``status``
    (``"running"``, ``"ok"`` after the last decision), and ``n_fixes`` (requested at this
    step), ``n_fixes_ok`` (fixes that gave a pose), ``fix_status`` (``"ok"``, ``"no_fix"`` for
    n = 0, or the localization's failure status, e.g. ``"inconsistent_distances"``),
    ``measurement_time_s`` (this step), ``dead_reckoning_position_error_m`` and
    ``dead_reckoning_heading_error_rad`` (before this step's correction),
    ``fix_position_error_m``/``fix_heading_error_rad`` (the averaged fix's; only when one was
    made), ``fix_z_m`` (its height in the paper's frame), ``predicted_position_std_m``,
    ``predicted_heading_std_rad``, ``decision_point``, ``elapsed_time_s`` (driving and
    measuring), ``collided``, ``true_pose`` and ``estimated_pose`` (``[x, y, theta]``, {W}).

    ## Arguments

    | argument | default | meaning |
    |---|---|---|
    | scenario | ``"wu_tsai_room"`` | name or file; its first three emitters: the transmitters |
    | fix_counts | (0, 1, 2, 3, 5, 10, 20) | the n offered by the actions |
    | route_length_m | 8.0 | total straight-line length of the route, m |
    | n_decision_points | 16 | decision points (legs) per episode |
    | correction | ``"replace"`` | or ``"fuse"`` (covariance weighting, not in the paper) |
    | sensing_cost_per_s | 0.2 | reward per second of measuring |
    | position_scale_m | 0.05 | position error worth 1 |
    | heading_scale_deg | 3.0 | heading error worth 1 |
    | max_error_loss | 50.0 | cap of the error part of one reward |
    | temperature_c | 27.0 | air temperature (the paper's), known to the ranger |
    | counter_rate_hz | 50e3 | TOF counter rate (the paper's 8051) |
    | range_noise_std_m | 0.002 | timing jitter as a distance, m |
    | firing_interval_s | 0.05 | time between two transmitters' firings, s (3 per fix) |
    | encoder_std_m_per_sqrt_m | 0.005 | encoder noise, m after 1 m |
    | wheel_scale_error_std | 0.002 | std of each wheel's radius error, drawn per episode |
    | slip_probability_per_m | 0.01 | chance per metre that a wheel slips |
    | slip_fraction_max | 0.3 | largest fraction of a command a slip loses |
    | initial_position_std_m | 0.0 | start estimate error per axis, m |
    | initial_heading_std_deg | 0.0 | start heading error, deg |
    | wall_clearance_m | 0.3 | route clearance from walls beyond the robot radius, m |
    | robot_speed_mps | 0.3 | driving speed (time features only), m/s |
    | turn_rate_rad_s | 1.0 | turning rate (time features only), rad/s |

    ## Version History

    * v0: first release. Later, without changing any default episode:
      ``measurement_cost_per_s`` renamed ``sensing_cost_per_s`` and ``max_error_score``
      renamed ``max_error_loss`` (the names the other tasks use); the old names still work,
      with a ``DeprecationWarning``.

    ## Example

    >>> import gymnasium as gym, sonar_gym
    >>> env = gym.make("SonarGym/Trilateration-v0")
    >>> obs, info = env.reset(seed=4)
    >>> obs.shape, obs.dtype, info["status"]
    ((15,), dtype('float32'), 'running')
    >>> ten_fixes = env.unwrapped.action_for(10)
    >>> obs, reward, terminated, truncated, info = env.step(ten_fixes)
    >>> info["n_fixes"], info["fix_status"], round(info["measurement_time_s"], 2)
    (10, 'ok', 1.5)
    >>> info["position_error_m"] < 0.06, terminated
    (True, False)
    """

    required_info_keys = INFO_KEYS

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        super().__init__(render_mode)
        self.config = build_config(TrilaterationConfig, kwargs, ENV_ID)
        config = self.config
        self.scenario = load_scenario(config.scenario)
        self.transmitter_frame = TransmitterFrame.from_scenario(self.scenario)
        self._receiver_z_m = self.transmitter_frame.height_in_t(self.scenario.robot.sensor_height)
        self.ranger = BeaconRanger.wu_tsai(
            timer_period_s=1.0 / config.counter_rate_hz,
            range_noise_std_m=config.range_noise_std_m,
            firing_interval_s=config.firing_interval_s,
        ).with_assumed_speed(speed_of_sound_mps(config.temperature_c))
        self.range_error = quantised_range_error(
            config.range_noise_std_m, self.ranger.range_quantum_m
        )
        self.fix_duration_s = 3 * config.firing_interval_s
        (x0, y0), (x1, y1) = self.scenario.bounds
        self._centre = np.array([(x0 + x1) / 2.0, (y0 + y1) / 2.0])
        self._half_size = np.array([(x1 - x0) / 2.0, (y1 - y0) / 2.0])
        # One world for every episode: ``World.reset_episode`` keeps its static geometry.
        self._world = World(self.scenario, temperature_c=config.temperature_c)
        self._check_route_fits()
        self._use_action_type(
            make_action_type("discrete", DiscreteChoices((len(config.fix_counts),)))
        )
        self._use_observation_spec(OBSERVATION)
        self._feature_scales = FeatureScales(
            centre_xy=self._centre,
            half_size_xy=self._half_size,
            transmitter_centroid_xy=self.transmitter_frame.centroid_xy(),
            route_length_m=config.route_length_m,
            position_scale_m=config.position_scale_m,
            heading_scale_rad=config.heading_scale_rad,
            n_decision_points=config.n_decision_points,
        )
        self._episode: TrilaterationEpisode | None = None

    # --- actions -----------------------------------------------------------------------
    def fix_count(self, action: Any) -> int:
        """The number of repeated fixes an action takes."""
        (index,) = self.action_type.decode(action)
        return self.config.fix_counts[index]

    def action_for(self, n_fixes: int) -> int:
        """The action that takes ``n_fixes`` fixes (one of ``fix_counts``)."""
        check_choice("n_fixes", n_fixes, self.config.fix_counts)
        return self.action_type.encode((self.config.fix_counts.index(n_fixes),))

    @property
    def paper_action(self) -> int:
        """The action nearest to the paper's n = 10 (ties: the larger n)."""
        counts = self.config.fix_counts
        return min(
            range(len(counts)), key=lambda k: (abs(counts[k] - PAPER_REPEATED_FIXES), -counts[k])
        )

    # --- uncertainty models --------------------------------------------------------------
    def fix_covariance(self, pose: Pose, n_fixes: int = 1) -> FloatArray:
        """Predicted 3x3 covariance ({W}) of the average of ``n_fixes`` fixes at ``pose`` ({W})."""
        frame = self.transmitter_frame
        covariance = predicted_fix_covariance(
            frame.to_transmitter(pose),
            self._receiver_z_m,
            frame.spacing_m,
            self.range_error.total_variance_m2,
            self.ranger.receivers_xy,
        )
        factor = self.range_error.averaging_factor(max(int(n_fixes), 1))
        return rotate_covariance(covariance, frame.rotation_rad) * factor

    # --- episode -----------------------------------------------------------------------
    def _check_route_fits(self) -> None:
        margin = self._world.robot_radius + self.config.wall_clearance_m
        if self.scenario.room is not None:
            (x0, y0), (x1, y1) = self.scenario.room.min, self.scenario.room.max
        else:
            (x0, y0), (x1, y1) = self.scenario.bounds
        if min(x1 - x0, y1 - y0) - 2.0 * margin < self.config.leg_length_m:
            raise ValueError(
                f"argument 'route_length_m': legs of {self.config.leg_length_m:g} m "
                f"(route_length_m / n_decision_points) do not fit in {self.scenario.name!r} with "
                f"wall_clearance_m = {self.config.wall_clearance_m:g} m"
            )

    def _reset_task(self, options: dict[str, Any] | None) -> dict[str, Any]:
        config = self.config
        rng = self.np_random
        world = self._world
        world.reset_episode(config.temperature_c)
        scale_left, scale_right = np.clip(
            rng.normal(0.0, config.wheel_scale_error_std, 2), -0.05, 0.05
        )
        noise = OdometryConfig(
            encoder_std_m_per_sqrt_m=config.encoder_std_m_per_sqrt_m,
            scale_error_left=float(scale_left),
            scale_error_right=float(scale_right),
            slip_probability_per_m=config.slip_probability_per_m,
            slip_fraction_max=config.slip_fraction_max,
        )
        waypoints = draw_equal_legs(
            world,
            rng,
            config.n_decision_points,
            config.leg_length_m,
            config.wall_clearance_m,
            fallback_towards=self._centre,
        )
        start, first = waypoints[0], waypoints[1]
        true_start = Pose(
            float(start[0]), float(start[1]), math.atan2(first[1] - start[1], first[0] - start[0])
        )
        world.set_robot_pose(true_start)
        position_error = rng.normal(0.0, config.initial_position_std_m, 2)
        heading_error = rng.normal(0.0, math.radians(config.initial_heading_std_deg))
        estimate = Pose(
            true_start.x + float(position_error[0]),
            true_start.y + float(position_error[1]),
            true_start.theta + float(heading_error),
        )
        covariance = np.diag(
            [
                config.initial_position_std_m**2,
                config.initial_position_std_m**2,
                math.radians(config.initial_heading_std_deg) ** 2,
            ]
        )
        robot = DifferentialDriveRobot(noise, odometry_pose=estimate)
        episode = TrilaterationEpisode(world, robot, waypoints, true_start, estimate, covariance)
        episode.true_trail.append((true_start.x, true_start.y))
        self._episode = episode
        self._drive_next_leg(episode)
        return episode_info(
            episode, STATUS_RUNNING, n_fixes=0, fix_status=NO_FIX, measurement_time_s=0.0
        )

    def _drive_next_leg(self, episode: TrilaterationEpisode) -> None:
        """Drive to the next waypoint; dead reckoning and its covariance follow."""
        config = self.config
        leg = drive_leg_dead_reckoned(
            episode.robot,
            episode.world,
            episode.waypoints[episode.decisions + 1],
            episode.covariance,
            config.encoder_std_m_per_sqrt_m**2,
            config.wheel_scale_error_std**2,
            config.robot_speed_mps,
            config.turn_rate_rad_s,
            self.np_random,
        )
        episode.true_pose, episode.estimate = leg.motion.true_pose, leg.motion.odometry_pose
        episode.covariance = leg.covariance
        episode.collided = episode.collided or leg.motion.collided
        episode.elapsed_time_s += leg.drive_time_s
        episode.time_since_fix_s += leg.drive_time_s
        episode.distance_since_fix_m += leg.travelled_m
        episode.true_trail.append((episode.true_pose.x, episode.true_pose.y))

    def _apply_action(self, action: Any) -> StepOutcome:
        episode = self._require_episode()
        config = self.config
        n_fixes = self.fix_count(action)
        dead_reckoning = episode.estimate
        failure = NO_FIX
        n_ok = 0
        fix_pose: Pose | None = None
        measurement_time_s = 0.0
        if n_fixes > 0:
            with self._timed("sensing"):
                rounds = self.ranger.measure_repeated(
                    episode.world,
                    episode.true_pose,
                    n_fixes,
                    self.np_random,
                    self.transmitter_frame.names,
                )
            measurement_time_s = float(np.sum(rounds.round_durations_s))
            with self._timed("localization"):
                repeated = localize_repeated(
                    rounds.distances,
                    self.transmitter_frame.spacing_m,
                    self.ranger.receivers_xy,
                    z_sign=-1,
                )
                ok = repeated.ok
                n_ok = int(np.count_nonzero(ok))
                if n_ok < n_fixes:
                    failure = str(repeated.statuses[~ok][-1])
                averaged = repeated.average()  # eqs (12)-(16), circular mean of headings
                if averaged is not None:
                    fix_pose = self.transmitter_frame.to_world(averaged.pose)
                    episode.last_fix = averaged
                    self._correct(episode, fix_pose, n_ok)
        episode.sensing_time_s += measurement_time_s
        episode.elapsed_time_s += measurement_time_s
        episode.decisions += 1

        position_error = position_error_m(episode.estimate, episode.true_pose)
        heading_error = heading_error_rad(episode.estimate, episode.true_pose)
        error_score = (
            position_error / config.position_scale_m + heading_error / config.heading_scale_rad
        )
        terms = {
            "pose_error": -min(error_score, config.max_error_loss),
            "sensing_cost": -(config.sensing_cost_per_s * measurement_time_s),
        }
        done = episode.decisions >= config.n_decision_points
        info = episode_info(
            episode,
            STATUS_OK if done else STATUS_RUNNING,
            n_fixes=n_fixes,
            fix_status=STATUS_OK if n_ok else failure,
            measurement_time_s=measurement_time_s,
            n_fixes_ok=n_ok,
            dead_reckoning=dead_reckoning,
            fix_pose=fix_pose,
        )
        if not done:
            self._drive_next_leg(episode)
        return StepOutcome(reward_terms=terms, terminated=done, info=info)

    def _correct(self, episode: TrilaterationEpisode, fix_pose: Pose, n_ok: int) -> None:
        """Correct the estimate with an averaged fix of ``n_ok`` fixes (see ``correction``)."""
        fix_covariance = self.fix_covariance(fix_pose, n_ok)
        if self.config.correction == "replace":
            episode.estimate, episode.covariance = fix_pose, fix_covariance
        else:
            episode.estimate, episode.covariance = ekf_update(
                episode.estimate, episode.covariance, fix_pose, fix_covariance, joseph_form=True
            )
        episode.robot.reset_odometry(episode.estimate)
        episode.time_since_fix_s = 0.0
        episode.distance_since_fix_m = 0.0
        episode.fix_trail.append((fix_pose.x, fix_pose.y))

    # --- observation and info ---------------------------------------------------------
    def _observe(self) -> np.ndarray:
        episode = self._require_episode()
        return trilateration_observation(
            self._feature_scales,
            episode.estimate,
            episode.covariance,
            self.fix_covariance(episode.estimate, 1),
            episode.time_since_fix_s,
            episode.distance_since_fix_m,
            episode.decisions,
        )

    # --- rendering ----------------------------------------------------------------------
    def _render_frame(self) -> np.ndarray:
        from sonar_gym.render import render_topdown

        episode = self._require_episode()
        points = [*densify(episode.waypoints, 0.05), *episode.true_trail, *episode.fix_trail]
        return render_topdown(
            self.scenario,
            true_pose=episode.true_pose,
            estimated_pose=episode.estimate,
            scan_points=np.array(points),
            title=f"Trilateration  decision {episode.decisions}/{self.config.n_decision_points}",
            extra={
                "E_xy [m]": position_error_m(episode.estimate, episode.true_pose),
                "E_theta [deg]": math.degrees(
                    heading_error_rad(episode.estimate, episode.true_pose)
                ),
                "measuring [s]": episode.sensing_time_s,
            },
        )

    def _require_episode(self) -> TrilaterationEpisode:
        if self._episode is None:
            raise RuntimeError("TrilaterationEnv: call reset() first")
        return self._episode


__all__ = [
    "DEFAULT_FIX_COUNTS",
    "TIME_SINCE_FIX_SCALE_S",
    "RangeErrorModel",
    "TransmitterFrame",
    "TrilaterationConfig",
    "TrilaterationEnv",
    "predicted_fix_covariance",
    "quantised_range_error",
]
