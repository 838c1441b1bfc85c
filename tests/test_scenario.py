"""Scenario loading and validation: every error names the file and the field."""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from sonar_gym.scenario import (
    Box,
    Cylinder,
    Scenario,
    ScenarioError,
    builtin_names,
    load_scenario,
    scenario_from_dict,
)

MINIMAL = """
[room]
min = [-1.0, -1.0]
max = [1.0, 1.0]
"""


def write(tmp_path: Path, text: str, name: str = "world.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def assert_error_names(tmp_path: Path, text: str, *fragments: str) -> None:
    path = write(tmp_path, text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    message = str(info.value)
    assert str(path) in message
    for fragment in fragments:
        assert fragment in message, message


def test_minimal_room_loads_with_defaults(tmp_path: Path) -> None:
    scenario = load_scenario(write(tmp_path, MINIMAL))
    assert scenario.name == "world"
    assert scenario.room is not None and scenario.room.size == (2.0, 2.0)
    assert scenario.robot.radius == 0.3
    assert scenario.reflector.distance == 0.515
    assert scenario.sensor.preset == "polaroid-6500"


def test_malformed_toml_names_the_file(tmp_path: Path) -> None:
    assert_error_names(tmp_path, "[room\nmin = [0, 0]", "not valid TOML")


def test_undecodable_file_names_the_file(tmp_path: Path) -> None:
    path = tmp_path / "binary.toml"
    path.write_bytes(b"\xff\xfe[room]")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(path) in str(info.value) and "not valid TOML" in str(info.value)


def test_unknown_top_level_key_is_named(tmp_path: Path) -> None:
    assert_error_names(tmp_path, MINIMAL + "\n[furniture]\nx = 1\n", "furniture", "<top level>")


def test_unknown_key_inside_an_entry_is_named(tmp_path: Path) -> None:
    text = MINIMAL + "\n[[cylinders]]\ncenter = [0, 0]\nradius = 0.1\ncolour = 'red'\n"
    assert_error_names(tmp_path, text, "colour", "cylinders[0]")


def test_wrong_type_names_the_field(tmp_path: Path) -> None:
    text = MINIMAL + "\n[[boxes]]\ncenter = [0, 'a']\nsize = [0.2, 0.2]\n"
    assert_error_names(tmp_path, text, "boxes[0].center", "finite number")


def test_vector_of_wrong_length_names_the_field(tmp_path: Path) -> None:
    text = MINIMAL + "\n[[emitters]]\nname = 'A'\nposition = [0, 0]\n"
    assert_error_names(tmp_path, text, "emitters[0].position", "[x, y, z]")


def test_negative_radius_names_the_field(tmp_path: Path) -> None:
    text = MINIMAL + "\n[[cylinders]]\ncenter = [0, 0]\nradius = -0.1\n"
    assert_error_names(tmp_path, text, "cylinders[0].radius", "positive")


def test_negative_robot_radius_names_the_field(tmp_path: Path) -> None:
    assert_error_names(tmp_path, MINIMAL + "\n[robot]\nradius = -0.3\n", "robot.radius", "positive")


def test_unknown_role_lists_the_roles(tmp_path: Path) -> None:
    text = MINIMAL + "\n[[cylinders]]\ncenter = [0, 0]\nradius = 0.1\nrole = 'beacon'\n"
    assert_error_names(
        tmp_path, text, "cylinders[0].role", "small_beacon", "large_beacon", "clutter"
    )


def test_unknown_preset_lists_the_presets(tmp_path: Path) -> None:
    text = MINIMAL + "\n[sensor]\npreset = 'sick-lms'\n"
    assert_error_names(tmp_path, text, "sensor.preset", "polaroid-6500", "srf04", "ma40b8")


def test_zero_length_wall_is_rejected(tmp_path: Path) -> None:
    text = MINIMAL + "\n[[walls]]\na = [0.5, 0.5]\nb = [0.5, 0.5]\n"
    assert_error_names(tmp_path, text, "walls[0]", "non-zero length")


def test_duplicate_beacon_role_is_rejected(tmp_path: Path) -> None:
    text = MINIMAL + (
        "\n[[cylinders]]\ncenter = [0, 0]\nradius = 0.02\nrole = 'small_beacon'\n"
        "\n[[cylinders]]\ncenter = [0.5, 0]\nradius = 0.02\nrole = 'small_beacon'\n"
    )
    assert_error_names(tmp_path, text, "cylinders", "small_beacon")


def test_duplicate_emitter_names_are_rejected(tmp_path: Path) -> None:
    text = MINIMAL + (
        "\n[[emitters]]\nname = 'A'\nposition = [0, 0, 1]\n"
        "\n[[emitters]]\nname = 'A'\nposition = [1, 0, 1]\n"
    )
    assert_error_names(tmp_path, text, "emitters", "unique")


def test_inverted_room_is_rejected(tmp_path: Path) -> None:
    assert_error_names(tmp_path, "[room]\nmin = [1, 1]\nmax = [0, 2]\n", "room", "min < max")


def test_empty_room_table_is_rejected_not_ignored(tmp_path: Path) -> None:
    text = "[room]\n\n[[cylinders]]\ncenter = [0, 0]\nradius = 0.1\n"
    assert_error_names(tmp_path, text, "room.min", "present")


def test_mapped_must_be_boolean(tmp_path: Path) -> None:
    text = MINIMAL + "\n[[walls]]\na = [0, 0]\nb = [0.5, 0]\nmapped = 1\n"
    assert_error_names(tmp_path, text, "walls[0].mapped", "true or false")


def test_empty_scenario_is_rejected(tmp_path: Path) -> None:
    assert_error_names(tmp_path, "[meta]\nname = 'nothing'\n", "at least one of")


def test_unknown_builtin_name_lists_the_builtins() -> None:
    with pytest.raises(ScenarioError) as info:
        load_scenario("no_such_world")
    for name in builtin_names():
        assert name in str(info.value)


def test_missing_file_is_reported(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match="does not exist"):
        load_scenario(tmp_path / "absent.toml")


def test_json_loads_like_toml(tmp_path: Path) -> None:
    data = {
        "meta": {"name": "json-room"},
        "room": {"min": [-1, -1], "max": [1, 1]},
        "boxes": [{"center": [0.2, 0.3], "size": [0.2, 0.4], "angle_deg": 30}],
        "cylinders": [{"center": [-0.5, 0.5], "radius": 0.05, "role": "large_beacon"}],
    }
    scenario = load_scenario(write(tmp_path, json.dumps(data), "room.json"))
    assert scenario.name == "json-room"
    assert scenario.boxes == (Box((0.2, 0.3), (0.2, 0.4), 30.0),)
    assert scenario.cylinders == (Cylinder((-0.5, 0.5), 0.05, "large_beacon"),)


def test_malformed_json_names_the_file(tmp_path: Path) -> None:
    path = write(tmp_path, "{ not json", "room.json")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(path) in str(info.value) and "JSON" in str(info.value)


def test_non_finite_json_number_is_rejected(tmp_path: Path) -> None:
    text = '{"room": {"min": [-1, -1], "max": [1, NaN]}}'
    path = write(tmp_path, text, "room.json")
    with pytest.raises(ScenarioError, match="room.max"):
        load_scenario(path)


def test_box_corners_are_counter_clockwise_and_rotated() -> None:
    box = Box((1.0, 2.0), (2.0, 1.0), 90.0)
    expected = ((1.5, 1.0), (1.5, 3.0), (0.5, 3.0), (0.5, 1.0))
    for corner, want in zip(box.corners, expected, strict=True):
        assert corner == pytest.approx(want, abs=1e-12)


@pytest.mark.parametrize("name", builtin_names())
def test_every_builtin_loads_with_meta(name: str) -> None:
    scenario = load_scenario(name)
    assert scenario.name == name
    assert scenario.description.strip() and scenario.source.strip()


def test_all_five_paper_scenarios_ship() -> None:
    assert {"beom_cho_lab", "kim_arena", "wu_tsai_room", "roh_beacons", "apcs_corridor"} <= set(
        builtin_names()
    )


def test_beom_cho_lab_matches_the_paper() -> None:
    lab = load_scenario("beom_cho_lab")
    assert lab.room is not None and lab.room.size == pytest.approx((6.2, 5.0))
    small, large = lab.beacon("small_beacon"), lab.beacon("large_beacon")
    assert small.center == (2.85, -0.6) and small.radius == pytest.approx(0.0382 / 2)
    assert large.center == (0.3, -1.5) and large.radius == pytest.approx(0.14 / 2)
    # sec. V.A: "The distance between two beacons is 2.704 m."
    assert math.dist(small.center, large.center) == pytest.approx(2.704, abs=5e-4)
    assert any(box.center == (-1.25, -0.2) for box in lab.boxes)
    assert lab.robot.radius == 0.3 and lab.robot.sensor_offset == (0.0, 0.0)
    assert lab.reflector.distance == 0.515
    assert lab.sensor.preset == "polaroid-6500"


def test_beom_cho_clutter_sits_behind_table_two_rcds_three_and_four() -> None:
    lab = load_scenario("beom_cho_lab")
    clutter = [c for c in lab.cylinders if c.role == "clutter"]
    for delta, beta_deg in ((1.4612, -140.3), (1.8311, 158.7)):
        front = (delta * math.cos(math.radians(beta_deg)), delta * math.sin(math.radians(beta_deg)))
        assert any(abs(math.dist(front, c.center) - c.radius) < 2e-3 for c in clutter)


def test_roh_beacons_are_table_one_in_metres() -> None:
    roh = load_scenario("roh_beacons")
    table_one_mm = {
        "A": (3467, 101, 825),
        "B": (1551, 139, 1441),
        "C": (2459, 1870, 1457),
        "D": (921, 2065, 1341),
        "E": (351, 132, 835),
    }
    for name, position_mm in table_one_mm.items():
        assert roh.emitter(name).position == pytest.approx(
            tuple(v / 1000 for v in position_mm), abs=1e-12
        )


def test_wu_tsai_transmitters_reproduce_the_papers_heights() -> None:
    room = load_scenario("wu_tsai_room")
    t1, t2, t3 = (room.emitter(n).position for n in ("T1", "T2", "T3"))
    a = 0.2
    assert (t2[0] - t1[0], t2[1] - t1[1]) == pytest.approx((a, 0.0))
    assert (t3[0] - t1[0], t3[1] - t1[1]) == pytest.approx((0.0, a))
    assert t1[2] == t2[2] == t3[2]
    # Example 1 (Table I): receivers at z = -190 cm in the transmitters' frame.
    assert room.robot.sensor_height - t1[2] == pytest.approx(-1.90)
    # Example 2 (Table II) needs z = -150 cm: a receiver height that is physically possible.
    assert 0.0 < t1[2] - 1.50 < t1[2]


def test_apcs_corridor_has_an_unmapped_wall() -> None:
    corridor = load_scenario("apcs_corridor")
    assert corridor.sensor.preset == "ma40b8"
    assert sum(not wall.mapped for wall in corridor.walls) == 1


def test_kim_arena_holds_every_table_one_position() -> None:
    arena = load_scenario("kim_arena")
    assert arena.sensor.preset == "srf04"
    assert arena.room is not None
    table_one_cm = [
        (2.5, 10.0),
        (45.0, 42.5),
        (22.5, 75.0),
        (107.5, 82.5),
        (185.0, 147.5),
        (192.5, 175.0),
        (180.0, 190.0),
    ]
    r = arena.robot.radius
    for x_cm, y_cm in table_one_cm:
        x, y = x_cm / 100, y_cm / 100
        assert arena.room.min[0] + r <= x <= arena.room.max[0] - r
        assert arena.room.min[1] + r <= y <= arena.room.max[1] - r


def test_scenario_from_dict_reports_its_source() -> None:
    with pytest.raises(ScenarioError, match="<dict>: field 'room.max'"):
        scenario_from_dict({"room": {"min": [0, 0], "max": [1]}})


def test_scenarios_are_hashable_values() -> None:
    a = load_scenario("kim_arena")
    b = load_scenario("kim_arena")
    assert a == b and hash(a) == hash(b)
    assert isinstance(a, Scenario)


# -- limits and geometry checked at load -------------------------------------------------------

BEACON_ROOM = """
[room]
min = [-3.0, -2.0]
max = [3.0, 2.0]

[[cylinders]]
center = [2.0, 0.5]
radius = 0.02
role = "small_beacon"

[[cylinders]]
center = [-1.0, -1.0]
radius = 0.07
role = "large_beacon"
"""


def with_small_beacon_at(x: float, y: float, extra: str = "") -> str:
    return BEACON_ROOM.replace("center = [2.0, 0.5]", f"center = [{x}, {y}]") + extra


def test_beacon_room_fixture_loads() -> None:
    assert scenario_from_dict(tomllib.loads(BEACON_ROOM)).has_beacons()


def test_huge_integer_names_the_file_and_field(tmp_path: Path) -> None:
    text = MINIMAL.replace("max = [1.0, 1.0]", f"max = [1{'0' * 400}, 1.0]")
    assert_error_names(tmp_path, text, "room.max[0]", "[-1000, 1000]")


def test_huge_integer_in_json_names_the_file(tmp_path: Path) -> None:
    path = write(tmp_path, '{"room": {"min": [0, 0], "max": [1, 1' + "0" * 5000 + "]}}", "w.json")
    with pytest.raises(ScenarioError, match="not valid JSON"):
        load_scenario(path)


@pytest.mark.parametrize("depth", [500, 50_000])
@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_deeply_nested_arrays_are_a_scenario_error(tmp_path: Path, suffix: str, depth: int) -> None:
    nested = "[" * depth + "]" * depth
    text = (
        f"[robot]\nradius = {nested}\n"
        if suffix == ".toml"
        else '{"robot": {"radius": ' + nested + "}}"
    )
    path = write(tmp_path, text, "deep" + suffix)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(path) in str(info.value)
    assert "robot.radius" in str(info.value) or "nested too deeply" in str(info.value)


def test_enormous_box_is_refused_at_load(tmp_path: Path) -> None:
    text = MINIMAL + "[[boxes]]\ncenter = [0.0, 0.0]\nsize = [1e300, 0.5]\n"
    assert_error_names(tmp_path, text, "boxes[0].size[0]", "1000")


@pytest.mark.parametrize("distance", ["1e-300", "1e6", "0.0"])
def test_reflector_distance_must_be_physical(tmp_path: Path, distance: str) -> None:
    assert_error_names(tmp_path, MINIMAL + f"[reflector]\ndistance = {distance}\n", "reflector")


@pytest.mark.parametrize("key", ["description", "source", "name"])
def test_meta_text_must_be_a_string(tmp_path: Path, key: str) -> None:
    assert_error_names(tmp_path, MINIMAL + f"[meta]\n{key} = 3\n", f"meta.{key}", "string")


def test_coincident_emitters_are_refused(tmp_path: Path) -> None:
    emitter = '[[emitters]]\nname = "{}"\nposition = [0.5, 0.5, 2.0]\n'
    text = MINIMAL + emitter.format("A") + emitter.format("B")
    assert_error_names(tmp_path, text, "emitters", "apart")


def test_emitter_outside_the_room_is_refused(tmp_path: Path) -> None:
    text = MINIMAL + '[[emitters]]\nname = "A"\nposition = [5.0, 0.0, 2.0]\n'
    assert_error_names(tmp_path, text, "emitters[0].position")


def test_beacon_outside_the_room_is_refused(tmp_path: Path) -> None:
    assert_error_names(tmp_path, with_small_beacon_at(3.5, 0.0), "cylinders[0].center", "room")


def test_beacon_touching_the_room_wall_is_refused(tmp_path: Path) -> None:
    assert_error_names(tmp_path, with_small_beacon_at(2.98, 0.0), "cylinders[0]")


def test_beacon_inside_a_box_is_refused(tmp_path: Path) -> None:
    box = "\n[[boxes]]\ncenter = [2.0, 0.5]\nsize = [0.4, 0.4]\n"
    assert_error_names(tmp_path, with_small_beacon_at(2.0, 0.5, box), "cylinders[0]", "box")


def test_coincident_beacons_are_refused(tmp_path: Path) -> None:
    assert_error_names(tmp_path, with_small_beacon_at(-1.0, -1.0), "cylinders[0]", "overlaps")


def test_walled_in_beacon_is_refused(tmp_path: Path) -> None:
    ring = "".join(
        f"\n[[walls]]\na = [{a[0]}, {a[1]}]\nb = [{b[0]}, {b[1]}]\n"
        for a, b in [
            ((1.8, 0.3), (2.2, 0.3)),
            ((2.2, 0.3), (2.2, 0.7)),
            ((2.2, 0.7), (1.8, 0.7)),
            ((1.8, 0.7), (1.8, 0.3)),
        ]
    )
    assert_error_names(tmp_path, with_small_beacon_at(2.0, 0.5, ring), "walled in")


def test_beacon_behind_an_open_wall_still_loads() -> None:
    wall = "\n[[walls]]\na = [1.8, 0.3]\nb = [2.2, 0.3]\n"
    assert scenario_from_dict(tomllib.loads(with_small_beacon_at(2.0, 0.5, wall))).has_beacons()


@pytest.mark.parametrize("name", ["", "   ", "x" * 5000])
def test_empty_or_overlong_scenario_name_is_a_scenario_error(name: str) -> None:
    with pytest.raises(ScenarioError, match="non-empty string"):
        load_scenario(name)


def test_directory_is_a_scenario_error(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match="not a file"):
        load_scenario(tmp_path)
    with pytest.raises(ScenarioError, match="not a file"):
        load_scenario(str(tmp_path))


def test_numpy_numbers_in_a_dict_are_accepted_as_python_floats() -> None:
    data = {"room": {"min": [np.float32(-1.0), np.int64(-1)], "max": np.array([1.0, 1.0])}}
    room = scenario_from_dict(data).room
    assert room is not None
    assert room.min == (-1.0, -1.0) and room.max == (1.0, 1.0)
    assert all(type(v) is float for v in (*room.min, *room.max))
