"""Compiled loops of driving: a run of commands' random draws, the plan of a route's commands
from the estimate, and the drive of commands where no physics is needed, alone or with the EKF
prediction over its encoder increments (numba, :mod:`sonar_gym.compiled`).

numba's ``Generator`` draws from the caller's bit generator with numpy's own algorithms, so
the loops (handed the generator by :mod:`sonar_gym.generator_handles`, which spares each call
numba's conversion of the ``Generator`` object) take the same numbers, in the same order, as
:meth:`~sonar_gym.robot.DifferentialDriveRobot.drive` (two standard normals, then four
uniforms, per command) and leave the generator in the same state. The arithmetic is the
Python loops' (``math.cos`` and ``math.sin`` are libm's in both; headings wrap as
:class:`~sonar_gym.pose.Pose` wraps them), so the plans are the same bits.
"""

from __future__ import annotations

import math

import numpy as np
from numba import types

from sonar_gym.compiled import INDICES, NUMBERS, TABLE, compiled, wrap_angle
from sonar_gym.generator_handles import (
    GENERATOR_HANDLE,
    GeneratorHandle,
    generator_handle,
    handle_generator,
)
from sonar_gym.odometry_kernels import predict_commands
from sonar_gym.path_clearance import arc_is_clear
from sonar_gym.pose import FloatArray

_GENERATOR = types.NumPyRandomGeneratorType("NumPyRandomGeneratorType")
_DRAWS = types.Tuple((types.Array(types.float64, 2, "C"), types.Array(types.float64, 2, "C")))


def _draw_into(rng: np.random.Generator, normals: FloatArray, uniforms: FloatArray) -> None:
    """One command's numbers per row of ``normals`` ``(K, 2)`` and ``uniforms`` ``(K, 4)``."""
    for command in range(normals.shape[0]):
        normals[command, 0] = rng.standard_normal()
        normals[command, 1] = rng.standard_normal()
        for slot in range(4):
            uniforms[command, slot] = rng.random()


_draw_into_compiled = compiled(
    types.none,
    _GENERATOR,
    types.Array(types.float64, 2, "C"),
    types.Array(types.float64, 2, "C"),
    inline=True,
)(_draw_into)


@compiled(_DRAWS, GENERATOR_HANDLE, types.int64)  # type: ignore[misc]
def _draw_commands_compiled(handle: GeneratorHandle, count: int) -> tuple[FloatArray, FloatArray]:
    normals = np.empty((count, 2))
    uniforms = np.empty((count, 4))
    _draw_into_compiled(handle_generator(handle), normals, uniforms)
    return normals, uniforms


def _draw_run(rng: np.random.Generator, draws: FloatArray) -> None:
    """The numbers of ``len(draws) / 6`` commands into ``draws``: per command two standard
    normals, then four uniforms (the layout of :func:`drive_commands`' ``draws``)."""
    for first in range(0, draws.shape[0], 6):
        draws[first] = rng.standard_normal()
        draws[first + 1] = rng.standard_normal()
        for slot in range(first + 2, first + 6):
            draws[slot] = rng.random()


_draw_run_compiled = compiled(
    types.none, _GENERATOR, types.Array(types.float64, 1, "C"), inline=True
)(_draw_run)


def draw_commands(rng: np.random.Generator, count: int) -> tuple[FloatArray, FloatArray]:
    """The random numbers of ``count`` drive commands: ``(count, 2)`` standard normals and
    ``(count, 4)`` uniforms, drawn command by command from ``rng`` (in one compiled loop,
    handed ``rng`` by :func:`~sonar_gym.generator_handles.generator_handle`)."""
    return _draw_commands_compiled(generator_handle(rng), count)  # type: ignore[no-any-return]


def _grown_rows(table: FloatArray, rows: int) -> FloatArray:
    out = np.empty((rows, table.shape[1]))
    out[: table.shape[0]] = table
    return out


_grown_rows_compiled = compiled(
    types.Array(types.float64, 2, "C"), types.Array(types.float64, 2, "C"), types.int64, inline=True
)(_grown_rows)

_PLAN = types.Tuple(
    (
        types.Array(types.float64, 2, "C"),  # commanded (d_left, d_right)
        types.Array(types.float64, 2, "C"),  # normals
        types.Array(types.float64, 2, "C"),  # uniforms
        types.Array(types.int64, 2, "C"),  # stops: (command count, next waypoint)
        types.UniTuple(types.float64, 3),  # the dead-reckoned end pose
    )
)


@compiled(  # type: ignore[misc]
    _PLAN,
    GENERATOR_HANDLE,
    TABLE,  # targets
    types.int64,  # waypoint
    types.UniTuple(types.float64, 3),  # pose
    types.float64,  # step_m
    types.int64,  # steps_per_aim
    types.float64,  # wheel_base_m
    types.float64,  # encoder_std_m_per_sqrt_m
    types.float64,  # tolerance_rad
)
def _plan_to_targets_compiled(
    handle: GeneratorHandle,
    targets: FloatArray,
    waypoint: int,
    pose: tuple[float, float, float],
    step_m: float,
    steps_per_aim: int,
    wheel_base_m: float,
    encoder_std_m_per_sqrt_m: float,
    tolerance_rad: float,
) -> tuple[FloatArray, FloatArray, FloatArray, np.ndarray, tuple[float, float, float]]:
    rng = handle_generator(handle)
    capacity = 64
    commanded = np.empty((capacity, 2))
    normals = np.empty((capacity, 2))
    uniforms = np.empty((capacity, 4))
    stops = np.empty((16, 2), dtype=np.int64)
    count = 0
    n_stops = 0
    x, y, theta = pose
    step_noise = encoder_std_m_per_sqrt_m * math.sqrt(abs(step_m))
    while waypoint < targets.shape[0]:
        dx, dy = targets[waypoint, 0] - x, targets[waypoint, 1] - y
        remaining = int(np.rint(math.hypot(dx, dy) / step_m))
        if remaining == 0:
            waypoint += 1
            continue
        n = min(remaining, steps_per_aim)
        if count + n + 1 > capacity:
            capacity = 2 * capacity + n + 1
            commanded = _grown_rows_compiled(commanded, capacity)
            normals = _grown_rows_compiled(normals, capacity)
            uniforms = _grown_rows_compiled(uniforms, capacity)
        turn = wrap_angle(math.atan2(dy, dx) - theta)
        if abs(turn) > tolerance_rad:
            half = 0.5 * turn * wheel_base_m
            _draw_into_compiled(rng, normals[count : count + 1], uniforms[count : count + 1])
            left = -half + encoder_std_m_per_sqrt_m * math.sqrt(abs(half)) * normals[count, 0]
            right = half + encoder_std_m_per_sqrt_m * math.sqrt(abs(half)) * normals[count, 1]
            distance, turned = 0.5 * (right + left), (right - left) / wheel_base_m
            heading = theta + 0.5 * turned
            x, y = x + distance * math.cos(heading), y + distance * math.sin(heading)
            theta = wrap_angle(theta + turned)
            commanded[count, 0], commanded[count, 1] = -half, half
            count += 1
        _draw_into_compiled(rng, normals[count : count + n], uniforms[count : count + n])
        for command in range(count, count + n):
            left = step_m + step_noise * normals[command, 0]
            right = step_m + step_noise * normals[command, 1]
            distance, turned = 0.5 * (right + left), (right - left) / wheel_base_m
            heading = theta + 0.5 * turned
            x, y = x + distance * math.cos(heading), y + distance * math.sin(heading)
            theta = wrap_angle(theta + turned)
            commanded[command, 0], commanded[command, 1] = step_m, step_m
        count += n
        if n < steps_per_aim:
            waypoint += 1
        if n_stops == stops.shape[0]:
            more = np.empty((2 * n_stops, 2), dtype=np.int64)
            more[:n_stops] = stops
            stops = more
        stops[n_stops, 0], stops[n_stops, 1] = count, waypoint
        n_stops += 1
    return (
        commanded[:count].copy(),
        normals[:count].copy(),
        uniforms[:count].copy(),
        stops[:n_stops].copy(),
        (x, y, theta),
    )


def plan_to_targets(
    rng: np.random.Generator,
    targets: FloatArray,
    waypoint: int,
    pose: tuple[float, float, float],
    step_m: float,
    steps_per_aim: int,
    wheel_base_m: float,
    encoder_std_m_per_sqrt_m: float,
    tolerance_rad: float,
) -> tuple[FloatArray, FloatArray, FloatArray, np.ndarray, tuple[float, float, float]]:
    """Plan, from ``pose`` (the estimate, {W}), the drive commands to ``targets[waypoint:]``.

    Steering points come every ``steps_per_aim`` straight commands of ``step_m`` per wheel
    and at the start of each target: there the remaining straight commands are
    ``round(distance / step_m)`` (to the nearest, ties to even, as Python's ``round``) and the
    bearing to the target is taken; a bearing off by more than ``tolerance_rad`` is first
    turned in place (wheels ``-+ turn l / 2``). A target fewer than half a step away is
    passed. Every command draws its numbers (two normals, four uniforms, as
    :func:`draw_commands`) and is dead-reckoned with its encoder reading ``d + encoder_std
    sqrt(|d|) normal`` per wheel (midpoint integration).

    Returns the ``(K, 2)`` commanded increments ``(d_left, d_right)`` (metres), their
    ``(K, 2)`` normals and ``(K, 4)`` uniforms, the steering points as rows ``(commands
    planned so far, target aimed at from there)`` and the end pose. The distance is libm's
    ``hypot``, which can differ from Python's ``math.hypot`` by one rounding; that changes
    the count only for a distance within one rounding of a half step.
    """
    return _plan_to_targets_compiled(  # type: ignore[no-any-return]
        generator_handle(rng),
        targets,
        waypoint,
        pose,
        step_m,
        steps_per_aim,
        wheel_base_m,
        encoder_std_m_per_sqrt_m,
        tolerance_rad,
    )


EULER, MIDPOINT, ARC = 0, 1, 2
"""Codes of :data:`sonar_gym.odometry.INTEGRATIONS` (their indices) for the loops below."""


def _sinc(x: float) -> float:
    if abs(x) < 1e-4:
        return 1.0 - x * x / 6.0
    return math.sin(x) / x


_sinc_compiled = compiled(types.float64, types.float64, inline=True)(_sinc)


def _integrate_substeps(
    x: float,
    y: float,
    theta: float,
    d_left_m: float,
    d_right_m: float,
    wheel_base_m: float,
    substeps: int,
    integration: int,
) -> tuple[float, float, float]:
    n = substeps
    distance = 0.5 * (d_left_m + d_right_m) / n
    delta = (d_right_m - d_left_m) / (wheel_base_m * n)
    if delta == 0.0:
        return x + n * distance * math.cos(theta), y + n * distance * math.sin(theta), theta
    lead = 0.0 if integration == EULER else 0.5
    if integration == ARC:
        distance *= _sinc_compiled(0.5 * delta)
    half = 0.5 * delta
    gain = float(n) if abs(half) < 1e-300 else math.sin(n * half) / math.sin(half)
    heading = theta + (lead + 0.5 * (n - 1)) * delta
    return (
        x + distance * gain * math.cos(heading),
        y + distance * gain * math.sin(heading),
        wrap_angle(theta + n * delta),
    )


_integrate_substeps_compiled = compiled(
    types.UniTuple(types.float64, 3), *[types.float64] * 6, types.int64, types.int64, inline=True
)(_integrate_substeps)
""":func:`sonar_gym.odometry.integrate_substeps` of ``(x, y, theta)`` inside a compiled loop
(the integration as a code: :data:`EULER`, :data:`MIDPOINT`, :data:`ARC`)."""


def _encoder_increment(commanded_m: float, encoder_std_m_per_sqrt_m: float, normal: float) -> float:
    return commanded_m + encoder_std_m_per_sqrt_m * math.sqrt(abs(commanded_m)) * normal


encoder_increment = compiled(types.float64, *[types.float64] * 3, inline=True)(_encoder_increment)
""":meth:`sonar_gym.odometry.OdometryConfig.encoder_increments` of one wheel inside a compiled
loop: ``encoder_increment(commanded_m, encoder_std_m_per_sqrt_m, normal)``, metres."""


def _slipped_travel(
    commanded_m: float,
    scale_error: float,
    slip_draw: float,
    size_draw: float,
    slip_probability: float,
    slip_fraction_max: float,
) -> float:
    slip_loss = size_draw * slip_fraction_max if slip_draw < slip_probability else 0.0
    return commanded_m * (1.0 + scale_error) * (1.0 - slip_loss)


slipped_travel = compiled(types.float64, *[types.float64] * 6, inline=True)(_slipped_travel)
""":meth:`sonar_gym.odometry.OdometryConfig.ground_travel` of one wheel inside a compiled loop,
given its :meth:`~sonar_gym.odometry.OdometryConfig.slip_probability`: ``slipped_travel(
commanded_m, scale_error, slip_draw, size_draw, slip_probability, slip_fraction_max)``,
metres."""


def _ground_travel(
    commanded_m: float,
    scale_error: float,
    slip_draw: float,
    size_draw: float,
    slip_probability_per_m: float,
    slip_fraction_max: float,
) -> float:
    slip_probability = 1.0 - (1.0 - slip_probability_per_m) ** abs(commanded_m)
    return slipped_travel(
        commanded_m, scale_error, slip_draw, size_draw, slip_probability, slip_fraction_max
    )


_ground_travel_compiled = compiled(types.float64, *[types.float64] * 6, inline=True)(_ground_travel)

ENCODER, GROUND, SUBSTEPS, ODOMETRY, TRUE_POSE, PATH_LENGTH = 0, 2, 4, 5, 8, 11
"""First columns of a motion table (:func:`drive_commands`): the encoder increments ``(left,
right)`` and the ground travel (metres), the physics substeps, the odometry pose and the true
pose after the command (``(x, y, theta)``, {W}) and the true centre's path length (metres)."""
MOTION_COLUMNS = 12

_MOTIONS = types.Array(types.float64, 2, "C")
_SHAPES = (TABLE, INDICES, TABLE)  # StaticShapeTable: bounds, kinds, shapes


def _clear_arcs(
    motions: FloatArray,
    first: int,
    start: tuple[float, float, float],
    wheel_base_m: float,
    robot_radius_m: float,
    bounds: FloatArray,
    kinds: np.ndarray,
    shapes: FloatArray,
) -> int:
    x, y, theta = start
    for command in range(first, motions.shape[0]):
        left, right = motions[command, GROUND], motions[command, GROUND + 1]
        end_x, end_y, end_theta = _integrate_substeps_compiled(
            x, y, theta, left, right, wheel_base_m, 1, ARC
        )
        if not arc_is_clear(
            x, y, end_x, end_y, left, right, wheel_base_m, robot_radius_m, bounds, kinds, shapes
        ):
            return command
        half_turn = 0.5 * (right - left) / (wheel_base_m * motions[command, SUBSTEPS])
        motions[command, PATH_LENGTH] = abs(0.5 * (left + right)) * abs(_sinc_compiled(half_turn))
        motions[command, TRUE_POSE] = end_x
        motions[command, TRUE_POSE + 1] = end_y
        motions[command, TRUE_POSE + 2] = end_theta
        x, y, theta = end_x, end_y, end_theta
    return motions.shape[0]


_CLEAR_ARCS_SIGNATURE = (
    types.int64,
    _MOTIONS,  # motions (written)
    types.int64,  # first
    types.UniTuple(types.float64, 3),  # start
    types.float64,  # wheel_base_m
    types.float64,  # robot_radius_m
    *_SHAPES,
)
_clear_arcs_compiled = compiled(*_CLEAR_ARCS_SIGNATURE, inline=True)(_clear_arcs)
clear_arcs = compiled(*_CLEAR_ARCS_SIGNATURE)(_clear_arcs)
"""``clear_arcs(motions, first, start, wheel_base_m, robot_radius_m, bounds, kinds, shapes)``:
the true motion of the commands of the motion table ``motions`` from ``first`` on, from
``start`` (``(x, y, theta)``, {W}), while each one's arc (:data:`ARC`, of its ground travel)
is clear of the static shapes ``(bounds, kinds, shapes)``
(:data:`sonar_gym.path_clearance.arc_is_clear`): pymunk would impose it exactly, so the robot
ends where the arc ends and its centre travels the chords of the substeps. Writes each clear
command's true pose and path length; returns the first command that is not clear (``K`` if
none)."""


def _drive_commands(
    commands_m: FloatArray,
    draws: FloatArray,
    noise: FloatArray,
    wheel_base_m: float,
    substeps: int,
    integration: int,
    odometry: tuple[float, float, float],
    start: tuple[float, float, float],
    robot_radius_m: float,
    bounds: FloatArray,
    kinds: np.ndarray,
    shapes: FloatArray,
) -> tuple[FloatArray, int]:
    encoder_std, scale_left, scale_right = noise[0], noise[1], noise[2]
    slip_probability, slip_fraction = noise[3], noise[4]
    max_substep_m, max_substep_rad = noise[5], noise[6]
    count = commands_m.shape[0]
    motions = np.empty((count, MOTION_COLUMNS))
    x, y, theta = odometry
    for command in range(count):
        left, right = commands_m[command, 0], commands_m[command, 1]
        first = 6 * command
        encoder_left = encoder_increment(left, encoder_std, draws[first])
        encoder_right = encoder_increment(right, encoder_std, draws[first + 1])
        ground_left = _ground_travel_compiled(
            left, scale_left, draws[first + 2], draws[first + 4], slip_probability, slip_fraction
        )
        ground_right = _ground_travel_compiled(
            right, scale_right, draws[first + 3], draws[first + 5], slip_probability, slip_fraction
        )
        if substeps > 0:
            n = substeps
        else:
            travel = max(abs(ground_left), abs(ground_right), abs(encoder_left), abs(encoder_right))
            turn = abs(ground_right - ground_left) / wheel_base_m
            n = max(1, math.ceil(travel / max_substep_m), math.ceil(turn / max_substep_rad))
        x, y, theta = _integrate_substeps_compiled(
            x, y, theta, encoder_left, encoder_right, wheel_base_m, n, integration
        )
        row = motions[command]
        row[ENCODER], row[ENCODER + 1] = encoder_left, encoder_right
        row[GROUND], row[GROUND + 1] = ground_left, ground_right
        row[SUBSTEPS] = n
        row[ODOMETRY], row[ODOMETRY + 1], row[ODOMETRY + 2] = x, y, theta
    blocked = _clear_arcs_compiled(
        motions, 0, start, wheel_base_m, robot_radius_m, bounds, kinds, shapes
    )
    return motions, blocked


_DRIVE_ARGUMENTS = (
    TABLE,  # commands_m
    NUMBERS,  # draws
    NUMBERS,  # noise
    types.float64,  # wheel_base_m
    types.int64,  # substeps
    types.int64,  # integration
    types.UniTuple(types.float64, 3),  # odometry
    types.UniTuple(types.float64, 3),  # start
    types.float64,  # robot_radius_m
    *_SHAPES,
)
_DRIVE = types.Tuple((_MOTIONS, types.int64))
_drive_commands_compiled = compiled(_DRIVE, *_DRIVE_ARGUMENTS, inline=True)(_drive_commands)


@compiled(_DRIVE, *_DRIVE_ARGUMENTS)  # type: ignore[misc]
def drive_commands(
    commands_m: FloatArray,
    draws: FloatArray,
    noise: FloatArray,
    wheel_base_m: float,
    substeps: int,
    integration: int,
    odometry: tuple[float, float, float],
    start: tuple[float, float, float],
    robot_radius_m: float,
    bounds: FloatArray,
    kinds: np.ndarray,
    shapes: FloatArray,
) -> tuple[FloatArray, int]:
    """:meth:`~sonar_gym.robot.DifferentialDriveRobot.drive` of each of the ``(K, 2)``
    commanded increments ``commands_m`` (``(d_l, d_r)``, metres), as far as no physics is
    needed.

    Per command: the draws of ``drive`` (``draws``: ``6 K`` numbers, two standard normals then
    four uniforms per command, in the order :func:`draw_commands` draws them); the encoder
    increments and the ground travel of :class:`~sonar_gym.odometry.OdometryConfig`
    (``noise``: its five fields in their order, then the robot's ``max_substep_m`` and
    ``max_substep_rad``); the physics substeps (``substeps``, or if 0 enough that no wheel
    travels more than ``max_substep_m`` and the heading turns by at most ``max_substep_rad``
    per substep); the odometry integrated over them from ``odometry`` (``(x, y, theta)``,
    {W}; ``integration`` a code :data:`EULER`, :data:`MIDPOINT` or :data:`ARC`); then the
    true motion from ``start`` while it is clear (:data:`clear_arcs`).

    Returns the ``(K, MOTION_COLUMNS)`` motion table (columns :data:`ENCODER` ...) and the
    first command that needs the physics (``K`` if none); that command's and the later ones'
    true poses and path lengths are not written.
    """
    return _drive_commands_compiled(
        commands_m,
        draws,
        noise,
        wheel_base_m,
        substeps,
        integration,
        odometry,
        start,
        robot_radius_m,
        bounds,
        kinds,
        shapes,
    )


_PREDICTED_DRIVE = types.Tuple(
    (_MOTIONS, types.int64, types.UniTuple(types.float64, 3), types.Array(types.float64, 2, "C"))
)
_PREDICTION_ARGUMENTS = (
    types.UniTuple(types.float64, 3),  # estimate
    TABLE,  # covariance
    types.float64,  # variance_per_m
)


def _drive_and_predict(
    rng: np.random.Generator,
    commands_m: FloatArray,
    noise: FloatArray,
    wheel_base_m: float,
    substeps: int,
    integration: int,
    odometry: tuple[float, float, float],
    start: tuple[float, float, float],
    robot_radius_m: float,
    bounds: FloatArray,
    kinds: np.ndarray,
    shapes: FloatArray,
    estimate: tuple[float, float, float],
    covariance: FloatArray,
    variance_per_m: float,
) -> tuple[FloatArray, int, tuple[float, float, float], FloatArray]:
    draws = np.empty(6 * commands_m.shape[0])
    _draw_run_compiled(rng, draws)
    motions, blocked = _drive_commands_compiled(
        commands_m,
        draws,
        noise,
        wheel_base_m,
        substeps,
        integration,
        odometry,
        start,
        robot_radius_m,
        bounds,
        kinds,
        shapes,
    )
    predicted, predicted_covariance = predict_commands(
        estimate,
        covariance,
        motions[:, ENCODER : ENCODER + 2],
        wheel_base_m,
        variance_per_m,
        0.0,
        False,
    )
    last = predicted.shape[0] - 1
    end = (predicted[last, 0], predicted[last, 1], predicted[last, 2])
    return motions, blocked, end, predicted_covariance


_drive_and_predict_inline = compiled(
    _PREDICTED_DRIVE,
    _GENERATOR,
    _DRIVE_ARGUMENTS[0],  # commands_m
    *_DRIVE_ARGUMENTS[2:],
    *_PREDICTION_ARGUMENTS,
    inline=True,
)(_drive_and_predict)


def _move_commands(
    belief: tuple[float, float, float],
    target_xy: tuple[float, float],
    distance_m: float,
    wheel_base_m: float,
) -> FloatArray:
    x, y, theta = belief
    if distance_m > 1e-9:
        bearing = math.atan2(target_xy[1] - y, target_xy[0] - x)
        half = 0.5 * wrap_angle(bearing - theta) * wheel_base_m
        commands = np.empty((2, 2))
        commands[0, 0], commands[0, 1] = -half, half
        commands[1, 0], commands[1, 1] = distance_m, distance_m
        return commands
    return np.zeros((1, 2))


move_commands = compiled(
    types.Array(types.float64, 2, "C"),
    types.UniTuple(types.float64, 3),  # belief
    types.UniTuple(types.float64, 2),  # target_xy
    types.float64,  # distance_m
    types.float64,  # wheel_base_m
    inline=True,
)(_move_commands)
""":func:`sonar_gym.robot.move_commands` to a point, no heading, inside a compiled loop, as a
``(K, 2)`` table: ``move_commands(belief, target_xy, distance_m, wheel_base_m)`` from
``belief`` (``(x, y, theta)``, {W}) to ``target_xy`` (metres) whose distance from it is
``distance_m``, Python's ``math.hypot`` of the differences (taken by the caller: it is not
libm's ``hypot``)."""


@compiled(  # type: ignore[misc]
    _PREDICTED_DRIVE,
    GENERATOR_HANDLE,  # handle
    types.UniTuple(types.float64, 2),  # target_xy
    types.float64,  # distance_m
    *_DRIVE_ARGUMENTS[2:],
    *_PREDICTION_ARGUMENTS,
)
def _drive_to_and_predict_compiled(
    handle: GeneratorHandle,
    target_xy: tuple[float, float],
    distance_m: float,
    noise: FloatArray,
    wheel_base_m: float,
    substeps: int,
    integration: int,
    odometry: tuple[float, float, float],
    start: tuple[float, float, float],
    robot_radius_m: float,
    bounds: FloatArray,
    kinds: np.ndarray,
    shapes: FloatArray,
    estimate: tuple[float, float, float],
    covariance: FloatArray,
    variance_per_m: float,
) -> tuple[FloatArray, int, tuple[float, float, float], FloatArray]:
    return _drive_and_predict_inline(  # type: ignore[no-any-return]
        handle_generator(handle),
        move_commands(estimate, target_xy, distance_m, wheel_base_m),
        noise,
        wheel_base_m,
        substeps,
        integration,
        odometry,
        start,
        robot_radius_m,
        bounds,
        kinds,
        shapes,
        estimate,
        covariance,
        variance_per_m,
    )


def drive_to_and_predict(
    rng: np.random.Generator,
    target_xy: tuple[float, float],
    distance_m: float,
    noise: FloatArray,
    wheel_base_m: float,
    substeps: int,
    integration: int,
    odometry: tuple[float, float, float],
    start: tuple[float, float, float],
    robot_radius_m: float,
    bounds: FloatArray,
    kinds: np.ndarray,
    shapes: FloatArray,
    estimate: tuple[float, float, float],
    covariance: FloatArray,
    variance_per_m: float,
) -> tuple[FloatArray, int, tuple[float, float, float], FloatArray]:
    """The drive to the point ``target_xy`` ({W}, metres) planned from ``estimate`` (the
    commands of :func:`sonar_gym.robot.move_commands` without a heading: the turn towards the
    point, then the straight of ``distance_m``, Python's ``math.hypot`` of the differences;
    one command of no travel if the point is within 1 nm), with the EKF prediction over it, in
    one compiled call handed ``rng`` by
    :func:`~sonar_gym.generator_handles.generator_handle`.

    Per command: :func:`drive_commands` with its draws taken from ``rng`` (the numbers of
    :func:`draw_commands`, in its order, leaving ``rng`` as it leaves it); then the EKF
    prediction (Kim et al. sec. 3.1 eqs. (5)-(6)) over the commands' encoder increments from
    ``estimate`` (``(x, y, theta)``, {W}) and its ``covariance``:
    :func:`sonar_gym.odometry_kernels.predict_commands` with the paper's Jacobians, ``V`` of
    ``variance_per_m`` m^2 per metre rolled and no scale variance.

    Returns the motion table (its commands those planned), the first command that needs the
    physics, the predicted pose after the last command and its 3x3 covariance.
    """
    return _drive_to_and_predict_compiled(  # type: ignore[no-any-return]
        generator_handle(rng),
        target_xy,
        distance_m,
        noise,
        wheel_base_m,
        substeps,
        integration,
        odometry,
        start,
        robot_radius_m,
        bounds,
        kinds,
        shapes,
        estimate,
        covariance,
        variance_per_m,
    )
