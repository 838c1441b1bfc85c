"""Transducer presets: the papers' numbers, the counter reading and the derived thresholds."""

from __future__ import annotations

import dataclasses
import math

import pytest
from scipy.optimize import brentq

from sonar_gym.scenario import SENSOR_PRESETS
from sonar_gym.sonar.acoustics import (
    absorption_amplitude_factor,
    speed_of_sound_mps,
    two_way_directivity,
    two_way_pattern,
)
from sonar_gym.sonar.echoes import cylinder_echo_amplitude, plane_echo_amplitude
from sonar_gym.sonar.presets import (
    PRESET_NAMES,
    Transducer,
    beacon_extent_threshold,
    polaroid_6500,
    preset,
)


def test_every_scenario_sensor_name_is_a_preset() -> None:
    assert set(SENSOR_PRESETS) == set(PRESET_NAMES)


def test_unknown_preset_raises_listing_the_names() -> None:
    with pytest.raises(ValueError, match="name") as error:
        preset("polaroid-9000")
    for name in PRESET_NAMES:
        assert name in str(error.value)


def test_polaroid_matches_beom_and_cho_table_1_and_the_worked_check() -> None:
    polaroid = preset("polaroid-6500")
    assert (polaroid.frequency_hz, polaroid.piston_radius_m) == (50e3, 0.0192)
    assert (polaroid.min_range_m, polaroid.max_range_m) == (0.3, 4.0)
    assert math.degrees(polaroid.first_null_rad) == pytest.approx(12.6, abs=0.03)


def test_polaroid_counter_is_a_12_bit_count_of_32_microsecond_periods() -> None:
    # "12 bit counter operating at frequency f0 = 1/32 MHz": 31.25 kHz, 32 us per count.
    polaroid = preset("polaroid-6500")
    assert polaroid.timer_period_s == pytest.approx(1.0 / (1e6 / 32.0))
    assert polaroid.range_quantum_m(343.2) == pytest.approx(0.0055, abs=1e-4)
    full_scale_s = 4096 * polaroid.timer_period_s
    assert full_scale_s > 2.0 * polaroid.max_range_m / speed_of_sound_mps(0.0)


@pytest.mark.parametrize(("name", "half_width_deg"), [("srf04", 20.0), ("ma40b8", 17.5)])
def test_small_transducers_have_the_papers_beam_width(name: str, half_width_deg: float) -> None:
    assert math.degrees(preset(name).beam_half_width_rad) == pytest.approx(half_width_deg, abs=1e-6)
    assert preset(name).frequency_hz == 40e3


def test_apcs_and_kim_ranges() -> None:
    assert (preset("ma40b8").min_range_m, preset("ma40b8").max_range_m) == (0.3, 5.0)
    assert preset("srf04").max_range_m == 3.0


@pytest.mark.parametrize("name", ["srf04", "ma40b8"])
def test_small_transducers_detect_a_wall_exactly_up_to_their_maximum_range(name: str) -> None:
    transducer = preset(name)
    limit = transducer.max_range_m
    on_axis = plane_echo_amplitude(limit) * absorption_amplitude_factor(
        2 * limit, transducer.absorption_db_per_m
    )
    assert on_axis == pytest.approx(transducer.detection_threshold, rel=1e-12)


@pytest.mark.parametrize("absorption", [True, False])
def test_polaroid_threshold_gives_the_small_beacon_a_23_degree_window(absorption: bool) -> None:
    # Table II: eta = 22 deg at 1 deg increments -> a continuous window of 22 + 1 deg.
    transducer = preset("polaroid-6500", atmospheric_absorption=absorption)
    ka = transducer.wavenumber_ka(speed_of_sound_mps(20.0))
    echo_range = math.hypot(2.85, -0.6) - 0.0191
    on_axis = cylinder_echo_amplitude(echo_range, 0.0191) * absorption_amplitude_factor(
        2 * echo_range, transducer.absorption_db_per_m
    )
    edge = brentq(
        lambda t: on_axis * two_way_directivity(t, ka) - transducer.detection_threshold,
        0.05,
        0.2195,
    )
    assert 2 * math.degrees(edge) == pytest.approx(23.0, abs=1e-6)


def test_an_extent_beyond_the_main_lobe_is_refused() -> None:
    with pytest.raises(ValueError, match="extent_rad"):
        beacon_extent_threshold(
            frequency_hz=50e3,
            piston_radius_m=0.0192,
            absorption_db_per_m=0.0,
            extent_rad=math.radians(26.0),
        )


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("max_range_m", -1.0),
        ("detection_threshold", 0.0),
        ("timer_period_s", -1e-6),
        ("timer_period_s", 5e-324),
        ("min_range_m", 9.0),
    ],
)
def test_bad_transducer_fields_raise_naming_the_field(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        dataclasses.replace(preset("polaroid-6500"), **{field: value})


def test_transducer_is_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        preset("srf04").max_range_m = 9.0  # type: ignore[misc]
    assert isinstance(preset("srf04"), Transducer)


def test_polaroid_threshold_is_the_same_with_and_without_gain_ramp_and_leakage() -> None:
    # G(r_ref) = 1 at the small beacon, and 11.5 deg lies on the main lobe for S < 0.10.
    ideal = polaroid_6500(time_varying_gain=False, side_lobe_leakage=0.0)
    for transducer in (polaroid_6500(), polaroid_6500(time_varying_gain=False)):
        assert transducer.detection_threshold == pytest.approx(ideal.detection_threshold, rel=1e-15)


@pytest.mark.parametrize("absorption", [True, False])
def test_small_beacon_window_is_23_degrees_with_gain_ramp_and_leakage(absorption: bool) -> None:
    transducer = preset("polaroid-6500", atmospheric_absorption=absorption)
    assert transducer.time_varying_gain is not None and transducer.side_lobe_leakage > 0.0
    ka = transducer.wavenumber_ka(speed_of_sound_mps(20.0))
    echo_range = math.hypot(2.85, -0.6) - 0.0191
    at_comparator = (
        cylinder_echo_amplitude(echo_range, 0.0191)
        * absorption_amplitude_factor(2 * echo_range, transducer.absorption_db_per_m)
        * transducer.time_varying_gain.gain(echo_range)
    )
    edge = brentq(
        lambda t: (
            at_comparator
            * two_way_pattern(
                t, ka, side_lobes=False, side_lobe_leakage=transducer.side_lobe_leakage
            )
            - transducer.detection_threshold
        ),
        1e-6,
        math.pi / 2 - 1e-9,
    )
    assert 2 * math.degrees(edge) == pytest.approx(23.0, abs=1e-6)


@pytest.mark.parametrize("name", ["srf04", "ma40b8"])
def test_small_transducers_are_ideal_pistons_with_constant_gain(name: str) -> None:
    transducer = preset(name)
    assert transducer.time_varying_gain is None
    assert transducer.side_lobe_leakage == 0.0
    assert transducer.side_lobes is False


@pytest.mark.parametrize(
    ("field", "value"),
    [("side_lobe_leakage", -0.1), ("side_lobe_leakage", 1.2), ("time_varying_gain", 2.0)],
)
def test_bad_fidelity_fields_raise_naming_the_field(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        dataclasses.replace(preset("polaroid-6500"), **{field: value})
