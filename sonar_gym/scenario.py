"""Declarative worlds: rooms, walls, boxes, cylinders, emitters, robot and sensor, as data.

A scenario is a TOML (or JSON) file validated on load. Every field is in metres, except
``angle_deg`` of a box (degrees, as a person writes it). The tables::

    [meta]        name = "...", description = "...", source = "..."     (optional)
    [room]        min = [x, y], max = [x, y]       a rectangular room: four walls
    [[walls]]     a = [x, y], b = [x, y], mapped = true
    [[boxes]]     center = [x, y], size = [w, h], angle_deg = 0.0, mapped = true
    [[cylinders]] center = [x, y], radius = r, role = "clutter", mapped = true
    [[emitters]]  name = "A", position = [x, y, z]  active ultrasonic transmitters
    [robot]       radius = 0.3, sensor_offset = [0, 0], wheel_base = 0.4, sensor_height = 0.0
    [sensor]      preset = "polaroid-6500"
    [reflector]   distance = 0.515                 the calibration reflector (Beom & Cho)

``mapped = false`` marks an object that exists in the world but not in the map a localizer is
given (the APCS corridor's wall B). ``role`` of a cylinder is one of :data:`CYLINDER_ROLES`.
A malformed file raises :class:`ScenarioError` naming the file, the field and what is allowed.
"""

from __future__ import annotations

import json
import math
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sonar_gym.scenario_checks import geometry_problem
from sonar_gym.validation import checked_number, is_bool, shown

BUILTIN_DIR = Path(__file__).with_name("scenarios")
CYLINDER_ROLES = ("small_beacon", "large_beacon", "clutter")
SENSOR_PRESETS = ("polaroid-6500", "srf04", "ma40b8")
Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]


MAX_COORDINATE_M = 1000.0
"""Largest magnitude of any coordinate, metres (pymunk loses precision far beyond)."""
MIN_SIZE_M = 1e-3
"""Least box side, cylinder radius and wall length, metres."""
MAX_SIZE_M = 1000.0
"""Largest box side, metres."""
MAX_RADIUS_M = 100.0
"""Largest cylinder radius, metres."""
ROBOT_RADIUS_RANGE_M = (0.01, 5.0)
"""Allowed robot footprint radius, metres (also bounds each sensor-offset coordinate)."""
WHEEL_BASE_RANGE_M = (0.01, 10.0)
"""Allowed distance between the drive wheels, metres."""
MAX_HEIGHT_M = 100.0
"""Largest sensor height above the floor, metres."""
REFLECTOR_DISTANCE_RANGE_M = (0.05, 2.0)
"""Allowed calibration-reflector distance, metres: a reflector on the robot, in the near field
of no transducer and far from the 12-bit counter's overflow (Beom & Cho: 0.515 m)."""
MAX_ITEMS = 10_000
"""Most walls, boxes, cylinders or emitters in one scenario."""
MAX_TEXT_CHARS = 100_000
"""Longest ``meta`` text and emitter name, characters."""
MAX_PATH_CHARS = 4096
"""Longest scenario name or path, characters."""
MAX_FILE_BYTES = 10_000_000
"""Largest scenario file read, bytes."""


class ScenarioError(ValueError):
    """A scenario file or dictionary that does not describe a valid world."""


@dataclass(frozen=True)
class Room:
    """An axis-aligned rectangular room; its four walls face inwards. Metres, {W}."""

    min: Vec2
    max: Vec2

    @property
    def corners(self) -> tuple[Vec2, Vec2, Vec2, Vec2]:
        """Counter-clockwise corners starting at ``min``."""
        (x0, y0), (x1, y1) = self.min, self.max
        return ((x0, y0), (x1, y0), (x1, y1), (x0, y1))

    @property
    def size(self) -> Vec2:
        """Width and height in metres."""
        return (self.max[0] - self.min[0], self.max[1] - self.min[1])


@dataclass(frozen=True)
class Wall:
    """A wall as a line segment from ``a`` to ``b`` (metres, {W})."""

    a: Vec2
    b: Vec2
    mapped: bool = True


@dataclass(frozen=True)
class Box:
    """A rectangular obstacle (a table, a cabinet).

    Centre and size ``(w, h)`` in metres ({W}), angle in degrees.
    """

    center: Vec2
    size: Vec2
    angle_deg: float = 0.0
    mapped: bool = True

    @property
    def corners(self) -> tuple[Vec2, Vec2, Vec2, Vec2]:
        """Counter-clockwise corners in {W}, metres."""
        c, s = math.cos(math.radians(self.angle_deg)), math.sin(math.radians(self.angle_deg))
        hw, hh = self.size[0] / 2.0, self.size[1] / 2.0
        local = ((-hw, -hh), (hw, -hh), (hw, hh), (-hw, hh))
        return tuple(  # type: ignore[return-value]
            (self.center[0] + c * px - s * py, self.center[1] + s * px + c * py) for px, py in local
        )


@dataclass(frozen=True)
class Cylinder:
    """A vertical cylinder: centre (metres, {W}), radius (metres) and role."""

    center: Vec2
    radius: float
    role: str = "clutter"
    mapped: bool = True


@dataclass(frozen=True)
class Emitter:
    """An active ultrasonic transmitter at a 3D position (metres, {W}; z up from the floor)."""

    name: str
    position: Vec3


@dataclass(frozen=True)
class RobotSpec:
    """The robot's footprint and sensor mounting.

    Attributes:
        radius: footprint radius, metres (Beom & Cho Table I: 0.3 m).
        sensor_offset: the pan axis of the rotating sonar in {R}, metres.
        wheel_base: distance between the drive wheels, metres.
        sensor_height: height of the ranging receivers above the floor, metres.
    """

    radius: float = 0.3
    sensor_offset: Vec2 = (0.0, 0.0)
    wheel_base: float = 0.4
    sensor_height: float = 0.0


@dataclass(frozen=True)
class SensorSpec:
    """Which transducer preset the scenario's pulse-echo sonar uses.

    Attributes:
        preset: one of :data:`SENSOR_PRESETS`.
        given: whether the scenario chose the preset (``sensor.preset`` in the file) rather
            than leaving the default; a task built around its paper's own sensor keeps that
            sensor unless the scenario chose one (:meth:`preset_or`).
    """

    preset: str = "polaroid-6500"
    given: bool = False

    def preset_or(self, task_default: str) -> str:
        """The scenario's preset if it chose one, else ``task_default``."""
        return self.preset if self.given else task_default


@dataclass(frozen=True)
class Reflector:
    """The calibration reflector on the robot's front face, ``distance`` metres from the sonar."""

    distance: float = 0.515


@dataclass(frozen=True)
class Scenario:
    """A complete world description.

    Build it with :func:`load_scenario` or :func:`scenario_from_dict`.
    """

    name: str
    room: Room | None = None
    walls: tuple[Wall, ...] = ()
    boxes: tuple[Box, ...] = ()
    cylinders: tuple[Cylinder, ...] = ()
    emitters: tuple[Emitter, ...] = ()
    robot: RobotSpec = field(default_factory=RobotSpec)
    sensor: SensorSpec = field(default_factory=SensorSpec)
    reflector: Reflector = field(default_factory=Reflector)
    description: str = ""
    source: str = ""

    def beacon(self, role: str) -> Cylinder:
        """The cylinder with the given beacon role (``"small_beacon"`` or ``"large_beacon"``)."""
        matches = [c for c in self.cylinders if c.role == role]
        if len(matches) != 1:
            raise ScenarioError(
                f"scenario {self.name!r} has {len(matches)} cylinders with role {role!r}; "
                "exactly one is needed"
            )
        return matches[0]

    def has_beacons(self) -> bool:
        """Whether both the small and the large beacon are present, once each."""
        roles = [c.role for c in self.cylinders]
        return roles.count("small_beacon") == 1 and roles.count("large_beacon") == 1

    def emitter(self, name: str) -> Emitter:
        """The emitter with the given name."""
        for emitter in self.emitters:
            if emitter.name == name:
                return emitter
        raise ScenarioError(
            f"scenario {self.name!r} has no emitter {name!r}; it has "
            f"{[e.name for e in self.emitters]}"
        )

    @property
    def bounds(self) -> tuple[Vec2, Vec2]:
        """``(min, max)`` corners of everything in the scenario, metres."""
        xs: list[float] = []
        ys: list[float] = []
        if self.room is not None:
            xs += [self.room.min[0], self.room.max[0]]
            ys += [self.room.min[1], self.room.max[1]]
        for wall in self.walls:
            xs += [wall.a[0], wall.b[0]]
            ys += [wall.a[1], wall.b[1]]
        for box in self.boxes:
            xs += [p[0] for p in box.corners]
            ys += [p[1] for p in box.corners]
        for cyl in self.cylinders:
            xs += [cyl.center[0] - cyl.radius, cyl.center[0] + cyl.radius]
            ys += [cyl.center[1] - cyl.radius, cyl.center[1] + cyl.radius]
        if not xs:
            return ((-1.0, -1.0), (1.0, 1.0))
        return ((min(xs), min(ys)), (max(xs), max(ys)))


# --- loading -----------------------------------------------------------------------------


def builtin_names() -> list[str]:
    """Names of the scenarios shipped with the package."""
    return sorted(p.stem for p in BUILTIN_DIR.glob("*.toml"))


def load_scenario(name_or_path: str | Path) -> Scenario:
    """Load a built-in scenario by name, or any ``.toml`` / ``.json`` file by path.

    Raises:
        ScenarioError: the name is unknown (the message lists the built-ins), the path is not
            a readable file, or the file is malformed (the message names the file, the field
            and what is allowed).
    """
    text = str(name_or_path) if isinstance(name_or_path, (str, Path)) else None
    if text is None or not text.strip() or len(text) > MAX_PATH_CHARS:
        raise ScenarioError(
            "a scenario must be a built-in name or a path to a .toml or .json file (a non-empty "
            f"string of at most {MAX_PATH_CHARS} characters); got {shown(name_or_path)}"
        )
    path = Path(name_or_path)
    try:
        if path.suffix.lower() not in (".toml", ".json") and not path.exists():
            candidate = BUILTIN_DIR / f"{name_or_path}.toml"
            if not candidate.is_file():
                raise ScenarioError(
                    f"unknown scenario {shown(text)}; built-in scenarios are "
                    f"{builtin_names()}, or give a path to a .toml or .json file"
                )
            path = candidate
        if not path.exists():
            raise ScenarioError(f"scenario file {shown(str(path))} does not exist")
        if not path.is_file():
            raise ScenarioError(
                f"scenario path {shown(str(path))} is not a file; give a .toml or .json file"
            )
        if path.stat().st_size > MAX_FILE_BYTES:
            raise ScenarioError(
                f"scenario file {shown(str(path))} is larger than {MAX_FILE_BYTES} bytes"
            )
        raw = path.read_text(encoding="utf-8")
    except OSError as error:
        raise ScenarioError(
            f"scenario {shown(text)} cannot be read: {error.strerror or error}"
        ) from error
    except UnicodeDecodeError as error:
        kind = "JSON" if path.suffix.lower() == ".json" else "TOML"
        raise ScenarioError(f"{path}: not valid {kind}: not UTF-8 text: {error}") from error
    kind = "JSON" if path.suffix.lower() == ".json" else "TOML"
    try:
        data = json.loads(raw) if kind == "JSON" else tomllib.loads(raw)
    except RecursionError as error:
        raise ScenarioError(f"{path}: not valid {kind}: nested too deeply") from error
    except ValueError as error:  # TOMLDecodeError, JSONDecodeError, int digit limit
        raise ScenarioError(f"{path}: not valid {kind}: {error}") from error
    return scenario_from_dict(data, source=str(path), default_name=path.stem)


_TOP_LEVEL_KEYS = {
    "meta",
    "room",
    "walls",
    "boxes",
    "cylinders",
    "emitters",
    "robot",
    "sensor",
    "reflector",
}


def scenario_from_dict(
    data: Mapping[str, Any], source: str = "<dict>", default_name: str = "custom"
) -> Scenario:
    """Validate a parsed scenario mapping (the TOML layout above) and build a :class:`Scenario`."""
    reader = _Reader(source)
    if not isinstance(data, Mapping):
        raise reader.error("<top level>", "a table of scenario sections", data)
    reader.no_unknown_keys("<top level>", data, _TOP_LEVEL_KEYS)
    meta = reader.table(data, "meta", {"name", "description", "source"})
    room_data = reader.table(data, "room", {"min", "max"}, required=("min", "max"))
    room = None
    if room_data:
        room = Room(
            reader.vec2("room.min", room_data["min"]), reader.vec2("room.max", room_data["max"])
        )
        if not (room.min[0] < room.max[0] and room.min[1] < room.max[1]):
            raise reader.error(
                "room", "min < max in both x and y", f"min={room.min}, max={room.max}"
            )

    walls = []
    for i, item in enumerate(reader.array(data, "walls", {"a", "b", "mapped"}, ("a", "b"))):
        where = f"walls[{i}]"
        a, b = reader.vec2(f"{where}.a", item["a"]), reader.vec2(f"{where}.b", item["b"])
        if math.dist(a, b) < MIN_SIZE_M:
            raise reader.error(
                where,
                f"a wall of non-zero length, at least {MIN_SIZE_M:g} m (a != b)",
                f"a={a}, b={b}",
            )
        walls.append(Wall(a, b, reader.boolean(f"{where}.mapped", item.get("mapped", True))))

    boxes = []
    for i, item in enumerate(
        reader.array(data, "boxes", {"center", "size", "angle_deg", "mapped"}, ("center", "size"))
    ):
        where = f"boxes[{i}]"
        size = reader.vec2(f"{where}.size", item["size"], MIN_SIZE_M, MAX_SIZE_M)
        boxes.append(
            Box(
                reader.vec2(f"{where}.center", item["center"]),
                size,
                reader.number(f"{where}.angle_deg", item.get("angle_deg", 0.0), -360.0, 360.0),
                reader.boolean(f"{where}.mapped", item.get("mapped", True)),
            )
        )

    cylinders = []
    for i, item in enumerate(
        reader.array(
            data, "cylinders", {"center", "radius", "role", "mapped"}, ("center", "radius")
        )
    ):
        where = f"cylinders[{i}]"
        radius = reader.number(f"{where}.radius", item["radius"], MIN_SIZE_M, MAX_RADIUS_M)
        role = item.get("role", "clutter")
        if role not in CYLINDER_ROLES:
            raise reader.error(f"{where}.role", f"one of {list(CYLINDER_ROLES)}", role)
        cylinders.append(
            Cylinder(
                reader.vec2(f"{where}.center", item["center"]),
                radius,
                role,
                reader.boolean(f"{where}.mapped", item.get("mapped", True)),
            )
        )
    for role in ("small_beacon", "large_beacon"):
        if sum(c.role == role for c in cylinders) > 1:
            raise reader.error("cylinders", f"at most one cylinder with role {role!r}", "several")

    emitters = []
    for i, item in enumerate(
        reader.array(data, "emitters", {"name", "position"}, ("name", "position"))
    ):
        where = f"emitters[{i}]"
        name = reader.text(f"{where}.name", item["name"])
        if not name:
            raise reader.error(f"{where}.name", "a non-empty string", name)
        emitters.append(Emitter(name, reader.vec3(f"{where}.position", item["position"])))
    names = [e.name for e in emitters]
    if len(set(names)) != len(names):
        raise reader.error("emitters", "unique names", names)

    robot_data = reader.table(
        data, "robot", {"radius", "sensor_offset", "wheel_base", "sensor_height"}
    )
    defaults = RobotSpec()
    robot = RobotSpec(
        radius=reader.number(
            "robot.radius", robot_data.get("radius", defaults.radius), *ROBOT_RADIUS_RANGE_M
        ),
        sensor_offset=reader.vec2(
            "robot.sensor_offset",
            robot_data.get("sensor_offset", defaults.sensor_offset),
            -ROBOT_RADIUS_RANGE_M[1],
            ROBOT_RADIUS_RANGE_M[1],
        ),
        wheel_base=reader.number(
            "robot.wheel_base",
            robot_data.get("wheel_base", defaults.wheel_base),
            *WHEEL_BASE_RANGE_M,
        ),
        sensor_height=reader.number(
            "robot.sensor_height",
            robot_data.get("sensor_height", defaults.sensor_height),
            0.0,
            MAX_HEIGHT_M,
        ),
    )
    sensor_data = reader.table(data, "sensor", {"preset"})
    preset = sensor_data.get("preset", SensorSpec().preset)
    if preset not in SENSOR_PRESETS:
        raise reader.error("sensor.preset", f"one of {list(SENSOR_PRESETS)}", preset)
    reflector_data = reader.table(data, "reflector", {"distance"})
    reflector = Reflector(
        reader.number(
            "reflector.distance",
            reflector_data.get("distance", Reflector().distance),
            *REFLECTOR_DISTANCE_RANGE_M,
        )
    )

    if room is None and not walls and not boxes and not cylinders and not emitters:
        raise reader.error(
            "<top level>", "at least one of room, walls, boxes, cylinders, emitters", "nothing"
        )
    scenario = Scenario(
        name=reader.text("meta.name", meta.get("name", default_name)),
        room=room,
        walls=tuple(walls),
        boxes=tuple(boxes),
        cylinders=tuple(cylinders),
        emitters=tuple(emitters),
        robot=robot,
        sensor=SensorSpec(preset, given="preset" in sensor_data),
        reflector=reflector,
        description=reader.text("meta.description", meta.get("description", "")),
        source=reader.text("meta.source", meta.get("source", source)),
    )
    problem = geometry_problem(scenario)
    if problem is not None:
        raise reader.error(*problem)
    return scenario


class _Reader:
    """Field readers that raise :class:`ScenarioError` naming the source file and the field.

    Numbers go through :func:`sonar_gym.validation.checked_number`, the validator of the
    ``gym.make`` arguments too.
    """

    def __init__(self, source: str) -> None:
        self.source = source

    def error(self, field_name: str, allowed: str, got: object) -> ScenarioError:
        return ScenarioError(
            f"{self.source}: field '{field_name}' must be {allowed}; got {shown(got)}"
        )

    def no_unknown_keys(self, where: str, table: Mapping[str, Any], allowed: set[str]) -> None:
        unknown = sorted(set(table) - allowed, key=str)
        if unknown:
            raise ScenarioError(
                f"{self.source}: unknown key(s) {shown(unknown)} in '{where}'; "
                f"allowed keys are {sorted(allowed)}"
            )

    def table(
        self, data: Mapping[str, Any], key: str, allowed: set[str], required: Sequence[str] = ()
    ) -> Mapping[str, Any]:
        value = data.get(key, {})
        if not isinstance(value, Mapping):
            raise self.error(key, "a table", value)
        self.no_unknown_keys(key, value, allowed)
        if key in data:
            for name in required:
                if name not in value:
                    raise self.error(f"{key}.{name}", "present", "missing")
        return value

    def array(
        self, data: Mapping[str, Any], key: str, allowed: set[str], required: Sequence[str]
    ) -> list[Mapping[str, Any]]:
        value = data.get(key, [])
        if not isinstance(value, (list, tuple)):
            raise self.error(key, "an array of tables ([[...]] in TOML)", value)
        if len(value) > MAX_ITEMS:
            raise self.error(key, f"at most {MAX_ITEMS} items", f"{len(value)} items")
        for i, item in enumerate(value):
            if not isinstance(item, Mapping):
                raise self.error(f"{key}[{i}]", "a table", item)
            self.no_unknown_keys(f"{key}[{i}]", item, allowed)
            for name in required:
                if name not in item:
                    raise self.error(f"{key}[{i}].{name}", "present", "missing")
        return list(value)

    def number(
        self,
        where: str,
        value: object,
        low: float = -MAX_COORDINATE_M,
        high: float = MAX_COORDINATE_M,
    ) -> float:
        subject = f"{self.source}: field '{where}'"
        return float(checked_number(subject, value, low=low, high=high, error=ScenarioError))

    def boolean(self, where: str, value: object) -> bool:
        if not is_bool(value):
            raise self.error(where, "true or false", value)
        return bool(value)

    def text(self, where: str, value: object) -> str:
        if not isinstance(value, str) or len(value) > MAX_TEXT_CHARS:
            raise self.error(where, f"a string of at most {MAX_TEXT_CHARS} characters", value)
        return value

    def vector(
        self,
        where: str,
        value: object,
        names: str,
        low: float = -MAX_COORDINATE_M,
        high: float = MAX_COORDINATE_M,
    ) -> tuple[float, ...]:
        """A list ``[x, y]`` or ``[x, y, z]`` (``names`` gives the letters) of numbers, metres."""
        if isinstance(value, np.ndarray):
            value = value.tolist()
        if not isinstance(value, (list, tuple)) or len(value) != len(names):
            listed = ", ".join(names)
            kind = "pair" if len(names) == 2 else "triple"
            raise self.error(where, f"a {kind} [{listed}] of numbers in metres", value)
        return tuple(self.number(f"{where}[{i}]", v, low, high) for i, v in enumerate(value))

    def vec2(
        self,
        where: str,
        value: object,
        low: float = -MAX_COORDINATE_M,
        high: float = MAX_COORDINATE_M,
    ) -> Vec2:
        return self.vector(where, value, "xy", low, high)  # type: ignore[return-value]

    def vec3(self, where: str, value: object) -> Vec3:
        return self.vector(where, value, "xyz")  # type: ignore[return-value]
