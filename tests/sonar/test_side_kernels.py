"""The side sonars' compiled first echoes against the array form they replace, bit for bit.

:func:`~sonar_gym.sonar.swept._side_first_echoes` runs the loops of
:mod:`sonar_gym.sonar.side_kernels`; ``side_echoes_reference.side_first_echoes_arrays``
is the ``(P, N)`` array form (itself checked pose by pose against the pan's echo search in
``test_swept.py``). Every transducer option the loops branch on is covered: air absorption,
the receiver's gain, side lobes, leakage, the GTD edge law, sensors off the robot centre, the
robot's footprint, cylinders, T-junctions and occlusion.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sonar_gym.scenario import load_scenario
from sonar_gym.sonar import side_kernels, swept
from sonar_gym.sonar.acoustics import TABLE_STEPS_PER_UNIT, PistonBeam, speed_of_sound_mps
from sonar_gym.sonar.pulse_echo import FirstEchoes, Readout
from sonar_gym.sonar.swept import SIDE_NAMES, SideSonars
from sonar_gym.world import World
from tests.fuzzing import fuzz_settings
from tests.sonar.side_echoes_reference import (
    read_echoes_arrays,
    sensor_rows_arrays,
    side_first_echoes_arrays,
    side_sensor_arrays,
)
from tests.sonar.worlds import cluttered_room, world


def _sonar_variants() -> dict[str, SideSonars]:
    apcs = SideSonars.apcs()
    transducer = apcs.transducer
    return {
        "apcs": apcs,
        "polaroid_gain": SideSonars.apcs(preset="polaroid-6500"),
        "srf04": SideSonars.apcs(preset="srf04"),
        "side_lobes": dataclasses.replace(
            apcs, transducer=dataclasses.replace(transducer, side_lobes=True)
        ),
        "side_lobes_leakage": dataclasses.replace(
            apcs,
            transducer=dataclasses.replace(transducer, side_lobes=True, side_lobe_leakage=0.05),
        ),
        "leakage": dataclasses.replace(
            apcs, transducer=dataclasses.replace(transducer, side_lobe_leakage=0.05)
        ),
        "no_absorption": dataclasses.replace(
            apcs, transducer=dataclasses.replace(transducer, absorption_db_per_m=0.0)
        ),
        "gtd_edges": dataclasses.replace(apcs, edge_law="gtd"),
        "offset_sensors": dataclasses.replace(apcs, lateral_offset_m=0.15),
    }


SONARS = _sonar_variants()


def _worlds() -> dict[str, Any]:
    return {
        "cluttered_room": cluttered_room(),
        "apcs_corridor": World(load_scenario("apcs_corridor"), temperature_c=15.0),
        "kim_arena": World(load_scenario("kim_arena"), temperature_c=30.0),
    }


WORLDS = _worlds()


def _both(sonar: SideSonars, world: Any, poses: np.ndarray) -> tuple[FirstEchoes, FirstEchoes]:
    """The compiled and the array first echoes of both sensors at ``poses`` ``(P, 3)``."""
    arguments = side_sensor_arrays(sonar, poses, SIDE_NAMES)
    return (
        swept._side_first_echoes(sonar, world, *sensor_rows_arrays(*arguments)),
        side_first_echoes_arrays(sonar, world, *arguments),
    )


def _assert_same_bits(compiled: FirstEchoes, arrays: FirstEchoes) -> None:
    for name in ("detected", "path_lengths", "amplitudes"):
        got, want = getattr(compiled, name), getattr(arrays, name)
        assert got.dtype == want.dtype and got.shape == want.shape, name
        assert got.tobytes() == want.tobytes(), name


def _poses_in(world: Any, rng: np.random.Generator, n: int) -> np.ndarray:
    """Poses anywhere in the room's bounds (in boxes, on walls, with a wall inside the robot's
    footprint) with any heading, but with no sensor inside a cylinder: no robot gets there,
    and there the array form's side-lobe pattern is read at cosines beyond 1 (the echo point
    of a cylinder around the sensor is 1 nm away by the clipped range)."""
    room = world.scenario.room
    low, high = np.asarray(room.min) - 0.2, np.asarray(room.max) + 0.2
    xy = rng.uniform(low, high, size=(4 * n, 2))
    poses = np.column_stack([xy, rng.uniform(-math.pi, math.pi, 4 * n)])
    return poses[_no_sensor_in_a_cylinder(world, poses)][:n]


def _no_sensor_in_a_cylinder(world: Any, poses: np.ndarray) -> np.ndarray:
    """Per pose, whether every sensor of every variant (offsets 0 and 0.15 m) is outside every
    cylinder."""
    keep = np.ones(len(poses), dtype=bool)
    for offset in {sonar.lateral_offset_m for sonar in SONARS.values()}:
        for sign in (1.0, -1.0):
            angle = poses[:, 2] + sign * math.pi / 2.0
            sensor_x = poses[:, 0] + offset * np.cos(angle)
            sensor_y = poses[:, 1] + offset * np.sin(angle)
            for cylinder in world.scenario.cylinders:
                centre_x, centre_y = cylinder.center
                distance = np.hypot(sensor_x - centre_x, sensor_y - centre_y)
                keep &= distance > cylinder.radius
    return keep


@pytest.mark.parametrize("world_name", sorted(WORLDS))
@pytest.mark.parametrize("sonar_name", sorted(SONARS))
def test_compiled_side_echoes_are_the_array_echoes(world_name: str, sonar_name: str) -> None:
    world, sonar = WORLDS[world_name], SONARS[sonar_name]
    rng = np.random.default_rng(sum(map(ord, world_name + sonar_name)))
    detected = total = 0
    for count in (1, 2, 3, 40, 160):
        compiled, arrays = _both(sonar, world, _poses_in(world, rng, count))
        _assert_same_bits(compiled, arrays)
        detected += int(arrays.detected.sum())
        total += arrays.detected.size
    assert 0 < detected < total  # both outcomes were compared


def test_occlusion_decides_some_first_echoes(monkeypatch: pytest.MonkeyPatch) -> None:
    """The comparisons above cover occlusion: here some sensors' nearest heard paths are
    blocked, so their first echoes come from farther (or from nothing)."""
    world, sonar = WORLDS["cluttered_room"], SONARS["apcs"]
    seen: list[tuple[np.ndarray, np.ndarray]] = []
    side_heard = side_kernels.side_heard

    def recording(*arguments: Any) -> Any:
        heard, cosines, facing = side_heard(*arguments)
        seen.append((heard, arguments[2]))  # heard paths and their ranges
        return heard, cosines, facing

    monkeypatch.setattr(side_kernels, "side_heard", recording)
    compiled, arrays = _both(sonar, world, _poses_in(world, np.random.default_rng(3), 400))
    _assert_same_bits(compiled, arrays)
    ((heard, ranges),) = seen
    nearest_heard = np.where(heard, ranges, np.inf).min(axis=1)
    blocked = heard.any(axis=1) & (~compiled.detected | (compiled.path_lengths > nearest_heard))
    assert blocked.sum() >= 5


def test_a_leg_of_no_poses_or_of_one_sensor_side_reads_nothing_or_that_side() -> None:
    world, sonar = WORLDS["apcs_corridor"], SONARS["apcs"]
    none = sonar.first_echoes_along(world, np.zeros((0, 3)))
    assert none.detected.shape == (0,)
    poses = _poses_in(world, np.random.default_rng(5), 30)
    both = sonar.first_echoes_along(world, poses)
    for index, side in enumerate(SIDE_NAMES):
        alone = sonar.first_echoes_along(world, poses, sides=(side,))
        rows = slice(index, None, 2)
        assert alone.path_lengths[rows].tobytes() == both.path_lengths[rows].tobytes()
        assert not alone.detected[1 - index :: 2].any()


@fuzz_settings(200)
@given(
    x=st.floats(-3.5, 3.5),
    y=st.floats(-3.0, 3.0),
    heading=st.floats(-4.0, 4.0),
    step=st.floats(0.0, 0.2),
    count=st.integers(1, 12),
)
def test_compiled_side_echoes_are_the_array_echoes_along_any_leg(
    x: float, y: float, heading: float, step: float, count: int
) -> None:
    """Legs from anywhere (on walls, in boxes, outside the room), any heading and spacing."""
    world = WORLDS["cluttered_room"]
    along = np.arange(count) * step
    poses = np.column_stack(
        [x + along * math.cos(heading), y + along * math.sin(heading), np.full(count, heading)]
    )
    poses = poses[_no_sensor_in_a_cylinder(world, poses)]
    for sonar in (SONARS["apcs"], SONARS["offset_sensors"], SONARS["side_lobes_leakage"]):
        _assert_same_bits(*_both(sonar, world, poses))


def test_equally_near_paths_give_the_first_candidates_echo() -> None:
    """Two free walls' ends at exactly equal ranges, both heard (GTD edges): the first
    candidate's echo wins, as numpy's ``argmin`` picks it. The heading makes their cosines, so
    their echoes, differ."""
    test_world = world(
        room={"min": [-3.0, -3.0], "max": [3.0, 3.0]},
        walls=[{"a": [-0.02, 0.31], "b": [-0.02, 1.6]}, {"a": [0.02, 0.31], "b": [0.02, 1.6]}],
    )
    sonar = SONARS["gtd_edges"]
    amplitudes = []
    for heading in (0.02, -0.02):
        compiled, arrays = _both(sonar, test_world, np.array([[0.0, 0.0, heading]]))
        _assert_same_bits(compiled, arrays)
        assert compiled.detected[0] and compiled.path_lengths[0] == math.hypot(0.02, 0.31)
        amplitudes.append(compiled.amplitudes[0])
    assert amplitudes[0] != amplitudes[1]  # the same wall end both times: the first one


def test_a_foot_exactly_at_a_walls_end_is_no_plane_echo() -> None:
    """``along`` is exactly 0: the wall gives no specular echo (strictly inside only), its end's
    edge echo is too weak, and the room behind is hidden by the wall's end."""
    test_world = world(
        room={"min": [-3.0, -3.0], "max": [3.0, 3.0]}, walls=[{"a": [0.0, 0.35], "b": [2.0, 0.35]}]
    )
    compiled, arrays = _both(SONARS["apcs"], test_world, np.array([[0.0, 0.0, 0.0]]))
    _assert_same_bits(compiled, arrays)
    assert not compiled.detected[0] and compiled.detected[1]


@pytest.mark.parametrize("side_lobes", [False, True])
def test_compiled_pattern_is_the_beams_pattern_at_every_cosine(side_lobes: bool) -> None:
    beam = PistonBeam.for_ka(5.0, side_lobes, 0.05)  # wide, leaking: it reaches behind
    assert beam.reaches_back
    tiny = np.nextafter(0.0, 1.0)
    cosines = np.concatenate(
        [np.linspace(-1.0, 1.0, 4001), [0.0, -0.0, tiny, -tiny, np.nextafter(1.0, 0.0)]]
    )
    steps = float(TABLE_STEPS_PER_UNIT)
    compiled = np.array(
        [
            side_kernels._two_way_from_cos(cosine, beam.cells, steps, beam.reaches_back)
            for cosine in cosines
        ]
    )
    assert compiled.tobytes() == beam.two_way_from_cos(cosines).tobytes()


def test_compiled_occlusion_products_are_numpys_einsum() -> None:
    rng = np.random.default_rng(1)
    matrix = rng.normal(size=(20, 30, 3)) * 10.0 ** rng.uniform(-4, 4, size=(20, 30, 3))
    paths = rng.normal(size=(20, 3)) * 10.0 ** rng.uniform(-4, 4, size=(20, 3))
    compiled = np.array(
        [
            [side_kernels._product(matrix, path, row, *paths[path]) for row in range(30)]
            for path in range(20)
        ]
    )
    assert compiled.tobytes() == np.einsum("hrk,hk->hr", matrix, paths).tobytes()


def test_numpys_einsum_of_three_terms_sums_first_and_third_then_second() -> None:
    """The order :func:`sonar_gym.sonar.side_kernels._product` sums the occlusion products in:
    if numpy's ``einsum`` changes it, this says so before the comparisons above fail."""
    rng = np.random.default_rng(0)
    matrix = rng.normal(size=(60, 70, 3)) * 10.0 ** rng.uniform(-4, 4, size=(60, 70, 3))
    paths = rng.normal(size=(60, 3)) * 10.0 ** rng.uniform(-4, 4, size=(60, 3))
    terms = matrix * paths[:, None, :]
    ordered = (terms[..., 0] + terms[..., 2]) + terms[..., 1]
    sequential = (terms[..., 0] + terms[..., 1]) + terms[..., 2]
    einsum = np.einsum("hrk,hk->hr", matrix, paths)
    assert einsum.tobytes() == ordered.tobytes()
    assert einsum.tobytes() != sequential.tobytes()  # the order shows in these numbers


def _array_echoes_along(
    sonar: SideSonars, world: Any, poses: np.ndarray, sides: tuple[str, ...]
) -> FirstEchoes:
    """:meth:`SideSonars.first_echoes_along` through the array forms of the reference."""
    sensed = side_first_echoes_arrays(sonar, world, *side_sensor_arrays(sonar, poses, sides))
    if len(set(sides)) == len(SIDE_NAMES):
        return sensed
    n = len(poses)
    echoes = FirstEchoes(np.zeros(2 * n, dtype=bool), np.zeros(2 * n), np.zeros(2 * n))
    rows = slice(SIDE_NAMES.index(sides[0]), None, 2)
    echoes.detected[rows] = sensed.detected
    echoes.path_lengths[rows] = sensed.path_lengths
    echoes.amplitudes[rows] = sensed.amplitudes
    return echoes


@fuzz_settings(200)
@given(
    seed=st.integers(0, 2**32 - 1),
    count=st.integers(0, 12),
    sides=st.sampled_from([SIDE_NAMES, ("left",), ("right",), ("right", "left")]),
    offset=st.sampled_from([0.0, 0.15, 1e-300, 2.5]),
)
def test_compiled_sensor_rows_are_the_array_sensor_rows(
    seed: int, count: int, sides: tuple[str, ...], offset: float
) -> None:
    """Headings of any size and sign (huge ones too), sensors at or off the centre, either
    or both sides."""
    rng = np.random.default_rng(seed)
    poses = np.column_stack([rng.normal(0.0, 10.0, (count, 2)), rng.normal(0.0, 10.0, count) ** 3])
    sonar = dataclasses.replace(SONARS["apcs"], lateral_offset_m=offset)
    first, stride = (0, 1) if len(set(sides)) == 2 else (SIDE_NAMES.index(sides[0]), 2)
    headings = poses[:, 2]
    got = side_kernels.side_sensors(
        poses,
        np.cos(headings),
        np.sin(headings),
        sonar._sensor_offsets(headings),
        first,
        stride,
    )
    want = sensor_rows_arrays(*side_sensor_arrays(sonar, poses, sides))
    for got_rows, want_rows in zip(got, want, strict=True):
        assert got_rows.shape == want_rows.shape
        assert got_rows.tobytes() == want_rows.tobytes()


@pytest.mark.parametrize("sonar_name", ["apcs", "gtd_edges", "side_lobes_leakage", "srf04"])
def test_first_echoes_along_are_the_array_echoes_as_air_and_world_change(
    sonar_name: str,
) -> None:
    """One sonar object asked in turn in two worlds (robot radii 0.3 and 0.2 m) and at changing
    temperatures: every answer is that of the array form, which remembers nothing."""
    sonar = SONARS[sonar_name]
    worlds = [cluttered_room(), World(load_scenario("apcs_corridor"))]
    rng = np.random.default_rng(11)
    poses = [_poses_in(world, rng, 40) for world in worlds]
    changed = 0
    last_amplitudes: dict[int, bytes] = {}
    for temperature, which, sides in [
        (20.0, 0, SIDE_NAMES),
        (20.0, 1, SIDE_NAMES),
        (-10.0, 1, ("left",)),
        (-10.0, 1, SIDE_NAMES),
        (40.0, 1, SIDE_NAMES),
        (40.0, 0, ("right",)),
        (40.0, 0, SIDE_NAMES),
        (20.0, 0, SIDE_NAMES),
        (20.0, 1, SIDE_NAMES),
    ]:
        world = worlds[which]
        world.temperature_c = temperature
        got = sonar.first_echoes_along(world, poses[which], sides)
        _assert_same_bits(got, _array_echoes_along(sonar, world, poses[which], sides))
        if len(sides) == 2:
            previous = last_amplitudes.get(which)
            changed += previous is not None and previous != got.amplitudes.tobytes()
            last_amplitudes[which] = got.amplitudes.tobytes()
    assert changed >= 2  # the temperature changed what was heard


@fuzz_settings(200)
@given(
    seed=st.integers(0, 2**32 - 1),
    shape=st.tuples(st.integers(0, 30), st.integers(0, 40)),
    density=st.sampled_from([0.0, 0.05, 0.5, 1.0]),
)
def test_compiled_heard_paths_are_numpys_nonzero(
    seed: int, shape: tuple[int, int], density: float
) -> None:
    rng = np.random.default_rng(seed)
    heard = rng.random(shape) < density
    homogeneous = np.column_stack([rng.normal(size=(shape[0], 2)), np.ones(shape[0])])
    sensor_rows, candidate_rows, sensors = side_kernels.heard_paths(heard, homogeneous)
    want_sensors, want_candidates = np.nonzero(heard)
    assert sensor_rows.dtype == want_sensors.dtype
    assert sensor_rows.tobytes() == want_sensors.tobytes()
    assert candidate_rows.tobytes() == want_candidates.tobytes()
    assert sensors.tobytes() == homogeneous[want_sensors].tobytes()
    assert sensors.shape == (len(want_sensors), 3)


_READOUTS = [
    Readout(range_noise=noise, crossing_delay=delay, quantisation=counter)
    for noise in (True, False)
    for delay in (True, False)
    for counter in (True, False)
]


@fuzz_settings(200)
@given(
    seed=st.integers(0, 2**32 - 1),
    count=st.integers(0, 40),
    sonar_name=st.sampled_from(["apcs", "polaroid_gain", "srf04"]),
    readout=st.sampled_from(_READOUTS),
    temperature=st.sampled_from([-20.0, 15.0, 20.0, 45.0]),
    assumed_speed=st.sampled_from([None, 331.0, 350.0]),
)
def test_compiled_side_readings_are_the_array_readings(
    seed: int,
    count: int,
    sonar_name: str,
    readout: Readout,
    temperature: float,
    assumed_speed: float | None,
) -> None:
    """Any first echoes (detected or not, at the threshold, beyond the maximum range, at the
    counter's steps) under every readout switch: the same ranges and the same draws."""
    sonar = dataclasses.replace(SONARS[sonar_name], readout=readout)
    if assumed_speed is not None:
        sonar = sonar.with_assumed_speed(assumed_speed)
    transducer = sonar.transducer
    world = WORLDS["apcs_corridor"]
    world.temperature_c = temperature
    rng = np.random.default_rng(seed)
    path_lengths = rng.uniform(0.0, 1.2 * transducer.max_range_m, 2 * count)
    edges = _edge_paths(sonar, speed_of_sound_mps(temperature), rng)
    chosen = rng.random(2 * count) < 0.4
    path_lengths[chosen] = rng.choice(edges, int(chosen.sum()))
    amplitudes = transducer.detection_threshold * rng.uniform(1.0, 50.0, 2 * count)
    amplitudes[rng.random(2 * count) < 0.2] = transducer.detection_threshold
    echoes = FirstEchoes(rng.random(2 * count) < 0.8, path_lengths, amplitudes)
    draws, reference_draws = np.random.default_rng(seed), np.random.default_rng(seed)
    try:
        got = sonar.read_echoes(world, echoes, draws)
        want = read_echoes_arrays(sonar, world, echoes, reference_draws)
    finally:
        world.temperature_c = 15.0
    assert got.left_m.tobytes() == want[0].tobytes()
    assert got.right_m.tobytes() == want[1].tobytes()
    assert draws.bit_generator.state == reference_draws.bit_generator.state


def _edge_paths(sonar: SideSonars, speed_mps: float, rng: np.random.Generator) -> np.ndarray:
    """Paths (m) a few ulps either side of a whole number of counter periods of flight and
    of the maximum range (where the counter's floor and the range check decide)."""
    transducer = sonar.transducer
    metres_per_period = transducer.timer_period_s * speed_mps / 2.0
    steps = rng.integers(1, int(transducer.max_range_m / metres_per_period), 8)
    centres = np.concatenate(
        [
            steps * metres_per_period,
            [transducer.max_range_m * speed_mps / sonar.assumed_speed_of_sound_mps],
        ]
    )
    ulps = np.arange(-6, 7)
    return (centres[:, None] + ulps[None, :] * np.spacing(centres)[:, None]).ravel()


def test_side_readings_need_a_generator_only_with_noise() -> None:
    world, sonar = WORLDS["apcs_corridor"], SONARS["apcs"]
    echoes = FirstEchoes(np.ones(4, dtype=bool), np.full(4, 1.0), np.full(4, 1.0))
    with pytest.raises(ValueError, match="'rng' is needed"):
        sonar.read_echoes(world, echoes, None)
    quiet = sonar.with_readout(range_noise=False).read_echoes(world, echoes, None)
    assert (
        quiet.left_m.tobytes()
        == read_echoes_arrays(sonar.with_readout(range_noise=False), world, echoes, None)[
            0
        ].tobytes()
    )
    with pytest.raises(ValueError, match="a left and a right echo"):
        sonar.read_echoes(world, FirstEchoes(np.ones(3, dtype=bool), np.ones(3), np.ones(3)), None)
