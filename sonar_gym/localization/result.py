"""The result type every localization method returns.

A method never raises on bad geometry or returns NaN: it returns a :class:`Localization`
whose ``status`` says why it failed (``"no_pair"``, ``"no_intersection"``, ...), with
``pose`` set only when ``status == "ok"``. Methods that carry more (the chosen RCD pair, a 3D
position) subclass it with extra fields.
"""

from __future__ import annotations

from dataclasses import dataclass

from sonar_gym.pose import Pose

OK = "ok"
OUT_OF_FLOAT_RANGE = "out_of_float_range"
"""The status of a solution that exists but lies beyond the largest float (inputs near
``1.8e308`` m); shared by every method that scales its inputs to stay finite."""


@dataclass(frozen=True)
class Localization:
    """Outcome of one localization.

    Attributes:
        status: ``"ok"`` or a short machine-readable reason for failure.
        pose: the estimated robot pose in the world frame {W} (metres, radians); ``None``
            unless ``status == "ok"``.
        message: a human-readable explanation, empty when ok.
    """

    status: str
    pose: Pose | None = None
    message: str = ""

    def __post_init__(self) -> None:
        if (self.status == OK) != (self.pose is not None):
            raise ValueError("Localization: pose must be given exactly when status is 'ok'")

    @property
    def ok(self) -> bool:
        """Whether a pose was produced."""
        return self.status == OK
