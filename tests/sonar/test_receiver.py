"""The receiver's time-varying gain against its closed form and the spreading it compensates."""

from __future__ import annotations

import dataclasses
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonar_gym.sonar.acoustics import absorption_amplitude_factor
from sonar_gym.sonar.echoes import cylinder_echo_amplitude
from sonar_gym.sonar.presets import preset
from sonar_gym.sonar.receiver import TimeVaryingGain

ALPHA_50KHZ = 1.66  # dB/m, ISO 9613-1 at 20 deg C, 50 % RH


def test_gain_is_exactly_one_at_the_reference_range() -> None:
    gain = TimeVaryingGain(
        reference_range_m=2.8743, spreading_exponent=1.5, absorption_db_per_m=1.7
    )
    assert float(gain.gain(2.8743)) == 1.0


@settings(max_examples=50, deadline=None)
@given(st.floats(0.05, 10.0), st.floats(0.0, 3.0), st.floats(0.0, 3.0))
def test_gain_follows_the_closed_form(range_m: float, exponent: float, alpha: float) -> None:
    gain = TimeVaryingGain(2.0, spreading_exponent=exponent, absorption_db_per_m=alpha)
    expected = (range_m / 2.0) ** exponent * 10.0 ** (alpha * 2.0 * (range_m - 2.0) / 20.0)
    assert float(gain.gain(range_m)) == pytest.approx(expected, rel=1e-12)


@settings(max_examples=50, deadline=None)
@given(st.floats(0.3, 4.0), st.floats(0.005, 0.2))
def test_a_cylinders_echo_at_the_comparator_does_not_depend_on_range(
    range_m: float, radius_m: float
) -> None:
    # 1/(2 r) sqrt(rho / (r + rho)) 10^(-alpha 2 r / 20) G(r) = sqrt(rho r / (r + rho)) times
    # the constant 10^(-alpha 2 r_ref / 20) / (2 r_ref^1.5).
    reference = 2.8743
    gain = TimeVaryingGain(reference, spreading_exponent=1.5, absorption_db_per_m=ALPHA_50KHZ)
    at_comparator = (
        cylinder_echo_amplitude(range_m, radius_m)
        * absorption_amplitude_factor(2.0 * range_m, ALPHA_50KHZ)
        * gain.gain(range_m)
    )
    constant = 10.0 ** (-ALPHA_50KHZ * 2.0 * reference / 20.0) / (2.0 * reference**1.5)
    expected = math.sqrt(radius_m * range_m / (range_m + radius_m)) * constant
    assert float(at_comparator) == pytest.approx(expected, rel=1e-12)


def test_gain_is_held_beyond_the_saturation_range() -> None:
    gain = TimeVaryingGain(2.0, absorption_db_per_m=1.0, saturation_range_m=4.0)
    assert float(gain.gain(6.0)) == float(gain.gain(4.0)) > float(gain.gain(3.9))


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("reference_range_m", 0.0),
        ("reference_range_m", math.inf),
        ("spreading_exponent", -1.0),
        ("absorption_db_per_m", math.nan),
        ("saturation_range_m", -2.0),
    ],
)
def test_bad_gain_fields_raise_naming_the_field(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        dataclasses.replace(TimeVaryingGain(2.0), **{field: value})


def test_polaroid_gain_ramp_is_referred_to_the_small_beacon_and_compensates_its_absorption() -> (
    None
):
    polaroid = preset("polaroid-6500")
    gain = polaroid.time_varying_gain
    assert gain is not None
    assert gain.reference_range_m == pytest.approx(math.hypot(2.85, -0.6) - 0.0191, rel=1e-15)
    assert gain.spreading_exponent == 1.5
    assert gain.absorption_db_per_m == polaroid.absorption_db_per_m > 1.6
    assert gain.saturation_range_m == polaroid.max_range_m
    dry = preset("polaroid-6500", atmospheric_absorption=False).time_varying_gain
    assert dry is not None and dry.absorption_db_per_m == 0.0
