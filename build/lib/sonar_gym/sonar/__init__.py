"""Ultrasonic sensing: transducer presets, echo physics, the rotating pan, beacon ranging.

Modules:
    acoustics: speed of sound, the piston beam pattern and its side-lobe leakage, air absorption.
    receiver: the receiver's time-varying gain.
    presets: the Polaroid 6500, SRF04 and MA40B8 transducers and their calibrated thresholds.
    echoes: echo candidates (walls, cylinders, corners, edges) of a sensor position.
    echo_tables: per-geometry constant tables that make the echo search array arithmetic.
    pulse_echo: the vectorised ping engine shared by every pulse-echo sonar.
    rotating: the rotating pan and speed-of-sound self-calibration of Beom & Cho.
    swept: the servo-swept sonar of Kim et al. and the side sonars of APCS.
    ranging: one-way ranging from fixed emitters (Wu & Tsai, Roh et al.).
    scan: the :class:`Scan` result of a pan.
"""

from sonar_gym.sonar.acoustics import speed_of_sound_mps
from sonar_gym.sonar.presets import PRESET_NAMES, Transducer, preset
from sonar_gym.sonar.pulse_echo import Readout
from sonar_gym.sonar.receiver import TimeVaryingGain
from sonar_gym.sonar.ranging import BeaconRanger, RangeMeasurement
from sonar_gym.sonar.rotating import RotatingSonar, SpeedCalibration
from sonar_gym.sonar.scan import Scan
from sonar_gym.sonar.swept import SideReadings, SideSonars, SweptSonar

__all__ = [
    "PRESET_NAMES",
    "BeaconRanger",
    "RangeMeasurement",
    "Readout",
    "RotatingSonar",
    "Scan",
    "SideReadings",
    "SideSonars",
    "SpeedCalibration",
    "SweptSonar",
    "TimeVaryingGain",
    "Transducer",
    "preset",
    "speed_of_sound_mps",
]
