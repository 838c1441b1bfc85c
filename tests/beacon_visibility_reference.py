""":func:`sonar_gym.beacon_visibility.beacons_visible` in its array form (the pan axis and the
echo points as numpy vectors, the distance by ``np.linalg.norm``), which the form on floats
replaced, kept as the tests' reference."""

from __future__ import annotations

import numpy as np

from sonar_gym.beacon_visibility import BEACON_ROLES
from sonar_gym.pose import Pose
from sonar_gym.sonar.rotating import RotatingSonar
from sonar_gym.world import World


def reference_beacons_visible(world: World, sonar: RotatingSonar, pose: Pose) -> bool:
    """Whether both beacons are in the sonar's range and in line of sight from ``pose``."""
    sensor = pose.transform_point(world.scenario.robot.sensor_offset)
    transducer = sonar.transducer
    beacons = [world.scenario.beacon(role) for role in BEACON_ROLES]
    for centre, radius in [(np.asarray(b.center), b.radius) for b in beacons]:
        distance = float(np.linalg.norm(centre - sensor)) - radius
        if not transducer.min_range_m + 0.05 <= distance <= transducer.max_range_m - 0.2:
            return False
        echo_point = centre + (sensor - centre) * radius / (distance + radius)
        if not world.line_of_sight(sensor, echo_point):
            return False
    return True
