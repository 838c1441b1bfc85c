"""The pan's fast paths against the plain forms they replace: the same numbers, bit for bit.

* the fused main-lobe readout (:func:`~sonar_gym.sonar.pulse_echo._main_lobe_readings`)
  against :func:`~sonar_gym.sonar.pulse_echo.first_echoes` then
  :func:`~sonar_gym.sonar.pulse_echo.echo_readings`, noise included (same generator state);
* the compiled occlusion test (:func:`~sonar_gym.sonar.kernels.unoccluded`) against the
  array test kind by kind, written out below;
* the beam pattern for cosines in front of the transducer, and the main-lobe limits of levels
  known to be reachable, against the checked and clipped forms.
"""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from sonar_gym.pose import Pose
from sonar_gym.scenario import load_scenario
from sonar_gym.pose import FloatArray
from sonar_gym.sonar import kernels
from sonar_gym.sonar import pulse_echo
from sonar_gym.sonar.acoustics import (
    SMALLEST_COSINE,
    TABLE_STEPS_PER_UNIT,
    PistonBeam,
    speed_of_sound_mps,
)
from sonar_gym.sonar.echo_tables import PATH_END_TOLERANCE, EchoTables, echo_tables
from sonar_gym.sonar.echoes import EchoKind
from sonar_gym.sonar.pulse_echo import IDEAL_READOUT, Readout
from sonar_gym.sonar.rotating import RotatingSonar, _pan_grid
from sonar_gym.world import World
from tests.sonar.worlds import cluttered_room, free_positions

SCENARIOS = ("beom_cho_lab", "kim_arena", "apcs_corridor")
READOUTS = (
    Readout(),
    Readout(range_noise=False),
    Readout(crossing_delay=False, quantisation=False),
    IDEAL_READOUT,
)


def _world(name: str) -> World:
    return World(load_scenario(name), temperature_c=24.0)


@pytest.mark.parametrize("scenario", SCENARIOS)
@pytest.mark.parametrize("preset", ["polaroid-6500", "srf04", "ma40b8"])
def test_fused_main_lobe_readout_reads_what_first_echoes_then_readings_read(
    scenario: str, preset: str
) -> None:
    world = _world(scenario)
    rng = np.random.default_rng(7)
    _, directions = _pan_grid(-math.pi, math.pi, math.radians(1.0))
    compared = detected = 0
    for readout in READOUTS:
        sonar = RotatingSonar.preset(preset, readout=readout)
        transducer = sonar.transducer
        assert not transducer.side_lobes  # the fused path is the path of every preset
        true_speed = speed_of_sound_mps(world.temperature_c)
        beam = PistonBeam.for_ka(
            transducer.wavenumber_ka(true_speed), False, transducer.side_lobe_leakage
        )
        for _ in range(8):
            pose = world.sample_free_pose(rng, clearance=0.05)
            candidates = sonar.candidates(world, pose, pose.position)
            seed = int(rng.integers(1 << 30))
            fused = pulse_echo._main_lobe_readings(
                candidates,
                directions,
                beam,
                transducer,
                true_speed,
                sonar.assumed_speed_of_sound_mps,
                readout,
                np.random.default_rng(seed),
                pose.theta,
            )
            echoes = pulse_echo.first_echoes(
                candidates, directions, beam, transducer.detection_threshold, pose.theta
            )
            plain = pulse_echo.echo_readings(
                echoes,
                transducer,
                true_speed,
                sonar.assumed_speed_of_sound_mps,
                readout,
                np.random.default_rng(seed),
            )
            np.testing.assert_array_equal(fused[0], plain[0])  # NaN where both drop out
            np.testing.assert_array_equal(fused[1], plain[1])
            compared += 1
            detected += int(np.isfinite(plain[0]).sum())
    assert compared == 32 and detected > 0


def test_the_remembered_readout_steps_follow_each_change_of_readout_and_speeds() -> None:
    """One transducer object, its readout and speeds changing from ping to ping: the fused
    readout's remembered constants are those of each ping's own readout and speeds."""
    world = _world("kim_arena")
    rng = np.random.default_rng(3)
    sonar = RotatingSonar.preset("srf04")
    transducer = sonar.transducer
    _, directions = _pan_grid(-math.pi, math.pi, math.radians(5.0))
    pose = world.sample_free_pose(rng, clearance=0.05)
    candidates = sonar.candidates(world, pose, pose.position)
    # from one ping to the next, one of readout, true and assumed speed changes alone
    first, *others = READOUTS
    changes = [(first, 340.0, 330.0), (first, 346.0, 330.0), (first, 346.0, 343.2)]
    changes += [(readout, 346.0, 343.2) for readout in others]
    changes += [(others[-1], 340.0, 343.2), (others[-1], 340.0, 330.0)]
    for readout, true_speed, assumed_speed in changes:
        beam = PistonBeam.for_ka(
            transducer.wavenumber_ka(true_speed), False, transducer.side_lobe_leakage
        )
        seed = int(rng.integers(1 << 30))
        fused = pulse_echo._main_lobe_readings(
            candidates,
            directions,
            beam,
            transducer,
            true_speed,
            assumed_speed,
            readout,
            np.random.default_rng(seed),
            pose.theta,
        )
        echoes = pulse_echo.first_echoes(
            candidates, directions, beam, transducer.detection_threshold, pose.theta
        )
        plain = pulse_echo.echo_readings(
            echoes, transducer, true_speed, assumed_speed, readout, np.random.default_rng(seed)
        )
        np.testing.assert_array_equal(fused[0], plain[0])
        np.testing.assert_array_equal(fused[1], plain[1])


@pytest.mark.parametrize("n_pings", [1, 2, 3, 19, 60])
@pytest.mark.parametrize("scenario", SCENARIOS)
def test_a_ping_of_any_count_reads_what_first_echoes_then_readings_read(
    scenario: str, n_pings: int
) -> None:
    """One ping goes through numpy, two or more through the compiled loop: both read alike."""
    world = _world(scenario)
    rng = np.random.default_rng(n_pings)
    sonar = RotatingSonar.preset("polaroid-6500")
    _, directions = _pan_grid(-math.pi, math.pi, math.radians(1.0))
    detected = 0
    for _ in range(20):
        pose = world.sample_free_pose(rng, clearance=0.05)
        start = int(rng.integers(len(directions) - n_pings))
        beams = directions[start : start + n_pings]
        seed = int(rng.integers(1 << 30))
        ranges, amplitudes = sonar.ping(
            world, pose, pose.position, beams, np.random.default_rng(seed)
        )
        plain = sonar.readings(
            world,
            sonar.first_echoes_at(world, pose, pose.position, beams),
            np.random.default_rng(seed),
        )
        np.testing.assert_array_equal(ranges, plain[0])
        np.testing.assert_array_equal(amplitudes, plain[1])
        detected += int(np.isfinite(ranges).sum())
    assert detected > 0


def test_a_sonar_with_side_lobes_still_reads_through_first_echoes() -> None:
    world, pose = _world("beom_cho_lab"), Pose(2.0, 2.0, 0.4)
    sonar = RotatingSonar(
        dataclasses.replace(RotatingSonar.preset("srf04").transducer, side_lobes=True)
    )
    _, directions = _pan_grid(-math.pi, math.pi, math.radians(1.0))
    ranges, amplitudes = sonar.ping(
        world, pose, pose.position, directions, np.random.default_rng(3)
    )
    plain = sonar.readings(
        world,
        sonar.first_echoes_at(world, pose, pose.position, directions),
        np.random.default_rng(3),
    )
    np.testing.assert_array_equal(ranges, plain[0])
    np.testing.assert_array_equal(amplitudes, plain[1])


def plain_unoccluded(
    tables: EchoTables,
    products: FloatArray,
    ranges: FloatArray,
    centre_distance: FloatArray,
    occluders: np.ndarray,
) -> np.ndarray:
    """The occlusion test over whole arrays, segments then circles (``occluders``: ``(S,)``).

    A segment that may not occlude gets a zero crossing denominator (no crossing); a segment
    blocks with ``0 <= u <= 1 - tol`` and ``0 <= v <= 1``, a circle with ``0 <= u* <= 1 - tol``
    and a gap below its radius.
    """
    n_segments, n_circles = tables.n_segments, tables.n_circles
    centre = np.array([(1.0 - PATH_END_TOLERANCE) / 2.0, 0.5])[:, None, None]
    n_paths = len(ranges)
    blocked = np.zeros(n_paths, dtype=bool)
    if n_segments:
        crossing_denominator = products[:n_segments] * occluders[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = (
                products[n_segments : 3 * n_segments].reshape(2, n_segments, n_paths)
                / crossing_denominator
            )
        inside = np.abs(uv - centre) <= centre
        blocked = np.logical_or.reduce(inside[0] & inside[1], axis=0)
    if n_circles:
        dots = products[3 * n_segments :]
        nearest = dots / (ranges * ranges)
        on_path = np.abs(nearest - centre[0, 0]) <= centre[0, 0]
        gap_sq = (centre_distance * centre_distance)[:, None] - dots * nearest
        blocked = blocked | np.logical_or.reduce(
            on_path & (gap_sq < tables.radius_sq[:, None]), axis=0
        )
    return ~blocked


def _occlusion_inputs(
    world: Any, position: tuple[float, float], rng: np.random.Generator
) -> tuple[EchoTables, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Products, ranges, centre distances and occluders at ``position`` for paths to every
    candidate echo point and to random points (some through walls, some into cylinders)."""
    tables = echo_tables(world.geometry, EchoKind.PLANE, EchoKind.CYLINDER, EchoKind.EDGE)
    mapped = tables.position_and_occlusion_map @ np.array((position[0], position[1], 1.0))
    to_candidates = mapped[tables.rel_rows].reshape(-1, 3)
    angles = rng.uniform(-math.pi, math.pi, 200)
    lengths = rng.uniform(0.05, 6.0, 200)
    to_random = np.column_stack([lengths * np.cos(angles), lengths * np.sin(angles), np.ones(200)])
    rel = np.concatenate([to_candidates, to_random])
    matrix = mapped[tables.occlusion_rows].reshape(-1, 3)
    centres = world.geometry.circles[:, :2]
    centre_distance = np.hypot(centres[:, 0] - position[0], centres[:, 1] - position[1])
    occluders = rng.random(tables.n_segments) < 0.7
    return tables, matrix @ rel.T, np.hypot(rel[:, 0], rel[:, 1]), centre_distance, occluders


@pytest.mark.parametrize(
    "world_name", ["beom_cho_lab", "kim_arena", "cluttered_room", "apcs_corridor"]
)
def test_compiled_occlusion_test_blocks_what_the_array_test_blocks(world_name: str) -> None:
    rng = np.random.default_rng(11)
    world: Any
    if world_name == "cluttered_room":
        world = cluttered_room()
        positions = free_positions(world, rng, 10)
    else:
        world = World(load_scenario(world_name))
        poses = [world.sample_free_pose(rng, clearance=0.05) for _ in range(10)]
        positions = [(pose.x, pose.y) for pose in poses]
    blocked = clear = 0
    for position in positions:
        tables, products, ranges, centre_distance, occluders = _occlusion_inputs(
            world, position, rng
        )
        compiled = kernels.unoccluded(
            products,
            ranges,
            centre_distance,
            tables.radius_sq,
            np.concatenate([occluders, np.ones(tables.n_circles, dtype=bool)]),
            (1.0 - PATH_END_TOLERANCE) / 2.0,
        )
        plain = plain_unoccluded(tables, products, ranges, centre_distance, occluders)
        np.testing.assert_array_equal(compiled, plain)
        blocked += int((~plain).sum())
        clear += int(plain.sum())
    assert blocked > 0 and clear > 0


def test_compiled_occlusion_test_keeps_the_interval_ends_of_the_array_test() -> None:
    """Ratios exactly at the ends of the blocking intervals, and just outside them."""
    end = 1.0 - PATH_END_TOLERANCE
    ratios = np.array([0.0, -5e-324, end, np.nextafter(end, 2.0), 0.5, 1.0, 1.0 + 2e-16, np.nan])
    u, v = (grid.ravel() for grid in np.meshgrid(ratios, ratios))
    n_paths = len(u)
    denominator = np.full(n_paths, 2.0)
    ranges = np.full(n_paths, 2.0)
    # one segment (denominator, u and v numerators), then one circle: u* = dot / range^2 and
    # a gap of centre distance^2 - dot u* against a squared radius of 1
    circle_dot = 4.0 * u
    products = np.vstack([denominator, 2.0 * u, 2.0 * v, circle_dot])
    centre_distance = np.sqrt(circle_dot * u + np.where(v > 0.5, 0.5, 1.0))[:1]
    tables: Any = SimpleNamespace(n_segments=1, n_circles=1, radius_sq=np.array([1.0]))
    for occluding in (True, False):
        occluders = np.array([occluding])
        compiled = kernels.unoccluded(
            products,
            ranges,
            centre_distance,
            tables.radius_sq,
            np.concatenate([occluders, [True]]),
            end / 2.0,
        )
        plain = plain_unoccluded(tables, products, ranges, centre_distance, occluders)
        np.testing.assert_array_equal(compiled, plain)
        assert 0 < plain.sum() < n_paths


def array_passing_candidates(
    tested: np.ndarray,
    strict_bounds: np.ndarray,
    inclusive_bounds: np.ndarray,
    concave: np.ndarray,
    twin: np.ndarray,
    twin_comes_last: np.ndarray,
    n_specular: int,
    has_t_junctions: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """The echo search's per-candidate tests over whole arrays (the compiled loop's reference)."""
    n_candidates = len(strict_bounds) // 2
    tests = np.empty(len(tested), dtype=bool)
    np.greater(tested[: 2 * n_candidates], strict_bounds, out=tests[: 2 * n_candidates])
    np.greater_equal(tested[2 * n_candidates :], inclusive_bounds, out=tests[2 * n_candidates :])
    valid = np.logical_and.reduce(tests[: 5 * n_candidates].reshape(5, n_candidates), axis=0)
    if has_t_junctions:
        wedges = slice(n_specular, n_specular + len(concave))
        valid[wedges] &= np.where(concave.take(twin) == concave, twin_comes_last, concave)
    return valid.nonzero()[0], tests[5 * n_candidates :]


@pytest.mark.parametrize("t_junctions", [False, True])
def test_compiled_candidate_tests_pass_what_the_array_tests_pass(t_junctions: bool) -> None:
    rng = np.random.default_rng(13)
    passed = 0
    for _ in range(200):
        n_specular, n_wedges, n_others = (int(n) for n in rng.integers(1, 12, 3))
        n_candidates = n_specular + n_wedges + n_others
        n_occluders = int(rng.integers(0, 10))
        strict = rng.choice([0.0, -1.0], 2 * n_candidates)
        inclusive = rng.choice([0.0, 0.3, 1e-4], 3 * n_candidates + n_occluders)
        # values on, just above and below the bounds, and NaN
        tested = np.concatenate([strict, inclusive]) + rng.choice(
            [0.0, 1e-17, -1e-17, 0.5, -0.5, np.nan], 5 * n_candidates + n_occluders
        )
        concave = rng.random(n_wedges) < 0.5
        twin = np.arange(n_wedges)
        if t_junctions and n_wedges > 1:
            pair = rng.choice(n_wedges, 2, replace=False)
            twin[pair[0]], twin[pair[1]] = pair[1], pair[0]
        args = (tested, strict, inclusive, concave, twin, twin >= np.arange(n_wedges))
        compiled = kernels.passing_candidates(*args, n_specular, t_junctions)
        array = array_passing_candidates(*args, n_specular, t_junctions)
        np.testing.assert_array_equal(compiled[0], array[0])
        np.testing.assert_array_equal(compiled[1], array[1])
        passed += len(array[0])
    assert passed > 0


@pytest.mark.parametrize("leakage", [0.0, 0.07])
def test_pattern_in_front_and_reachable_limits_equal_the_checked_forms(leakage: float) -> None:
    beam = PistonBeam.for_ka(17.6, False, leakage)
    rng = np.random.default_rng(2)
    cosines = np.concatenate([rng.uniform(1e-12, 1.0, 5000), [1.0, 0.5, 1e-300]])
    np.testing.assert_array_equal(beam.two_way_in_front(cosines), beam.two_way_from_cos(cosines))
    levels = np.concatenate([10.0 ** rng.uniform(-6.0, 0.0, 5000), [1.0, 1e-9]])
    np.testing.assert_array_equal(
        beam.main_lobe_cos_limits(levels, reachable=True), beam.main_lobe_cos_limits(levels)
    )


@pytest.mark.parametrize("ka", [4.0, 17.6, 40.0])
@pytest.mark.parametrize("leakage", [0.0, 0.07])
def test_compiled_main_lobe_limit_is_the_beams_limit_bit_for_bit(ka: float, leakage: float) -> None:
    """The limit the compiled readouts compute per candidate, against the beam's array form,
    over reachable levels, levels above 1 (never heard) and the table's own values."""
    beam = PistonBeam.for_ka(ka, False, leakage)
    rng = np.random.default_rng(3)
    levels = np.concatenate(
        [
            10.0 ** rng.uniform(-9.0, 0.5, 4000),
            beam.main_lobe_rising,
            [1.0, np.nextafter(1.0, 2.0), 3.0, 1e-300, SMALLEST_COSINE],
        ]
    )
    expected = beam.main_lobe_cos_limits(levels)
    compiled = [
        kernels.main_lobe_cos_limit(
            level,
            beam.main_lobe_rising,
            beam.main_lobe_cells,
            1.0 / TABLE_STEPS_PER_UNIT,
            SMALLEST_COSINE,
        )
        for level in levels.tolist()
    ]
    assert np.array(compiled).tobytes() == expected.tobytes()
    assert (expected == 2.0).sum() == (levels > 1.0).sum() > 0


@pytest.mark.parametrize("side_lobes", [False, True])
@pytest.mark.parametrize("leakage", [0.0, 0.07])
def test_beam_table_samples_are_the_exact_pattern_at_the_grid_angles(
    side_lobes: bool, leakage: float
) -> None:
    """Without side lobes the table evaluates 2 J1(x) / x on the main lobe alone; every sample,
    main lobe, null, leakage floor and back, must still be :func:`two_way_pattern` exactly."""
    from sonar_gym.sonar.acoustics import _table_grid, two_way_pattern

    _, theta, _ = _table_grid()
    rng = np.random.default_rng(5)
    for ka in [17.6, 14.3, 3.9, 1.2, *rng.uniform(0.5, 40.0, 20)]:
        beam = PistonBeam.for_ka.__wrapped__(float(ka), side_lobes, leakage)
        exact = two_way_pattern(theta, float(ka), side_lobes=side_lobes, side_lobe_leakage=leakage)
        np.testing.assert_array_equal(beam.cells[:, 0], exact[:-1])
        np.testing.assert_array_equal(beam.cells[:, 1], np.diff(exact))
