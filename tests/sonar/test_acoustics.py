"""Speed of sound, the piston beam pattern and air absorption against closed forms and tables."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq
from scipy.special import j1

from sonar_gym.sonar.acoustics import (
    FIRST_ZERO_OF_J1,
    HALF_AMPLITUDE_ARGUMENT,
    PistonBeam,
    absorption_amplitude_factor,
    atmospheric_absorption_db_per_m,
    first_null_rad,
    leakage_onset_argument,
    piston_directivity,
    piston_radius_for_half_width,
    speed_of_sound_from_round_trip,
    side_lobe_envelope,
    speed_of_sound_mps,
    two_way_directivity,
    two_way_pattern,
    wavenumber_per_m,
)

POLAROID_KA = wavenumber_per_m(50e3, 343.2) * 0.0192


def test_speed_of_sound_is_331_3_at_zero_and_343_2_at_twenty_celsius() -> None:
    assert speed_of_sound_mps(0.0) == 331.3
    assert speed_of_sound_mps(20.0) == pytest.approx(343.2, abs=0.02)
    assert speed_of_sound_mps(40.0) == pytest.approx(331.3 * math.sqrt(313.15 / 273.15), rel=1e-12)


def test_humidity_adds_about_the_0_35_percent_beom_and_cho_quote_at_saturation() -> None:
    dry, humid = speed_of_sound_mps(20.0), speed_of_sound_mps(20.0, relative_humidity=100.0)
    assert 0.003 < humid / dry - 1.0 < 0.004


def test_temperature_from_0_to_40_celsius_changes_the_speed_by_about_7_percent() -> None:
    # Beom & Cho sec. II.A: "7% variation from 0 deg C to 40 deg C".
    assert speed_of_sound_mps(40.0) / speed_of_sound_mps(0.0) - 1.0 == pytest.approx(
        0.07, abs=0.005
    )


def test_round_trip_speed_is_twice_distance_over_time() -> None:
    assert speed_of_sound_from_round_trip(0.515, 0.003) == pytest.approx(
        2 * 0.515 / 0.003, rel=1e-15
    )


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: speed_of_sound_from_round_trip(0.0, 0.003), "distance_m"),
        (lambda: speed_of_sound_from_round_trip(0.5, -1.0), "tof_s"),
        (lambda: speed_of_sound_mps(-300.0), "temperature_c"),
        (lambda: speed_of_sound_mps(20.0, relative_humidity=120.0), "relative_humidity"),
    ],
)
def test_bad_acoustic_arguments_raise_naming_the_argument(call, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        call()


def test_worked_check_ka_17_6_and_first_null_at_12_6_degrees() -> None:
    # DESIGN sec. 3: 50 kHz, a = 19.2 mm, c = 343.2 m/s.
    assert pytest.approx(17.6, abs=0.03) == POLAROID_KA
    assert math.degrees(first_null_rad(POLAROID_KA)) == pytest.approx(12.6, abs=0.03)
    assert abs(piston_directivity(first_null_rad(POLAROID_KA), POLAROID_KA)) < 1e-12


def test_piston_directivity_is_one_on_axis_and_matches_the_bessel_formula() -> None:
    assert piston_directivity(0.0, POLAROID_KA) == 1.0
    theta = np.radians([3.0, 7.5, 20.0, 60.0])
    x = POLAROID_KA * np.sin(theta)
    np.testing.assert_allclose(piston_directivity(theta, POLAROID_KA), 2 * j1(x) / x, rtol=1e-14)


def test_two_way_pattern_is_the_square_and_zero_behind_the_transducer() -> None:
    theta = np.radians([5.0, 30.0, 89.0])
    np.testing.assert_allclose(two_way_directivity(theta, 5.0), piston_directivity(theta, 5.0) ** 2)
    np.testing.assert_array_equal(two_way_directivity(np.radians([91.0, 135.0, 180.0]), 5.0), 0.0)


def test_piston_radius_for_half_width_gives_a_minus_6_db_point_there() -> None:
    radius = piston_radius_for_half_width(math.radians(20.0), 40e3, 343.2)
    ka = wavenumber_per_m(40e3, 343.2) * radius
    assert piston_directivity(math.radians(20.0), ka) == pytest.approx(0.5, abs=1e-6)


@pytest.mark.parametrize(
    ("temperature_c", "band_db_per_km"),
    [
        # ISO 9613-2 Table 2, 70 % relative humidity, third-octave mid-band frequencies.
        (20.0, {1000.0: 5.0, 1995.26: 9.0, 3981.07: 22.9, 7943.28: 76.6}),
        (10.0, {1000.0: 3.7, 1995.26: 9.7, 3981.07: 32.8, 7943.28: 117.0}),
    ],
)
def test_air_absorption_reproduces_the_iso_9613_table(
    temperature_c: float, band_db_per_km: dict
) -> None:
    for frequency, expected in band_db_per_km.items():
        got = atmospheric_absorption_db_per_m(frequency, temperature_c, 70.0) * 1000.0
        assert got == pytest.approx(expected, rel=0.02, abs=0.06)


def test_air_absorption_at_the_sonar_frequencies_is_over_a_decibel_per_metre() -> None:
    assert atmospheric_absorption_db_per_m(50e3) == pytest.approx(1.66, abs=0.01)
    assert atmospheric_absorption_db_per_m(40e3) == pytest.approx(1.32, abs=0.01)
    assert absorption_amplitude_factor(10.0, 2.0) == pytest.approx(0.1, rel=1e-12)


@settings(max_examples=50, deadline=None)
@given(st.floats(0.0, math.pi), st.sampled_from([POLAROID_KA, 6.5, 7.4]))
def test_tabulated_beam_matches_the_exact_pattern(theta: float, ka: float) -> None:
    beam = PistonBeam.for_ka(ka, True)
    assert beam.two_way(theta) == pytest.approx(float(two_way_directivity(theta, ka)), abs=3e-6)


def test_main_lobe_beam_is_zero_beyond_the_first_null() -> None:
    beam = PistonBeam.for_ka(POLAROID_KA, False)
    null = first_null_rad(POLAROID_KA)
    assert beam.two_way(null + 1e-3) == 0.0
    assert beam.two_way(math.radians(17.0)) == 0.0  # first side lobe peak of the full pattern
    assert PistonBeam.for_ka(POLAROID_KA, True).two_way(math.radians(17.0)) > 0.017


@settings(max_examples=50, deadline=None)
@given(st.floats(1e-7, 1.0))
def test_main_lobe_limit_is_where_the_pattern_falls_to_the_level(level: float) -> None:
    beam = PistonBeam.for_ka(POLAROID_KA, False)
    limit = float(beam.main_lobe_cos_limits(np.array([level]))[0])
    exact = brentq(
        lambda t: two_way_directivity(t, POLAROID_KA) - level, 0.0, first_null_rad(POLAROID_KA)
    )
    assert math.acos(limit) == pytest.approx(
        exact, abs=math.radians(0.004 if level < 1e-4 else 0.001)
    )
    assert float(beam.two_way_from_cos(np.array([limit]))[0]) == pytest.approx(
        level, rel=1e-9, abs=1e-15
    )


def test_a_level_above_one_is_never_reached() -> None:
    beam = PistonBeam.for_ka(POLAROID_KA, False)
    limits = beam.main_lobe_cos_limits(np.array([1.0, 1.5]))
    assert limits[0] == pytest.approx(1.0) and limits[1] > 1.0


def leakage_formula(theta: float, ka: float, leakage: float) -> float:
    """``S 8 / (pi x^3)``, ``x = k a sin(theta)``: the two-way side-lobe envelope times ``S``."""
    x = ka * math.sin(theta)
    return leakage * 8.0 / (math.pi * x**3)


def test_side_lobe_envelope_is_the_asymptote_of_the_squared_piston_pattern() -> None:
    # 2 J1(x) / x ~ 2 sqrt(2 / (pi x)) cos(x - 3 pi / 4) / x: far out, D^2 peaks touch it.
    for start in (60.0, 200.0):
        x = np.linspace(start, start + 2 * math.pi, 20001)
        ratio = (2 * j1(x) / x) ** 2 / side_lobe_envelope(x)
        assert ratio.max() == pytest.approx(1.0, abs=0.02)


@pytest.mark.parametrize("leakage", [0.066, 0.07, 0.09])
def test_leakage_starts_where_the_main_lobe_falls_to_it(leakage: float) -> None:
    onset = leakage_onset_argument(leakage)
    assert HALF_AMPLITUDE_ARGUMENT < onset < FIRST_ZERO_OF_J1
    assert (2 * j1(onset) / onset) ** 2 == pytest.approx(
        leakage * 8 / (math.pi * onset**3), rel=1e-9
    )
    assert leakage_onset_argument(0.0) == FIRST_ZERO_OF_J1


def leaky_pattern_formula(theta: float, leakage: float) -> float:
    """The expected pattern without side lobes: ``D^2`` up to the onset, the leakage beyond."""
    x = POLAROID_KA * math.sin(theta)
    if x >= leakage_onset_argument(leakage):
        return leakage_formula(theta, POLAROID_KA, leakage)
    return float((2 * j1(x) / x) ** 2)


def _in_leakage_onset_cell(theta: float, leakage: float) -> bool:
    """Whether ``theta`` lies in the beam table's cell (in ``s = sqrt(1 - cos)``) that holds
    the leakage onset, where the pattern has a kink that linear interpolation cannot follow."""
    onset = math.asin(leakage_onset_argument(leakage) / POLAROID_KA)
    cell = 1.0 / 4096.0
    return abs(math.sqrt(1.0 - math.cos(theta)) - math.sqrt(1.0 - math.cos(onset))) <= cell


def _leaky_table_tolerance(theta: float, leakage: float, expected: float) -> float:
    if _in_leakage_onset_cell(theta, leakage):
        return 0.01 * expected
    return 3e-6


@settings(max_examples=60, deadline=None)
@given(st.floats(1e-3, math.pi / 2 - 1e-6), st.sampled_from([0.066, 0.07, 0.08]))
def test_leaky_beam_table_matches_the_formula(theta: float, leakage: float) -> None:
    expected = leaky_pattern_formula(theta, leakage)
    beam = PistonBeam.for_ka(POLAROID_KA, False, leakage)
    tolerance = _leaky_table_tolerance(theta, leakage, expected)
    assert float(beam.two_way(theta)) == pytest.approx(expected, abs=tolerance)
    assert float(
        two_way_pattern(theta, POLAROID_KA, side_lobes=False, side_lobe_leakage=leakage)
    ) == pytest.approx(expected, rel=1e-12)


def test_leakage_fills_the_first_null_and_nothing_behind_the_transducer() -> None:
    beam = PistonBeam.for_ka(POLAROID_KA, False, 0.07)
    null = first_null_rad(POLAROID_KA)
    assert beam.two_way(null) == pytest.approx(leakage_formula(null, POLAROID_KA, 0.07), rel=1e-4)
    assert 10 * math.log10(float(beam.two_way(null))) == pytest.approx(-25.0, abs=0.05)
    assert float(beam.two_way(math.radians(91.0))) == 0.0


def test_with_side_lobes_the_leakage_only_fills_the_nulls() -> None:
    beam = PistonBeam.for_ka(POLAROID_KA, True, 0.07)
    side_lobe_peak = math.asin(5.1356 / POLAROID_KA)  # first maximum of |J1(x) / x| past the null
    assert beam.two_way(side_lobe_peak) == pytest.approx(
        float(two_way_directivity(side_lobe_peak, POLAROID_KA)), abs=3e-6
    )
    second_null = math.asin(7.0156 / POLAROID_KA)
    assert beam.two_way(second_null) == pytest.approx(
        leakage_formula(second_null, POLAROID_KA, 0.07), rel=1e-3
    )


@settings(max_examples=50, deadline=None)
@given(st.floats(1e-7, 0.999))
def test_leaky_beam_limit_is_where_the_pattern_falls_to_the_level(level: float) -> None:
    beam = PistonBeam.for_ka(POLAROID_KA, False, 0.07)
    limit = float(beam.main_lobe_cos_limits(np.array([level]))[0])
    if level <= leakage_formula(math.pi / 2, POLAROID_KA, 0.07):
        assert 0.0 < limit < 1e-300  # heard over the whole front half-space, not behind
        return
    exact = brentq(lambda t: leaky_pattern_formula(t, 0.07) - level, 1e-4, math.pi / 2)
    assert math.acos(limit) == pytest.approx(exact, abs=math.radians(0.004))


def test_the_polaroid_main_lobe_holds_to_11_5_degrees_for_leakage_below_0_1() -> None:
    # The threshold is fixed at 11.5 deg off axis, on the main lobe, for any S < 0.10.
    at_threshold = math.radians(11.5)
    for leakage in (0.06, 0.07, 0.09):
        assert float(
            two_way_pattern(at_threshold, POLAROID_KA, side_lobes=False, side_lobe_leakage=leakage)
        ) == float(two_way_directivity(at_threshold, POLAROID_KA))
    assert leakage_formula(at_threshold, POLAROID_KA, 0.11) > float(
        two_way_directivity(at_threshold, POLAROID_KA)
    )


def test_bad_leakage_raises_naming_it() -> None:
    with pytest.raises(ValueError, match="side_lobe_leakage"):
        PistonBeam.for_ka(POLAROID_KA, False, 1.5)


@pytest.mark.parametrize("leakage", [0.066, 0.07, 0.08])
def test_leaky_beam_table_error_bound_holds_on_a_dense_grid(leakage: float) -> None:
    """The documented bound everywhere, the onset cell included, on 200,001 angles."""
    beam = PistonBeam.for_ka(POLAROID_KA, False, leakage)
    thetas = np.linspace(1e-3, math.pi / 2 - 1e-6, 200_001)
    exact = two_way_pattern(thetas, POLAROID_KA, side_lobes=False, side_lobe_leakage=leakage)
    error = np.abs(beam.two_way(thetas) - exact)
    onset = np.array([_in_leakage_onset_cell(float(t), leakage) for t in thetas])
    assert onset.any()
    assert error[~onset].max() <= 3e-6
    assert np.all(error[onset] <= 0.01 * exact[onset])


def _reference_beam_values(ka: float, side_lobes: bool, leakage: float) -> np.ndarray:
    """The table's samples as the array form computed them for every ``k a`` afresh: the
    angle grid, then the directivity at every sample (behind the transducer too)."""
    from sonar_gym.sonar.acoustics import (
        _TABLE_SIZE,
        TABLE_STEPS_PER_UNIT,
        first_null_rad,
        leakage_onset_argument,
        piston_directivity,
        side_lobe_envelope,
    )

    s = np.arange(_TABLE_SIZE + 1, dtype=np.float64) / TABLE_STEPS_PER_UNIT
    front = s <= 1.0
    theta = np.full(len(s), math.pi)
    theta[front] = np.arccos(1.0 - s[front] ** 2)
    values = np.where(front, piston_directivity(theta, ka) ** 2, 0.0)
    if not side_lobes:
        values[(theta >= first_null_rad(ka)) | ~front] = 0.0
    if leakage > 0.0:
        x = ka * np.sin(theta[front])
        leaking = x >= leakage_onset_argument(leakage)
        floor = leakage * side_lobe_envelope(np.where(leaking, x, 1.0))
        values[front] = np.where(leaking, np.maximum(values[front], floor), values[front])
    return values


@pytest.mark.parametrize("side_lobes", [True, False])
@pytest.mark.parametrize("leakage", [0.0, 0.02])
@pytest.mark.parametrize("ka", [1.5, POLAROID_KA, 7.123456789, 13.0, 30.0])
def test_beam_table_is_the_per_ka_array_forms(ka: float, side_lobes: bool, leakage: float) -> None:
    """The angle grid shared by every ``k a`` gives each table the same bits."""
    beam = PistonBeam.for_ka(ka, side_lobes, leakage)
    values = _reference_beam_values(ka, side_lobes, leakage)
    assert np.array_equal(beam.cells[:, 0], values[:-1])
    assert np.array_equal(beam.cells[:, 1], np.diff(values))
