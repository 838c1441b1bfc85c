"""The side sonars' first echoes as ``(P, N)`` arrays: the form the compiled loops of
:mod:`sonar_gym.sonar.side_kernels` replaced, kept as the tests' reference.

It evaluates the echo search and the detection for ``P`` sensor positions as arrays of ``N``
candidates, row by row the computation of :func:`~sonar_gym.sonar.echoes.echo_candidates`
followed by :func:`~sonar_gym.sonar.pulse_echo.first_echoes`.
"""

from __future__ import annotations

import math

import numpy as np

from sonar_gym.pose import FloatArray
from sonar_gym.sonar.acoustics import PistonBeam, speed_of_sound_mps, wavenumber_per_m
from sonar_gym.sonar.echo_tables import PATH_END_TOLERANCE, echo_tables
from sonar_gym.sonar.echoes import EchoKind, edge_echo_amplitude
from sonar_gym.sonar.pulse_echo import FirstEchoes, WorldLike
from sonar_gym.sonar.swept import SideSonars

_UV_CENTRE_SCALAR = (1.0 - PATH_END_TOLERANCE) / 2.0
_UV_CENTRE = np.array([_UV_CENTRE_SCALAR, 0.5])[None, :, None]
_UV_HALF_WIDTH = _UV_CENTRE


def side_sensor_arrays(
    sonar: SideSonars, poses: FloatArray, sides: tuple[str, ...]
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """``(sensors, centres, headings, side_sign)`` of the sensors named in ``sides`` (left,
    right of each of ``poses`` ``(n, 3)``, in that order), as numpy arrays: the form
    :func:`~sonar_gym.sonar.side_kernels.side_sensors` replaced."""
    n = len(poses)
    headings = np.repeat(poses[:, 2], 2)
    side_sign = np.tile([1.0, -1.0], n)
    centres = np.repeat(poses[:, :2], 2, axis=0)
    if sonar.lateral_offset_m == 0.0:
        sensors = centres.copy()
    else:
        angle = headings + side_sign * (math.pi / 2.0)
        sensors = centres + sonar.lateral_offset_m * np.column_stack([np.cos(angle), np.sin(angle)])
    if len(set(sides)) == 2:
        return sensors, centres, headings, side_sign
    rows = slice(("left", "right").index(sides[0]), None, 2)
    return sensors[rows], centres[rows], headings[rows], side_sign[rows]


def sensor_rows_arrays(
    sensors: FloatArray, centres: FloatArray, headings: FloatArray, side_sign: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """``(homogeneous (P, 3), sensor_frames (P, 5))`` of the sensors, as numpy arrays: the form
    :func:`~sonar_gym.sonar.side_kernels.side_sensors` replaced."""
    homogeneous = np.column_stack([sensors, np.ones(len(sensors))])
    frames = np.column_stack([np.cos(headings), np.sin(headings), side_sign, sensors - centres])
    return homogeneous, frames


def side_first_echoes_arrays(
    sonar: SideSonars,
    world: WorldLike,
    sensors: FloatArray,
    centres: FloatArray,
    headings: FloatArray,
    side_sign: FloatArray,
) -> FirstEchoes:
    """:func:`~sonar_gym.sonar.swept._side_first_echoes` as ``(P, N)`` arrays, the reference
    its loops are checked against.

    Row by row the computation of :func:`~sonar_gym.sonar.echoes.echo_candidates` followed by
    :func:`~sonar_gym.sonar.pulse_echo.first_echoes`, over ``P`` sensor positions at once.
    """
    transducer = sonar.transducer
    speed = speed_of_sound_mps(world.temperature_c)
    wavenumber = wavenumber_per_m(transducer.frequency_hz, speed)
    threshold = transducer.detection_threshold
    tables = echo_tables(world.geometry, EchoKind.PLANE, EchoKind.CYLINDER, EchoKind.EDGE)
    n_segments, n_wedges = tables.n_segments, tables.n_wedges
    n_specular = n_segments + tables.n_circles
    n_candidates = n_specular + tables.n_vertices
    wedge_end = n_specular + n_wedges
    count = len(sensors)
    homogeneous = np.column_stack([sensors, np.ones(count)])  # (P, 3)

    mapped = homogeneous @ tables.position_map.T  # (P, M)
    rel = mapped[:, : 3 * n_candidates].reshape(count, n_candidates, 3).copy()
    along = mapped[:, 3 * n_candidates : 3 * n_candidates + n_segments]
    signed_distance = mapped[:, 3 * n_candidates + n_segments : 3 * n_candidates + 2 * n_segments]
    wedge_tests = mapped[:, 3 * n_candidates + 2 * n_segments :]
    concave = (wedge_tests[:, :n_wedges] > 0.0) & (wedge_tests[:, n_wedges:] > 0.0)

    ranges = np.hypot(rel[:, :, 0], rel[:, :, 1])
    centre_distance = ranges[:, n_segments:n_specular].copy()
    if tables.n_circles:
        ranges[:, n_segments:n_specular] -= tables.radius
        rel[:, n_segments:n_specular, :2] *= (
            1.0 - tables.radius / np.maximum(centre_distance, 1e-12)
        )[:, :, None]

    safe = np.maximum(ranges, 1e-9)
    amplitudes = 0.5 / safe
    if tables.n_circles:
        cylinder_ranges = safe[:, n_segments:n_specular]
        amplitudes[:, n_segments:n_specular] *= np.sqrt(
            tables.radius / (cylinder_ranges + tables.radius)
        )
    edges = edge_echo_amplitude(safe[:, n_specular:], wavenumber, sonar.edge_law)
    amplitudes[:, n_specular:wedge_end] = np.where(
        concave, amplitudes[:, n_specular:wedge_end], edges[:, :n_wedges]
    )
    amplitudes[:, wedge_end:] = edges[:, n_wedges:]
    if transducer.absorption_db_per_m > 0.0:
        amplitudes *= np.exp((-transducer.absorption_db_per_m * math.log(10.0) / 10.0) * safe)
    if transducer.time_varying_gain is not None:
        amplitudes *= transducer.time_varying_gain.gain(safe)

    valid = (ranges >= max(transducer.min_range_m, 1e-9)) & (amplitudes >= threshold)
    facing = tables.solid_side * signed_distance <= 0.0
    valid[:, :n_segments] &= (along > 0.0) & (along < 1.0) & facing
    twin_concave = concave[:, tables.twin]
    valid[:, n_specular:wedge_end] &= ~np.where(
        twin_concave == concave, tables.twin_comes_first, twin_concave
    )
    footprint = world.scenario.robot.radius
    if footprint > 0.0:
        offset = sensors - centres
        test = footprint > transducer.min_range_m - np.hypot(offset[:, 0], offset[:, 1])
        if test.any():  # else no path is dropped: skip the (P, C) distances
            inside = (
                np.hypot(rel[:, :, 0] + offset[:, 0:1], rel[:, :, 1] + offset[:, 1:2]) < footprint
            )
            valid &= ~(test[:, None] & inside)

    # Detection along each sensor's beam (first_echoes with one ping per sensor).
    cos_h, sin_h = np.cos(headings), np.sin(headings)
    unit_x = rel[:, :, 0] / safe  # safe >= 1e-9: no division by zero
    unit_y = rel[:, :, 1] / safe
    # The beam is (0, +-1) in {R}: its cosine with a direction is +-(robot-frame y).
    cosines = side_sign[:, None] * (-sin_h[:, None] * unit_x + cos_h[:, None] * unit_y)
    beam = PistonBeam.for_ka(
        transducer.wavenumber_ka(speed), transducer.side_lobes, transducer.side_lobe_leakage
    )
    if beam.side_lobes:
        safe_amplitudes = np.where(valid, amplitudes, threshold)
        heard = (beam.two_way_from_cos(cosines) * safe_amplitudes >= threshold) & valid
    else:
        # The limit grows with the level, so no path outside the widest main lobe (that of
        # the faintest level) is heard: the limits are needed only inside it.
        inside = valid & (cosines >= beam.widest_main_lobe_cos)
        heard = np.zeros_like(valid)
        limits = beam.main_lobe_cos_limits(threshold / amplitudes[inside])
        heard[inside] = cosines[inside] >= limits

    # Occlusion (echo_candidates' _unoccluded_nearest_first), only for the paths a beam hears.
    sensor_rows, candidate_rows = np.nonzero(heard)
    if len(sensor_rows):
        occluders = (facing & ~tables.encloses)[sensor_rows]  # (H, S)
        matrix = (homogeneous[sensor_rows] @ tables.occlusion_map.T).reshape(
            len(sensor_rows), -1, 3
        )
        paths = rel[sensor_rows, candidate_rows]  # (H, 3)
        products = np.einsum("hrk,hk->hr", matrix, paths)  # (H, 3 S + C)
        blocked = np.zeros(len(sensor_rows), dtype=bool)
        if n_segments:
            with np.errstate(divide="ignore", invalid="ignore"):
                uv = (
                    products[:, n_segments : 3 * n_segments].reshape(-1, 2, n_segments)
                    / products[:, None, :n_segments]
                )
            inside_uv = np.abs(uv - _UV_CENTRE) <= _UV_HALF_WIDTH
            # Only occluding segments block (masked here rather than by zeroing their rows).
            blocked |= (inside_uv[:, 0] & inside_uv[:, 1] & occluders).any(axis=1)
        if tables.n_circles:
            dots = products[:, 3 * n_segments :]
            path_sq = ranges[sensor_rows, candidate_rows] ** 2
            nearest = dots / path_sq[:, None]
            on_path = np.abs(nearest - _UV_CENTRE_SCALAR) <= _UV_CENTRE_SCALAR
            centre_sq = (centre_distance * centre_distance)[sensor_rows]
            gap_sq = centre_sq - dots * nearest
            blocked |= (on_path & (gap_sq < tables.radius_sq[None, :])).any(axis=1)
        heard[sensor_rows[blocked], candidate_rows[blocked]] = False
    order_ranges = np.where(heard, ranges, np.inf)
    first = np.argmin(order_ranges, axis=1)
    rows = np.arange(count)
    hit = heard[rows, first]
    first_amplitude = beam.two_way_from_cos(cosines[rows, first]) * amplitudes[rows, first]
    return FirstEchoes(
        detected=hit,
        path_lengths=np.where(hit, ranges[rows, first], 0.0),
        amplitudes=np.where(hit, first_amplitude, 0.0),
    )


def read_echoes_arrays(
    sonar: SideSonars, world: WorldLike, echoes: FirstEchoes, rng: np.random.Generator | None
) -> tuple[FloatArray, FloatArray]:
    """``(left, right)`` readings of :meth:`~sonar_gym.sonar.swept.SideSonars.read_echoes`
    through :meth:`~sonar_gym.sonar.pulse_echo.PulseEchoSonar.readings`: the form
    :func:`~sonar_gym.sonar.side_kernels.side_readings` replaced."""
    ranges, _ = sonar.readings(world, echoes, rng)
    pairs = ranges.reshape(-1, 2)
    return pairs[:, 0].copy(), pairs[:, 1].copy()
