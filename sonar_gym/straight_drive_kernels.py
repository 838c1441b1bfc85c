"""Compiled loops of the straight drive (:mod:`sonar_gym.straight_drive`) of a run of commands.

:func:`sonar_gym.straight_drive.drive_commands` runs on a few dozen commands per call, where
numpy's per-call cost of the array form (about forty small-array calls) was most of its time.
These loops do that form's elementwise and running-sum arithmetic element by element, in the
same order (running sums as ``cumsum`` adds, left to right), so they return the same bits. The
trigonometry stays in numpy, between the loops (its ``sin`` and ``cos`` of arrays round
differently from libm's): callers pass it in.

For a run of ``K`` commands, in order:

1. :func:`wheel_travel`: each command's encoder increments and ground travel;
2. :func:`command_substeps`: each command's heading change on the ground and its physics
   substeps, and the odometry's substeps (distance and midpoint heading of each);
3. :func:`arc_headings`: the headings of the planned arcs of the ground travel from the
   robot's true pose;
4. :func:`clear_commands`: the planned end poses, and how many commands keep clear of every
   static shape (:func:`clearance`);
5. :func:`odometry_poses`: the dead-reckoned pose after each command.

Positions are metres in {W}, angles radians counter-clockwise from the {W} x-axis.
"""

from __future__ import annotations

import math

import numpy as np
from numba import types

from sonar_gym.compiled import NUMBERS, TABLE, compiled, nan_max, nan_min, wrap_to_pi
from sonar_gym.drive_kernels import encoder_increment, slipped_travel
from sonar_gym.pose import FloatArray

_VECTOR_OUT = types.Array(types.float64, 1, "C")
_INDICES_OUT = types.Array(types.int64, 1, "C")
_TABLE_OUT = types.Array(types.float64, 2, "C")
_SUBSTEPS = types.Array(types.int64, 1, "A", readonly=True)
_POINT = types.UniTuple(types.float64, 2)

ROUNDING_M = 1e-6
"""Slack (metres) added to every clearance bound, for the rounding of the planned path."""
_SMALL_HALF_TURN_RAD = 1e-4
""":func:`sonar_gym.odometry.sinc` takes its series below this argument (radians)."""


@compiled(  # type: ignore[misc]
    types.UniTuple(_TABLE_OUT, 2),
    TABLE,  # commanded
    TABLE,  # normals
    TABLE,  # uniforms
    TABLE,  # slip_probability
    types.float64,  # encoder_std_m_per_sqrt_m
    types.float64,  # scale_error_left
    types.float64,  # scale_error_right
    types.float64,  # slip_fraction_max
)
def wheel_travel(
    commanded: FloatArray,
    normals: FloatArray,
    uniforms: FloatArray,
    slip_probability: FloatArray,
    encoder_std_m_per_sqrt_m: float,
    scale_error_left: float,
    scale_error_right: float,
    slip_fraction_max: float,
) -> tuple[FloatArray, FloatArray]:
    """``(encoder, ground)``, each ``(K, 2)`` ``(left, right)`` (metres): what the encoders
    report and how far the wheels roll for the ``(K, 2)`` ``commanded`` increments, as
    :meth:`~sonar_gym.odometry.OdometryConfig.encoder_increments` and
    :meth:`~sonar_gym.odometry.OdometryConfig.ground_travel` of the arrays.

    Per command, ``normals`` ``(K, 2)`` are its two standard normals and ``uniforms``
    ``(K, 4)`` its slip draws (left, right) then slip sizes (left, right);
    ``slip_probability`` ``(K, 2)`` is numpy's
    :meth:`~sonar_gym.odometry.OdometryConfig.slip_probability` of ``commanded``.
    """
    count = commanded.shape[0]
    encoder = np.empty((count, 2))
    ground = np.empty((count, 2))
    for command in range(count):
        for wheel in range(2):
            encoder[command, wheel] = encoder_increment(
                commanded[command, wheel], encoder_std_m_per_sqrt_m, normals[command, wheel]
            )
            ground[command, wheel] = slipped_travel(
                commanded[command, wheel],
                scale_error_left if wheel == 0 else scale_error_right,
                uniforms[command, wheel],
                uniforms[command, 2 + wheel],
                slip_probability[command, wheel],
                slip_fraction_max,
            )
    return encoder, ground


@compiled(  # type: ignore[misc]
    types.Tuple((_VECTOR_OUT, _INDICES_OUT, _VECTOR_OUT, _VECTOR_OUT, _VECTOR_OUT)),
    TABLE,  # encoder
    TABLE,  # ground
    types.float64,  # wheel_base_m
    types.float64,  # max_substep_m
    types.float64,  # max_substep_rad
    types.float64,  # odometry_theta
)
def command_substeps(
    encoder: FloatArray,
    ground: FloatArray,
    wheel_base_m: float,
    max_substep_m: float,
    max_substep_rad: float,
    odometry_theta: float,
) -> tuple[FloatArray, np.ndarray, FloatArray, FloatArray, FloatArray]:
    """Per command, its heading change on the ground and its physics substeps; per substep,
    the odometry's distance and midpoint heading.

    A command takes enough substeps (at least one) that no wheel travels more than
    ``max_substep_m`` (on the ground or by its encoder) and the heading turns by at most
    ``max_substep_rad`` per substep. The odometry splits the encoder increments evenly over the
    substeps and integrates them from ``odometry_theta`` with the midpoint rule (Kim et al.,
    sec. 3.1).

    Args:
        encoder, ground: ``(K, 2)`` encoder increments and ground travel ``(left, right)``,
            metres.
        wheel_base_m: the wheel base, metres.
        max_substep_m, max_substep_rad: the largest wheel travel (metres) and heading change
            (radians) of one substep.
        odometry_theta: the odometry's heading before the first command, radians.

    Returns:
        ``(ground_turn, substeps, substep_distance, substep_heading, odometry_theta_after)``:
        ``(K,)`` heading changes (radians) and substep counts, ``(M,)`` distances (metres) and
        midpoint headings (radians) of the ``M = sum(substeps)`` substeps, and ``(K,)`` the
        odometry's heading after each command, wrapped to (-pi, pi].
    """
    count = encoder.shape[0]
    ground_turn = np.empty(count)
    substeps = np.empty(count, dtype=np.int64)
    total = 0
    for command in range(count):
        travel = nan_max(
            nan_max(abs(ground[command, 0]), abs(ground[command, 1])),
            nan_max(abs(encoder[command, 0]), abs(encoder[command, 1])),
        )
        turn = (ground[command, 1] - ground[command, 0]) / wheel_base_m
        ground_turn[command] = turn
        substeps[command] = max(
            1, int(np.ceil(travel / max_substep_m)), int(np.ceil(abs(turn) / max_substep_rad))
        )
        total += substeps[command]
    substep_distance = np.empty(total)
    substep_heading = np.empty(total)
    theta_after = np.empty(count)
    turned = 0.0
    substep = 0
    for command in range(count):
        n = substeps[command]
        distance = 0.5 * (encoder[command, 0] + encoder[command, 1]) / n
        turn = (encoder[command, 1] - encoder[command, 0]) / wheel_base_m / n
        for _ in range(n):
            # numpy's theta + concatenate([[0.0], cumsum(turns)]): the sum starts at its first
            # term, and theta + 0.0 differs from theta for theta = -0.0
            theta = odometry_theta + 0.0 if substep == 0 else odometry_theta + turned
            turned = turn if substep == 0 else turned + turn
            substep_distance[substep] = distance
            substep_heading[substep] = theta + 0.5 * turn
            substep += 1
        theta_after[command] = wrap_to_pi(odometry_theta + turned)
    return ground_turn, substeps, substep_distance, substep_heading, theta_after


@compiled(  # type: ignore[misc]
    _TABLE_OUT,
    NUMBERS,  # substep_distance
    NUMBERS,  # heading_cos
    NUMBERS,  # heading_sin
    _SUBSTEPS,  # substeps
    NUMBERS,  # theta_after
    _POINT,  # start
)
def odometry_poses(
    substep_distance: FloatArray,
    heading_cos: FloatArray,
    heading_sin: FloatArray,
    substeps: np.ndarray,
    theta_after: FloatArray,
    start: tuple[float, float],
) -> FloatArray:
    """``(K, 3)`` the odometry's ``[x, y, theta]`` after each command ({W}): the substeps'
    chords (``substep_distance`` times numpy's ``cos`` and ``sin`` of their headings from
    :func:`command_substeps`) added in turn to ``start`` ``(x, y)``, metres."""
    count = substeps.shape[0]
    poses = np.empty((count, 3))
    x, y = start
    substep = 0
    for command in range(count):
        for _ in range(substeps[command]):
            x = x + substep_distance[substep] * heading_cos[substep]
            y = y + substep_distance[substep] * heading_sin[substep]
            substep += 1
        poses[command, 0], poses[command, 1], poses[command, 2] = x, y, theta_after[command]
    return poses


@compiled(  # type: ignore[misc]
    types.Tuple((_VECTOR_OUT, _VECTOR_OUT, _VECTOR_OUT)),
    NUMBERS,  # ground_turn
    types.float64,  # start_theta
)
def arc_headings(
    ground_turn: FloatArray, start_theta: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The planned arcs of ``K`` commands of heading changes ``ground_turn`` (radians) from
    the heading ``start_theta``.

    Returns ``(chord_heading, sinc_argument, theta_after)``, each ``(K,)``: the heading of
    each arc's chord (its start heading plus half its turn), where numpy's ``sin`` is to be
    taken for :func:`sonar_gym.odometry.sinc_of_array` of the half turns (the half turn, or 1
    where the series is used), and the heading after each arc, wrapped to (-pi, pi].
    """
    count = ground_turn.shape[0]
    chord_heading = np.empty(count)
    sinc_argument = np.empty(count)
    theta_after = np.empty(count)
    turned = 0.0
    for command in range(count):
        # as in command_substeps: numpy's start_theta + concatenate([[0.0], cumsum(turns)])
        theta = start_theta + 0.0 if command == 0 else start_theta + turned
        turned = ground_turn[command] if command == 0 else turned + ground_turn[command]
        half_turn = 0.5 * ground_turn[command]
        chord_heading[command] = theta + half_turn
        sinc_argument[command] = 1.0 if abs(half_turn) < _SMALL_HALF_TURN_RAD else half_turn
        theta_after[command] = wrap_to_pi(start_theta + turned)
    return chord_heading, sinc_argument, theta_after


def _clip_unit(value: float) -> float:
    """``np.clip(value, 0.0, 1.0)`` (NaN stays NaN)."""
    if value != value:
        return value
    above = value if value > 0.0 else 0.0
    return above if above < 1.0 else 1.0


_clip_unit_compiled = compiled(types.float64, types.float64, inline=True)(_clip_unit)


def _clearance(
    points: FloatArray,
    within_m: float,
    segment_starts: FloatArray,
    segment_ends: FloatArray,
    circles: FloatArray,
) -> FloatArray:
    count = points.shape[0]
    low_x, low_y = points[0, 0], points[0, 1]
    high_x, high_y = low_x, low_y
    for point in range(1, count):
        low_x, high_x = nan_min(low_x, points[point, 0]), nan_max(high_x, points[point, 0])
        low_y, high_y = nan_min(low_y, points[point, 1]), nan_max(high_y, points[point, 1])
    reach = within_m + ROUNDING_M
    near_segments = np.empty(segment_starts.shape[0], dtype=np.int64)
    n_segments = 0
    for segment in range(segment_starts.shape[0]):
        start_x, start_y = segment_starts[segment, 0], segment_starts[segment, 1]
        end_x, end_y = segment_ends[segment, 0], segment_ends[segment, 1]
        if (
            nan_min(start_x, end_x) - high_x <= reach
            and low_x - nan_max(start_x, end_x) <= reach
            and nan_min(start_y, end_y) - high_y <= reach
            and low_y - nan_max(start_y, end_y) <= reach
        ):
            near_segments[n_segments] = segment
            n_segments += 1
    near_circles = np.empty(circles.shape[0], dtype=np.int64)
    n_circles = 0
    for circle in range(circles.shape[0]):
        centre_x, centre_y, radius = circles[circle, 0], circles[circle, 1], circles[circle, 2]
        if (
            centre_x - radius - high_x <= reach
            and low_x - centre_x - radius <= reach
            and centre_y - radius - high_y <= reach
            and low_y - centre_y - radius <= reach
        ):
            near_circles[n_circles] = circle
            n_circles += 1
    nearest = np.full(count, math.inf)
    for point in range(count):
        x, y = points[point, 0], points[point, 1]
        if n_segments:
            closest = math.inf
            for index in range(n_segments):
                segment = near_segments[index]
                start_x, start_y = segment_starts[segment, 0], segment_starts[segment, 1]
                edge_x = segment_ends[segment, 0] - start_x
                edge_y = segment_ends[segment, 1] - start_y
                length_sq = nan_max(edge_x * edge_x + edge_y * edge_y, 1e-24)
                rel_x, rel_y = x - start_x, y - start_y
                t = _clip_unit_compiled((rel_x * edge_x + rel_y * edge_y) / length_sq)
                gap_x, gap_y = rel_x - t * edge_x, rel_y - t * edge_y
                distance = math.sqrt(gap_x * gap_x + gap_y * gap_y)
                closest = distance if index == 0 else nan_min(closest, distance)
            nearest[point] = nan_min(nearest[point], closest)
        if n_circles:
            closest = math.inf
            for index in range(n_circles):
                circle = near_circles[index]
                gap = abs(
                    math.hypot(x - circles[circle, 0], y - circles[circle, 1]) - circles[circle, 2]
                )
                closest = gap if index == 0 else nan_min(closest, gap)
            nearest[point] = nan_min(nearest[point], closest)
    return nearest


_CLEARANCE_SIGNATURE = (_VECTOR_OUT, TABLE, types.float64, TABLE, TABLE, TABLE)
_clearance_compiled = compiled(*_CLEARANCE_SIGNATURE, inline=True)(_clearance)
clearance = compiled(*_CLEARANCE_SIGNATURE)(_clearance)
"""``clearance(points, within_m, segment_starts, segment_ends, circles)``: ``(P,)`` the
distance (metres) from each of the ``(P, 2)`` points ({W}) to the nearest of the static segments
``segment_starts`` to ``segment_ends`` ``(S, 2)`` and circles ``(C, 3)`` ``[x, y, radius]``,
exact up to ``within_m``: shapes whose bounding box lies farther than ``within_m`` from the
points' bounding box are left out, so a point whose nearest shape is farther gets some value
above ``within_m`` (``inf`` with none left)."""


@compiled(  # type: ignore[misc]
    types.int64,
    TABLE,  # ground
    NUMBERS,  # ground_turn
    NUMBERS,  # sinc_sine
    NUMBERS,  # chord_cos
    NUMBERS,  # chord_sin
    NUMBERS,  # theta_after
    _POINT,  # start
    types.float64,  # margin_m
    TABLE,  # segment_starts
    TABLE,  # segment_ends
    TABLE,  # circles
    types.Array(types.float64, 2, "A"),  # out
)
def clear_commands(
    ground: FloatArray,
    ground_turn: FloatArray,
    sinc_sine: FloatArray,
    chord_cos: FloatArray,
    chord_sin: FloatArray,
    theta_after: FloatArray,
    start: tuple[float, float],
    margin_m: float,
    segment_starts: FloatArray,
    segment_ends: FloatArray,
    circles: FloatArray,
    out: FloatArray,
) -> int:
    """How many of ``K`` commands, from ``start`` ``(x, y)`` (metres, {W}), keep the robot at
    more than ``margin_m`` (its radius plus a margin, metres) from every static shape; fills
    ``out[:k]`` with their planned end poses ``[x, y, theta]`` (``k`` the returned count).

    Each command rolls the arc of its ``(K, 2)`` ``ground`` travel (metres), turning by
    ``ground_turn`` (radians): its chord is ``(d_l + d_r) / 2 sinc(turn / 2)`` long (the sinc
    from ``sinc_sine``, numpy's ``sin`` of :func:`arc_headings`' sinc arguments) along the
    heading whose numpy ``cos`` and ``sin`` are ``chord_cos`` and ``chord_sin``; it ends
    heading ``theta_after``. Distance to a shape is 1-Lipschitz: no point of a chord is nearer a
    shape than the chord's nearer end minus half its length, and the arc leaves its chord by at
    most its sagitta, ``|d dtheta| / 8``; so a command is clear when both its ends are farther
    than that reach plus ``margin_m`` from the static shapes (:data:`clearance`; segments
    ``segment_starts`` to ``segment_ends``, circles ``[x, y, radius]``).
    """
    count = ground.shape[0]
    ends = np.empty((count + 1, 2))
    ends[0, 0], ends[0, 1] = start
    reach = np.empty(count)
    farthest = -math.inf
    for command in range(count):
        distance = 0.5 * (ground[command, 0] + ground[command, 1])
        half_turn = 0.5 * ground_turn[command]
        if abs(half_turn) < _SMALL_HALF_TURN_RAD:
            sinc = 1.0 - half_turn * half_turn / 6.0
        else:
            sinc = sinc_sine[command] / half_turn
        chord = distance * sinc
        ends[command + 1, 0] = ends[command, 0] + chord * chord_cos[command]
        ends[command + 1, 1] = ends[command, 1] + chord * chord_sin[command]
        reach[command] = (
            0.5 * abs(distance) + abs(distance * ground_turn[command]) / 8.0 + ROUNDING_M
        )
        farthest = reach[command] if command == 0 else nan_max(farthest, reach[command])
    gaps = _clearance_compiled(ends, farthest + margin_m, segment_starts, segment_ends, circles)
    free = count
    for command in range(count):
        if not nan_min(gaps[command], gaps[command + 1]) - reach[command] > margin_m:
            free = command
            break
    for command in range(free):
        out[command, 0] = ends[command + 1, 0]
        out[command, 1] = ends[command + 1, 1]
        out[command, 2] = theta_after[command]
    return free
