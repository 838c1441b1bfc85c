"""Where a Beom & Cho robot can stand: both passive beacons in the sonar's range and in sight.

The two-beacon method (Beom & Cho 1995, section III) needs an RCD from each beacon, so a start
pose is only useful when both beacons lie within the transducer's working range and no shape
blocks the line from the pan axis to them. Metres and radians in the world frame {W}.
"""

from __future__ import annotations

import math

import numpy as np

from sonar_gym.pose import Pose, vector_norm
from sonar_gym.scenario import Scenario
from sonar_gym.sonar.rotating import RotatingSonar
from sonar_gym.world import World

BEACON_ROLES = ("small_beacon", "large_beacon")
START_CLEARANCE_M = 0.05
"""Distance a drawn start pose keeps from walls and obstacles beyond the robot radius."""
START_POSE_TRIES = 2000
"""Free poses drawn before :func:`sample_start_pose` gives up."""


def beacons_visible(world: World, sonar: RotatingSonar, pose: Pose) -> bool:
    """Whether both beacons are in the sonar's range and in line of sight from ``pose``.

    In range: the beacon's surface lies between 5 cm beyond the sensor's minimum range and
    0.2 m short of its maximum. In sight: no shape blocks the segment from the pan axis to the
    point of the beacon nearest it. ``pose`` is the robot pose in {W}; metres throughout.
    """
    scenario = world.scenario
    offset_x, offset_y, beacons = _scenario_parts(scenario)
    # the pan axis in {W}, as Pose.transform_point computes it, on floats
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    sensor_x = pose.x + c * offset_x - s * offset_y
    sensor_y = pose.y + s * offset_x + c * offset_y
    sensor = np.array([sensor_x, sensor_y])
    transducer = sonar.transducer
    for centre, centre_x, centre_y, radius in beacons:
        distance = vector_norm(centre - sensor) - radius
        if not transducer.min_range_m + 0.05 <= distance <= transducer.max_range_m - 0.2:
            return False
        # centre + (sensor - centre) * radius / (distance + radius), coordinate by coordinate
        echo_point = (
            centre_x + (sensor_x - centre_x) * radius / (distance + radius),
            centre_y + (sensor_y - centre_y) * radius / (distance + radius),
        )
        if not world.line_of_sight_unchecked((sensor_x, sensor_y), echo_point):
            return False
    return True


_Beacon = tuple[np.ndarray, float, float, float]
_last_parts: tuple[Scenario, tuple[float, float, list[_Beacon]]] | None = None


def _scenario_parts(scenario: Scenario) -> tuple[float, float, list[_Beacon]]:
    """The sensor offset ``(x, y)`` in {R} and ``(centre, centre x, centre y, radius)`` of the
    small then the large beacon ({W}), metres, as floats; the last scenario's are kept, as
    start poses are drawn many times in one scenario."""
    global _last_parts
    if _last_parts is None or _last_parts[0] is not scenario:
        offset = np.asarray(scenario.robot.sensor_offset, dtype=np.float64).reshape(2)
        beacons: list[_Beacon] = []
        for role in BEACON_ROLES:
            beacon = scenario.beacon(role)
            centre = np.asarray(beacon.center)
            beacons.append((centre, float(centre[0]), float(centre[1]), beacon.radius))
        _last_parts = (scenario, (float(offset[0]), float(offset[1]), beacons))
    return _last_parts[1]


def sample_start_pose(
    world: World, sonar: RotatingSonar, rng: np.random.Generator, require_beacons: bool = True
) -> Pose:
    """A start pose drawn uniformly over free space, ``START_CLEARANCE_M`` clear of obstacles.

    With ``require_beacons`` only poses from which :func:`beacons_visible` holds are kept
    (rejection sampling, at most :data:`START_POSE_TRIES` draws from ``rng``).

    Raises:
        RuntimeError: no such pose in :data:`START_POSE_TRIES` draws.
    """
    for _ in range(START_POSE_TRIES):
        pose = world.sample_free_pose(rng, clearance=START_CLEARANCE_M)
        if not require_beacons or beacons_visible(world, sonar, pose):
            return pose
    raise RuntimeError(
        f"scenario {world.scenario.name!r}: found no free pose from which both beacons are "
        "visible; use start_pose='any' or check the scenario"
    )
