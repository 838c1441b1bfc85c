"""A top-down picture of a block expansion drive (Roh et al., Sec. II, Fig. 3).

The room and its beacons, the robot where the drive has got to (heading along the path),
its last fix, the fixes so far as points, and text lines with the chosen d's, the status
and each calibrated beacon's error. Metres in {W}; the image is RGB ``uint8``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from sonar_gym.pose import FloatArray, Pose
from sonar_gym.scenario import Scenario


def render_drive(
    scenario: Scenario,
    path: FloatArray,
    shown: int,
    fixes: FloatArray | None,
    distances_m: Sequence[tuple[float, float, float]],
    status: str,
    calibration_errors_m: Mapping[str, float],
    title: str,
) -> np.ndarray:
    """An RGB image ``(H, W, 3)`` of a drive along ``path`` ``(n, 2)`` up to sample
    ``shown - 1``.

    Args:
        scenario: the room and its beacons.
        path: the true path, metres.
        shown: how many path samples have been driven (>= 1).
        fixes: ``(k, 2)`` the successful fixes so far, metres, or None before any run.
        distances_m: the (d1, d2, d3) triples chosen so far, metres.
        status: the episode's status line.
        calibration_errors_m: per calibrated beacon, its calibration error, metres.
        title: the first text line.
    """
    from sonar_gym.render import render_topdown

    index = shown - 1
    direction = path[min(index + 1, len(path) - 1)] - path[max(index - 1, 0)]
    heading = math.atan2(direction[1], direction[0])
    true_pose = Pose(float(path[index, 0]), float(path[index, 1]), heading)
    estimated_pose = None
    if fixes is not None and len(fixes):
        estimated_pose = Pose(float(fixes[-1, 0]), float(fixes[-1, 1]), heading)
    extra = [
        f"d (mm): {[[round(d * 1000) for d in t] for t in distances_m]}",
        f"status: {status}",
    ]
    extra += [
        f"{name} calibrated, error {error * 1000:.0f} mm"
        for name, error in calibration_errors_m.items()
    ]
    return render_topdown(
        scenario,
        true_pose=true_pose,
        estimated_pose=estimated_pose,
        scan_points=fixes,
        title=title,
        extra=extra,
    )
