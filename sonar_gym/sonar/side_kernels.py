"""Compiled loops of the side sonars' first echoes (numba): one ping from each of many sensors.

The array form (``tests/sonar/side_echoes_reference.py``, the tests' reference) evaluates the
echo search and the detection for ``P`` sensor positions as ``(P, N)`` arrays of ``N``
candidates. On the few dozen
positions of a leg and the few dozen candidates of a room, numpy's per-call cost is most of
that time. These loops do the same arithmetic element by element, in the same order, so they
return the same bits (see :mod:`sonar_gym.sonar.kernels` for why elementwise steps agree).
What only numpy rounds its own way stays in numpy, between the loops: the products taken
through BLAS (the search map at the sensors and the occlusion map at the heard paths), the
``einsum`` of the occlusion products and the air absorption's ``exp``.

The loops, in order:

0. :func:`side_sensors`: each sensor's homogeneous position and frame, from the robot's poses;
1. :func:`side_ranges`: ranges, echo points and the on-axis echo laws per sensor and candidate;
2. :func:`side_heard`: the candidate tests, the footprint and the beam's detection;
   :func:`heard_paths` lists the heard paths and their sensors' rows;
3. :func:`side_first`: occlusion of the heard paths and the nearest path left, per sensor.

:func:`side_readings` then turns the first echoes of both sensors into their readings.
"""

from __future__ import annotations

import math

import numpy as np
from numba import types

from sonar_gym.compiled import FLAGS, INDICES, NUMBERS, TABLE, compiled, nan_max
from sonar_gym.pose import FloatArray
from sonar_gym.sonar.kernels import main_lobe_cos_limit

_TABLE_OUT = types.Array(types.float64, 2, "C")
_FLAGS_OUT = types.Array(types.boolean, 2, "C")
_GRID = types.Array(types.float64, 3, "A", readonly=True)


@compiled(  # type: ignore[misc]
    types.float64,
    types.float64,  # cosine
    TABLE,  # cells
    types.float64,  # steps per unit of s
    types.boolean,  # reaches back
    inline=True,
)
def _two_way_from_cos(cosine: float, cells: FloatArray, steps: float, reaches_back: bool) -> float:
    """:meth:`~sonar_gym.sonar.acoustics.PistonBeam.two_way_from_cos` of one cosine."""
    scaled = math.sqrt(abs(1.0 - cosine)) * steps
    index = int(scaled)
    value = cells[index, 0] + (scaled - float(index)) * cells[index, 1]
    if reaches_back and not cosine > 0.0:
        return 0.0
    return value


@compiled(  # type: ignore[misc]
    types.Tuple((_TABLE_OUT, _TABLE_OUT)),
    TABLE,  # robot
    NUMBERS,  # cos_heading
    NUMBERS,  # sin_heading
    TABLE,  # offsets
    types.int64,  # first
    types.int64,  # stride
)
def side_sensors(
    robot: FloatArray,
    cos_heading: FloatArray,
    sin_heading: FloatArray,
    offsets: FloatArray,
    first: int,
    stride: int,
) -> tuple[FloatArray, FloatArray]:
    """``(homogeneous (P, 3), sensor_frames (P, 5))`` of the sensors ``first, first + stride,
    ...`` of the ``2 n`` sensors left, right of each of ``robot``'s poses.

    ``homogeneous`` holds each sensor's ``(x, y, 1)`` in {W} (metres); ``sensor_frames`` is the
    input of :func:`side_heard`: ``cos`` and ``sin`` of the robot heading, the side sign (+1
    left, -1 right) and the sensor's offset from the robot centre (m, {W}).

    Args:
        robot: ``(n, 3)`` poses ``[x, y, theta]`` in {W} (metres, radians).
        cos_heading, sin_heading: ``(n,)`` numpy's ``cos`` and ``sin`` of ``theta``.
        offsets: ``(2 n, 2)`` each sensor's offset from its robot centre (m, {W}), or
            ``(0, 2)`` for sensors at the centre.
        first, stride: the sensors evaluated (``0, 1`` for all, ``0, 2`` or ``1, 2`` for one
            side).
    """
    n_all = 2 * robot.shape[0]
    count = max(0, (n_all - first + stride - 1) // stride)
    at_centre = offsets.shape[0] == 0
    homogeneous = np.empty((count, 3))
    frames = np.empty((count, 5))
    for row in range(count):
        sensor = first + row * stride
        pose = sensor // 2
        centre_x, centre_y = robot[pose, 0], robot[pose, 1]
        sensor_x, sensor_y = centre_x, centre_y
        if not at_centre:
            sensor_x = centre_x + offsets[sensor, 0]
            sensor_y = centre_y + offsets[sensor, 1]
        homogeneous[row, 0] = sensor_x
        homogeneous[row, 1] = sensor_y
        homogeneous[row, 2] = 1.0
        frames[row, 0] = cos_heading[pose]
        frames[row, 1] = sin_heading[pose]
        frames[row, 2] = 1.0 if sensor % 2 == 0 else -1.0
        frames[row, 3] = sensor_x - centre_x
        frames[row, 4] = sensor_y - centre_y
    return homogeneous, frames


@compiled(  # type: ignore[misc]
    types.Tuple(
        (
            types.Array(types.float64, 3, "C"),
            _TABLE_OUT,
            _TABLE_OUT,
            _TABLE_OUT,
            _TABLE_OUT,
            _FLAGS_OUT,
        )
    ),
    TABLE,  # mapped
    INDICES,  # layout
    NUMBERS,  # radius
    NUMBERS,  # edge law
)
def side_ranges(
    mapped: FloatArray, layout: np.ndarray, radius: FloatArray, edge_law: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, np.ndarray]:
    """Per sensor and candidate: ``(rel (P, N, 3), ranges (P, N), safe ranges (P, N), on-axis
    amplitudes before air and gain (P, N), centre distances (P, C), concave (P, W))``.

    ``rel`` is each candidate's ``(rel_x, rel_y, 1)`` row of ``mapped`` with a cylinder's offset
    moved from its centre to its echo point; a range is ``|rel|`` (a cylinder's centre distance
    minus its radius), the safe range that clipped at 1 nm. Metres and 1/m.

    Args:
        mapped: ``(P, M)`` the search map's product at each sensor (``(rel_x, rel_y, 1)`` per
            candidate, ``along`` and the signed distance per segment, then the two wedge-side
            tests per wedge).
        layout: ``(S, C, W, V)``, segments, circles, wedges and vertices.
        radius: ``(C,)`` cylinder radii, metres.
        edge_law: ``(1, s)`` for the weak law ``s / r^2``, ``(0, G / (2 sqrt(pi k)))`` for the
            GTD law.
    """
    n_segments, n_circles, n_wedges, n_vertices = layout[0], layout[1], layout[2], layout[3]
    weak, edge_constant = edge_law[0] > 0.0, edge_law[1]
    n_specular = n_segments + n_circles
    n_candidates = n_specular + n_vertices
    wedge_start = 3 * n_candidates + 2 * n_segments
    n_sensors = mapped.shape[0]
    rel = np.empty((n_sensors, n_candidates, 3))
    ranges = np.empty((n_sensors, n_candidates))
    safe = np.empty((n_sensors, n_candidates))
    on_axis = np.empty((n_sensors, n_candidates))
    centre_distance = np.empty((n_sensors, n_circles))
    concave = np.empty((n_sensors, n_wedges), dtype=np.bool_)
    for sensor in range(n_sensors):
        for wedge in range(n_wedges):
            concave[sensor, wedge] = (mapped[sensor, wedge_start + wedge] > 0.0) and (
                mapped[sensor, wedge_start + n_wedges + wedge] > 0.0
            )
        for candidate in range(n_candidates):
            x = mapped[sensor, 3 * candidate]
            y = mapped[sensor, 3 * candidate + 1]
            distance = np.hypot(x, y)
            reach = distance
            circle = candidate - n_segments
            if 0 <= circle < n_circles:
                centre_distance[sensor, circle] = distance
                reach = distance - radius[circle]
                shrink = 1.0 - radius[circle] / nan_max(distance, 1e-12)
                x = x * shrink
                y = y * shrink
            rel[sensor, candidate, 0] = x
            rel[sensor, candidate, 1] = y
            rel[sensor, candidate, 2] = mapped[sensor, 3 * candidate + 2]
            ranges[sensor, candidate] = reach
            r = nan_max(reach, 1e-9)
            safe[sensor, candidate] = r
            inverse_square = 0.5 / r
            if candidate < n_segments:
                on_axis[sensor, candidate] = inverse_square
            elif candidate < n_specular:
                rho = radius[circle]
                on_axis[sensor, candidate] = inverse_square * math.sqrt(rho / (r + rho))
            else:
                wedge = candidate - n_specular
                if wedge < n_wedges and concave[sensor, wedge]:
                    on_axis[sensor, candidate] = inverse_square
                elif weak:
                    on_axis[sensor, candidate] = edge_constant / (r * r)
                else:
                    on_axis[sensor, candidate] = edge_constant / (r * math.sqrt(r))
    return rel, ranges, safe, on_axis, centre_distance, concave


@compiled(  # type: ignore[misc]
    types.Tuple((_FLAGS_OUT, _TABLE_OUT, _FLAGS_OUT)),
    TABLE,  # mapped
    _GRID,  # rel
    TABLE,  # ranges
    TABLE,  # safe
    TABLE,  # amplitudes
    types.Array(types.boolean, 2, "A", readonly=True),  # concave
    TABLE,  # sensor_frames: cos, sin of the heading, side sign, sensor offset x, y
    INDICES,  # layout
    NUMBERS,  # solid_side
    INDICES,  # twin
    FLAGS,  # twin_comes_first
    NUMBERS,  # constants
    TABLE,  # cells
    NUMBERS,  # rising
    TABLE,  # main_lobe_cells
)
def side_heard(
    mapped: FloatArray,
    rel: FloatArray,
    ranges: FloatArray,
    safe: FloatArray,
    amplitudes: FloatArray,
    concave: np.ndarray,
    sensor_frames: FloatArray,
    layout: np.ndarray,
    solid_side: FloatArray,
    twin: np.ndarray,
    twin_comes_first: np.ndarray,
    constants: FloatArray,
    cells: FloatArray,
    rising: FloatArray,
    main_lobe_cells: FloatArray,
) -> tuple[np.ndarray, FloatArray, np.ndarray]:
    """``(heard (P, N), cosines (P, N), facing (P, S))``: which paths each sensor's beam hears
    before occlusion, the cosine of each path with the beam, and which segments face each
    sensor.

    A path is valid when it passes the echo search's tests (minimum range, threshold, a
    segment's foot strictly inside it and its free side facing the sensor, a T-junction echoing
    once) and its echo point lies outside the robot's footprint; it is heard when the two-way
    pattern at its cosine times its amplitude reaches the threshold (with side lobes), or when
    its cosine reaches its main-lobe limit (without).

    Args:
        amplitudes: ``(P, N)`` amplitudes with air and gain (1/m).
        sensor_frames: ``(P, 5)`` per sensor ``cos`` and ``sin`` of the robot heading, the side
            sign (+1 left, -1 right) and the offset of the sensor from the robot centre (m).
        layout: ``(S, C, W, V)``.
        solid_side, twin, twin_comes_first: of the echo tables.
        constants: the minimum range (m, at least 1 nm), the detection threshold (1/m), the
            footprint radius (m), the transducer's own minimum range (m), the widest main
            lobe's cosine, side lobes (1 or 0), table steps per unit of ``s``, its inverse,
            the smallest positive cosine, whether the pattern reaches behind (1 or 0).
        cells, rising, main_lobe_cells: the beam's tables
            (:class:`~sonar_gym.sonar.acoustics.PistonBeam`).
    """
    n_segments, n_circles, n_wedges, n_vertices = layout[0], layout[1], layout[2], layout[3]
    n_specular = n_segments + n_circles
    n_candidates = n_specular + n_vertices
    along_start = 3 * n_candidates
    distance_start = along_start + n_segments
    min_range, threshold, footprint = constants[0], constants[1], constants[2]
    transducer_min_range, widest_cos = constants[3], constants[4]
    side_lobes, steps, inverse_steps = constants[5] > 0.0, constants[6], constants[7]
    smallest_cosine, reaches_back = constants[8], constants[9] > 0.0
    n_sensors = mapped.shape[0]
    heard = np.zeros((n_sensors, n_candidates), dtype=np.bool_)
    cosines = np.empty((n_sensors, n_candidates))
    facing = np.empty((n_sensors, n_segments), dtype=np.bool_)
    for sensor in range(n_sensors):
        cos_h, sin_h = sensor_frames[sensor, 0], sensor_frames[sensor, 1]
        sign = sensor_frames[sensor, 2]
        offset_x, offset_y = sensor_frames[sensor, 3], sensor_frames[sensor, 4]
        in_footprint = footprint > transducer_min_range - np.hypot(offset_x, offset_y)
        for segment in range(n_segments):
            facing[sensor, segment] = (
                solid_side[segment] * mapped[sensor, distance_start + segment] <= 0.0
            )
        for candidate in range(n_candidates):
            r = safe[sensor, candidate]
            cosine = sign * (
                (-sin_h) * (rel[sensor, candidate, 0] / r) + cos_h * (rel[sensor, candidate, 1] / r)
            )
            cosines[sensor, candidate] = cosine
            amplitude = amplitudes[sensor, candidate]
            valid = ranges[sensor, candidate] >= min_range and amplitude >= threshold
            if candidate < n_segments:
                along = mapped[sensor, along_start + candidate]
                valid = valid and along > 0.0 and along < 1.0 and facing[sensor, candidate]
            wedge = candidate - n_specular
            if 0 <= wedge < n_wedges:
                twin_concave = concave[sensor, twin[wedge]]
                if twin_concave == concave[sensor, wedge]:
                    valid = valid and not twin_comes_first[wedge]
                else:
                    valid = valid and not twin_concave
            if valid and in_footprint:
                point_x = rel[sensor, candidate, 0] + offset_x
                point_y = rel[sensor, candidate, 1] + offset_y
                valid = not np.hypot(point_x, point_y) < footprint
            if not valid:
                continue
            if side_lobes:
                pattern = _two_way_from_cos(cosine, cells, steps, reaches_back)
                heard[sensor, candidate] = pattern * amplitude >= threshold
            elif cosine >= widest_cos:
                limit = main_lobe_cos_limit(
                    threshold / amplitude, rising, main_lobe_cells, inverse_steps, smallest_cosine
                )
                heard[sensor, candidate] = cosine >= limit
    return heard, cosines, facing


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.int64, 1, "C"), types.Array(types.int64, 1, "C"), _TABLE_OUT)),
    types.Array(types.boolean, 2, "A", readonly=True),  # heard
    TABLE,  # homogeneous
)
def heard_paths(
    heard: np.ndarray, homogeneous: FloatArray
) -> tuple[np.ndarray, np.ndarray, FloatArray]:
    """``(sensor_rows (H,), candidate_rows (H,), sensors (H, 3))``: ``np.nonzero(heard)`` (the
    heard paths, sensors ascending) and the ``homogeneous`` row of each path's sensor."""
    n_sensors, n_candidates = heard.shape
    count = 0
    for sensor in range(n_sensors):
        for candidate in range(n_candidates):
            if heard[sensor, candidate]:
                count += 1
    sensor_rows = np.empty(count, dtype=np.int64)
    candidate_rows = np.empty(count, dtype=np.int64)
    sensors = np.empty((count, 3))
    path = 0
    for sensor in range(n_sensors):
        for candidate in range(n_candidates):
            if heard[sensor, candidate]:
                sensor_rows[path] = sensor
                candidate_rows[path] = candidate
                sensors[path, 0] = homogeneous[sensor, 0]
                sensors[path, 1] = homogeneous[sensor, 1]
                sensors[path, 2] = homogeneous[sensor, 2]
                path += 1
    return sensor_rows, candidate_rows, sensors


@compiled(  # type: ignore[misc]
    types.float64,
    _GRID,  # matrix
    types.int64,  # path
    types.int64,  # row
    types.float64,
    types.float64,
    types.float64,
    inline=True,
)
def _product(matrix: FloatArray, path: int, row: int, x: float, y: float, w: float) -> float:
    """Row ``row`` of the occlusion map at ``path`` times ``(x, y, w)``, summed as numpy's
    ``einsum`` sums it."""
    return (matrix[path, row, 0] * x + matrix[path, row, 2] * w) + matrix[path, row, 1] * y


@compiled(  # type: ignore[misc]
    types.Tuple(
        (
            types.Array(types.boolean, 1, "C"),
            types.Array(types.float64, 1, "C"),
            types.Array(types.float64, 1, "C"),
        )
    ),
    _GRID,  # matrix
    _GRID,  # rel
    INDICES,  # sensor_rows
    INDICES,  # candidate_rows
    TABLE,  # ranges
    TABLE,  # cosines
    TABLE,  # amplitudes
    types.Array(types.boolean, 2, "A", readonly=True),  # facing
    FLAGS,  # encloses
    TABLE,  # centre_distance
    NUMBERS,  # radius_sq
    NUMBERS,  # constants
    TABLE,  # cells
)
def side_first(
    matrix: FloatArray,
    rel: FloatArray,
    sensor_rows: np.ndarray,
    candidate_rows: np.ndarray,
    ranges: FloatArray,
    cosines: FloatArray,
    amplitudes: FloatArray,
    facing: np.ndarray,
    encloses: np.ndarray,
    centre_distance: FloatArray,
    radius_sq: FloatArray,
    constants: FloatArray,
    cells: FloatArray,
) -> tuple[np.ndarray, FloatArray, FloatArray]:
    """``(detected (P,), path lengths (P,), amplitudes (P,))``: each sensor's nearest heard
    path that nothing occludes (the first candidate of equal ranges), its one-way length (m)
    and its amplitude through the beam (1/m); 0 where a sensor hears nothing.

    The occlusion tests of :func:`sonar_gym.sonar.kernels.unoccluded`, path by path, on the
    products of the occlusion map and the path, ``np.einsum("hrk,hk->hr", matrix, paths)``:
    numpy's ``einsum`` sums the three terms of such a product as ``(t0 + t2) + t1`` (its
    two-lane loop adds the third term to the first lane), and so does this loop.

    Args:
        matrix: ``(H, 3 S + C, 3)`` the occlusion map at the sensor of each heard path
            (numpy's product).
        rel: ``(P, N, 3)`` the paths' ``(rel_x, rel_y, 1)`` rows (:func:`side_ranges`).
        sensor_rows, candidate_rows: ``(H,)`` the sensor and candidate of each heard path,
            sensors ascending.
        ranges, cosines, amplitudes: ``(P, N)``.
        facing: ``(P, S)`` which segments face each sensor (:func:`side_heard`).
        encloses: ``(S,)`` which segments enclose the room (they never occlude).
        centre_distance: ``(P, C)``.
        radius_sq: ``(C,)`` squared circle radii, m^2.
        constants: the middle (and half width) of the blocking interval of ``u``; table steps
            per unit of ``s``; whether the pattern reaches behind (1 or 0).
    """
    path_centre, steps, reaches_back = constants[0], constants[1], constants[2] > 0.0
    n_sensors = ranges.shape[0]
    n_segments = facing.shape[1]
    n_circles = centre_distance.shape[1]
    detected = np.zeros(n_sensors, dtype=np.bool_)
    path_lengths = np.zeros(n_sensors)
    first_amplitudes = np.zeros(n_sensors)
    first = np.full(n_sensors, -1, dtype=np.int64)
    for path in range(sensor_rows.shape[0]):
        sensor, candidate = sensor_rows[path], candidate_rows[path]
        reach = ranges[sensor, candidate]
        if first[sensor] >= 0 and not reach < ranges[sensor, first[sensor]]:
            continue  # a nearer (or equally near, earlier) path is already clear
        px, py, pw = rel[sensor, candidate, 0], rel[sensor, candidate, 1], rel[sensor, candidate, 2]
        clear = True
        for segment in range(n_segments):
            if encloses[segment] or not facing[sensor, segment]:
                continue
            denominator = _product(matrix, path, segment, px, py, pw)
            u = _product(matrix, path, n_segments + segment, px, py, pw) / denominator
            if abs(u - path_centre) <= path_centre:
                v = _product(matrix, path, 2 * n_segments + segment, px, py, pw) / denominator
                if abs(v - 0.5) <= 0.5:
                    clear = False
                    break
        if clear:
            path_sq = reach * reach
            for circle in range(n_circles):
                dot = _product(matrix, path, 3 * n_segments + circle, px, py, pw)
                nearest = dot / path_sq
                if abs(nearest - path_centre) <= path_centre:
                    distance = centre_distance[sensor, circle]
                    if distance * distance - dot * nearest < radius_sq[circle]:
                        clear = False
                        break
        if clear:
            first[sensor] = candidate
    for sensor in range(n_sensors):
        candidate = first[sensor]
        if candidate < 0:
            continue
        detected[sensor] = True
        path_lengths[sensor] = ranges[sensor, candidate]
        first_amplitudes[sensor] = (
            _two_way_from_cos(cosines[sensor, candidate], cells, steps, reaches_back)
            * amplitudes[sensor, candidate]
        )
    return detected, path_lengths, first_amplitudes


@compiled(  # type: ignore[misc]
    types.Tuple((types.Array(types.float64, 1, "C"), types.Array(types.float64, 1, "C"))),
    FLAGS,  # detected
    NUMBERS,  # path_lengths
    NUMBERS,  # amplitudes
    NUMBERS,  # normals
    NUMBERS,  # constants
)
def side_readings(
    detected: np.ndarray,
    path_lengths: FloatArray,
    amplitudes: FloatArray,
    normals: FloatArray,
    constants: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """``(left (n,), right (n,))`` ranges (m, NaN for a dropout) the electronics report for the
    first echoes of ``2 n`` pings, left then right of each sample.

    Steps 1-5 of the readout of :mod:`sonar_gym.sonar.pulse_echo` (``echo_readings``), ping by
    ping in its order of operations; a ping that detects nothing is a dropout.

    Args:
        detected, path_lengths, amplitudes: ``(2 n,)`` the first echoes (m, 1/m).
        normals: ``(2 n,)`` standard normals of the jitter, or empty without jitter.
        constants: seconds of flight per metre of path (``2 / c_true``); whether the crossing
            delay is on (1 or 0) and its numerator (``rise time x threshold``, s/m); jitter in
            seconds per normal; ``1 / T0`` and ``T0`` (0 without a counter); metres per second
            of flight (``c_assumed / 2``); the maximum range (m).
    """
    tof_per_m, delay, delay_numerator = constants[0], constants[1] > 0.0, constants[2]
    jitter_s, inverse_period, period = constants[3], constants[4], constants[5]
    metres_per_s, max_range = constants[6], constants[7]
    n_samples = path_lengths.shape[0] // 2
    left = np.empty(n_samples)
    right = np.empty(n_samples)
    for ping in range(2 * n_samples):
        reading = np.nan
        if detected[ping]:
            tof = path_lengths[ping] * tof_per_m
            if delay:
                tof = tof + delay_numerator / amplitudes[ping]
            if normals.shape[0] > 0:
                tof = tof + normals[ping] * jitter_s
            if period > 0.0:
                tof = np.floor(tof * inverse_period) * period
            in_range = tof * metres_per_s
            if in_range <= max_range:
                reading = in_range
        if ping % 2 == 0:
            left[ping // 2] = reading
        else:
            right[ping // 2] = reading
    return left, right


__all__ = [
    "heard_paths",
    "side_first",
    "side_heard",
    "side_ranges",
    "side_readings",
    "side_sensors",
]
