"""``sonar_gym.robot._command_draws`` as it was written on the rows of a ``(count, 6)`` table,
kept as the tests' reference for its one-slice form."""

from __future__ import annotations

import numpy as np

from sonar_gym.pose import FloatArray


def command_draws_reference(rng: np.random.Generator, count: int) -> FloatArray:
    """The ``6 count`` numbers of ``count`` :meth:`DifferentialDriveRobot.drive` commands:
    per command two standard normals, then four uniforms, drawn from ``rng`` in that order."""
    draws = np.empty((count, 6))
    for command in draws:
        rng.standard_normal(out=command[:2])
        rng.random(out=command[2:])
    return draws.reshape(-1)
