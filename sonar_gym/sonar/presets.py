"""Transducer presets: the three ultrasonic sensors of the papers, with their derivations.

=================  =========  ===========  ===========  ========  ==========================
preset             frequency  piston       ranges       timer     source
=================  =========  ===========  ===========  ========  ==========================
``polaroid-6500``  50 kHz     19.2 mm      0.3 - 4.0 m  32 us     Beom & Cho (Table I, III.A)
``srf04``          40 kHz     8.8 mm       0.03 - 3 m   10 us     Kim et al. (sec. 4.1)
``ma40b8``         40 kHz     10.1 mm      0.3 - 5 m    10 us     Yamamoto et al. (APCS, 6)
=================  =========  ===========  ===========  ========  ==========================

Polaroid 6500 (Beom & Cho)
    "The round-trip TOF is measured by 12 bit counter operating at frequency f0 = 1/32 MHz"
    (sec. III.A). Read as a 31.25 kHz clock (the 8031's 1 MHz machine cycle divided by 32):
    period 32 us, a range quantum of 5.5 mm at 343 m/s, full scale 4096 x 32 us = 131 ms
    (22 m), comfortably above R_max = 4 m. The other reading, a 32 MHz clock, would overflow
    12 bits after 128 us, i.e. 2.2 cm of range, and cannot be meant.
    The detection threshold is *derived*, not tuned (:func:`beacon_extent_threshold`): the
    small beacon of Table I (radius 0.0191 m) at (2.85, -0.6) m seen from the origin must give
    the RCD of Table II, angular extent ``eta = beta_e - beta_s = 22 deg`` at the 1 deg
    increment of Table I. A beacon whose continuous detection window is ``W`` wide yields
    ``floor(W)`` or ``ceil(W)`` pings depending on the phase of the ping grid; ``W = eta + 1 deg
    = 23 deg`` gives exactly 23 pings, hence ``eta = 22 deg``, at any phase. So the threshold
    is the small beacon's echo at 11.5 deg off axis.
    Pan unit speed (90 deg/s) and noise (2 mm) are assumptions; the paper gives neither.

    Two properties of the real module and transducer make the angular extent a property of
    the *object*, as the paper's filters need (sec. III.B, Fig. 4: cylinders over 12 cm
    diameter span 24.0-25.5 deg "with variation of the cylinder location", smaller ones
    20-24 deg; walls do not pass the 18-26 deg filter, which leaves 4 RCDs in Fig. 8(c)):

    * Time-varying gain (:class:`~sonar_gym.sonar.receiver.TimeVaryingGain`): the 6500 raises
      its receiver gain in steps after the ping. Modelled as ``G(r) = (r / r_ref)^1.5
      10^(alpha 2 (r - r_ref) / 20)``: it compensates a cylinder's ``r^-1.5`` spreading and the
      air absorption ``alpha`` (the preset's, 1.66 dB/m), with ``r_ref`` = 2.874 m, the small
      beacon's range in the threshold derivation, so the derived threshold is unchanged and
      exact there. The gain is held at its 4 m value (``R_max``, Table I); the module's own
      ramp runs on towards its 10.7 m (35 ft) rating, so within the paper's 0.3-4 m window it
      never saturates and the hold only stops the model extrapolating. A cylinder's echo at
      the comparator is then nearly independent of range (within 0.4 dB from 0.6 to 3.5 m for
      the large beacon), a wall's grows as ``r^0.5``, an edge's (``s / r^2``) falls as
      ``r^-0.5`` and stays over 20 dB below the threshold: the preset hears no edge.
    * Side-lobe leakage ``S = 0.07`` (:func:`~sonar_gym.sonar.acoustics.two_way_pattern`): the
      two-way pattern beyond the main lobe is ``S 8 / (pi x^3)``, 25 dB down at the first null
      (12.6 deg), instead of the ideal piston's infinitely deep null. The main lobe holds to
      11.7 deg, beyond the 11.5 deg that fixes the threshold (it would for any ``S < 0.10``).
      Strong reflectors are heard through the leakage: walls and concave corners span
      32-51 deg (a wall at normal incidence: 35 deg at 0.5 m, 45 deg at 2 m, 51 deg at 3.9 m),
      so the angular-extent filter removes them as in the paper.

    Continuous detection windows (deg) with both, from the exact pattern; ``eta`` is the window
    less 0 or 1 deg with the phase of the ping grid:

    ===============  ======  ======  ======  ======  ======
    cylinder         0.6 m   1.2 m   1.8 m   2.7 m   3.5 m
    ===============  ======  ======  ======  ======  ======
    3.82 cm (small)  23.0    23.0    23.0    23.0    23.0
    10 cm            23.6    23.7    23.8    23.8    23.8
    12 cm            24.3    24.4    24.5    24.6    24.6
    14 cm (large)    24.8    25.1    25.1    25.2    25.2
    20 cm            26.2    26.5    26.6    26.7    26.8
    ===============  ======  ======  ======  ======  ======

    ``S`` was chosen in [0.06, 0.09] for Table II and Fig. 4 with walls above 26 deg: from the
    origin of ``beom_cho_lab`` the small beacon gives 22 deg and the large one 24 deg (25 deg
    at 10 % of the grid phases), as in Table II; cylinders up to 10 cm give 21-23 deg and 12-16
    cm ones 23-25 deg at 0.6-3.5 m (Fig. 4: 20-24 and 24-25.5). ``S = 0.066`` gives the large
    beacon 23 deg from the origin, ``S = 0.075`` 25 deg, ``S = 0.08`` pushes 12 cm cylinders
    to 24-25 deg and 14 cm ones to 24-26 deg, and ``S = 0.09`` 14 cm ones out of the filter
    (26-27 deg; the paper's method then finds no pose from 40-50 % of the poses). Not reproduced:
    the extent keeps growing slowly with the diameter (20 cm: 25-26 deg, 30 cm: 27-28 deg),
    where Fig. 4 shows a plateau at 24-25.5 deg.
    ``polaroid_6500(time_varying_gain=False, side_lobe_leakage=0.0)`` is the ideal piston with
    constant gain (same threshold): there every strong reflector saturates just below the
    first null, walls give 22-25 deg RCDs that pass the filter, and the beacons' extents
    depend on range more than on diameter (the large beacon's window from the origin is
    24.4 deg, 23 deg of extent; the small one gives 21-24 deg between 3.5 and 0.6 m).

SRF04 (Kim et al.)
    40 kHz, 3 m, "operates in 0 degrees - 40 degrees": read as a 40 deg one-way -6 dB beam,
    which a piston of radius 8.8 mm produces. Threshold: a wall at normal incidence returns
    exactly the threshold at the 3 m maximum range. Devantech's recommended 50 ms between
    pings is the listening time; the hobby servo turns at 300 deg/s (0.2 s per 60 deg).

Murata MA40B8 (APCS)
    40 kHz, "directivity +-15 deg ~ 20 deg", "30 cm ~ 500 cm": a -6 dB half-width of 17.5 deg
    gives a piston radius of 10.1 mm. Threshold: a wall at normal incidence at 5 m.

Every preset includes ISO 9613-1 air absorption at 20 deg C, 50 % relative humidity
(:func:`~sonar_gym.sonar.acoustics.atmospheric_absorption_db_per_m`); ``preset(name,
atmospheric_absorption=False)`` drops it and re-derives the threshold without it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from sonar_gym.sonar.acoustics import (
    HALF_AMPLITUDE_ARGUMENT,
    REFERENCE_TEMPERATURE_C,
    absorption_amplitude_factor,
    atmospheric_absorption_db_per_m,
    first_null_rad,
    piston_radius_for_half_width,
    speed_of_sound_mps,
    two_way_pattern,
    wavenumber_per_m,
)
from sonar_gym.sonar.echoes import cylinder_echo_amplitude, plane_echo_amplitude
from sonar_gym.sonar.receiver import TimeVaryingGain
from sonar_gym.validation import MIN_TIMER_PERIOD_S

SMALL_BEACON_RADIUS_M = 0.0382 / 2.0
"""Beom & Cho Table I: radius of the small beacon, metres."""
SMALL_BEACON_CENTER_M = (2.85, -0.6)
"""Beom & Cho sec. V.A: the small beacon's centre in {W}; Table II's scan is taken at the origin."""
SMALL_BEACON_EXTENT_RAD = math.radians(22.0)
"""Beom & Cho Table II, RCD 1 (the small beacon): angular extent ``eta``."""
PAN_INCREMENT_RAD = math.radians(1.0)
"""Beom & Cho Table I: incremental rotational angle of the pan."""
SMALL_BEACON_ECHO_RANGE_M = math.hypot(*SMALL_BEACON_CENTER_M) - SMALL_BEACON_RADIUS_M
"""One-way path from the origin to the small beacon's surface (2.874 m): the reference range of
the threshold derivation, where the Polaroid's time-varying gain is 1."""
POLAROID_SIDE_LOBE_LEAKAGE = 0.07
"""Side-lobe leakage ``S`` of the Polaroid preset (see the module docstring)."""
POLAROID_TVG_EXPONENT = 1.5
"""Spreading exponent ``p`` of the Polaroid's gain ramp: a cylinder's ``r^-1.5``."""


@dataclass(frozen=True)
class Transducer:
    """A pulse-echo ultrasonic transducer with its ranging electronics.

    Attributes:
        name: preset name.
        frequency_hz: carrier frequency, Hz.
        piston_radius_m: radius of the equivalent circular piston, metres.
        min_range_m: echoes from nearer than this are lost in the ring-down, metres.
        max_range_m: the receiver stops listening at this range, metres; later echoes are
            dropouts.
        detection_threshold: the receiver fires when an echo's amplitude reaches this, in the
            units of :mod:`sonar_gym.sonar.echoes` (pressure relative to 1 m on axis, 1/m).
        range_noise_std_m: standard deviation of the timing jitter expressed as one-way range,
            metres.
        timer_period_s: period of the time-of-flight counter, seconds (0 = no quantisation, else
            at least :data:`~sonar_gym.validation.MIN_TIMER_PERIOD_S`).
        listen_time_s: time spent per ping (transmit, listen, reset), seconds.
        pan_speed_rad_s: speed of the pan unit or servo the transducer rides on, rad/s.
        absorption_db_per_m: air absorption at the carrier, dB per metre of path.
        echo_rise_time_s: time the received echo envelope takes to rise to its peak, seconds;
            a threshold crossing is late by ``rise * threshold / amplitude`` (weak echoes at
            the edge of the beam read long, bending the ends of an RCD).
        side_lobes: whether echoes received through the side lobes of the beam count. The
            ideal piston's side lobes are only 35-65 dB down, so with the sensitivity the
            beacon calibration implies a bare threshold would hear a wall or the large beacon
            through them at almost any pan angle; real rangers do not (the 6500's
            "digitally controlled-gain, variable-bandwidth amplifier minimizes noise and
            side-lobe detection", Polaroid data sheet). False (default) keeps the main lobe
            (and the leakage floor beyond it, if ``side_lobe_leakage > 0``).
        side_lobe_leakage: ``S`` in [0, 1], dimensionless: the floor of the two-way pattern
            beyond the main lobe as a fraction of the ideal piston's side-lobe envelope
            ``8 / (pi x^3)`` (filled nulls; :func:`~sonar_gym.sonar.acoustics.two_way_pattern`).
            0 (default) is the ideal piston.
        time_varying_gain: the receiver's gain ramp
            (:class:`~sonar_gym.sonar.receiver.TimeVaryingGain`); echo amplitudes are multiplied
            by it before the threshold test. None (default): constant gain.
    """

    name: str
    frequency_hz: float
    piston_radius_m: float
    min_range_m: float
    max_range_m: float
    detection_threshold: float
    range_noise_std_m: float
    timer_period_s: float
    listen_time_s: float
    pan_speed_rad_s: float
    absorption_db_per_m: float = 0.0
    echo_rise_time_s: float = 0.0
    side_lobes: bool = False
    side_lobe_leakage: float = 0.0
    time_varying_gain: TimeVaryingGain | None = None

    def __post_init__(self) -> None:
        for name in (
            "frequency_hz",
            "piston_radius_m",
            "max_range_m",
            "detection_threshold",
            "listen_time_s",
            "pan_speed_rad_s",
        ):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(
                    f"Transducer.{name} must be a positive finite number; got {value!r}"
                )
        for name in (
            "min_range_m",
            "range_noise_std_m",
            "timer_period_s",
            "absorption_db_per_m",
            "echo_rise_time_s",
        ):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(f"Transducer.{name} must be a finite number >= 0; got {value!r}")
        if 0 < self.timer_period_s < MIN_TIMER_PERIOD_S:
            raise ValueError(
                "Transducer.timer_period_s must be 0 (no counter) or at least "
                f"{MIN_TIMER_PERIOD_S:g} s; got {self.timer_period_s!r}"
            )
        if not isinstance(self.side_lobes, bool):
            raise ValueError(
                f"Transducer.side_lobes must be True or False; got {self.side_lobes!r}"
            )
        leakage = self.side_lobe_leakage
        if not (isinstance(leakage, (int, float)) and 0.0 <= leakage <= 1.0):
            raise ValueError(
                f"Transducer.side_lobe_leakage must be a number in [0, 1]; got {leakage!r}"
            )
        gain = self.time_varying_gain
        if not (gain is None or isinstance(gain, TimeVaryingGain)):
            raise ValueError(
                "Transducer.time_varying_gain must be a TimeVaryingGain or None; "
                f"got {type(gain).__name__}"
            )
        if self.min_range_m >= self.max_range_m:
            raise ValueError(
                "Transducer.min_range_m must be below max_range_m; "
                f"got {self.min_range_m} >= {self.max_range_m}"
            )

    def wavenumber_ka(self, speed_of_sound: float) -> float:
        """``k a`` at a given speed of sound (m/s)."""
        return wavenumber_per_m(self.frequency_hz, speed_of_sound) * self.piston_radius_m

    @property
    def beam_half_width_rad(self) -> float:
        """One-way -6 dB half-width of the beam at 20 deg C, radians (for documentation)."""
        ka = self.wavenumber_ka(speed_of_sound_mps(REFERENCE_TEMPERATURE_C))
        return math.asin(min(1.0, HALF_AMPLITUDE_ARGUMENT / ka))

    @property
    def first_null_rad(self) -> float:
        """Off-axis angle of the first null at 20 deg C, radians."""
        return first_null_rad(self.wavenumber_ka(speed_of_sound_mps(REFERENCE_TEMPERATURE_C)))

    def range_quantum_m(self, assumed_speed_of_sound: float) -> float:
        """Range step of one timer count, ``c T0 / 2`` metres (0 without quantisation)."""
        return assumed_speed_of_sound * self.timer_period_s / 2.0


def beacon_extent_threshold(
    *,
    frequency_hz: float,
    piston_radius_m: float,
    absorption_db_per_m: float,
    beacon_radius_m: float = SMALL_BEACON_RADIUS_M,
    beacon_center_m: tuple[float, float] = SMALL_BEACON_CENTER_M,
    extent_rad: float = SMALL_BEACON_EXTENT_RAD,
    increment_rad: float = PAN_INCREMENT_RAD,
    temperature_c: float = REFERENCE_TEMPERATURE_C,
    side_lobe_leakage: float = 0.0,
    receiver_gain: TimeVaryingGain | None = None,
) -> float:
    """Threshold at which a cylinder seen from the origin gives an RCD of extent ``extent_rad``.

    The extent is measured as Beom & Cho do, ``eta = beta_e - beta_s = (N - 1) increment`` over
    the ``N`` pings of the RCD. A continuous detection window ``eta + increment`` wide holds
    exactly ``N`` pings at any phase of the ping grid, so the threshold is the cylinder's echo
    (after the receiver's gain, if any) at the off-axis angle ``(eta + increment) / 2`` of the
    pattern without side lobes (:func:`~sonar_gym.sonar.acoustics.two_way_pattern`), which
    falls monotonically there: on the main lobe for the ideal piston, anywhere in front with
    leakage.
    """
    speed = speed_of_sound_mps(temperature_c)
    ka = wavenumber_per_m(frequency_hz, speed) * piston_radius_m
    half_window = (extent_rad + increment_rad) / 2.0
    limit = first_null_rad(ka) if side_lobe_leakage == 0.0 else math.pi / 2.0
    if not 0.0 < half_window < limit:
        raise ValueError(
            f"argument 'extent_rad': a window of {math.degrees(2 * half_window):.2f} deg does not "
            f"fit where the pattern falls monotonically (to {math.degrees(limit):.2f} deg)"
        )
    echo_range = math.hypot(*beacon_center_m) - beacon_radius_m
    on_axis = cylinder_echo_amplitude(echo_range, beacon_radius_m) * absorption_amplitude_factor(
        2.0 * echo_range, absorption_db_per_m
    )
    if receiver_gain is not None:
        on_axis = on_axis * receiver_gain.gain(echo_range)
    pattern = two_way_pattern(
        half_window, ka, side_lobes=False, side_lobe_leakage=side_lobe_leakage
    )
    return float(on_axis * pattern)


def wall_range_threshold(max_range_m: float, absorption_db_per_m: float) -> float:
    """Threshold at which a wall at normal incidence is detected exactly up to ``max_range_m``."""
    return float(
        plane_echo_amplitude(max_range_m)
        * absorption_amplitude_factor(2.0 * max_range_m, absorption_db_per_m)
    )


def _absorption(frequency_hz: float, enabled: bool) -> float:
    return atmospheric_absorption_db_per_m(frequency_hz) if enabled else 0.0


def polaroid_6500(
    atmospheric_absorption: bool = True,
    *,
    time_varying_gain: bool = True,
    side_lobe_leakage: float = POLAROID_SIDE_LOBE_LEAKAGE,
) -> Transducer:
    """The Polaroid 6500 ranging module with a 600-series transducer, as in Beom & Cho.

    Args:
        atmospheric_absorption: include ISO 9613-1 air absorption (and its compensation by the
            gain ramp).
        time_varying_gain: model the module's gain ramp (False: constant gain).
        side_lobe_leakage: ``S`` of the transducer (0: the ideal piston).
    """
    frequency_hz, radius_m, max_range_m = 50e3, 0.0192, 4.0
    absorption = _absorption(frequency_hz, atmospheric_absorption)
    gain = (
        TimeVaryingGain(
            reference_range_m=SMALL_BEACON_ECHO_RANGE_M,
            spreading_exponent=POLAROID_TVG_EXPONENT,
            absorption_db_per_m=absorption,
            saturation_range_m=max_range_m,
        )
        if time_varying_gain
        else None
    )
    return Transducer(
        name="polaroid-6500",
        frequency_hz=frequency_hz,
        piston_radius_m=radius_m,
        min_range_m=0.3,
        max_range_m=max_range_m,
        detection_threshold=beacon_extent_threshold(
            frequency_hz=frequency_hz,
            piston_radius_m=radius_m,
            absorption_db_per_m=absorption,
            side_lobe_leakage=side_lobe_leakage,
            receiver_gain=gain,
        ),
        range_noise_std_m=0.002,
        timer_period_s=32e-6,
        listen_time_s=2.0 * max_range_m / speed_of_sound_mps(REFERENCE_TEMPERATURE_C),
        pan_speed_rad_s=math.radians(90.0),
        absorption_db_per_m=absorption,
        echo_rise_time_s=4.0 / frequency_hz,
        side_lobe_leakage=side_lobe_leakage,
        time_varying_gain=gain,
    )


def srf04(atmospheric_absorption: bool = True) -> Transducer:
    """The Devantech SRF04 ranger on a hobby servo, as in Kim et al."""
    frequency_hz, max_range_m = 40e3, 3.0
    absorption = _absorption(frequency_hz, atmospheric_absorption)
    return Transducer(
        name="srf04",
        frequency_hz=frequency_hz,
        piston_radius_m=piston_radius_for_half_width(
            math.radians(20.0), frequency_hz, speed_of_sound_mps(REFERENCE_TEMPERATURE_C)
        ),
        min_range_m=0.03,
        max_range_m=max_range_m,
        detection_threshold=wall_range_threshold(max_range_m, absorption),
        range_noise_std_m=0.005,
        timer_period_s=10e-6,
        listen_time_s=0.05,
        pan_speed_rad_s=math.radians(300.0),
        absorption_db_per_m=absorption,
        echo_rise_time_s=8.0 / frequency_hz,
    )


def ma40b8(atmospheric_absorption: bool = True) -> Transducer:
    """The Murata MA40B8 pair of the APCS robot Yamabico (fixed side-looking sensors)."""
    frequency_hz, max_range_m = 40e3, 5.0
    absorption = _absorption(frequency_hz, atmospheric_absorption)
    return Transducer(
        name="ma40b8",
        frequency_hz=frequency_hz,
        piston_radius_m=piston_radius_for_half_width(
            math.radians(17.5), frequency_hz, speed_of_sound_mps(REFERENCE_TEMPERATURE_C)
        ),
        min_range_m=0.3,
        max_range_m=max_range_m,
        detection_threshold=wall_range_threshold(max_range_m, absorption),
        range_noise_std_m=0.003,
        timer_period_s=10e-6,
        listen_time_s=2.0 * max_range_m / speed_of_sound_mps(REFERENCE_TEMPERATURE_C),
        pan_speed_rad_s=math.radians(300.0),
        absorption_db_per_m=absorption,
        echo_rise_time_s=8.0 / frequency_hz,
    )


_PRESETS: dict[str, Callable[[bool], Transducer]] = {
    "polaroid-6500": polaroid_6500,
    "srf04": srf04,
    "ma40b8": ma40b8,
}
PRESET_NAMES = tuple(_PRESETS)


def preset(name: str, atmospheric_absorption: bool = True) -> Transducer:
    """The transducer preset called ``name`` (one of :data:`PRESET_NAMES`).

    Args:
        name: preset name.
        atmospheric_absorption: include ISO 9613-1 air absorption (the threshold is derived
            with the same choice, so the calibration holds either way).
    """
    factory = _PRESETS.get(name)
    if factory is None:
        raise ValueError(
            f"argument 'name': unknown transducer preset {name!r}; presets are {list(PRESET_NAMES)}"
        )
    return factory(atmospheric_absorption)
