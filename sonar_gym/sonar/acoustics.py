"""Air acoustics for the sonar models: speed of sound, piston beam pattern, air absorption.

Everything is in SI units: metres, seconds, radians, hertz; temperatures in degrees Celsius.

Speed of sound
    ``c(T) = 331.3 sqrt(1 + T / 273.15)`` m/s for dry air, with an optional linear humidity
    term ``+0.0124 m/s per % relative humidity`` (the usual ranging-sensor approximation; at
    20 deg C and 100 % it adds 0.36 %, the "max. 0.35 % at 20 deg C" Beom & Cho quote in
    sec. II.A). Beom & Cho eq. (1), ``delta = v_s t_0 / 2``, read backwards gives the
    self-calibration ``v_s = 2 d_c / t_0`` (:func:`speed_of_sound_from_round_trip`).

Beam pattern
    A circular piston of radius ``a`` in a rigid baffle, wavenumber ``k = 2 pi f / c``:
    ``D(theta) = 2 J1(k a sin theta) / (k a sin theta)`` (one way, ``D(0) = 1``); transmit and
    receive through the same transducer give the two-way pattern ``D^2``. Nothing radiates
    behind the transducer: ``D^2 = 0`` beyond 90 deg off axis. Worked check: 50 kHz,
    ``a = 19.2 mm``, ``c = 343.2 m/s`` give ``k a = 17.6`` and the first null at
    ``asin(3.8317 / 17.6) = 12.6 deg``.

Side-lobe leakage (filled nulls)
    A real transducer is no ideal piston (a stretched membrane on a grooved backplate for the
    Polaroid electrostatic transducers): its nulls are not infinitely deep and the pattern
    beyond the main lobe keeps a floor of leaked energy. The model: beyond the main lobe the
    two-way pattern is ``S * 8 / (pi x^3)``, ``x = k a sin(theta)``, where ``8 / (pi x^3)`` is
    the two-way envelope of the piston's side lobes (``2 J1(x) / x`` falls as
    ``2 sqrt(2 / (pi x)) / x``, squared ``8 / (pi x^3)``) and ``S`` in ``[0, 1]`` is the leakage
    (:func:`two_way_pattern`). On the main lobe's flank ``D^2`` holds while it is the larger,
    i.e. up to the argument ``x_S`` where ``D^2 = S 8 / (pi x^3)`` (between the -6 dB point and
    the first null for any ``S <= 1``, :func:`leakage_onset_argument`). ``S = 0`` is the ideal
    piston. Without side lobes the pattern is then monotone over the whole front half-space;
    with them, ``max(D^2, S 8 / (pi x^3))`` beyond ``x_S`` (side lobes with filled nulls).

Air absorption
    ISO 9613-1 (1993), the pure-tone attenuation coefficient in dB/m as a function of
    frequency, temperature, relative humidity and pressure (its formulae hold at ultrasonic
    frequencies): about 1.66 dB/m at 50 kHz and 1.32 dB/m at 40 kHz (20 deg C, 50 %).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from scipy.optimize import brentq
from scipy.special import j1

from sonar_gym.pose import FloatArray

ZERO_CELSIUS_K = 273.15
SPEED_OF_SOUND_0C_MPS = 331.3
"""Speed of sound in dry air at 0 deg C, m/s."""
HUMIDITY_SPEED_COEFFICIENT_MPS = 0.0124
"""Increase of the speed of sound per percent of relative humidity, m/s (near room temperature)."""
REFERENCE_TEMPERATURE_C = 20.0
"""The temperature a sensor assumes unless told otherwise, and the calibration reference."""
FIRST_ZERO_OF_J1 = 3.831705970207512
"""First positive zero of the Bessel J1: the piston's first null has ``k a sin t`` = this."""
HALF_AMPLITUDE_ARGUMENT = 2.215089367724233
"""``x`` where ``2 J1(x) / x = 1/2``: the one-way -6 dB point of the piston pattern."""


def speed_of_sound_mps(temperature_c: float, relative_humidity: float | None = None) -> float:
    """Speed of sound in air, m/s: ``331.3 sqrt(1 + T / 273.15)`` (+ ``0.0124 * RH`` if given).

    Args:
        temperature_c: air temperature in deg C (above -273.15).
        relative_humidity: relative humidity in percent (0-100), or None for dry air.
    """
    if not temperature_c > -ZERO_CELSIUS_K:
        raise ValueError(
            f"argument 'temperature_c' must be above -273.15 deg C; got {temperature_c!r}"
        )
    speed = SPEED_OF_SOUND_0C_MPS * math.sqrt(1.0 + temperature_c / ZERO_CELSIUS_K)
    if relative_humidity is not None:
        if not 0.0 <= relative_humidity <= 100.0:
            raise ValueError(
                "argument 'relative_humidity' must be a percentage in [0, 100]; "
                f"got {relative_humidity!r}"
            )
        speed += HUMIDITY_SPEED_COEFFICIENT_MPS * relative_humidity
    return speed


def speed_of_sound_from_round_trip(distance_m: float, tof_s: float) -> float:
    """Speed of sound from a round trip to a known distance, ``v = 2 d / t`` (Beom & Cho eq. (1)).

    Args:
        distance_m: one-way distance to the reflector, metres (> 0).
        tof_s: measured round-trip time of flight, seconds (> 0).
    """
    if not distance_m > 0.0:
        raise ValueError(f"argument 'distance_m' must be positive (metres); got {distance_m!r}")
    if not tof_s > 0.0:
        raise ValueError(f"argument 'tof_s' must be positive (seconds); got {tof_s!r}")
    return 2.0 * distance_m / tof_s


def wavenumber_per_m(frequency_hz: float, speed_of_sound: float) -> float:
    """Acoustic wavenumber ``k = 2 pi f / c`` in rad/m."""
    return 2.0 * math.pi * frequency_hz / speed_of_sound


def piston_directivity(theta_rad: npt.ArrayLike, wavenumber_ka: float) -> FloatArray:
    """One-way pressure directivity ``D = 2 J1(x) / x`` with ``x = k a sin(theta)`` (``D(0) = 1``).

    Args:
        theta_rad: off-axis angle(s) in radians.
        wavenumber_ka: the dimensionless product ``k a`` (wavenumber times piston radius).

    Returns:
        ``D`` with the shape of ``theta_rad``; signed (negative on odd side lobes).
    """
    return _piston_directivity_of(
        wavenumber_ka * np.sin(np.abs(np.asarray(theta_rad, dtype=np.float64)))
    )


def _piston_directivity_of(x: FloatArray) -> FloatArray:
    """``2 J1(x) / x`` of ``x = k a sin(theta)`` (:func:`piston_directivity`)."""
    small = x < 1e-4  # 2 J1(x) / x = 1 - x^2/8 + x^4/192 - ...
    safe = np.where(small, 1.0, x)
    return np.where(small, 1.0 - x * x / 8.0, 2.0 * j1(safe) / safe)


def _piston_directivity_of_rising(x: FloatArray) -> FloatArray:
    """:func:`_piston_directivity_of` of a rising ``x``: its small arguments are the first ones,
    so each part is evaluated on its own slice (each sample by the same formula)."""
    n_small = int(x.searchsorted(1e-4, side="left"))
    directivity = np.empty(len(x))
    small, rest = x[:n_small], x[n_small:]
    directivity[:n_small] = 1.0 - small * small / 8.0
    directivity[n_small:] = 2.0 * j1(rest) / rest
    return directivity


def two_way_directivity(theta_rad: npt.ArrayLike, wavenumber_ka: float) -> FloatArray:
    """Two-way (transmit and receive) amplitude pattern ``D^2``; zero beyond 90 deg off axis."""
    theta = np.abs(np.asarray(theta_rad, dtype=np.float64))
    d = piston_directivity(theta, wavenumber_ka)
    return np.where(np.cos(theta) > 0.0, d * d, 0.0)


def side_lobe_envelope(x: npt.ArrayLike) -> FloatArray:
    """Two-way envelope ``8 / (pi x^3)`` of the piston's side lobes (``x = k a sin(theta) > 0``)."""
    x = np.asarray(x, dtype=np.float64)
    return 8.0 / (math.pi * x * x * x)


def _validated_leakage(side_lobe_leakage: float) -> float:
    value = side_lobe_leakage
    if not (isinstance(value, (int, float)) and 0.0 <= value <= 1.0):
        raise ValueError(
            f"argument 'side_lobe_leakage' must be a number in [0, 1]; got {side_lobe_leakage!r}"
        )
    return float(value)


@functools.lru_cache(maxsize=32)
def leakage_onset_argument(side_lobe_leakage: float) -> float:
    """``x_S``: where the main lobe's ``D^2`` falls to the leakage ``S 8 / (pi x^3)``.

    The unique root of ``(2 J1(x) / x)^2 = S 8 / (pi x^3)`` between the one-way -6 dB point
    (``x = 2.215``, where ``D^2 = 0.25 > 0.234 S``) and the first null (``x = 3.832``);
    the first null itself when ``S = 0``.
    """
    leakage = _validated_leakage(side_lobe_leakage)
    if leakage == 0.0:
        return FIRST_ZERO_OF_J1

    def excess(x: float) -> float:
        d = 2.0 * float(j1(x)) / x
        return d * d - leakage * float(side_lobe_envelope(x))

    return float(brentq(excess, HALF_AMPLITUDE_ARGUMENT, FIRST_ZERO_OF_J1, xtol=1e-15))


def two_way_pattern(
    theta_rad: npt.ArrayLike,
    wavenumber_ka: float,
    *,
    side_lobes: bool = True,
    side_lobe_leakage: float = 0.0,
) -> FloatArray:
    """The two-way amplitude pattern of a transducer, exactly (see "Side-lobe leakage").

    Args:
        theta_rad: off-axis angle(s) in radians.
        wavenumber_ka: ``k a`` of the piston.
        side_lobes: keep the piston's side lobes (False: nothing but the main lobe and the
            leakage floor beyond it).
        side_lobe_leakage: ``S`` in [0, 1]; 0 is the ideal piston.

    Returns:
        The pattern with the shape of ``theta_rad``; 1 on the axis, 0 behind the transducer.
    """
    theta = np.abs(np.asarray(theta_rad, dtype=np.float64))
    values = two_way_directivity(theta, wavenumber_ka)
    if not side_lobes:
        values = np.where(theta >= first_null_rad(wavenumber_ka), 0.0, values)
    leakage = _validated_leakage(side_lobe_leakage)
    if leakage > 0.0:
        x = wavenumber_ka * np.sin(theta)
        leaking = (x >= leakage_onset_argument(leakage)) & (np.cos(theta) > 0.0)
        floor = leakage * side_lobe_envelope(np.where(leaking, x, 1.0))
        values = np.where(leaking, np.maximum(values, floor), values)
    return values


def first_null_rad(wavenumber_ka: float) -> float:
    """Off-axis angle of the piston's first null, radians (pi/2 if ``k a`` is too small for one)."""
    return math.asin(min(1.0, FIRST_ZERO_OF_J1 / wavenumber_ka))


def piston_radius_for_half_width(
    half_width_rad: float, frequency_hz: float, speed_of_sound: float
) -> float:
    """Piston radius (metres) whose one-way -6 dB half-width is ``half_width_rad``."""
    if not 0.0 < half_width_rad < math.pi / 2:
        raise ValueError(f"argument 'half_width_rad' must be in (0, pi/2); got {half_width_rad!r}")
    return HALF_AMPLITUDE_ARGUMENT / (
        math.sin(half_width_rad) * wavenumber_per_m(frequency_hz, speed_of_sound)
    )


def atmospheric_absorption_db_per_m(
    frequency_hz: float,
    temperature_c: float = REFERENCE_TEMPERATURE_C,
    relative_humidity: float = 50.0,
    pressure_kpa: float = 101.325,
) -> float:
    """Pure-tone attenuation of sound by air, dB per metre of path (ISO 9613-1:1993, eqs (3)-(5)).

    Args:
        frequency_hz: frequency in Hz.
        temperature_c: air temperature in deg C.
        relative_humidity: relative humidity in percent.
        pressure_kpa: ambient pressure in kPa.
    """
    reference_pressure_kpa = 101.325
    reference_temperature_k = 293.15
    triple_point_k = 273.16
    temperature_k = temperature_c + ZERO_CELSIUS_K
    p_ratio = pressure_kpa / reference_pressure_kpa
    t_ratio = temperature_k / reference_temperature_k
    saturation_ratio = 10.0 ** (-6.8346 * (triple_point_k / temperature_k) ** 1.261 + 4.6151)
    molar_water = relative_humidity * saturation_ratio / p_ratio
    relax_oxygen = p_ratio * (
        24.0 + 4.04e4 * molar_water * (0.02 + molar_water) / (0.391 + molar_water)
    )
    relax_nitrogen = (
        p_ratio
        * t_ratio**-0.5
        * (9.0 + 280.0 * molar_water * math.exp(-4.170 * (t_ratio ** (-1.0 / 3.0) - 1.0)))
    )
    f2 = frequency_hz * frequency_hz
    relaxation = t_ratio**-2.5 * (
        0.01275 * math.exp(-2239.1 / temperature_k) / (relax_oxygen + f2 / relax_oxygen)
        + 0.1068 * math.exp(-3352.0 / temperature_k) / (relax_nitrogen + f2 / relax_nitrogen)
    )
    return 8.686 * f2 * (1.84e-11 / p_ratio * math.sqrt(t_ratio) + relaxation)


def absorption_amplitude_factor(path_m: npt.ArrayLike, absorption_db_per_m: float) -> FloatArray:
    """Amplitude factor ``10^(-alpha L / 20)`` after ``path_m`` metres of air (``alpha``: dB/m)."""
    return np.power(10.0, -absorption_db_per_m * np.asarray(path_m, dtype=np.float64) / 20.0)


TABLE_STEPS_PER_UNIT = 1 << 12
"""Samples of :class:`PistonBeam`'s table per unit of ``s = sqrt(1 - cos(theta))``."""
_TABLE_SIZE = math.ceil(math.sqrt(2.0) * TABLE_STEPS_PER_UNIT) + 1


@functools.cache
def _table_grid() -> tuple[npt.NDArray[np.bool_], FloatArray, FloatArray]:
    """The samples of :class:`PistonBeam`'s table, the same for every ``k a``: which lie in
    front (``s <= 1``), their off-axis angles (radians; pi behind) and ``sin(theta)`` of those
    in front. Read-only.

    The samples in front are the first ``TABLE_STEPS_PER_UNIT + 1`` (``s`` rises from 0), and
    the angles do not fall from one sample to the next (:func:`_main_lobe_samples` counts on
    both)."""
    s = np.arange(_TABLE_SIZE + 1, dtype=np.float64) / TABLE_STEPS_PER_UNIT
    front = s <= 1.0
    theta = np.full(len(s), math.pi)
    theta[front] = np.arccos(1.0 - s[front] ** 2)
    sin_front = np.sin(theta[front])
    for array in (front, theta, sin_front):
        array.flags.writeable = False
    return front, theta, sin_front


def _main_lobe_samples(theta: FloatArray, wavenumber_ka: float) -> int:
    """How many of the table's first samples lie before the piston's first null: the samples
    with ``theta < first_null_rad(k a)``, a prefix since the angles do not fall."""
    return int(np.searchsorted(theta, first_null_rad(wavenumber_ka), side="left"))


@functools.lru_cache(maxsize=8)
def _cell_numbers_down_from(last: int) -> FloatArray:
    """``last, last - 1, ..., 0, -1`` as floats (read-only): the cell numbers of
    :attr:`PistonBeam.main_lobe_cells`."""
    numbers = np.arange(last, -2, -1, dtype=np.float64)
    numbers.flags.writeable = False
    return numbers


@dataclass(frozen=True, eq=False)
class PistonBeam:
    """The two-way pattern of one transducer, tabulated for fast vectorised evaluation.

    The pattern is :func:`two_way_pattern`: the piston's ``D^2``, with or without its side
    lobes, and with the side-lobe leakage ``S`` filling the nulls. The argument is
    ``cos(theta)`` of the off-axis angle (what a dot product of unit vectors gives), mapped to
    ``s = sqrt(1 - cos(theta))`` in ``[0, sqrt(2)]``, where the pattern is smooth; ``2^12``
    samples per unit of ``s`` (a table small enough to stay in cache) with linear interpolation
    reproduce the exact pattern to ``3e-6`` absolute (checked in the tests), which moves the
    edge of a detection window by at most 0.004 deg (under 0.001 deg for echoes less than 40 dB
    above the threshold, such as the beacons). The one exception is the table cell holding the
    leakage onset (near 11.7 deg for the Polaroid 6500), where the pattern has a kink (the larger
    of the lobe and the leakage floor): there the interpolation is within 1 % of the pattern.
    ``s = 1`` (90 deg) is a sample; behind the transducer the pattern is 0. Without side lobes
    the pattern falls monotonically from the axis (over the main lobe, and with leakage over
    the whole front half-space), so it can be inverted exactly (:meth:`main_lobe_cos_limits`).

    Build it with :meth:`for_ka` (cached per ``k a``, side lobes and leakage).
    """

    wavenumber_ka: float
    side_lobes: bool
    _cells: FloatArray = field(repr=False)
    _main_lobe_rising: FloatArray = field(repr=False)
    _reaches_back: bool = field(repr=False)
    side_lobe_leakage: float = 0.0
    _values: FloatArray = field(init=False, repr=False)
    _slopes: FloatArray = field(init=False, repr=False)
    _main_lobe_cells: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        # (value, slope) of a cell side by side: a lookup reads one cache line, not two.
        object.__setattr__(self, "_values", self._cells[:, 0])
        object.__setattr__(self, "_slopes", self._cells[:, 1])
        # Row i: (cell number, value, slope) of the cell that main_lobe_cos_limits finds for a
        # level placed at i in the rising table (cell len - 1 - i), so that one lookup serves;
        # the last row is the table's last cell (number -1).
        # Column by column: numpy copies a long strided column fast, a row of 2 slowly.
        last = len(self._main_lobe_rising) - 1
        main_lobe_cells = np.empty((last + 2, 3))
        main_lobe_cells[:, 0] = _cell_numbers_down_from(last)
        main_lobe_cells[: last + 1, 1] = self._values[last::-1]
        main_lobe_cells[: last + 1, 2] = self._slopes[last::-1]
        main_lobe_cells[last + 1, 1:] = self._cells[-1]
        main_lobe_cells.flags.writeable = False
        object.__setattr__(self, "_main_lobe_cells", main_lobe_cells)

    @staticmethod
    @functools.lru_cache(maxsize=8)
    def for_ka(
        wavenumber_ka: float, side_lobes: bool = True, side_lobe_leakage: float = 0.0
    ) -> PistonBeam:
        """The (cached) tabulated beam for a given ``k a``, side-lobe switch and leakage ``S``."""
        if not wavenumber_ka > 0.0:
            raise ValueError(f"argument 'wavenumber_ka' must be positive; got {wavenumber_ka!r}")
        leakage = _validated_leakage(side_lobe_leakage)
        _, theta, sin_front = _table_grid()
        n_front = len(sin_front)  # the samples in front come first; behind, the pattern is 0
        n_main = _main_lobe_samples(theta, wavenumber_ka)
        x = wavenumber_ka * sin_front  # k a sin(theta) of the samples in front, rising
        values = np.zeros(len(theta))
        if side_lobes:
            values[:n_front] = _piston_directivity_of_rising(x) ** 2
        else:
            # Without side lobes the pattern is 0 beyond the first null, so 2 J1(x) / x is
            # evaluated on the main lobe alone (about a sixth of the samples for k a = 17.6).
            values[:n_main] = _piston_directivity_of_rising(x[:n_main]) ** 2
        last_monotone = n_main - 1
        if leakage > 0.0:
            # sin(theta) rises over the front, so the leaking samples are its last ones
            first_leaking = int(np.searchsorted(x, leakage_onset_argument(leakage), side="left"))
            leaking = values[first_leaking:n_front]
            np.maximum(leaking, leakage * side_lobe_envelope(x[first_leaking:]), out=leaking)
            if not side_lobes:
                last_monotone = TABLE_STEPS_PER_UNIT  # monotone up to 90 deg
        cells = np.empty((len(values) - 1, 2))
        cells[:, 0] = values[:-1]
        np.subtract(values[1:], values[:-1], out=cells[:, 1])
        return PistonBeam(
            float(wavenumber_ka),
            bool(side_lobes),
            cells,
            values[last_monotone::-1].copy(),
            bool(values[TABLE_STEPS_PER_UNIT] != 0.0),
            leakage,
        )

    @property
    def cells(self) -> FloatArray:
        """``(cells, 2)`` the table: ``(value, slope)`` of the pattern per cell of ``s``
        (:data:`TABLE_STEPS_PER_UNIT` cells per unit), read by linear interpolation."""
        return self._cells

    @functools.cached_property
    def widest_main_lobe_cos(self) -> float:
        """The least of :meth:`main_lobe_cos_limits` over every positive level: the cosine limit
        of the faintest one. No path with a smaller cosine is heard through the main lobe."""
        return float(self.main_lobe_cos_limits(np.array([_FAINTEST_LEVEL]))[0])

    @property
    def reaches_back(self) -> bool:
        """Whether the pattern is nonzero at 90 deg (it then drops to 0 behind the transducer)."""
        return self._reaches_back

    @property
    def main_lobe_rising(self) -> FloatArray:
        """The falling pattern from its last monotone sample back to the axis, rising: where
        :meth:`main_lobe_cos_limits` searches a level."""
        return self._main_lobe_rising

    @property
    def main_lobe_cells(self) -> FloatArray:
        """``(len(main_lobe_rising) + 1, 3)`` per search position of a level, the (cell number,
        value, slope) of the cell :meth:`main_lobe_cos_limits` interpolates in."""
        return self._main_lobe_cells

    def two_way_from_cos(self, cos_off_axis: FloatArray) -> FloatArray:
        """The pattern at off-axis angles given by their cosines (any shape, values in [-1, 1])."""
        # Out-of-place arithmetic throughout: on arrays this small numpy's in-place operators
        # cost several times more than the operation.
        scaled = np.sqrt(np.abs(1.0 - cos_off_axis)) * TABLE_STEPS_PER_UNIT
        index = scaled.astype(np.intp)
        cells = self._cells.take(index.ravel(), axis=0)
        values = (cells[:, 0] + (scaled - index).ravel() * cells[:, 1]).reshape(index.shape)
        if self._reaches_back:  # the pattern jumps to 0 at 90 deg
            return np.where(cos_off_axis > 0.0, values, 0.0)
        return values

    def two_way_in_front(self, cos_off_axis: FloatArray) -> FloatArray:
        """:meth:`two_way_from_cos` for cosines known to be positive (in front of the transducer);
        elsewhere the result is meaningless."""
        scaled = np.sqrt(np.abs(1.0 - cos_off_axis)) * TABLE_STEPS_PER_UNIT
        # scaled >= 0, so its floor is the truncated cell index; the fraction then comes from
        # a float-float subtraction, not a slower mixed integer-float one (the same numbers).
        whole = np.floor(scaled)
        cells = self._cells.take(whole.astype(np.intp), axis=0)
        return cells[:, 0] + (scaled - whole) * cells[:, 1]

    def two_way(self, theta_rad: npt.ArrayLike) -> FloatArray:
        """The pattern of this beam at off-axis angles in radians."""
        return self.two_way_from_cos(np.cos(np.asarray(theta_rad, dtype=np.float64)))

    def main_lobe_cos_limits(self, levels: FloatArray, reachable: bool = False) -> FloatArray:
        """``cos`` of the off-axis angle where the falling pattern drops to each level.

        The falling part is the main lobe, and without side lobes but with leakage the whole
        front half-space. On it the pattern is ``>= level`` exactly when ``cos(theta) >=`` the
        returned limit (the same piecewise-linear pattern as :meth:`two_way_from_cos`). Levels
        must be positive; a level above 1 (an echo too weak even on the axis) gets the limit 2,
        which no cosine reaches; a level below the pattern at 90 deg gets the smallest positive
        cosine (the whole front half-space hears the echo, nothing behind it does).
        ``reachable=True`` promises that no level exceeds 1 (echoes loud enough on the axis),
        which spares the clipping.
        """
        rising = self._main_lobe_rising
        clipped = levels if reachable else np.minimum(levels, 1.0)
        # The cell is (len(rising) - 1) - searchsorted; (level - value) / slope the fraction of
        # it at which the falling pattern reaches the level. One lookup gives the cell's number
        # (as a float: no mixed integer-float arithmetic), value and slope.
        cells = self._main_lobe_cells.take(rising.searchsorted(clipped, side="left"), axis=0)
        s_limit = (cells[:, 0] + (clipped - cells[:, 1]) / cells[:, 2]) * (
            1.0 / TABLE_STEPS_PER_UNIT
        )
        limits = np.maximum(1.0 - s_limit * s_limit, SMALLEST_COSINE)
        return limits if reachable else np.where(levels > 1.0, 2.0, limits)


SMALLEST_COSINE = float(np.nextafter(0.0, 1.0))
"""The smallest positive cosine: the limit of a level the whole front half-space hears."""
_FAINTEST_LEVEL = SMALLEST_COSINE  # the smallest positive float, as a level
