"""Roh et al., *Development of new block expansion algorithm for indoor mobile robot localization*.

The public face of the method, split over three modules with one job each:

* :mod:`sonar_gym.localization.roh_trilateration`: trilateration from three beacons
  (Sec. III.A, with the reading of its "three lines of intersection" explained there) and
  auto-calibration of a new beacon from three robot positions (Sec. III.B).
* :mod:`sonar_gym.localization.roh_block_expansion`: three-point extraction at distances
  d1, d2, d3 from an area boundary (Sec. III.C), the block expansion runner over two and
  three triangular areas (Sec. II, Fig. 3) and the paper's Tables I-V.
* :mod:`sonar_gym.localization.roh_path_errors`: the path errors sigma and sigma'
  (Sec. IV.B) and the distance from a localized point to the true path (Figs. 5, 7, 8).

Units are metres; Table I and the d's of Tables II-V are printed in millimetres and converted
at the edge (``TABLE_I_BEACONS_M``, ``BlockExpansionConfig.paper``).
"""

from sonar_gym.localization.roh_block_expansion import (
    PAPER_D123_M,
    PAPER_THREE_AREAS,
    PAPER_TWO_AREAS,
    TABLE_I_BEACONS_M,
    TABLE_I_BEACONS_MM,
    TABLE_II_III_D_MM,
    TABLE_II_SIGMA_MM,
    TABLE_III_SIGMA_PRIME_MM,
    TABLE_IV_SIGMA_MM,
    TABLE_IV_V_D_MM,
    TABLE_V_SIGMA_PRIME_MM,
    BlockExpansion,
    BlockExpansionConfig,
    BlockExpansionResult,
    BoundaryCalibration,
    PathFixLog,
    RangeFunction,
    ThreePointExtractor,
    ThreePoints,
    distance_to_segment,
    extract_three_points,
    parabolic_path,
)
from sonar_gym.localization.roh_path_errors import TruePath, distances_to_polyline, path_errors
from sonar_gym.localization.roh_trilateration import (
    DEFAULT_SENSOR_HEIGHT_M,
    TRILATERATION_METHODS,
    CalibrationResult,
    PathFixes,
    TrilaterationResult,
    auto_calibrate,
    circle_intersections,
    linearised_least_squares,
    paper_centroid,
    radical_axis,
    radical_centre,
    trilaterate,
    trilaterate_path,
)

__all__ = [
    "DEFAULT_SENSOR_HEIGHT_M",
    "PAPER_D123_M",
    "PAPER_THREE_AREAS",
    "PAPER_TWO_AREAS",
    "TABLE_I_BEACONS_M",
    "TABLE_I_BEACONS_MM",
    "TABLE_II_III_D_MM",
    "TABLE_II_SIGMA_MM",
    "TABLE_III_SIGMA_PRIME_MM",
    "TABLE_IV_SIGMA_MM",
    "TABLE_IV_V_D_MM",
    "TABLE_V_SIGMA_PRIME_MM",
    "TRILATERATION_METHODS",
    "BlockExpansion",
    "BlockExpansionConfig",
    "BlockExpansionResult",
    "BoundaryCalibration",
    "CalibrationResult",
    "PathFixLog",
    "PathFixes",
    "RangeFunction",
    "ThreePointExtractor",
    "ThreePoints",
    "TrilaterationResult",
    "TruePath",
    "auto_calibrate",
    "circle_intersections",
    "distance_to_segment",
    "distances_to_polyline",
    "extract_three_points",
    "linearised_least_squares",
    "paper_centroid",
    "parabolic_path",
    "path_errors",
    "radical_axis",
    "radical_centre",
    "trilaterate",
    "trilaterate_path",
]
