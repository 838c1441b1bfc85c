"""The BLAS products of ``sonar_gym.sonar.swept._side_first_echoes`` as they were written,
kept as the tests' reference for :func:`sonar_gym.sonar.swept.map_at_points`."""

from __future__ import annotations

from sonar_gym.pose import FloatArray
from sonar_gym.sonar.echo_tables import EchoTables


def search_map_reference(tables: EchoTables, homogeneous: FloatArray) -> FloatArray:
    """The search map at the sensors ``(P, 3)``."""
    mapped = homogeneous @ tables.position_map.T  # (P, M)
    return mapped


def occlusion_map_reference(
    tables: EchoTables, sensor_rows: FloatArray, path_sensors: FloatArray
) -> FloatArray:
    """The occlusion map at the sensors ``(H, 3)`` of the heard paths."""
    matrix = (path_sensors @ tables.occlusion_map.T).reshape(
        len(sensor_rows), 3 * tables.n_segments + tables.n_circles, 3
    )
    return matrix
