"""The vectorised pan against a slow per-ping reference that asks pymunk about occlusion.

The reference finds echo points with plain Python loops over the primitives, decides
occlusion with pymunk's own ``segment_query_first`` cast from the sensor to each echo point,
and loops over the pings. It shares only the physics (amplitude laws, the receiver's gain, the
beam pattern, the corner test of the geometry) with the fast path. Both the Polaroid preset
(gain ramp and side-lobe leakage) and the ideal piston with constant gain are checked.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pymunk
import pytest

from sonar_gym.pose import Pose
from sonar_gym.sonar.acoustics import (
    PistonBeam,
    absorption_amplitude_factor,
    speed_of_sound_mps,
    wavenumber_per_m,
)
from sonar_gym.sonar.echoes import (
    cylinder_echo_amplitude,
    edge_echo_amplitude,
    plane_echo_amplitude,
)
from sonar_gym.sonar.presets import Transducer, polaroid_6500
from sonar_gym.sonar.pulse_echo import IDEAL_READOUT, Readout
from sonar_gym.sonar.rotating import RotatingSonar
from tests.sonar.worlds import StandInWorld, cluttered_room, free_positions, pymunk_space

IDEAL_PISTON = polaroid_6500(time_varying_gain=False, side_lobe_leakage=0.0)
END_TOLERANCE = 1e-6  # pymunk hits within this fraction of the path's end are the reflector itself


def reference_echoes(
    test_world: StandInWorld, space: pymunk.Space, sonar: RotatingSonar, pose: Pose
):
    """``[(path_length, unit_direction, on_axis_amplitude)]`` of every visible echo."""
    transducer = sonar.transducer
    geometry = test_world.geometry
    k = wavenumber_per_m(transducer.frequency_hz, speed_of_sound_mps(test_world.temperature_c))
    p = pose.transform_point(test_world.scenario.robot.sensor_offset)
    points: list[tuple[np.ndarray, float]] = []
    for a, b in zip(geometry.segment_starts, geometry.segment_ends, strict=True):
        t = float(np.dot(p - a, b - a) / np.dot(b - a, b - a))
        if 0.0 < t < 1.0:
            foot = a + t * (b - a)
            points.append((foot, float(plane_echo_amplitude(np.linalg.norm(foot - p)))))
    for x, y, radius in geometry.circles:
        centre = np.array([x, y])
        distance = float(np.linalg.norm(centre - p))
        point = centre + (p - centre) * radius / distance
        points.append((point, float(cylinder_echo_amplitude(distance - radius, radius))))
    concave = geometry.is_concave_from(p)
    by_position: dict[tuple[float, float], bool] = {}
    for vertex, is_concave in zip(geometry.vertices, concave, strict=True):
        key = (round(float(vertex[0]), 9), round(float(vertex[1]), 9))
        by_position[key] = by_position.get(key, False) or bool(is_concave)
    for (x, y), is_concave in by_position.items():
        vertex = np.array([x, y])
        r = float(np.linalg.norm(vertex - p))
        amplitude = plane_echo_amplitude(r) if is_concave else edge_echo_amplitude(r, k)
        points.append((vertex, float(amplitude)))

    echoes = []
    for point, amplitude in points:
        r = float(np.linalg.norm(point - p))
        if (
            r < transducer.min_range_m
            or np.linalg.norm(point - pose.position) < test_world.scenario.robot.radius
        ):
            continue
        hit = space.segment_query_first(tuple(p), tuple(point), 0.0, pymunk.ShapeFilter())
        if hit is not None and hit.alpha < 1.0 - END_TOLERANCE:
            continue
        amplitude *= float(absorption_amplitude_factor(2.0 * r, transducer.absorption_db_per_m))
        if transducer.time_varying_gain is not None:
            amplitude *= float(transducer.time_varying_gain.gain(r))
        echoes.append((r, (point - p) / r, amplitude))
    return echoes


def reference_pan(
    test_world, space, sonar: RotatingSonar, pose: Pose, angles: np.ndarray
) -> np.ndarray:
    """Ranges of a noise-free pan, ping by ping."""
    transducer = sonar.transducer
    true_speed = speed_of_sound_mps(test_world.temperature_c)
    beam = PistonBeam.for_ka(
        transducer.wavenumber_ka(true_speed), transducer.side_lobes, transducer.side_lobe_leakage
    )
    echoes = reference_echoes(test_world, space, sonar, pose)
    ranges = []
    for angle in angles:
        direction = np.array([math.cos(pose.theta + angle), math.sin(pose.theta + angle)])
        best: tuple[float, float] | None = None
        for r, unit, amplitude in echoes:
            heard = amplitude * float(beam.two_way_from_cos(np.array([float(direction @ unit)]))[0])
            if heard >= transducer.detection_threshold and (best is None or r < best[0]):
                best = (r, heard)
        if best is None:
            ranges.append(math.nan)
            continue
        tof = 2.0 * best[0] / true_speed
        if sonar.readout.crossing_delay:
            tof += transducer.echo_rise_time_s * transducer.detection_threshold / best[1]
        if sonar.readout.quantisation:
            tof = math.floor(tof / transducer.timer_period_s) * transducer.timer_period_s
        reading = sonar.assumed_speed_of_sound_mps * tof / 2.0
        ranges.append(reading if reading <= transducer.max_range_m else math.nan)
    return np.array(ranges)


@pytest.mark.parametrize(
    ("readout", "sensor_offset", "transducer"),
    [
        (IDEAL_READOUT, (0.0, 0.0), polaroid_6500()),
        (Readout(range_noise=False), (0.0, 0.0), polaroid_6500()),
        (IDEAL_READOUT, (0.12, -0.05), polaroid_6500()),
        (IDEAL_READOUT, (0.0, 0.0), IDEAL_PISTON),
        (Readout(range_noise=False), (0.12, -0.05), IDEAL_PISTON),
    ],
)
def test_fast_pan_equals_the_pymunk_reference_in_a_cluttered_room(
    readout: Readout, sensor_offset, transducer: Transducer
) -> None:
    test_world = cluttered_room(sensor_offset)
    space = pymunk_space(test_world.geometry)
    sonar = RotatingSonar(transducer, readout=readout)
    rng = np.random.default_rng(7)
    angles = np.radians(np.arange(-180, 180))
    for x, y in free_positions(test_world, rng, 6):
        pose = Pose(x, y, float(rng.uniform(-math.pi, math.pi)))
        scan = sonar.pan(test_world, pose, -math.pi, math.pi, math.radians(1.0), rng)
        expected = reference_pan(test_world, space, sonar, pose, angles)
        np.testing.assert_array_equal(np.isnan(scan.ranges), np.isnan(expected))
        np.testing.assert_allclose(scan.ranges, expected, rtol=0.0, atol=1e-9)
        assert np.isfinite(scan.ranges).sum() > 100


@pytest.mark.parametrize("transducer", [polaroid_6500(), IDEAL_PISTON])
def test_reference_sees_the_same_occlusions_with_side_lobes(transducer: Transducer) -> None:
    test_world = cluttered_room()
    space = pymunk_space(test_world.geometry)
    sonar = RotatingSonar(dataclasses.replace(transducer, side_lobes=True), readout=IDEAL_READOUT)
    rng = np.random.default_rng(3)
    angles = np.radians(np.arange(-180, 180))
    for x, y in free_positions(test_world, rng, 3):
        pose = Pose(x, y, 0.4)
        scan = sonar.pan(test_world, pose, -math.pi, math.pi, math.radians(1.0), rng)
        np.testing.assert_allclose(
            scan.ranges, reference_pan(test_world, space, sonar, pose, angles), atol=1e-9
        )
