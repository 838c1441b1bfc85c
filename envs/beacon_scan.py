"""``SonarGym/BeaconScan-v0``: localize with one rotating sonar and two cylindrical beacons.

The task of Beom & Cho (Robotica 1995): the agent decides which sectors to pan and at what
angular increment, whether to calibrate the speed of sound against the reflector, and when to
stop and localize with the paper's method (RCDs, eqs (3)-(7); two-circle pose, eqs (8)-(15)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from sonar_gym.beacon_visibility import (
    BEACON_ROLES,
    START_POSE_TRIES,
    beacons_visible,
    sample_start_pose,
)
from sonar_gym.envs.action_types import DiscreteChoices, make_action_type
from sonar_gym.envs.base import INFO_KEYS, SonarEnv, StepOutcome
from sonar_gym.envs.features import (
    Feature,
    Flag,
    Fraction,
    Heading,
    ObservationSpec,
    RangeBins,
    ScaledPosition,
    ScannedBins,
)
from sonar_gym.envs.config import (
    bool_field,
    build_config,
    check_choice,
    check_number,
    choice_field,
    number_field,
    numbers_field,
    scenario_field,
)
from sonar_gym.localization.beom_cho import (
    ASSIGNMENTS,
    EXTRACTIONS,
    METHODS,
    BeaconLocalization,
    BeomChoParameters,
    localize_scans,
)
from sonar_gym.metrics import heading_error_rad, position_error_m
from sonar_gym.pose import Pose, wrap_angle
from sonar_gym.random_room import random_scenario
from sonar_gym.scenario import Scenario, load_scenario
from sonar_gym.sonar.accumulate import ScanMemory
from sonar_gym.sonar.acoustics import speed_of_sound_mps
from sonar_gym.sonar.rotating import RotatingSonar
from sonar_gym.sonar.scan import Scan
from sonar_gym.validation import MIN_DURATION_S, MIN_LENGTH_M
from sonar_gym.world import World

__all__ = ["BeaconScanConfig", "BeaconScanEnv", "PanCommand", "beacons_visible"]

PAN, CALIBRATE, LOCALIZE = 0, 1, 2
ACTION_KINDS = ("pan", "calibrate", "localize")
ASSUMED_TEMPERATURE_C = 20.0
POSITION_UNIT_M = 0.03  # Beom & Cho's experimental position bound, section V.C
HEADING_UNIT_RAD = math.radians(2.0)  # and their heading bound
PAPER_SENSOR_PRESET = "polaroid-6500"
"""Beom & Cho's ranger, used unless the scenario's ``[sensor]`` chooses another preset."""


@dataclass(frozen=True)
class BeaconScanConfig:
    """The ``gym.make`` arguments of ``SonarGym/BeaconScan-v0`` (see the env docstring)."""

    RENAMED_ARGUMENTS: ClassVar[dict[str, str]] = {"n_bins": "n_range_bins"}

    scenario: str = "beom_cho_lab"
    temperature_c: float | None = None
    temperature_range_c: tuple[float, float] = (0.0, 40.0)
    allow_calibration: bool = True
    sensing_cost_per_s: float = 0.05
    failure_penalty: float = 20.0
    prior_position_std_m: float = 0.1
    prior_heading_std_deg: float = 5.0
    increments_deg: tuple[int, ...] = (1, 2, 5)
    sector_widths_deg: tuple[int, ...] = (30, 60, 90, 180, 360)
    n_sector_centres: int = 36
    n_range_bins: int = 72
    max_steps: int = 12
    start_pose: str = "beacons_visible"
    localization_method: str = "paper"
    pair_assignment: str = "extent"
    rcd_extraction: str = "paper"
    prior_gate_m: float | None = None
    action_type: str = "multi_discrete"
    time_budget_s: float = 60.0

    def __post_init__(self) -> None:
        scenario_field(self, extra=", or 'random'")
        number_field(self, "temperature_c", low=-20.0, high=50.0, optional=True)
        low, _ = numbers_field(self, "temperature_range_c", length=2, low=-20.0, high=50.0)
        check_number("temperature_range_c[1]", self.temperature_range_c[1], low=low, high=50.0)
        bool_field(self, "allow_calibration")
        number_field(self, "sensing_cost_per_s", low=0.0, high=100.0)
        number_field(self, "failure_penalty", low=0.0, high=1e4)
        number_field(self, "prior_position_std_m", low=0.0, high=2.0)
        number_field(self, "prior_heading_std_deg", low=0.0, high=90.0)
        _degree_set_field(self, "increments_deg", allowed=(1, 2, 3, 5, 6, 10))
        _degree_set_field(self, "sector_widths_deg", allowed=None)
        for width in self.sector_widths_deg:
            if width > 360 or any(width % inc for inc in self.increments_deg):
                raise ValueError(
                    "argument 'sector_widths_deg' must hold widths <= 360 deg that every "
                    f"increment in {self.increments_deg} divides; got {self.sector_widths_deg}"
                )
            if width % 2:  # a pan spans centre +- width / 2: its ends must be whole degrees
                raise ValueError(
                    "argument 'sector_widths_deg' must hold even widths (a pan spans its centre "
                    "+- half the width, on the scan memory's 1 deg grid); got "
                    f"{self.sector_widths_deg}"
                )
        number_field(self, "n_sector_centres", low=1, high=360, integer=True)
        if 360 % self.n_sector_centres or any(
            (360 // self.n_sector_centres) % inc for inc in self.increments_deg
        ):
            raise ValueError(
                "argument 'n_sector_centres' must divide 360 into whole-degree steps that every "
                f"increment divides; got {self.n_sector_centres}"
            )
        number_field(self, "n_range_bins", low=4, high=360, integer=True)
        if 360 % self.n_range_bins:
            raise ValueError(f"argument 'n_range_bins' must divide 360; got {self.n_range_bins}")
        number_field(self, "max_steps", low=1, high=1000, integer=True)
        choice_field(self, "start_pose", ("beacons_visible", "any"))
        choice_field(self, "localization_method", METHODS)
        choice_field(self, "pair_assignment", ASSIGNMENTS)
        choice_field(self, "rcd_extraction", EXTRACTIONS)
        number_field(self, "prior_gate_m", low=MIN_LENGTH_M, high=10.0, optional=True)
        choice_field(self, "action_type", ("multi_discrete", "discrete"))
        number_field(self, "time_budget_s", low=MIN_DURATION_S, high=1e5)


def _degree_set_field(config: object, name: str, allowed: tuple[int, ...] | None) -> None:
    """A non-empty set of distinct positive whole degrees (from ``allowed`` if given)."""
    choices = f" from {allowed}" if allowed else ""
    message = f"argument {name!r} must be distinct positive whole degrees{choices}"
    try:
        values = numbers_field(config, name, low=1, high=360, integer=True, min_length=1)
    except ValueError as error:
        raise ValueError(f"{message}; {error}") from error
    if len(set(values)) != len(values) or (
        allowed is not None and any(v not in allowed for v in values)
    ):
        raise ValueError(f"{message}; got {values!r}")


@dataclass(frozen=True)
class PanCommand:
    """A decoded action. Angles in degrees in the robot frame {R}."""

    kind: str
    centre_deg: int = 0
    width_deg: int = 0
    increment_deg: int = 0


@dataclass(frozen=True)
class _Room:
    """What stays the same between episodes in one scenario ({W}, metres)."""

    world: World
    sonar: RotatingSonar  # assuming 20 deg C, before any calibration
    bounds: np.ndarray  # (2, 2) scenario bounds, [min, max]
    beacon_centres: np.ndarray  # (2, 2) small then large beacon
    bounds_xy: tuple[tuple[float, float], tuple[float, float]]  # bounds as floats


@dataclass
class _Episode:
    room: _Room
    world: World
    true_pose: Pose
    prior: Pose
    sonar: RotatingSonar
    memory: ScanMemory
    calibrated: bool = False
    sensing_time_s: float = 0.0
    steps: int = 0
    estimate: Pose | None = None
    result: BeaconLocalization | None = None
    scans: list[Scan] = field(default_factory=list)  # kept for rendering only
    prior_features: np.ndarray = field(default_factory=lambda: np.zeros(10, dtype=np.float32))
    scan_features: np.ndarray | None = None  # cached until the next pan or calibration
    coverage: float = 0.0  # of the memory, cached with scan_features
    # the observation so far: scan features as cached, prior features, progress of last step
    observation: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.float32))


class BeaconScanEnv(SonarEnv):
    """
    ## Description

    A robot stands at an unknown pose in a room holding two passive cylindrical beacons of
    different diameters (Beom & Cho, *Mobile robot localization using a single rotating sonar
    and two passive cylindrical beacons*, Robotica 13, 1995). Its rotating sonar (Polaroid
    6500 by default) pans sectors; echoes from the beacons form regions of constant depth
    (RCDs). When the agent chooses to localize, the paper's method runs on every ping gathered
    so far: RCD extraction (eqs 3-5), angular-extent, symmetry (eq 6) and beacon-distance
    (eq 7) filters, the two-circle solution (eqs 8-14) and the heading (eq 15). The air
    temperature is drawn per episode and the sensor assumes 20 deg C until it calibrates its
    speed of sound against the reflector on the robot's front (section II.A); pings are kept
    as times of flight, so a calibration corrects pans made before it too.

    ## Action Space

    ``action_type="multi_discrete"`` (default): ``MultiDiscrete([3, n_sector_centres,
    len(sector_widths_deg), len(increments_deg)])``:

    | index | meaning | values |
    |---|---|---|
    | 0 | kind | 0 pan, 1 calibrate, 2 localize (ends the episode) |
    | 1 | sector centre, robot frame | ``k * 360 / n_sector_centres`` deg, k = 0.. |
    | 2 | sector width | ``sector_widths_deg`` (default 30, 60, 90, 180, 360 deg) |
    | 3 | angular increment | ``increments_deg`` (default 1, 2, 5 deg) |

    Indices 1-3 are ignored unless the kind is pan. ``action_type="discrete"`` flattens the
    same choices into ``Discrete(2 + centres * widths * increments)``: 0 calibrate,
    1 localize, then every pan. ``env.unwrapped.encode_action(...)`` builds either form.

    ## Observation Space

    ``Box(-1, 1, (2 * n_bins + 15,), float32)``; the robot frame {R} is the odometry prior's.

    | slice | meaning | range |
    |---|---|---|
    | ``[0, n_bins)`` | nearest range per bin / max range (1: no echo or not scanned) | [0, 1] |
    | ``[n_bins, 2 n_bins)`` | 1 where the bin has been scanned | {0, 1} |
    | ``+0, +1`` | prior position x, y, scaled to the scenario bounds | [-1, 1] |
    | ``+2, +3`` | cos, sin of the prior heading | [-1, 1] |
    | ``+4 .. +6`` | small beacon from the prior: cos, sin of bearing ({R}), range / max | [-1, 1] |
    | ``+7 .. +9`` | the same for the large beacon | [-1, 1] |
    | ``+10`` | sensing time so far / ``time_budget_s`` (clipped) | [0, 1] |
    | ``+11`` | 1 once the speed of sound is calibrated | {0, 1} |
    | ``+12`` | steps taken / ``max_steps`` | [0, 1] |
    | ``+13`` | calibration allowed | {0, 1} |
    | ``+14`` | fraction of the full circle scanned | [0, 1] |

    ``env.unwrapped.observation_layout`` maps these names to slices.

    ## Rewards

    Every step costs ``-sensing_cost_per_s * duration`` (pan motion plus listening, or the
    calibration pings). At localize: ``-min(E_xy / 0.03 m + E_theta / 2 deg, failure_penalty)``
    (Beom & Cho eq 16, in units of their experimental bounds); ``-failure_penalty`` when no pose
    comes out (no RCD pair, D < 0) or when ``max_steps`` pass without localizing.
    ``info["rewards"]`` holds the terms ``sensing_cost``, ``pose_error`` and ``failure``
    (zero when they do not apply), which sum to the reward.

    ## Starting State

    A scenario (``scenario``: built-in name, file path, or ``"random"`` for a new seeded random
    room per episode); a robot pose drawn uniformly over free space (with
    ``start_pose="beacons_visible"``, only poses from which both beacons are within the
    sensor's range and in line of sight); an odometry prior = truth + Gaussian noise
    (``prior_position_std_m``, ``prior_heading_std_deg``); a temperature ``temperature_c`` or
    uniform in ``temperature_range_c``.

    ## Episode End

    Terminates when the agent localizes; truncates after ``max_steps`` steps (counted as a
    failure, with the penalty).

    ## Info

    ``position_error_m``, ``heading_error_rad`` (of the estimate after localizing, of the prior
    before), ``sensing_time_s``, ``status`` (``"sensing"``, ``"ok"``, or the localizer's reason
    such as ``"no_pair"``, or ``"truncated"``), ``temperature_c``, ``calibrated``, ``true_pose``
    and ``estimated_pose`` (``[x, y, theta]``).

    ## Arguments

    | argument | default | meaning |
    |---|---|---|
    | scenario | ``"beom_cho_lab"`` | built-in name, path to .toml/.json, or ``"random"``; the |
    | | | sonar: its ``[sensor]`` preset if set, else the Polaroid 6500 |
    | temperature_c | None | air temperature in deg C; None draws from ``temperature_range_c`` |
    | temperature_range_c | (0, 40) | deg C |
    | allow_calibration | True | whether the calibrate action works (else it only costs time) |
    | sensing_cost_per_s | 0.05 | reward per second of sensing |
    | failure_penalty | 20 | reward lost on failure; also caps a bad estimate's loss |
    | prior_position_std_m / prior_heading_std_deg | 0.1 / 5 | odometry prior noise |
    | increments_deg | (1, 2, 5) | pan increments offered |
    | sector_widths_deg | (30, 60, 90, 180, 360) | sector widths offered (even, deg) |
    | n_sector_centres | 36 | sector centres, evenly spaced |
    | n_range_bins | 72 | angular bins of the observation (``n_bins`` in the formulas above) |
    | max_steps | 12 | decisions before truncation |
    | start_pose | ``"beacons_visible"`` | or ``"any"`` |
    | localization_method | ``"paper"`` | or ``"least_squares"`` (refinement beside the paper's) |
    | pair_assignment | ``"extent"`` | the paper's large/small rule, or ``"best_fit"`` (both) |
    | rcd_extraction | ``"paper"`` | or ``"occlusion_aware"`` (not in the paper): with no pair, |
    | | | retry with beacons rebuilt from RCDs a nearer echo cut |
    | prior_gate_m | None | not in the paper: keep the best beacon pair whose pose lies this |
    | | | close (m) to the odometry prior |
    | action_type | ``"multi_discrete"`` | or ``"discrete"`` (for DQN) |
    | time_budget_s | 60 | sensing time that fills the time feature |

    ## Version History

    * v0: first release. Later, without changing any default episode: ``n_bins`` renamed
      ``n_range_bins`` (the old name still works, with a ``DeprecationWarning``); a native
      vector env, ``gym.make_vec(..., vectorization_mode="vector_entry_point")`` (see
      :mod:`sonar_gym.envs.beacon_scan_vector`), that gives the sync vector env's results bit
      for bit.

    ## Example

    >>> import gymnasium as gym, sonar_gym
    >>> env = gym.make("SonarGym/BeaconScan-v0", temperature_c=20.0)
    >>> obs, info = env.reset(seed=3)
    >>> obs.shape, obs.dtype
    ((159,), dtype('float32'))
    >>> full_pan = env.unwrapped.encode_action("pan", centre_deg=0, width_deg=360, increment_deg=1)
    >>> obs, reward, terminated, truncated, info = env.step(full_pan)
    >>> obs, reward, terminated, truncated, info = env.step(env.unwrapped.encode_action("localize"))
    >>> terminated, info["status"], info["position_error_m"] < 0.03
    (True, 'ok', True)
    """

    required_info_keys = INFO_KEYS

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        super().__init__(render_mode)
        self.config = build_config(BeaconScanConfig, kwargs, "SonarGym/BeaconScan-v0")
        config = self.config
        self._fixed_scenario: Scenario | None = (
            None if config.scenario == "random" else load_scenario(config.scenario)
        )
        if self._fixed_scenario is not None and not self._fixed_scenario.has_beacons():
            raise ValueError(
                f"argument 'scenario': {self._fixed_scenario.name!r} needs exactly one "
                "'small_beacon' and one 'large_beacon' cylinder"
            )
        self._centres_deg = [
            k * 360 // config.n_sector_centres for k in range(config.n_sector_centres)
        ]
        self._use_action_type(
            make_action_type(
                config.action_type,
                DiscreteChoices(
                    (
                        len(ACTION_KINDS),
                        config.n_sector_centres,
                        len(config.sector_widths_deg),
                        len(config.increments_deg),
                    ),
                    parameterless_kinds=(CALIBRATE, LOCALIZE),
                ),
            )
        )
        n = config.n_range_bins
        self._range_bins = RangeBins("bin_ranges", n)
        self._scanned_bins = ScannedBins("bin_scanned", n)
        self._use_observation_spec(
            ObservationSpec(
                [
                    self._range_bins,
                    self._scanned_bins,
                    ScaledPosition("prior_xy"),
                    Heading("prior_heading"),
                    Feature("small_beacon", 3),
                    Feature("large_beacon", 3),
                    Fraction("sensing_time"),
                    Flag("calibrated"),
                    Fraction("steps"),
                    Flag("calibration_allowed"),
                    Fraction("coverage"),
                ]
            )
        )
        # the progress features run from sensing_time to the end of the vector
        self._progress_start = self.observation_spec.layout["sensing_time"].start
        # the method's parameters are the config's, the same for every localization
        self._localization_params = BeomChoParameters(
            assignment=config.pair_assignment, extraction=config.rcd_extraction
        )
        self._episode: _Episode | None = None
        self._room: _Room | None = None
        if self._fixed_scenario is not None and config.start_pose == "beacons_visible":
            self._check_start_poses(self._fixed_scenario)
        # bin_ranges and bin_scanned before the first pan: no echo, nothing scanned
        self._unscanned_features = np.concatenate([np.ones(n), np.zeros(n)]).astype(np.float32)
        self._unscanned_features.setflags(write=False)

    @property
    def world(self) -> World:
        """The :class:`~sonar_gym.world.World` of the current episode (reused between
        episodes while the scenario stays the same)."""
        return self._require_episode().world

    # --- actions -----------------------------------------------------------------------
    def encode_action(
        self, kind: str, centre_deg: float = 0, width_deg: int = 360, increment_deg: int = 1
    ) -> np.ndarray | int:
        """The action for a command; a pan's centre snaps to the nearest offered centre."""
        check_choice("kind", kind, ACTION_KINDS)
        if kind != "pan":
            return self.action_type.encode((ACTION_KINDS.index(kind), 0, 0, 0))
        return self.action_type.encode(
            (PAN, *self._pan_indices(centre_deg, width_deg, increment_deg))
        )

    def _pan_indices(
        self, centre_deg: float, width_deg: int, increment_deg: int
    ) -> tuple[int, int, int]:
        """The (centre, width, increment) indices of a pan; the centre snaps to the nearest."""
        config = self.config
        centre = check_number("centre_deg", centre_deg)
        check_choice("width_deg", width_deg, config.sector_widths_deg)
        check_choice("increment_deg", increment_deg, config.increments_deg)
        step = 360 / config.n_sector_centres
        centre_index = int(round((centre % 360) / step)) % config.n_sector_centres
        return (
            centre_index,
            config.sector_widths_deg.index(width_deg),
            config.increments_deg.index(increment_deg),
        )

    def decode_action(self, action: Any) -> PanCommand:
        """The command an action stands for.

        Raises:
            ValueError: ``action`` is not in the action space (the message says what is).
        """
        self.action_type.check(action)
        return self._command(action)

    def _command(self, action: Any) -> PanCommand:
        """:meth:`decode_action` of an action already checked (``step`` checks it)."""
        kind, centre_index, width_index, increment_index = self.action_type.decode(action)
        if kind != PAN:
            return PanCommand(ACTION_KINDS[kind])
        config = self.config
        return PanCommand(
            "pan",
            self._centres_deg[centre_index],
            config.sector_widths_deg[width_index],
            config.increments_deg[increment_index],
        )

    # --- episode -----------------------------------------------------------------------
    def _reset_task(self, options: dict[str, Any] | None) -> dict[str, Any]:
        config = self.config
        rng = self.np_random
        scenario = self._fixed_scenario or random_scenario(rng)
        if config.temperature_c is not None:
            temperature_c = float(config.temperature_c)
        else:
            temperature_c = float(rng.uniform(*config.temperature_range_c))
        room = self._room_for(scenario, temperature_c)
        world = room.world
        sonar = room.sonar
        true_pose = sample_start_pose(
            world, sonar, rng, require_beacons=config.start_pose == "beacons_visible"
        )
        # drawn free with a wider margin than the robot's radius: no need to check it again
        world.place_robot_on_clear_path(true_pose)
        prior = Pose(
            true_pose.x + rng.normal(0.0, config.prior_position_std_m),
            true_pose.y + rng.normal(0.0, config.prior_position_std_m),
            true_pose.theta + rng.normal(0.0, math.radians(config.prior_heading_std_deg)),
        )
        prior_features = self._prior_features(room, prior, sonar.transducer.max_range_m)
        self._episode = _Episode(
            room,
            world,
            true_pose,
            prior,
            sonar,
            ScanMemory(math.radians(1.0)),
            prior_features=prior_features,
            scan_features=self._unscanned_features,
            observation=np.concatenate(
                [self._unscanned_features, prior_features, np.zeros(5, dtype=np.float32)]
            ),
        )
        return self._info("sensing")

    def _check_start_poses(self, scenario: Scenario) -> None:
        """Refuse a scenario with no free pose that sees both beacons, before any episode.

        Builds the room the first episode reuses (the temperature only sets the speed of
        sound, which :func:`beacons_visible` does not read)."""
        temperatures = self.config.temperature_range_c
        temperature_c = self.config.temperature_c
        room = self._room_for(
            scenario, temperatures[0] if temperature_c is None else float(temperature_c)
        )
        try:
            sample_start_pose(room.world, room.sonar, np.random.default_rng(0))
        except RuntimeError:
            raise ValueError(
                f"argument 'scenario': {scenario.name!r} has no free pose from which both "
                f"beacons are in the sonar's range and in sight ({START_POSE_TRIES} free poses "
                "drawn); use start_pose='any' or move the beacons"
            ) from None

    def _room_for(self, scenario: Scenario, temperature_c: float) -> _Room:
        """The static part of an episode, built once per scenario and reused while it lasts."""
        room = self._room
        if room is not None and room.world.scenario is scenario:
            room.world.temperature_c = temperature_c
            return room
        world = World(scenario, temperature_c=temperature_c)
        sonar = RotatingSonar.preset(
            scenario.sensor.preset_or(PAPER_SENSOR_PRESET)
        ).with_assumed_speed(speed_of_sound_mps(ASSUMED_TEMPERATURE_C))
        centres = [scenario.beacon(role).center for role in BEACON_ROLES]
        bounds = np.array(scenario.bounds, dtype=np.float64)
        (x0, y0), (x1, y1) = bounds.tolist()
        self._room = _Room(
            world, sonar, bounds, np.array(centres, dtype=np.float64), ((x0, y0), (x1, y1))
        )
        return self._room

    def _apply_action(self, action: Any) -> StepOutcome:
        episode = self._require_episode()
        command = self._command(action)
        episode.steps += 1
        duration_s = 0.0
        if command.kind == "pan":
            duration_s = self._pan(episode, command)
        elif command.kind == "calibrate":
            duration_s = self._calibrate(episode)
        terms = self._sensing_terms(duration_s)
        if command.kind == "localize":
            status = self._localize(episode)
            terms.update(self._localization_terms(episode, status))
            return StepOutcome(reward_terms=terms, terminated=True, info=self._info(status))
        if episode.steps >= self.config.max_steps:
            terms["failure"] = -self.config.failure_penalty
            return StepOutcome(reward_terms=terms, truncated=True, info=self._info("truncated"))
        return StepOutcome(reward_terms=terms, info=self._info("sensing"))

    def _sensing_terms(self, duration_s: float) -> dict[str, float]:
        """A step's reward terms before localizing: ``sensing_cost`` for ``duration_s``
        seconds of sensing (or motion), and ``pose_error`` and ``failure`` still zero."""
        return {
            "sensing_cost": -self.config.sensing_cost_per_s * duration_s,
            "pose_error": 0.0,
            "failure": 0.0,
        }

    def _localization_terms(self, episode: _Episode, status: str) -> dict[str, float]:
        """The ``pose_error`` and ``failure`` terms of localizing with ``status`` (Rewards)."""
        loss = self._localization_loss(episode, status)
        if status != "ok" or episode.estimate is None:
            return {"pose_error": 0.0, "failure": -loss}
        return {"pose_error": -loss, "failure": 0.0}

    def _pan(self, episode: _Episode, command: PanCommand) -> float:
        centre = math.radians(command.centre_deg)
        half_width = math.radians(command.width_deg) / 2.0
        with self._timed("sensing"):
            scan = episode.sonar.pan(
                episode.world,
                episode.true_pose,
                centre - half_width,
                centre + half_width,
                math.radians(command.increment_deg),
                self.np_random,
            )
        episode.memory.add(scan, episode.sonar.assumed_speed_of_sound_mps)
        episode.scan_features = None
        episode.sensing_time_s += scan.duration_s
        episode.scans.append(scan)
        return scan.duration_s

    def _calibrate(self, episode: _Episode) -> float:
        with self._timed("sensing"):
            calibration = episode.sonar.calibrate(episode.world, episode.true_pose, self.np_random)
        if self.config.allow_calibration:
            episode.sonar = episode.sonar.with_assumed_speed(calibration.estimated_speed_mps)
            episode.scan_features = None
            episode.calibrated = True
        episode.sensing_time_s += calibration.duration_s
        return calibration.duration_s

    def _localize(self, episode: _Episode) -> str:
        scans = episode.memory.as_scans(episode.sonar.assumed_speed_of_sound_mps)
        with self._timed("localization"):
            result = localize_scans(
                scans,
                episode.world.scenario,
                params=self._localization_params,
                method=self.config.localization_method,
                prior=None if self.config.prior_gate_m is None else episode.prior,
                prior_gate_m=self.config.prior_gate_m or 0.5,
            )
        episode.result = result
        if result.ok and result.pose is not None:
            episode.estimate = result.pose
        return result.status

    def _localization_loss(self, episode: _Episode, status: str) -> float:
        if status != "ok" or episode.estimate is None:
            return self.config.failure_penalty
        score = (
            position_error_m(episode.estimate, episode.true_pose) / POSITION_UNIT_M
            + heading_error_rad(episode.estimate, episode.true_pose) / HEADING_UNIT_RAD
        )
        return min(score, self.config.failure_penalty)

    # --- observation and info ---------------------------------------------------------
    def _observe(self) -> np.ndarray:
        episode = self._require_episode()
        config = self.config
        observation = episode.observation
        if episode.scan_features is None:  # pans and calibrations change it, nothing else
            episode.scan_features = self._scan_features(episode)
            episode.coverage = episode.memory.coverage
            observation[: 2 * config.n_range_bins] = episode.scan_features
        observation[self._progress_start :] = (
            min(episode.sensing_time_s / config.time_budget_s, 1.0),
            float(episode.calibrated),
            min(episode.steps / config.max_steps, 1.0),
            float(config.allow_calibration),
            episode.coverage,
        )
        return observation.copy()

    def _scan_features(self, episode: _Episode) -> np.ndarray:
        """``bin_ranges`` and ``bin_scanned`` of the observation (float32)."""
        memory = episode.memory
        max_range = episode.sonar.transducer.max_range_m
        ranges = memory.ranges(episode.sonar.assumed_speed_of_sound_mps)
        return np.concatenate(
            [self._range_bins.values(ranges / max_range), self._scanned_bins.values(memory.scanned)]
        ).astype(np.float32)

    def _prior_features(self, room: _Room, prior: Pose, max_range: float) -> np.ndarray:
        """``prior_xy``, ``prior_heading`` and both beacons seen from the prior (float32)."""
        features = [
            *ScaledPosition.float_values((prior.x, prior.y), *room.bounds_xy),
            *Heading.values(prior.theta),
        ]
        for x, y in room.beacon_centres.tolist():
            dx, dy = x - prior.x, y - prior.y
            bearing = wrap_angle(math.atan2(dy, dx) - prior.theta)
            features += [*Heading.values(bearing), min(math.hypot(dx, dy) / max_range, 1.0)]
        return np.array(features, dtype=np.float32)

    def _info(self, status: str) -> dict[str, Any]:
        episode = self._require_episode()
        estimate = episode.estimate if episode.estimate is not None else episode.prior
        return {
            "position_error_m": position_error_m(estimate, episode.true_pose),
            "heading_error_rad": heading_error_rad(estimate, episode.true_pose),
            "sensing_time_s": episode.sensing_time_s,
            "status": status,
            "temperature_c": episode.world.temperature_c,
            "calibrated": episode.calibrated,
            "true_pose": episode.true_pose.as_array(),
            "estimated_pose": estimate.as_array(),
        }

    # --- rendering ----------------------------------------------------------------------
    def _render_frame(self) -> np.ndarray:
        from sonar_gym.render import render_topdown

        episode = self._require_episode()
        points = (
            np.concatenate([self._scan_points_world(episode, scan) for scan in episode.scans])
            if episode.scans
            else None
        )
        return render_topdown(
            episode.world.scenario,
            true_pose=episode.true_pose,
            estimated_pose=episode.estimate,
            scan_points=points,
            title=f"BeaconScan  t={episode.sensing_time_s:.1f} s",
        )

    @staticmethod
    def _scan_points_world(episode: _Episode, scan: Scan) -> np.ndarray:
        hit = scan.detected
        sensor = episode.true_pose.transform_point(episode.world.scenario.robot.sensor_offset)
        directions = scan.angles[hit] + episode.true_pose.theta
        return np.stack(
            [
                sensor[0] + scan.ranges[hit] * np.cos(directions),
                sensor[1] + scan.ranges[hit] * np.sin(directions),
            ],
            axis=1,
        )

    def _require_episode(self) -> _Episode:
        if self._episode is None:
            raise RuntimeError("BeaconScanEnv: call reset() first")
        return self._episode
