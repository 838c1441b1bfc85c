"""Compiled loops of driving: a run of commands' random draws, and the dead reckoning of a
planned straight run (numba, :mod:`sonar_gym.compiled`).

numba's ``Generator`` draws from the caller's bit generator with numpy's own algorithms, so
the loops take the same numbers, in the same order, as
:meth:`~sonar_gym.robot.DifferentialDriveRobot.drive` (two standard normals, then four
uniforms, per command) and leave the generator in the same state. The arithmetic is the
Python loops' (``math.cos`` and ``math.sin`` are libm's in both; headings wrap as
:class:`~sonar_gym.pose.Pose` wraps them), so the plans are the same bits.
"""

from __future__ import annotations

import math

import numpy as np
from numba import types

from sonar_gym.compiled import compiled, wrap_angle
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


@compiled(  # type: ignore[misc]
    types.Tuple((types.UniTuple(types.float64, 3), *_DRAWS.types)),
    _GENERATOR,
    types.UniTuple(types.float64, 3),  # pose
    types.int64,  # count
    types.float64,  # step_m
    types.float64,  # step_noise_m
    types.float64,  # wheel_base_m
)
def dead_reckon_straight(
    rng: np.random.Generator,
    pose: tuple[float, float, float],
    count: int,
    step_m: float,
    step_noise_m: float,
    wheel_base_m: float,
) -> tuple[tuple[float, float, float], FloatArray, FloatArray]:
    """Draw ``count`` straight commands of ``step_m`` per wheel and dead-reckon them.

    Each command's encoders read ``step_m + step_noise_m * normal`` per wheel (its two
    normals); the pose ``(x, y, theta)`` ({W}; metres, radians) moves by their mean along the
    heading half way through their turn (midpoint integration over wheel base
    ``wheel_base_m``). Returns the end pose and the commands' ``(normals, uniforms)``.
    """
    normals = np.empty((count, 2))
    uniforms = np.empty((count, 4))
    _draw_into_compiled(rng, normals, uniforms)
    x, y, theta = pose
    for command in range(count):
        left = step_m + step_noise_m * normals[command, 0]
        right = step_m + step_noise_m * normals[command, 1]
        distance, turn = 0.5 * (right + left), (right - left) / wheel_base_m
        heading = theta + 0.5 * turn
        x, y = x + distance * math.cos(heading), y + distance * math.sin(heading)
        theta = wrap_angle(theta + turn)
    return (x, y, theta), normals, uniforms
