"""Echo candidates: where the echo points are, how loud they are, and what hides them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.sonar.acoustics import absorption_amplitude_factor
from sonar_gym.sonar.echoes import (
    EDGE_ECHO_STRENGTH_M,
    EchoKind,
    corner_echo_amplitude,
    cylinder_echo_amplitude,
    echo_candidates,
    edge_echo_amplitude,
    plane_echo_amplitude,
)
from sonar_gym.sonar.presets import preset
from tests.sonar.worlds import cluttered_room, free_positions, world

K_50KHZ = 2 * math.pi * 50e3 / 343.2


def candidates(test_world, position, **kwargs):
    return echo_candidates(test_world.geometry, position, wavenumber=K_50KHZ, **kwargs)


def only(found, kind):
    mask = found.kinds == kind
    return found.points[mask], found.path_lengths[mask], found.amplitudes[mask]


def test_plane_echo_is_the_image_source_at_twice_the_range() -> None:
    assert plane_echo_amplitude(1.25) == pytest.approx(1 / 2.5)
    assert corner_echo_amplitude(1.25) == pytest.approx(1 / 2.5)


def test_cylinder_echo_tends_to_the_plane_for_a_huge_radius_and_to_r_to_the_minus_1_5() -> None:
    assert cylinder_echo_amplitude(2.0, 1e9) == pytest.approx(plane_echo_amplitude(2.0), rel=1e-8)
    # rho << r: sqrt(rho / 4) / r^1.5, DESIGN's sqrt(rho / 2) / r^1.5 up to 1 / sqrt(2).
    r, rho = 3.0, 1e-4
    assert cylinder_echo_amplitude(r, rho) == pytest.approx(
        math.sqrt(rho / 2) / r**1.5 / math.sqrt(2), rel=1e-4
    )


def test_amplitude_ratio_of_the_two_beacons_follows_sqrt_rho_over_r_to_the_1_5() -> None:
    small = cylinder_echo_amplitude(2.87, 0.0191)
    large = cylinder_echo_amplitude(1.44, 0.07)
    assert large / small == pytest.approx(math.sqrt(0.07 / 0.0191) * (2.87 / 1.44) ** 1.5, rel=0.03)


def test_ideal_wedge_edge_is_about_20_db_below_the_small_beacon_and_40_db_below_a_wall() -> None:
    edge = edge_echo_amplitude(2.0, K_50KHZ, "gtd")
    assert 20 * math.log10(cylinder_echo_amplitude(2.0, 0.0191) / edge) == pytest.approx(
        20.0, abs=1.5
    )
    assert 20 * math.log10(plane_echo_amplitude(2.0) / edge) == pytest.approx(40.0, abs=1.5)


def test_default_edge_is_heard_with_constant_gain_only_within_three_quarters_of_a_metre() -> None:
    polaroid = preset("polaroid-6500")  # its threshold; the constant-gain amplitude below

    def heard_on_axis(r: float) -> bool:
        loss = absorption_amplitude_factor(2 * r, polaroid.absorption_db_per_m)
        return bool(edge_echo_amplitude(r, K_50KHZ) * loss >= polaroid.detection_threshold)

    assert heard_on_axis(0.7) and not heard_on_axis(0.8)
    assert edge_echo_amplitude(2.0, K_50KHZ) == pytest.approx(EDGE_ECHO_STRENGTH_M / 4.0)


def test_unknown_edge_law_raises() -> None:
    with pytest.raises(ValueError, match="edge_law"):
        edge_echo_amplitude(1.0, K_50KHZ, "sharp")


def test_wall_echo_point_is_the_foot_of_the_perpendicular() -> None:
    test_world = world(walls=[{"a": [2.0, -3.0], "b": [2.0, 3.0]}])
    points, ranges, amplitudes = only(candidates(test_world, (0.5, 0.7)), EchoKind.PLANE)
    np.testing.assert_allclose(points, [[2.0, 0.7]], atol=1e-12)
    np.testing.assert_allclose(ranges, [1.5], atol=1e-12)
    np.testing.assert_allclose(amplitudes, [plane_echo_amplitude(1.5)], rtol=1e-12)


def test_no_plane_echo_when_the_foot_falls_off_the_segment() -> None:
    test_world = world(walls=[{"a": [2.0, 1.0], "b": [2.0, 3.0]}])
    points, _, _ = only(candidates(test_world, (0.0, 0.0)), EchoKind.PLANE)
    assert len(points) == 0
    edge_points, _, _ = only(candidates(test_world, (0.0, 0.0)), EchoKind.EDGE)
    np.testing.assert_allclose(sorted(map(tuple, edge_points)), [(2.0, 1.0), (2.0, 3.0)])


def test_cylinder_echo_point_faces_the_sensor() -> None:
    test_world = world(cylinders=[{"center": [3.0, 4.0], "radius": 0.5}])
    points, ranges, amplitudes = only(candidates(test_world, (0.0, 0.0)), EchoKind.CYLINDER)
    np.testing.assert_allclose(points, [[2.7, 3.6]], atol=1e-12)
    np.testing.assert_allclose(ranges, [4.5], atol=1e-12)
    np.testing.assert_allclose(amplitudes, [cylinder_echo_amplitude(4.5, 0.5)], rtol=1e-12)


def test_room_corners_are_corners_and_box_corners_are_edges() -> None:
    test_world = world(
        room={"min": [-2, -2], "max": [2, 2]}, boxes=[{"center": [1.0, 1.0], "size": [0.4, 0.4]}]
    )
    found = candidates(test_world, (-0.5, -0.3))
    corner_points, corner_ranges, corner_amplitudes = only(found, EchoKind.CORNER)
    # The box hides the room corner (2, 2) behind it.
    assert sorted(map(tuple, np.round(corner_points, 9))) == [
        (-2.0, -2.0),
        (-2.0, 2.0),
        (2.0, -2.0),
    ]
    np.testing.assert_allclose(corner_amplitudes, plane_echo_amplitude(corner_ranges))
    edge_points, edge_ranges, edge_amplitudes = only(found, EchoKind.EDGE)
    np.testing.assert_allclose(edge_amplitudes, edge_echo_amplitude(edge_ranges, K_50KHZ))
    # The box hides its own far corner.
    assert sorted(map(tuple, np.round(edge_points, 9))) == [(0.8, 0.8), (0.8, 1.2), (1.2, 0.8)]


def test_a_box_between_sensor_and_cylinder_hides_the_cylinder() -> None:
    cylinder = {"center": [2.0, 0.0], "radius": 0.1}
    clear = world(cylinders=[cylinder])
    blocked = world(cylinders=[cylinder], boxes=[{"center": [1.0, 0.0], "size": [0.2, 0.6]}])
    assert EchoKind.CYLINDER in candidates(clear, (0.0, 0.0)).kinds
    assert EchoKind.CYLINDER not in candidates(blocked, (0.0, 0.0)).kinds


def test_a_box_hides_the_wall_behind_it_but_not_its_own_front_face() -> None:
    test_world = world(
        walls=[{"a": [3.0, -2.0], "b": [3.0, 2.0]}],
        boxes=[{"center": [1.5, 0.0], "size": [0.4, 0.4]}],
    )
    points, ranges, _ = only(candidates(test_world, (0.0, 0.0)), EchoKind.PLANE)
    np.testing.assert_allclose(points, [[1.3, 0.0]], atol=1e-12)  # the front face only
    np.testing.assert_allclose(ranges, [1.3], atol=1e-12)


def test_a_thin_cylinder_in_front_hides_a_wall_point_behind_it() -> None:
    test_world = world(
        walls=[{"a": [2.0, -2.0], "b": [2.0, 2.0]}],
        cylinders=[{"center": [1.0, 0.0], "radius": 0.01}],
    )
    kinds = candidates(test_world, (0.0, 0.0)).kinds
    assert EchoKind.PLANE not in kinds and EchoKind.CYLINDER in kinds


def test_minimum_range_footprint_and_threshold_drop_candidates() -> None:
    test_world = world(
        walls=[{"a": [-0.2, -2.0], "b": [-0.2, 2.0]}, {"a": [2.0, -2.0], "b": [2.0, 2.0]}]
    )
    ranges = candidates(test_world, (0.0, 0.0), min_range_m=0.3).path_lengths
    assert 0.2 not in np.round(ranges, 9) and 2.0 in np.round(ranges, 9)
    footprint = candidates(
        test_world, (0.0, 0.0), footprint_center=(-0.1, 0.0), footprint_radius_m=0.15
    )
    assert 0.2 not in np.round(footprint.path_lengths, 9)
    loud = candidates(test_world, (0.0, 0.0), detection_threshold=plane_echo_amplitude(1.0))
    assert set(np.round(loud.path_lengths, 9)) == {0.2}


def test_air_absorption_scales_the_round_trip() -> None:
    test_world = world(walls=[{"a": [2.0, -2.0], "b": [2.0, 2.0]}])
    _, _, quiet = only(candidates(test_world, (0.0, 0.0), absorption_db_per_m=1.5), EchoKind.PLANE)
    assert quiet[0] == pytest.approx(plane_echo_amplitude(2.0) * 10 ** (-1.5 * 4.0 / 20), rel=1e-12)


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000))
def test_candidates_are_sorted_unit_directions_towards_their_points(seed: int) -> None:
    test_world = cluttered_room()
    (position,) = free_positions(test_world, np.random.default_rng(seed), 1)
    found = candidates(test_world, position)
    assert np.all(np.diff(found.path_lengths) >= 0)
    np.testing.assert_allclose(np.linalg.norm(found.directions, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(
        position + found.directions * found.path_lengths[:, None], found.points, atol=1e-12
    )
    assert not np.any(np.isnan(found.amplitudes))


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000))
def test_corner_classification_matches_the_geometry(seed: int) -> None:
    test_world = cluttered_room()
    (position,) = free_positions(test_world, np.random.default_rng(seed), 1)
    found = candidates(test_world, position)
    concave = test_world.geometry.is_concave_from(np.array(position))
    vertices = test_world.geometry.vertices
    for point, kind in zip(found.points, found.kinds, strict=True):
        if kind in (EchoKind.CORNER, EchoKind.EDGE):
            same = np.flatnonzero(np.linalg.norm(vertices - point, axis=1) < 1e-12)
            assert (kind == EchoKind.CORNER) == bool(concave[same].any())


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from(["weak", "gtd"]))
def test_every_candidate_is_as_loud_as_its_kinds_law(seed: int, edge_law: str) -> None:
    test_world = cluttered_room()
    (position,) = free_positions(test_world, np.random.default_rng(seed), 1)
    found = candidates(test_world, position, edge_law=edge_law)
    circles = test_world.geometry.circles
    laws = {
        EchoKind.PLANE: plane_echo_amplitude,
        EchoKind.CORNER: corner_echo_amplitude,
        EchoKind.EDGE: lambda r: edge_echo_amplitude(r, K_50KHZ, edge_law),
    }
    kinds = set()
    for point, kind, path, amplitude in zip(
        found.points, found.kinds, found.path_lengths, found.amplitudes, strict=True
    ):
        if kind == EchoKind.CYLINDER:
            radius = circles[
                np.argmin(np.abs(np.hypot(*(circles[:, :2] - point).T) - circles[:, 2])), 2
            ]
            expected = cylinder_echo_amplitude(path, radius)
        else:
            expected = laws[EchoKind(kind)](path)
        assert amplitude == pytest.approx(float(expected), rel=1e-12)
        kinds.add(int(kind))
    assert EchoKind.PLANE in kinds
