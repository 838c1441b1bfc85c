"""Compiled inner loops of the pan: the readout of many pings and the occlusion test (numba).

The array forms in :mod:`sonar_gym.sonar.pulse_echo` and :mod:`sonar_gym.sonar.echoes` spend
most of a pan in numpy's per-call overhead on arrays of a few hundred elements. These loops do
the same arithmetic element by element, in the same order, so they return the same bits:

* every elementwise step (``+ - * /``, ``sqrt``, ``floor``, comparisons) is IEEE-754 in both, and
  numba fuses no multiply-add unless asked (no ``fastmath``);
* a product that numpy takes through BLAS with both sides at least two wide (``(pings, 2) @
  (2, candidates)``) is a fused multiply-add there, ``fma(b1, f1, b0 * f0)``; ``_fma`` gives
  the loops that same single rounding. With one ping or one candidate numpy goes through
  another BLAS kernel that rounds differently, so callers keep numpy's path for those.
* the loops stop at the first detected candidate and the first occluder; numpy computes them
  all and discards the rest (the discarded values never reach a result).

How they are compiled (one signature, cached, numpy's division by zero):
:mod:`sonar_gym.compiled`. The sonar modules import this one; ``import sonar_gym`` alone does
not.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from sonar_gym.compiled import FLAGS, NUMBERS, TABLE, compiled
from sonar_gym.pose import FloatArray


def _fused_multiply_add(typing_context: Any, a: Any, b: Any, c: Any) -> Any:
    """``a * b + c`` with one rounding (LLVM's ``llvm.fma.f64``)."""
    signature = types.float64(types.float64, types.float64, types.float64)

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        double = ir.DoubleType()
        function = builder.module.declare_intrinsic(
            "llvm.fma", [double], ir.FunctionType(double, [double, double, double])
        )
        return builder.call(function, args)

    return signature, codegen


_fma: Any = intrinsic(_fused_multiply_add)


@compiled(  # type: ignore[misc]
    types.Array(types.float64, 2, "C"),  # readings
    TABLE,  # directions
    TABLE,  # in_frame
    NUMBERS,  # limits
    NUMBERS,  # amplitudes
    NUMBERS,  # path_lengths
    TABLE,  # cells
    NUMBERS,  # normals
    NUMBERS,  # constants
)
def _main_lobe_readings_loop(
    directions: FloatArray,
    in_frame: FloatArray,
    limits: FloatArray,
    amplitudes: FloatArray,
    path_lengths: FloatArray,
    cells: FloatArray,
    normals: FloatArray,
    constants: FloatArray,
) -> FloatArray:
    steps, tof_per_m, delay_numerator = constants[0], constants[1], constants[2]
    jitter_s, inverse_period, period = constants[3], constants[4], constants[5]
    metres_per_s, max_range = constants[6], constants[7]
    n_pings, n_candidates = directions.shape[0], path_lengths.shape[0]
    readings = np.empty((2, n_pings))
    for ping in range(n_pings):
        bx, by = directions[ping, 0], directions[ping, 1]
        first, cosine = -1, 0.0
        for candidate in range(n_candidates):  # sorted nearest first
            c = _fma(by, in_frame[1, candidate], bx * in_frame[0, candidate])
            if c >= limits[candidate]:
                first, cosine = candidate, c
                break
        readings[0, ping], readings[1, ping] = np.nan, 0.0
        if first < 0:
            continue
        scaled = math.sqrt(abs(1.0 - cosine)) * steps
        whole = math.floor(scaled)
        cell = int(whole)
        amplitude = (cells[cell, 0] + (scaled - whole) * cells[cell, 1]) * amplitudes[first]
        tof = path_lengths[first] * tof_per_m
        if delay_numerator > 0.0:
            tof = tof + delay_numerator / amplitude
        if normals.shape[0] > 0:
            tof = tof + normals[ping] * jitter_s
        if period > 0.0:
            tof = math.floor(tof * inverse_period) * period
        reading = tof * metres_per_s
        if reading <= max_range:
            readings[0, ping], readings[1, ping] = reading, amplitude
    return readings


@compiled(  # type: ignore[misc]
    types.Array(types.boolean, 1, "C"),  # clear
    TABLE,  # products
    NUMBERS,  # ranges
    NUMBERS,  # centre_distance
    NUMBERS,  # radius_sq
    FLAGS,  # occluders
    types.float64,  # path_centre
)
def _unoccluded_loop(
    products: FloatArray,
    ranges: FloatArray,
    centre_distance: FloatArray,
    radius_sq: FloatArray,
    occluders: np.ndarray,
    path_centre: float,
) -> np.ndarray:
    n_circles = centre_distance.shape[0]
    n_segments = (products.shape[0] - n_circles) // 3
    n_paths = ranges.shape[0]
    clear = np.ones(n_paths, dtype=np.bool_)
    for path in range(n_paths):
        for segment in range(n_segments):
            if not occluders[segment]:
                continue
            denominator = products[segment, path]
            u = products[n_segments + segment, path] / denominator
            if abs(u - path_centre) <= path_centre:
                v = products[2 * n_segments + segment, path] / denominator
                if abs(v - 0.5) <= 0.5:
                    clear[path] = False
                    break
        if not clear[path]:
            continue
        range_sq = ranges[path] * ranges[path]
        for circle in range(n_circles):
            dot = products[3 * n_segments + circle, path]
            nearest = dot / range_sq
            if abs(nearest - path_centre) <= path_centre:
                distance = centre_distance[circle]
                if distance * distance - dot * nearest < radius_sq[circle]:
                    clear[path] = False
                    break
    return clear


def main_lobe_readings(
    directions: FloatArray,
    in_frame: FloatArray,
    limits: FloatArray,
    amplitudes: FloatArray,
    path_lengths: FloatArray,
    cells: FloatArray,
    normals: FloatArray,
    constants: FloatArray,
) -> FloatArray:
    """``(2, pings)`` rows of ranges (m, NaN for a dropout) and amplitudes (1/m, 0 for one).

    The loop of :func:`sonar_gym.sonar.pulse_echo._main_lobe_readings`: per ping the first
    candidate whose cosine reaches its limit, the beam's table at that cosine, then steps 1-5
    of the readout.

    Args:
        directions: ``(pings, 2)`` beam directions in the robot frame {R} (unit vectors).
        in_frame: ``(2, candidates)`` candidate directions in {R}.
        limits: ``(candidates,)`` the cosine each candidate needs to be detected.
        amplitudes, path_lengths: ``(candidates,)`` on-axis amplitudes (1/m), one-way paths (m).
        cells: the beam's ``(value, slope)`` table, :class:`~sonar_gym.sonar.acoustics.PistonBeam`.
        normals: ``(pings,)`` standard normals of the jitter, or empty without jitter.
        constants: table steps per unit of ``s``; seconds of flight per metre of path (``2 /
            c_true``); the crossing-delay numerator (``rise time x threshold``, 0 without the
            delay); jitter in seconds per normal; ``1 / T0`` and ``T0`` (0 without a counter);
            metres per second of flight (``c_assumed / 2``); the maximum range (m).
    """
    return _main_lobe_readings_loop(  # type: ignore[no-any-return]
        directions, in_frame, limits, amplitudes, path_lengths, cells, normals, constants
    )


def unoccluded(
    products: FloatArray,
    ranges: FloatArray,
    centre_distance: FloatArray,
    radius_sq: FloatArray,
    occluders: np.ndarray,
    path_centre: float,
) -> np.ndarray:
    """``(paths,)`` which paths no occluding segment crosses and no circle cuts.

    The tests of :func:`sonar_gym.sonar.echoes._unoccluded`, path by path.

    Args:
        products: ``(3 S + C, paths)`` the occlusion map times each path (crossing
            denominators, the ``u`` and ``v`` numerators per segment, then ``c - p . rel`` per
            circle), metres squared.
        ranges: ``(paths,)`` path lengths, metres.
        centre_distance: ``(C,)`` sensor-to-centre distances, metres.
        radius_sq: ``(C,)`` squared circle radii, m^2.
        occluders: ``(S + C,)`` which segments may occlude (the circle entries are ignored:
            every circle may).
        path_centre: the middle (and half width) of the blocking interval of ``u`` and ``u*``,
            ``(1 - tol) / 2``.
    """
    return _unoccluded_loop(  # type: ignore[no-any-return]
        products, ranges, centre_distance, radius_sq, occluders, path_centre
    )
