"""The Polaroid's gain ramp and side-lobe leakage: angular extents as Beom & Cho measured them.

Beom & Cho sec. III.B and Fig. 4: cylinders over 12 cm diameter span 24.0-25.5 deg wherever they
stand, smaller ones 20-24 deg; Table II: the small beacon (3.82 cm) 22.0 deg and the large one
(14 cm) 24.0 deg from the origin; walls do not pass the 18-26 deg angular-extent filter.
Extents are measured as the paper does: ``eta = beta_e - beta_s`` over an RCD of a 1 deg pan
(eqs (3)-(5), ``eps`` = 0.02 m).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sonar_gym
from sonar_gym.localization.beom_cho import extract_rcds
from sonar_gym.pose import Pose, wrap_angle
from sonar_gym.sonar.presets import polaroid_6500
from sonar_gym.sonar.pulse_echo import IDEAL_READOUT, Readout
from sonar_gym.sonar.rotating import RotatingSonar
from sonar_gym.world import World
from tests.sonar.worlds import world

FULL_PAN = (-math.pi, math.pi, math.radians(1.0))
SMALL_BEACON = ((2.85, -0.6), 0.0191)
LARGE_BEACON = ((0.3, -1.5), 0.07)


def extent_deg(scan, echo_range: float, bearing: float) -> float | None:
    """``eta`` in degrees of the RCD at ``echo_range`` (within 3 cm) and ``bearing`` (within
    2 deg, {R}); None if the pan has no such RCD."""
    for rcd in extract_rcds(scan.angles, scan.ranges, eps=0.02):
        if abs(rcd.delta - echo_range) < 0.03 and abs(
            wrap_angle(rcd.beta - bearing)
        ) < math.radians(2.0):
            return round(math.degrees(rcd.eta), 6)
    return None


def cylinder_extent(sonar: RotatingSonar, radius: float, echo_range: float, phase_deg: float):
    scan = sonar.pan(
        world(cylinders=[{"center": [echo_range + radius, 0.0], "radius": radius}]),
        Pose(0.0, 0.0, math.radians(phase_deg)),
        *FULL_PAN,
        np.random.default_rng(0),
    )
    return extent_deg(scan, echo_range, -math.radians(phase_deg))


@settings(max_examples=15, deadline=None)
@given(st.floats(1.0, 3.5), st.floats(0.0, 1.0))
@pytest.mark.parametrize(("radius", "table_ii_extent"), [(0.0191, 22.0), (0.07, 24.0)])
def test_gain_ramp_makes_a_cylinders_extent_independent_of_range(
    radius: float, table_ii_extent: float, echo_range: float, phase_deg: float
) -> None:
    sonar = RotatingSonar.preset("polaroid-6500")
    extent = cylinder_extent(sonar, radius, echo_range, phase_deg)
    assert extent is not None and abs(extent - table_ii_extent) <= 1.0


def test_with_constant_gain_the_small_cylinders_extent_shrinks_with_range() -> None:
    sonar = RotatingSonar(polaroid_6500(time_varying_gain=False, side_lobe_leakage=0.0))
    near = [cylinder_extent(sonar, 0.0191, 1.0, phase) for phase in (0.0, 0.5)]
    far = [cylinder_extent(sonar, 0.0191, 3.5, phase) for phase in (0.0, 0.5)]
    assert min(near) - max(far) >= 1.0  # 23-24 deg at 1 m, 21-22 deg at 3.5 m


@pytest.mark.parametrize(
    "position",
    # The origin of Table II, and poses where the small beacon is the nearer one.
    [(0.0, 0.0), (-0.5, 0.3), (0.8, 1.2), (1.5, -0.3), (1.8, 0.3), (2.0, -0.2), (2.2, 0.8)],
)
def test_lab_beacons_span_22_and_23_to_25_degrees_large_wider_than_small(position) -> None:
    lab = World(sonar_gym.load_scenario("beom_cho_lab"), 20.0)
    sonar = RotatingSonar.preset("polaroid-6500")
    rng = np.random.default_rng(3)
    small_extents = []
    for heading_deg in (0.0, 0.3, 0.6, 0.9):
        pose = Pose(*position, math.radians(heading_deg))
        scan = sonar.pan(lab, pose, *FULL_PAN, rng)
        extents = []
        for (x, y), radius in (SMALL_BEACON, LARGE_BEACON):
            echo_range = math.hypot(x - pose.x, y - pose.y) - radius
            bearing = wrap_angle(math.atan2(y - pose.y, x - pose.x) - pose.theta)
            extents.append(extent_deg(scan, echo_range, bearing))
        small, large = extents
        assert small is not None and large is not None
        assert 21.0 <= small <= 22.0 and 23.0 <= large <= 25.0 and large > small
        small_extents.append(small)
    assert np.median(small_extents) == 22.0


@settings(max_examples=20, deadline=None)
@given(st.floats(0.5, 4.0), st.floats(0.0, 1.0))
def test_a_wall_at_normal_incidence_spans_more_than_the_26_degree_filter(
    distance: float, phase_deg: float
) -> None:
    sonar = RotatingSonar.preset("polaroid-6500", readout=IDEAL_READOUT)
    scan = sonar.pan(
        world(walls=[{"a": [distance, -30.0], "b": [distance, 30.0]}]),
        Pose(0.0, 0.0, math.radians(phase_deg)),
        *FULL_PAN,
        None,
    )
    extent = extent_deg(scan, distance, -math.radians(phase_deg))
    assert extent is not None and 26.0 < extent < 60.0


@pytest.mark.parametrize("distance", [0.5, 1.0, 2.0, 3.0])
def test_a_concave_corner_spans_more_than_the_26_degree_filter(distance: float) -> None:
    c = distance / math.sqrt(2.0)  # the corner (c, c) seen along its bisector
    corner = world(walls=[{"a": [c, c], "b": [c - 10.0, c]}, {"a": [c, c], "b": [c, c - 10.0]}])
    sonar = RotatingSonar.preset("polaroid-6500", readout=Readout(range_noise=False))
    scan = sonar.pan(corner, Pose(0.0, 0.0, 0.0), *FULL_PAN, None)
    extent = extent_deg(scan, distance, math.pi / 4)
    assert extent is not None and extent > 26.0


def test_with_constant_gain_a_wall_passes_the_filter_like_a_beacon() -> None:
    # The defect the two properties remove: the ideal piston saturates below its first null.
    sonar = RotatingSonar(
        polaroid_6500(time_varying_gain=False, side_lobe_leakage=0.0), readout=IDEAL_READOUT
    )
    scan = sonar.pan(
        world(walls=[{"a": [2.0, -30.0], "b": [2.0, 30.0]}]), Pose(0.0, 0.0, 0.0), *FULL_PAN, None
    )
    extent = extent_deg(scan, 2.0, 0.0)
    assert extent is not None and 18.0 <= extent <= 26.0


def test_the_polaroid_hears_no_edge_through_its_gain_ramp() -> None:
    # An edge's s / r^2 at the comparator falls as r^-0.5 and stays over 20 dB under the
    # threshold: Beom & Cho's "the edges produce weak echo".
    sonar = RotatingSonar.preset("polaroid-6500", readout=IDEAL_READOUT)
    for distance in (0.3, 0.6, 1.5, 3.0):
        box = world(
            boxes=[
                {
                    "center": [distance + 0.2 * math.sqrt(2.0), 0.0],
                    "size": [0.4, 0.4],
                    "angle_deg": 45.0,
                }
            ]
        )
        scan = sonar.pan(box, Pose(0.0, 0.0, 0.0), -0.5, 0.5, math.radians(0.25), None)
        assert not np.any(np.abs(scan.ranges - distance) < 1e-6)
