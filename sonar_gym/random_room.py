"""Procedural rooms for training diversity: clutter and the two Beom & Cho beacons at random.

:func:`random_scenario` draws a rectangular room centred on the origin, tables and cabinets
along its walls, free-standing boxes, thin clutter cylinders (pipes, table legs: the RCDs that
the angular-extent filter of Beom & Cho must reject by symmetry or distance), and the small
(r = 0.0382/2 m) and large (r = 0.14/2 m) beacons of Beom & Cho Table I.

The beacons are placed so the task is usually solvable: at least ``beacon_separation_min_m``
apart, and such that from at least ``visibility_min_fraction`` of the free robot poses both
beacons are *visible*: their surface lies between the sensor's minimum and maximum range
(Table I: 0.3 m and 4.0 m) and the straight path from the sensor to each beacon's echo point
(the point of the cylinder facing the sensor) is unobstructed (:meth:`World.line_of_sight`).
The fraction is estimated over ``n_visibility_samples`` free poses drawn with
:meth:`World.sample_free_pose`; beacon positions are redrawn until it passes, and the whole
room after ``beacon_tries_per_room`` failures.

Every draw comes from the ``rng`` argument, in a fixed order, so the same generator state gives
the same :class:`~sonar_gym.scenario.Scenario` (compared with ``==``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sonar_gym.scenario import Box, Cylinder, RobotSpec, Room, Scenario
from sonar_gym.validation import MIN_LENGTH_M, checked_number, checked_numbers, checked_sequence
from sonar_gym.world import NoFreePoseError, World

SMALL_BEACON_RADIUS_M = 0.0382 / 2.0
"""Beom & Cho Table I, r_s."""
LARGE_BEACON_RADIUS_M = 0.14 / 2.0
"""Beom & Cho Table I, r_L."""

MAX_ROOM_SIDE_M = 100.0
"""Largest room side and sensor range accepted, metres."""
MAX_COUNT = 10**6
"""Largest count argument (boxes, cylinders, samples, tries) accepted."""
_WALL_GAP_M = 0.02
_OBSTACLE_GAP_M = 0.05
_BEACON_CLEARANCE_M = 0.15
_BEACON_WALL_MARGIN_M = 0.3


@dataclass(frozen=True)
class _Rect:
    """Axis-aligned bounding rectangle used to keep generated objects apart (metres)."""

    x0: float
    y0: float
    x1: float
    y1: float

    def overlaps(self, other: _Rect, gap: float) -> bool:
        return not (
            self.x1 + gap <= other.x0
            or other.x1 + gap <= self.x0
            or self.y1 + gap <= other.y0
            or other.y1 + gap <= self.y0
        )

    def distance_to(self, x: float, y: float) -> float:
        dx = max(self.x0 - x, 0.0, x - self.x1)
        dy = max(self.y0 - y, 0.0, y - self.y1)
        return math.hypot(dx, dy)


def random_scenario(
    rng: np.random.Generator,
    size_range: tuple[tuple[float, float], tuple[float, float]] = ((4.0, 7.0), (3.5, 6.0)),
    n_boxes: tuple[int, int] = (2, 6),
    n_clutter_cylinders: tuple[int, int] = (0, 4),
    *,
    clutter_radius_range_m: tuple[float, float] = (0.02, 0.05),
    beacon_separation_min_m: float = 1.5,
    sensor_min_range_m: float = 0.3,
    sensor_max_range_m: float = 4.0,
    visibility_min_fraction: float = 0.7,
    n_visibility_samples: int = 100,
    beacon_tries_per_room: int = 20,
    max_rooms: int = 50,
    robot: RobotSpec | None = None,
    name: str = "random_room",
) -> Scenario:
    """Draw a random room with clutter and the two beacons (see the module docstring).

    Args:
        rng: the only source of randomness.
        size_range: ``((w_min, w_max), (h_min, h_max))``: room width (x) and height (y), metres.
        n_boxes: inclusive range of the number of boxes; about half stand along a wall
            (tables, cabinets: 0.6-1.8 m x 0.4-0.8 m, 2 cm off the wall), the rest free
            (0.2-0.7 m a side, any angle).
        n_clutter_cylinders: inclusive range of the number of clutter cylinders.
        clutter_radius_range_m: radius range of clutter cylinders, metres.
        beacon_separation_min_m: least distance between the beacon centres, metres.
        sensor_min_range_m, sensor_max_range_m: range window in which a beacon counts as
            visible, metres (Beom & Cho Table I: 0.3 and 4.0).
        visibility_min_fraction: least fraction of free poses that must see both beacons.
        n_visibility_samples: free poses drawn to estimate that fraction.
        beacon_tries_per_room: beacon placements tried before the room is redrawn.
        max_rooms: rooms tried before giving up with ``RuntimeError``.
        robot: the robot spec of the scenario (default Beom & Cho's: radius 0.3 m).
        name: the scenario's name.
    """
    _validate(
        rng,
        size_range,
        n_boxes,
        n_clutter_cylinders,
        clutter_radius_range_m,
        beacon_separation_min_m,
        sensor_min_range_m,
        sensor_max_range_m,
        visibility_min_fraction,
        n_visibility_samples,
        beacon_tries_per_room,
        max_rooms,
    )
    robot = RobotSpec() if robot is None else robot
    for _ in range(max_rooms):
        width = float(rng.uniform(*size_range[0]))
        height = float(rng.uniform(*size_range[1]))
        room = Room((-width / 2.0, -height / 2.0), (width / 2.0, height / 2.0))
        boxes, rects = _draw_boxes(rng, room, n_boxes)
        clutter = _draw_clutter(rng, room, rects, n_clutter_cylinders, clutter_radius_range_m)
        base = Scenario(
            name=name,
            room=room,
            boxes=tuple(boxes),
            cylinders=tuple(clutter),
            robot=robot,
            description=(
                f"random room {width:.2f} m x {height:.2f} m, {len(boxes)} boxes, "
                f"{len(clutter)} clutter cylinders, Beom & Cho beacons"
            ),
            source="sonar_gym.random_room.random_scenario",
        )
        for _ in range(beacon_tries_per_room):
            beacons = _draw_beacons(rng, room, rects, clutter, beacon_separation_min_m)
            if beacons is None:
                break
            candidate = Scenario(
                name=base.name,
                room=base.room,
                boxes=base.boxes,
                cylinders=base.cylinders + beacons,
                robot=base.robot,
                description=base.description,
                source=base.source,
            )
            if _visible_enough(
                candidate,
                rng,
                n_visibility_samples,
                visibility_min_fraction,
                sensor_min_range_m,
                sensor_max_range_m,
            ):
                return candidate
    raise RuntimeError(
        f"random_scenario: no room in {max_rooms} tries had both beacons visible from "
        f"{visibility_min_fraction:.0%} of the free poses; relax the arguments"
    )


def visibility_fraction(
    scenario: Scenario,
    rng: np.random.Generator,
    n_samples: int = 100,
    sensor_min_range_m: float = 0.3,
    sensor_max_range_m: float = 4.0,
) -> float:
    """Fraction of ``n_samples`` uniformly drawn free poses from which both beacons are visible.

    Visible: the beacon surface is within ``[sensor_min_range_m, sensor_max_range_m]`` of the
    sensor (at ``robot.sensor_offset`` in {R}) and the sensor has line of sight to the echo
    point. Returns 0.0 if no free pose exists.
    """
    world = World(scenario)
    beacons = [scenario.beacon("small_beacon"), scenario.beacon("large_beacon")]
    visible = 0
    for _ in range(n_samples):
        try:
            pose = world.sample_free_pose(rng)
        except NoFreePoseError:
            return 0.0
        sensor = pose.transform_point(scenario.robot.sensor_offset)
        if all(
            _beacon_visible(world, sensor, b, sensor_min_range_m, sensor_max_range_m)
            for b in beacons
        ):
            visible += 1
    return visible / n_samples


def _visible_enough(
    scenario: Scenario,
    rng: np.random.Generator,
    n_samples: int,
    fraction_min: float,
    min_range_m: float,
    max_range_m: float,
) -> bool:
    """Whether :func:`visibility_fraction` over ``n_samples`` poses would reach ``fraction_min``.

    Draws the same poses in the same order but stops as soon as the answer is settled.
    """
    world = World(scenario)
    beacons = [scenario.beacon("small_beacon"), scenario.beacon("large_beacon")]
    needed = math.ceil(fraction_min * n_samples - 1e-9)
    visible = 0
    for drawn in range(n_samples):
        if visible >= needed:
            return True
        if visible + (n_samples - drawn) < needed:
            return False
        try:
            pose = world.sample_free_pose(rng)
        except NoFreePoseError:
            return False
        sensor = pose.transform_point(scenario.robot.sensor_offset)
        if all(_beacon_visible(world, sensor, b, min_range_m, max_range_m) for b in beacons):
            visible += 1
    return visible >= needed


def _beacon_visible(
    world: World, sensor: np.ndarray, beacon: Cylinder, min_range_m: float, max_range_m: float
) -> bool:
    centre = np.asarray(beacon.center, dtype=np.float64)
    centre_distance = float(np.linalg.norm(centre - sensor))
    surface_distance = centre_distance - beacon.radius
    if not min_range_m <= surface_distance <= max_range_m:
        return False
    echo_point = centre + (sensor - centre) * (beacon.radius / centre_distance)
    return world.line_of_sight(sensor, echo_point)


def _draw_boxes(
    rng: np.random.Generator, room: Room, n_boxes: tuple[int, int]
) -> tuple[list[Box], list[_Rect]]:
    (x0, y0), (x1, y1) = room.min, room.max
    count = int(rng.integers(n_boxes[0], n_boxes[1] + 1))
    boxes: list[Box] = []
    rects: list[_Rect] = []
    for _ in range(count):
        for _attempt in range(20):
            along_wall = bool(rng.random() < 0.5)
            if along_wall:
                wall = int(rng.integers(4))  # 0 bottom, 1 right, 2 top, 3 left
                wall_length = (x1 - x0) if wall in (0, 2) else (y1 - y0)
                length = float(rng.uniform(0.6, min(1.8, 0.4 * wall_length)))
                depth = float(rng.uniform(0.4, 0.8))
                offset = float(rng.uniform(-0.5, 0.5)) * (wall_length - length - 2 * _WALL_GAP_M)
                if wall == 0:
                    center, size = (
                        ((x0 + x1) / 2 + offset, y0 + _WALL_GAP_M + depth / 2),
                        (length, depth),
                    )
                elif wall == 2:
                    center, size = (
                        ((x0 + x1) / 2 + offset, y1 - _WALL_GAP_M - depth / 2),
                        (length, depth),
                    )
                elif wall == 1:
                    center, size = (
                        (x1 - _WALL_GAP_M - depth / 2, (y0 + y1) / 2 + offset),
                        (depth, length),
                    )
                else:
                    center, size = (
                        (x0 + _WALL_GAP_M + depth / 2, (y0 + y1) / 2 + offset),
                        (depth, length),
                    )
                box = Box(center, size, 0.0)
            else:
                size = (float(rng.uniform(0.2, 0.7)), float(rng.uniform(0.2, 0.7)))
                angle = float(rng.uniform(0.0, 90.0))
                margin = 0.8
                center = (
                    float(rng.uniform(x0 + margin, x1 - margin)),
                    float(rng.uniform(y0 + margin, y1 - margin)),
                )
                box = Box(center, size, angle)
            xs = [p[0] for p in box.corners]
            ys = [p[1] for p in box.corners]
            rect = _Rect(min(xs), min(ys), max(xs), max(ys))
            if all(not rect.overlaps(other, _OBSTACLE_GAP_M) for other in rects):
                boxes.append(box)
                rects.append(rect)
                break
    return boxes, rects


def _draw_clutter(
    rng: np.random.Generator,
    room: Room,
    rects: list[_Rect],
    n_cylinders: tuple[int, int],
    radius_range: tuple[float, float],
) -> list[Cylinder]:
    (x0, y0), (x1, y1) = room.min, room.max
    count = int(rng.integers(n_cylinders[0], n_cylinders[1] + 1))
    cylinders: list[Cylinder] = []
    for _ in range(count):
        for _attempt in range(20):
            radius = float(rng.uniform(*radius_range))
            margin = radius + _OBSTACLE_GAP_M
            x = float(rng.uniform(x0 + margin, x1 - margin))
            y = float(rng.uniform(y0 + margin, y1 - margin))
            if _clear_of(x, y, margin, rects, cylinders):
                cylinders.append(Cylinder((x, y), radius, "clutter"))
                break
    return cylinders


def _draw_beacons(
    rng: np.random.Generator,
    room: Room,
    rects: list[_Rect],
    clutter: list[Cylinder],
    separation_min_m: float,
) -> tuple[Cylinder, Cylinder] | None:
    """Draw the small then the large beacon; ``None`` if no placement was found."""
    (x0, y0), (x1, y1) = room.min, room.max
    placed: list[Cylinder] = []
    for role, radius in (
        ("small_beacon", SMALL_BEACON_RADIUS_M),
        ("large_beacon", LARGE_BEACON_RADIUS_M),
    ):
        margin = _BEACON_WALL_MARGIN_M + radius
        for _attempt in range(50):
            x = float(rng.uniform(x0 + margin, x1 - margin))
            y = float(rng.uniform(y0 + margin, y1 - margin))
            if not _clear_of(x, y, radius + _BEACON_CLEARANCE_M, rects, clutter + placed):
                continue
            if placed and math.dist((x, y), placed[0].center) < separation_min_m:
                continue
            placed.append(Cylinder((x, y), radius, role))
            break
        else:
            return None
    return placed[0], placed[1]


def _clear_of(
    x: float, y: float, clearance: float, rects: list[_Rect], cylinders: list[Cylinder]
) -> bool:
    if any(rect.distance_to(x, y) < clearance for rect in rects):
        return False
    return all(math.dist((x, y), c.center) >= clearance + c.radius for c in cylinders)


def _validate(
    rng: object,
    size_range: tuple[tuple[float, float], tuple[float, float]],
    n_boxes: tuple[int, int],
    n_clutter_cylinders: tuple[int, int],
    clutter_radius_range_m: tuple[float, float],
    beacon_separation_min_m: float,
    sensor_min_range_m: float,
    sensor_max_range_m: float,
    visibility_min_fraction: float,
    n_visibility_samples: int,
    beacon_tries_per_room: int,
    max_rooms: int,
) -> None:
    """Check the arguments with the shared validator (:mod:`sonar_gym.validation`)."""
    if not isinstance(rng, np.random.Generator):
        raise ValueError(
            f"argument 'rng' must be a numpy.random.Generator; got {type(rng).__name__}"
        )
    try:
        sizes = [
            checked_numbers(f"size_range[{i}]", pair, length=2, low=2.0, high=MAX_ROOM_SIDE_M)
            for i, pair in enumerate(checked_sequence("size_range", size_range, length=2))
        ]
    except ValueError as error:
        raise ValueError(
            "argument 'size_range' must be ((w_min, w_max), (h_min, h_max)) in metres with "
            f"2.0 <= min <= max <= {MAX_ROOM_SIDE_M:g}; {error}"
        ) from error
    if any(low > high for low, high in sizes):
        raise ValueError(
            "argument 'size_range' must be ((w_min, w_max), (h_min, h_max)) in metres with "
            f"2.0 <= min <= max; got {size_range!r}"
        )
    for arg, pair in (("n_boxes", n_boxes), ("n_clutter_cylinders", n_clutter_cylinders)):
        low_count, _ = checked_numbers(
            f"argument '{arg}'", pair, length=2, low=0, high=MAX_COUNT, integer=True
        )
        checked_number(f"argument '{arg}[1]'", pair[1], low=low_count, integer=True)
    low_radius, _ = checked_numbers(
        "argument 'clutter_radius_range_m'",
        clutter_radius_range_m,
        length=2,
        low=MIN_LENGTH_M,
        high=0.5,
    )
    checked_number(
        "argument 'clutter_radius_range_m[1]'", clutter_radius_range_m[1], low=low_radius
    )
    checked_number(
        "argument 'beacon_separation_min_m'", beacon_separation_min_m, low=0.0, high=MAX_ROOM_SIDE_M
    )
    low_range = checked_number(
        "argument 'sensor_min_range_m'", sensor_min_range_m, low=0.0, high=MAX_ROOM_SIDE_M
    )
    checked_number(
        f"argument 'sensor_max_range_m' (above sensor_min_range_m = {low_range:g})",
        sensor_max_range_m,
        low=low_range + MIN_LENGTH_M,
        high=MAX_ROOM_SIDE_M,
    )
    checked_number("argument 'visibility_min_fraction'", visibility_min_fraction, low=0.0, high=1.0)
    for arg, value in (
        ("n_visibility_samples", n_visibility_samples),
        ("beacon_tries_per_room", beacon_tries_per_room),
        ("max_rooms", max_rooms),
    ):
        checked_number(f"argument '{arg}'", value, low=1, high=MAX_COUNT, integer=True)
