"""``SonarGym/ActiveBeaconScan-v0``: BeaconScan where the robot may move and try fixes.

Beom & Cho's task (Robotica 1995) with two more freedoms: the agent may run the paper's method
on the scans of the current pose without ending the episode (``try_fix``), and it may turn in
place or drive a short straight move to a pose from which the beacons are easier to resolve.
The method itself (RCDs, eqs (3)-(7); two-circle pose, eqs (8)-(15)) is the one of
:mod:`sonar_gym.envs.beacon_scan`, unchanged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any, ClassVar

import numpy as np

from sonar_gym.envs.action_types import DiscreteChoices, make_action_type
from sonar_gym.envs.base import StepOutcome
from sonar_gym.envs.features import Feature, Flag
from sonar_gym.envs.beacon_scan import BeaconScanConfig, BeaconScanEnv, PanCommand
from sonar_gym.envs.config import build_config, check_choice, number_field, numbers_field
from sonar_gym.odometry import OdometryConfig
from sonar_gym.pose import Pose, wrap_angle
from sonar_gym.robot import DifferentialDriveRobot
from sonar_gym.sonar.accumulate import ScanMemory

__all__ = ["ActiveBeaconScanConfig", "ActiveBeaconScanEnv", "ActiveCommand"]

ENV_ID = "SonarGym/ActiveBeaconScan-v0"
ACTION_KINDS = ("pan", "calibrate", "try_fix", "turn", "move", "commit")
PAN, CALIBRATE, TRY_FIX, TURN, MOVE, COMMIT = range(len(ACTION_KINDS))
FIX_FEATURES = (
    Flag("fix_tried"),
    Flag("fix_ok"),
    Feature("fix_offset_xy", 2),
    Feature("fix_offset_heading"),
)
"""The features about the fix at the current pose, after BeaconScan's."""
N_FIX_FEATURES = sum(feature.size for feature in FIX_FEATURES)


@dataclass(frozen=True)
class ActiveBeaconScanConfig(BeaconScanConfig):
    """The ``gym.make`` arguments of ``SonarGym/ActiveBeaconScan-v0`` (see the env docstring).

    BeaconScan's arguments, plus the motion ones; ``max_steps`` defaults to 24 here.
    """

    RENAMED_ARGUMENTS: ClassVar[dict[str, str]] = BeaconScanConfig.RENAMED_ARGUMENTS | {
        "linear_speed_mps": "robot_speed_mps",
    }
    max_steps: int = 24
    move_distance_m: float = 0.25
    turn_angles_deg: tuple[int, ...] = (30, -30, 90, -90)
    robot_speed_mps: float = 0.2
    turn_rate_deg_per_s: float = 45.0
    fix_offset_scale_m: float = 0.5

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.action_type != "multi_discrete":
            raise ValueError(
                f"argument 'action_type' must be 'multi_discrete' for {ENV_ID}; "
                f"got {self.action_type!r}"
            )
        number_field(self, "move_distance_m", low=0.01, high=2.0)
        values = numbers_field(
            self, "turn_angles_deg", low=-180, high=180, integer=True, min_length=1
        )
        if 0 in values or len(set(values)) != len(values):
            raise ValueError(
                "argument 'turn_angles_deg' must be distinct non-zero whole degrees in "
                f"[-180, 180]; got {values!r}"
            )
        number_field(self, "robot_speed_mps", low=0.01, high=5.0)
        number_field(self, "turn_rate_deg_per_s", low=1.0, high=720.0)
        number_field(self, "fix_offset_scale_m", low=0.01, high=10.0)


@dataclass(frozen=True)
class ActiveCommand(PanCommand):
    """A decoded action: BeaconScan's pan angles (degrees in {R}) and a turn (degrees, CCW)."""

    turn_deg: int = 0


@dataclass
class _FixState:
    """What ``try_fix`` gave at the current pose (cleared by every motion)."""

    tried: bool = False
    ok: bool = False


class ActiveBeaconScanEnv(BeaconScanEnv):
    """
    ## Description

    ``SonarGym/BeaconScan-v0`` (Beom & Cho, Robotica 13, 1995; scenario ``beom_cho_lab``)
    where the robot may also move and may try a fix without ending the episode. ``try_fix``
    runs the paper's method (eqs 3-15) on the scans taken at the current pose; the
    observation then says whether it gave a pose and where that pose lies relative to the
    odometry prior. ``turn`` and ``move`` drive a differential-drive robot through the pymunk
    world (walls stop it; odometry noise of :class:`sonar_gym.odometry.OdometryConfig`); the
    prior follows the odometry and the scan memory is cleared, since scans belong to a pose.
    ``commit`` ends the episode and scores the last successful fix at the final pose.

    ## Action Space

    ``MultiDiscrete([6, n_sector_centres, len(sector_widths_deg), len(increments_deg),
    len(turn_angles_deg)])``:

    | index | meaning | values |
    |---|---|---|
    | 0 | kind | 0 pan, 1 calibrate, 2 try_fix, 3 turn, 4 move, 5 commit (ends the episode) |
    | 1 | sector centre, robot frame | ``k * 360 / n_sector_centres`` deg, k = 0.. |
    | 2 | sector width | ``sector_widths_deg`` (default 30, 60, 90, 180, 360 deg) |
    | 3 | angular increment | ``increments_deg`` (default 1, 2, 5 deg) |
    | 4 | turn angle (CCW) | ``turn_angles_deg`` (default 30, -30, 90, -90 deg) |

    Indices 1-3 matter only for pan, index 4 only for turn; move drives ``move_distance_m``
    straight ahead. ``env.unwrapped.encode_action(...)`` builds an action.

    ## Observation Space

    ``Box(-1, 1, (2 * n_bins + 20,), float32)``: BeaconScan's ``2 * n_bins + 15`` features
    (the prior now follows the odometry) and five about the fix at the current pose:

    | slice | meaning | range |
    |---|---|---|
    | ``[0, 2 n_bins + 15)`` | as ``SonarGym/BeaconScan-v0`` (scans of this pose only) | [-1, 1] |
    | ``+15`` | 1 once ``try_fix`` ran at this pose | {0, 1} |
    | ``+16`` | 1 when a fix at this pose gave a pose | {0, 1} |
    | ``+17, +18`` | that pose minus the prior, prior's frame, / ``fix_offset_scale_m`` | [-1, 1] |
    | ``+19`` | its heading minus the prior's / pi | [-1, 1] |

    ``env.unwrapped.observation_layout`` maps these names to slices.

    ## Rewards

    Every step costs ``-sensing_cost_per_s * duration``: pans and calibrations as in
    BeaconScan, a move ``move_distance_m / robot_speed_mps`` (default 0.25 m at 0.2 m/s), a
    turn ``|angle| / turn_rate_deg_per_s`` (default 45 deg/s); ``try_fix`` and ``commit`` take
    no time. At commit: ``-min(E_xy / 0.03 m + E_theta / 2 deg, failure_penalty)`` (Beom & Cho
    eq 16) at the final pose, from the last successful fix there; ``-failure_penalty`` when
    there is none, or when ``max_steps`` pass without committing. ``info["rewards"]`` holds
    the terms ``sensing_cost``, ``pose_error`` and ``failure``, as in BeaconScan.

    ## Starting State

    As ``SonarGym/BeaconScan-v0`` (same draws for the same seed): scenario, a start pose from
    which both beacons are visible (``start_pose``), the odometry prior, the temperature.

    ## Episode End

    Terminates at commit; truncates after ``max_steps`` steps (a failure, with the penalty).

    ## Info

    As BeaconScan (``status`` ``"sensing"``, ``"ok"``, the localizer's reason after a failed
    ``try_fix``, ``"no_fix"`` at a commit without a fix, or ``"truncated"``), plus
    ``motion_time_s`` and ``collided`` (whether the last motion touched an obstacle).

    ## Arguments

    Every argument of ``SonarGym/BeaconScan-v0`` (``action_type`` only ``"multi_discrete"``),
    and:

    | argument | default | meaning |
    |---|---|---|
    | max_steps | 24 | decisions before truncation |
    | move_distance_m | 0.25 | length of a move, metres |
    | turn_angles_deg | (30, -30, 90, -90) | turn angles offered, degrees CCW |
    | robot_speed_mps | 0.2 | driving speed, for the time cost |
    | turn_rate_deg_per_s | 45 | turning rate, for the time cost |
    | fix_offset_scale_m | 0.5 | scale of the fix-minus-prior features, metres |

    ## Version History

    * v0: first release. Later, without changing any default episode: ``n_bins`` renamed
      ``n_range_bins`` and ``linear_speed_mps`` renamed ``robot_speed_mps`` (Trilateration's
      name); the old names still work, with a ``DeprecationWarning``.

    ## Example

    >>> import gymnasium as gym, sonar_gym
    >>> env = gym.make("SonarGym/ActiveBeaconScan-v0", temperature_c=20.0)
    >>> obs, info = env.reset(seed=3)
    >>> obs.shape, obs.dtype
    ((164,), dtype('float32'))
    >>> full_pan = env.unwrapped.encode_action("pan", centre_deg=0, width_deg=360, increment_deg=1)
    >>> obs, reward, terminated, truncated, info = env.step(full_pan)
    >>> obs, reward, terminated, truncated, info = env.step(env.unwrapped.encode_action("try_fix"))
    >>> bool(obs[env.unwrapped.observation_layout["fix_ok"]][0])
    True
    >>> obs, reward, terminated, truncated, info = env.step(env.unwrapped.encode_action("commit"))
    >>> terminated, info["status"], info["position_error_m"] < 0.03
    (True, 'ok', True)
    """

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        config = build_config(ActiveBeaconScanConfig, kwargs, ENV_ID)
        base_names = [f.name for f in fields(BeaconScanConfig)]
        super().__init__(render_mode, **{name: getattr(config, name) for name in base_names})
        self.config = config
        self._use_action_type(
            make_action_type(
                "multi_discrete",
                DiscreteChoices(
                    (
                        len(ACTION_KINDS),
                        config.n_sector_centres,
                        len(config.sector_widths_deg),
                        len(config.increments_deg),
                        len(config.turn_angles_deg),
                    )
                ),
            )
        )
        self._use_observation_spec(self.observation_spec.extended(FIX_FEATURES))
        self._fix = _FixState()
        self._motion_time_s = 0.0
        self._collided = False

    # --- actions -----------------------------------------------------------------------
    def encode_action(  # type: ignore[override]
        self,
        kind: str,
        centre_deg: float = 0,
        width_deg: int = 360,
        increment_deg: int = 1,
        turn_deg: int | None = None,
    ) -> np.ndarray:
        """The action for a command; a pan's centre snaps to the nearest offered centre,
        ``turn_deg`` must be one of ``turn_angles_deg`` (default: the first)."""
        check_choice("kind", kind, ACTION_KINDS)
        config = self.config
        pan, turn = (0, 0, 0), 0
        if kind == "pan":
            pan = self._pan_indices(centre_deg, width_deg, increment_deg)
        elif kind == "turn" and turn_deg is not None:
            check_choice("turn_deg", turn_deg, config.turn_angles_deg)
            turn = config.turn_angles_deg.index(turn_deg)
        return self.action_type.encode((ACTION_KINDS.index(kind), *pan, turn))

    def decode_action(self, action: Any) -> ActiveCommand:  # type: ignore[override]
        """The command an action stands for.

        Raises:
            ValueError: ``action`` is not in the action space (the message says what is).
        """
        self.action_type.check(action)
        return self._command(action)

    def _command(self, action: Any) -> ActiveCommand:
        """:meth:`decode_action` of an action already checked (``step`` checks it)."""
        config = self.config
        kind, centre_index, width_index, increment_index, turn_index = self.action_type.decode(
            action
        )
        if kind == PAN:
            return ActiveCommand(
                "pan",
                self._centres_deg[centre_index],
                config.sector_widths_deg[width_index],
                config.increments_deg[increment_index],
            )
        if kind == TURN:
            return ActiveCommand("turn", turn_deg=config.turn_angles_deg[turn_index])
        return ActiveCommand(ACTION_KINDS[kind])

    # --- episode -----------------------------------------------------------------------
    def _reset_task(self, options: dict[str, Any] | None) -> dict[str, Any]:
        self._fix = _FixState()
        self._motion_time_s = 0.0
        self._collided = False
        return super()._reset_task(options) | self._motion_info()

    def _apply_action(self, action: Any) -> StepOutcome:
        episode = self._require_episode()
        config = self.config
        command = self._command(action)
        episode.steps += 1
        duration_s = 0.0
        status = "sensing"
        if command.kind == "pan":
            duration_s = self._pan(episode, command)  # type: ignore[arg-type]
        elif command.kind == "calibrate":
            duration_s = self._calibrate(episode)
        elif command.kind == "try_fix":
            status = self._localize(episode)
            self._fix = _FixState(tried=True, ok=self._fix.ok or status == "ok")
        elif command.kind == "turn":
            duration_s = self._drive(episode, turn_rad=math.radians(command.turn_deg))
        elif command.kind == "move":
            duration_s = self._drive(episode, distance_m=config.move_distance_m)
        terms = self._sensing_terms(duration_s)
        if command.kind == "commit":
            status = "ok" if episode.estimate is not None else "no_fix"
            terms.update(self._localization_terms(episode, status))
            return StepOutcome(reward_terms=terms, terminated=True, info=self._full_info(status))
        if episode.steps >= config.max_steps:
            terms["failure"] = -config.failure_penalty
            return StepOutcome(
                reward_terms=terms, truncated=True, info=self._full_info("truncated")
            )
        return StepOutcome(reward_terms=terms, info=self._full_info(status))

    def _drive(self, episode: Any, distance_m: float = 0.0, turn_rad: float = 0.0) -> float:
        """Turn in place or drive straight; the prior follows the odometry, the scans of the
        old pose and any fix there are dropped. Returns the motion's duration, seconds."""
        config = self.config
        robot = DifferentialDriveRobot(OdometryConfig(), odometry_pose=episode.prior)
        # the world's robot body is already at the true pose (placed at reset, moved since);
        # placing it again would refuse the contact a blocked move leaves it in
        with self._timed("motion"):
            if turn_rad:
                result = robot.turn(episode.world, turn_rad, self.np_random)
            else:
                result = robot.drive_straight(episode.world, distance_m, self.np_random)
        episode.true_pose = result.true_pose
        episode.prior = Pose(
            result.odometry_pose.x, result.odometry_pose.y, wrap_angle(result.odometry_pose.theta)
        )
        episode.memory = ScanMemory(math.radians(1.0))
        episode.scans.clear()
        episode.scan_features = None
        episode.estimate = None
        episode.result = None
        episode.prior_features = self._prior_features(
            episode.room, episode.prior, episode.sonar.transducer.max_range_m
        )
        start = 2 * config.n_range_bins
        episode.observation[start : start + 10] = episode.prior_features
        self._fix = _FixState()
        self._collided = result.collided
        duration_s = (
            abs(distance_m) / config.robot_speed_mps
            + math.degrees(abs(turn_rad)) / config.turn_rate_deg_per_s
        )
        self._motion_time_s += duration_s
        return duration_s

    # --- observation and info ---------------------------------------------------------
    def _observe(self) -> np.ndarray:
        episode = self._require_episode()
        features = np.zeros(N_FIX_FEATURES, dtype=np.float32)
        features[0] = float(self._fix.tried)
        if episode.estimate is not None:
            prior, estimate = episode.prior, episode.estimate
            dx, dy = estimate.x - prior.x, estimate.y - prior.y
            cos_t, sin_t = math.cos(prior.theta), math.sin(prior.theta)
            scale = self.config.fix_offset_scale_m
            features[1] = 1.0
            features[2] = np.clip((cos_t * dx + sin_t * dy) / scale, -1.0, 1.0)
            features[3] = np.clip((-sin_t * dx + cos_t * dy) / scale, -1.0, 1.0)
            features[4] = wrap_angle(estimate.theta - prior.theta) / math.pi
        return np.concatenate([super()._observe(), features])

    def _motion_info(self) -> dict[str, Any]:
        return {"motion_time_s": self._motion_time_s, "collided": self._collided}

    def _full_info(self, status: str) -> dict[str, Any]:
        return self._info(status) | self._motion_info()
