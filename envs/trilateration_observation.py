"""The episode state of ``SonarGym/Trilateration-v0`` and what the agent is shown of it.

The table of features, their mappings and bounds is in the ``TrilaterationEnv`` docstring
(Observation Space); the predicted spreads come from the dead-reckoning covariance
(:func:`sonar_gym.odometry.propagate_covariance`) and the fix model of
:mod:`sonar_gym.localization.wu_tsai_models` (Wu & Tsai eqs (7)-(8)).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sonar_gym.envs.features import Feature, Fraction, Heading, ObservationSpec, ScaledPosition
from sonar_gym.localization.wu_tsai import Fix
from sonar_gym.localization.wu_tsai_models import heading_std_rad, position_std_m
from sonar_gym.metrics import heading_error_rad, position_error_m
from sonar_gym.pose import FloatArray, Pose, vector_norm
from sonar_gym.robot import DifferentialDriveRobot
from sonar_gym.world import World

TIME_SINCE_FIX_SCALE_S = 10.0
"""Time that maps to 0.5 in the ``time_since_fix`` feature, seconds."""
OBSERVATION = ObservationSpec(
    [
        ScaledPosition("estimated_xy"),
        Heading("estimated_heading"),
        Fraction("time_since_fix"),
        Fraction("distance_since_fix"),
        Fraction("dead_reckoning_position_std"),
        Fraction("dead_reckoning_heading_std"),
        Feature("transmitter_offset", 2),
        Fraction("transmitter_distance"),
        Fraction("fix_position_std"),
        Fraction("fix_heading_std"),
        Fraction("progress"),
        Fraction("steps_remaining"),
    ]
)
"""The observation's features (see the env docstring, Observation Space)."""
OBSERVATION_LAYOUT: dict[str, slice] = OBSERVATION.observation_layout()
OBSERVATION_SIZE = OBSERVATION.size


@dataclass
class TrilaterationEpisode:
    """The state of one episode (true and estimated poses in {W}; metres, radians, seconds)."""

    world: World
    robot: DifferentialDriveRobot
    waypoints: FloatArray
    true_pose: Pose
    estimate: Pose
    covariance: FloatArray
    decisions: int = 0
    sensing_time_s: float = 0.0
    elapsed_time_s: float = 0.0
    time_since_fix_s: float = 0.0
    distance_since_fix_m: float = 0.0
    collided: bool = False
    last_fix: Fix | None = None
    true_trail: list[tuple[float, float]] = field(default_factory=list)
    fix_trail: list[tuple[float, float]] = field(default_factory=list)


@dataclass(frozen=True)
class FeatureScales:
    """What the features are scaled by (all fixed per env).

    Attributes:
        centre_xy, half_size_xy: the room's centre and half size ({W}, metres).
        transmitter_centroid_xy: the centroid of the three transmitters ({W}, metres).
        route_length_m: the route's total length, metres.
        position_scale_m, heading_scale_rad: the spreads that map to 0.5.
        n_decision_points: decision points per episode.
    """

    centre_xy: FloatArray
    half_size_xy: FloatArray
    transmitter_centroid_xy: FloatArray
    route_length_m: float
    position_scale_m: float
    heading_scale_rad: float
    n_decision_points: int

    @functools.cached_property
    def centre_values(self) -> tuple[float, float]:
        """``centre_xy`` as two floats."""
        return float(self.centre_xy[0]), float(self.centre_xy[1])

    @functools.cached_property
    def half_size_values(self) -> tuple[float, float]:
        """``half_size_xy`` as two floats."""
        return float(self.half_size_xy[0]), float(self.half_size_xy[1])

    @functools.cached_property
    def half_diagonal_m(self) -> float:
        """The length of ``half_size_xy``: what maps to 1 in ``transmitter_distance``."""
        return float(np.linalg.norm(self.half_size_xy))


def trilateration_observation(
    scales: FeatureScales,
    estimate: Pose,
    covariance: FloatArray,
    single_fix_covariance: FloatArray,
    time_since_fix_s: float,
    distance_since_fix_m: float,
    decisions: int,
) -> np.ndarray:
    """The ``(15,)`` float32 observation (see the env docstring for every feature).

    Args:
        scales: the env's fixed scales.
        estimate: the estimated pose ({W}).
        covariance: its 3x3 covariance over ``[x, y, theta]`` (m^2, rad^2).
        single_fix_covariance: the predicted covariance of ONE fix at ``estimate``.
        time_since_fix_s, distance_since_fix_m: driving since the last fix (or the start).
        decisions: decision points already passed.
    """
    cx, cy = scales.centre_values
    hx, hy = scales.half_size_values
    x, y = estimate.x, estimate.y
    offset = estimate.position - scales.transmitter_centroid_xy
    offset_x, offset_y = offset.tolist()
    offset_length = vector_norm(offset)
    position_scale, heading_scale = scales.position_scale_m, scales.heading_scale_rad
    n = scales.n_decision_points
    # the room's centre and half size, not its corners: the env's own form of the scaling
    values = (
        _clip_unit((x - cx) / hx),  # estimated_xy
        _clip_unit((y - cy) / hy),
        *Heading.values(estimate.theta),  # estimated_heading
        time_since_fix_s / (time_since_fix_s + TIME_SINCE_FIX_SCALE_S),  # time_since_fix
        min(distance_since_fix_m / scales.route_length_m, 1.0),  # distance_since_fix
        saturate(position_std_m(covariance), position_scale),  # dead_reckoning_position_std
        saturate(heading_std_rad(covariance), heading_scale),  # dead_reckoning_heading_std
        _clip_unit(offset_x / hx),  # transmitter_offset
        _clip_unit(offset_y / hy),
        min(offset_length / scales.half_diagonal_m, 1.0),  # transmitter_distance
        saturate(position_std_m(single_fix_covariance), position_scale),  # fix_position_std
        saturate(heading_std_rad(single_fix_covariance), heading_scale),  # fix_heading_std
        decisions / n,  # progress
        (n - decisions) / n,  # steps_remaining
    )
    return np.array(values, dtype=np.float32)


def _clip_unit(value: float) -> float:
    """``value`` clipped to [-1, 1] (``np.clip`` of a finite float)."""
    return min(max(value, -1.0), 1.0)


def episode_info(
    episode: TrilaterationEpisode,
    status: str,
    *,
    n_fixes: int,
    fix_status: str,
    measurement_time_s: float,
    n_fixes_ok: int = 0,
    dead_reckoning: Pose | None = None,
    fix_pose: Pose | None = None,
) -> dict[str, Any]:
    """The ``info`` of a reset or step (the keys are listed in the env docstring, Info)."""
    before = dead_reckoning if dead_reckoning is not None else episode.estimate
    truth = episode.true_pose
    info: dict[str, Any] = {
        "position_error_m": position_error_m(episode.estimate, truth),
        "heading_error_rad": heading_error_rad(episode.estimate, truth),
        "sensing_time_s": episode.sensing_time_s,
        "status": status,
        "n_fixes": n_fixes,
        "n_fixes_ok": n_fixes_ok,
        "fix_status": fix_status,
        "measurement_time_s": measurement_time_s,
        "dead_reckoning_position_error_m": position_error_m(before, truth),
        "dead_reckoning_heading_error_rad": heading_error_rad(before, truth),
        "predicted_position_std_m": position_std_m(episode.covariance),
        "predicted_heading_std_rad": heading_std_rad(episode.covariance),
        "decision_point": episode.decisions,
        "elapsed_time_s": episode.elapsed_time_s,
        "collided": episode.collided,
        "true_pose": truth.as_array(),
        "estimated_pose": episode.estimate.as_array(),
    }
    if fix_pose is not None and episode.last_fix is not None:
        info["fix_position_error_m"] = position_error_m(fix_pose, truth)
        info["fix_heading_error_rad"] = heading_error_rad(fix_pose, truth)
        info["fix_z_m"] = episode.last_fix.z
    return info


def saturate(value: float, scale: float) -> float:
    """``value / (value + scale)``: 0 at 0, 0.5 at ``scale``, below 1 for any finite value."""
    return value / (value + scale) if value > 0.0 else 0.0


__all__ = [
    "OBSERVATION",
    "OBSERVATION_LAYOUT",
    "OBSERVATION_SIZE",
    "TIME_SINCE_FIX_SCALE_S",
    "FeatureScales",
    "TrilaterationEpisode",
    "episode_info",
    "saturate",
    "trilateration_observation",
]
