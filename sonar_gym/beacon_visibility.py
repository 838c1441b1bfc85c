"""Where a Beom & Cho robot can stand: both passive beacons in the sonar's range and in sight.

The two-beacon method (Beom & Cho 1995, section III) needs an RCD from each beacon, so a start
pose is only useful when both beacons lie within the transducer's working range and no shape
blocks the line from the pan axis to them. Metres and radians in the world frame {W}.
"""

from __future__ import annotations

import numpy as np

from sonar_gym.pose import Pose
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
    sensor = pose.transform_point(world.scenario.robot.sensor_offset)
    transducer = sonar.transducer
    for centre, radius in _beacons_of(world.scenario):
        distance = float(np.linalg.norm(centre - sensor)) - radius
        if not transducer.min_range_m + 0.05 <= distance <= transducer.max_range_m - 0.2:
            return False
        echo_point = centre + (sensor - centre) * radius / (distance + radius)
        if not world.line_of_sight(sensor, echo_point):
            return False
    return True


_last_beacons: tuple[Scenario, list[tuple[np.ndarray, float]]] | None = None


def _beacons_of(scenario: Scenario) -> list[tuple[np.ndarray, float]]:
    """``(centre, radius)`` of the small then the large beacon (metres, {W}); the last
    scenario's are kept, as start poses are drawn many times in one scenario."""
    global _last_beacons
    if _last_beacons is None or _last_beacons[0] is not scenario:
        beacons = [scenario.beacon(role) for role in BEACON_ROLES]
        _last_beacons = (scenario, [(np.asarray(b.center), b.radius) for b in beacons])
    return _last_beacons[1]


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
