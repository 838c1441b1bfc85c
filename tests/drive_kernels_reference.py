"""``sonar_gym.drive_kernels.draw_commands`` and ``plan_to_targets`` as they were written,
taking the numpy ``Generator`` itself as an argument, kept as the tests' reference for the
forms that take its bit generator's handle."""

from __future__ import annotations

import math

import numpy as np
from numba import types

from sonar_gym.compiled import TABLE, compiled, wrap_angle
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


@compiled(_DRAWS, _GENERATOR, types.int64)  # type: ignore[misc]
def draw_commands(rng: np.random.Generator, count: int) -> tuple[FloatArray, FloatArray]:
    """The random numbers of ``count`` drive commands: ``(count, 2)`` standard normals and
    ``(count, 4)`` uniforms, drawn command by command from ``rng``."""
    normals = np.empty((count, 2))
    uniforms = np.empty((count, 4))
    _draw_into_compiled(rng, normals, uniforms)
    return normals, uniforms


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
    _GENERATOR,
    TABLE,  # targets
    types.int64,  # waypoint
    types.UniTuple(types.float64, 3),  # pose
    types.float64,  # step_m
    types.int64,  # steps_per_aim
    types.float64,  # wheel_base_m
    types.float64,  # encoder_std_m_per_sqrt_m
    types.float64,  # tolerance_rad
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
