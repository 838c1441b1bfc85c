"""The five papers' localization methods, one module each, as pure functions over arrays.

Nothing here imports pymunk or gymnasium: a method takes plain arrays and dataclasses, so it
can be tested on a paper's printed numbers alone.
"""

from sonar_gym.localization.result import OK, Localization

__all__ = ["OK", "Localization"]
