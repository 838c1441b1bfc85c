"""Receiver electronics of a pulse-echo ranger: the time-varying gain (TVG) ramp.

A ranging module such as the Polaroid 6500 raises its receiver gain step by step after the
ping ("digitally controlled-gain, variable-bandwidth amplifier", Polaroid data sheet), so that
a distant echo, weakened by spreading and air absorption, is compared with the same threshold
as a near one. The comparator sees the echo amplitude times the gain at the echo's time of
flight, i.e. at its one-way path length ``r`` (metres):

    ``G(r) = (r / r_ref)^p * 10^(alpha * 2 (r - r_ref) / 20)``

``r_ref`` is where the gain is 1 (the range at which the detection threshold was derived, so
the derived threshold stays exact there), ``p`` the spreading the ramp compensates (``p = 1``
for a wall, whose echo falls as ``1/r``; ``p = 1.5`` for a vertical cylinder, ``r^-1.5``), and
``alpha`` (dB per metre of path) the air absorption it compensates over the round trip ``2 r``.
The real ramp is a staircase that ends at the module's last gain step; the model is its smooth
envelope, held constant beyond ``saturation_range_m``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sonar_gym.pose import FloatArray


@dataclass(frozen=True)
class TimeVaryingGain:
    """The receiver's gain ramp ``G(r)`` of the module docstring (dimensionless).

    Attributes:
        reference_range_m: ``r_ref``, the one-way path length at which the gain is 1, metres.
        spreading_exponent: ``p``, the power of the path length the ramp compensates
            (dimensionless, >= 0; 0 compensates no spreading).
        absorption_db_per_m: ``alpha``, the air absorption the ramp compensates, dB per metre
            of path (0 = none).
        saturation_range_m: the gain stops rising at this one-way path length, metres
            (``math.inf``: never).
    """

    reference_range_m: float
    spreading_exponent: float = 1.5
    absorption_db_per_m: float = 0.0
    saturation_range_m: float = math.inf

    def __post_init__(self) -> None:
        for name in ("reference_range_m", "saturation_range_m"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and value > 0 and not math.isnan(value)):
                raise ValueError(f"TimeVaryingGain.{name} must be a positive length; got {value!r}")
        if not math.isfinite(self.reference_range_m):
            raise ValueError(
                f"TimeVaryingGain.reference_range_m must be finite; got {self.reference_range_m!r}"
            )
        for name in ("spreading_exponent", "absorption_db_per_m"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(
                    f"TimeVaryingGain.{name} must be a finite number >= 0; got {value!r}"
                )

    def gain(self, path_m: npt.ArrayLike) -> FloatArray:
        """``G(r)`` at one-way path lengths ``path_m`` (metres, > 0); 1 at ``r_ref``."""
        r = np.minimum(np.asarray(path_m, dtype=np.float64), self.saturation_range_m)
        # 10^(alpha 2 (r - r_ref) / 20) = exp(alpha ln(10) (r - r_ref) / 10)
        return np.power(r / self.reference_range_m, self.spreading_exponent) * np.exp(
            (self.absorption_db_per_m * math.log(10.0) / 10.0) * (r - self.reference_range_m)
        )
