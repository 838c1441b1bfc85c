"""APCS position correction from one matched wall: eqs (7)-(14) of Yamamoto et al.

Section 4.4 of *APCS: autonomous position correction system using ultrasonic sensing*
(Yamamoto, Maeyama, Ohya & Yuta). The robot pose ``P_A = (x_A, y_A, theta_A)`` (eq. 7) with
covariance ``Sigma_PA`` (eq. 8) is corrected by a wall ``a x + b y + c = 0`` of the map seen
at distance ``r`` and bearing ``xi`` in the robot frame (Fig. 8):

- eq. (9):  ``b cos(theta_A + xi) - a sin(theta_A + xi) = 0``, the direction ``theta_A + xi``
  in {W} is along the wall's normal;
- eq. (10): ``(a x_A + b y_A + c)^2 - r^2 (a^2 + b^2) = 0``, the robot is ``r`` from the line;
- eqs (11)-(12): ``P_f = P_A + Sigma_f J^T Sigma_su^-1 P_su`` and
  ``Sigma_f = (Sigma_PA^-1 + J^T Sigma_su^-1 J)^-1``, the maximum-likelihood step of [6].

Units: metres, radians; ``sigma_r`` and ``sigma_xi`` are *variances* (m^2, rad^2), as the paper
defines them ("sigma_r means the variance of r and sigma_xi means the variance of xi").

Reading of eqs (13)-(14). The printed third rows (``(a sin - b cos) / ((-a cos - b sin)
sigma_xi)`` and ``1 / sigma_xi``) follow exactly from eq. (9) with the constraint covariance
``Sigma_su = J_z diag(sigma_r, sigma_xi) J_z^T`` (``J_z`` the derivative of the constraints with
respect to the measurement ``(r, xi)``) and ``P_su = -(constraint value)``. The printed first
two rows carry ``sigma_r^2`` in the numerator and drop a square on ``(c + a x_A + b y_A)`` in
eq. (13), which makes the information ``J^T Sigma_su^-1 J`` carry units of m^2 * sigma_r^2
instead of 1/m^2. The same derivation applied to eq. (10) gives the entries used here:

- eq. (13), rows 1-2: ``{a, b} D (r^2 (a^2 + b^2) - D^2) / (2 r^2 (a^2 + b^2)^2 sigma_r)``;
- eq. (14), xy block: ``{a^2, ab, b^2} D^2 / (r^2 (a^2 + b^2)^2 sigma_r)``,

with ``D = a x_A + b y_A + c``. They keep the printed denominators ``2 (a^2 + b^2)^2`` and
``(a^2 + b^2)^2`` and reduce, at a prior on the measured line (``D^2 = r^2 (a^2 + b^2)``), to
information ``1 / sigma_r`` along the wall normal, as a single range to a wall must.
The step itself is evaluated in the equivalent gain form (matrix inversion lemma), identical in
exact arithmetic to eqs (11)-(12) with these entries and accurate when the wall's information
dwarfs the prior's.

Beside the paper's step (``method="paper"``) the module offers ``method="linear"``: the wall
distance is linear in ``(x, y)`` and the bearing linear in ``theta``, so the exact
maximum-likelihood (Kalman) update needs no linearisation; with equal prior and measurement
variances it lands exactly halfway, where the paper's single step on the squared constraint
(10) and the sine constraint (9) misses halfway by a relative ``O(bias / r)`` across the wall
and by ``O(heading error^3)`` in heading.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import numpy.typing as npt

from sonar_gym.frozen import unchecked_instance
from sonar_gym.localization.apcs_walls import ZERO_LENGTH_M, DetectedWall, WallVector
from sonar_gym.localization.result import OK, Localization
from sonar_gym.pose import FloatArray, Pose, wrap_angle

# Statuses of a correction that could not be made (besides the match statuses).
PRIOR_ON_WALL_LINE = "prior_on_wall_line"
HEADING_DEGENERATE = "heading_degenerate"
NUMERICAL_FAILURE = "numerical_failure"

CorrectionMethod = Literal["paper", "linear"]

# |a cos(theta + xi) + b sin(theta + xi)| / sqrt(a^2 + b^2) below this: eq. (9) has no slope.
_MIN_NORMAL_ALIGNMENT = 1e-9


@dataclass(frozen=True)
class WallObservation:
    """A wall seen from the robot, as in Fig. 8.

    Attributes:
        r_m: perpendicular distance from the robot's position to the wall line, metres (> 0
            unless the robot is on the line).
        xi_rad: bearing of the foot of that perpendicular in the robot frame {R} (0 = robot
            forward, counter-clockwise positive), radians in (-pi, pi]. When the robot is on the
            line, the bearing of the wall's inward normal (towards the occupied side).
    """

    r_m: float
    xi_rad: float


def observe_wall(wall: DetectedWall | WallVector, pose: Pose) -> WallObservation:
    """``(r, xi)`` of a fitted wall line as seen from ``pose`` (Fig. 8).

    A detected wall is fitted to ERPs computed from the odometry positions (section 4.2), so
    it lives in the odometry's estimate of {W}; seen from the current odometry pose it is the
    robot-frame measurement of eqs (9)-(10): ``r`` the distance to the line, ``xi`` the bearing
    of the line's normal through the robot, both independent of where the sensor sits.

    Args:
        wall: a detected wall (or any wall vector), metres in {W}.
        pose: the robot pose the measurement is referred to (odometry estimate), {W}.
    """
    if isinstance(wall, DetectedWall):
        wall = wall.vector
    if not isinstance(wall, WallVector):
        raise ValueError(f"wall must be a DetectedWall or WallVector, got {type(wall).__name__}")
    if not isinstance(pose, Pose):
        raise ValueError(f"pose must be a Pose, got {type(pose).__name__}")
    return observed_wall(wall, pose)


def observed_wall(wall: WallVector, pose: Pose) -> WallObservation:
    """:func:`observe_wall` of a wall vector and a pose, without the type checks."""
    a, b, c = wall.line_coefficients  # (a, b) = (uy, -ux): the outward normal
    signed_distance = a * pose.x + b * pose.y + c
    # The normal from the robot towards the line: the inward one when on the free side.
    bearing_world = math.atan2(-b, -a) if signed_distance >= 0.0 else math.atan2(b, a)
    return WallObservation(abs(signed_distance), wrap_angle(bearing_world - pose.theta))


@dataclass(frozen=True, eq=False)
class CorrectionResult(Localization):
    """A corrected pose with its covariance (eqs 11-12).

    Attributes:
        covariance: ``(3, 3)`` covariance of ``(x, y, theta)`` after the correction (the
            prior's when no correction was made), m^2, m rad, rad^2; symmetric, read-only.
        method: ``"paper"`` or ``"linear"``.

    The message of a correction not made for want of a unique match lists every rejected map
    wall; such a result is made by :meth:`explained_when_read` and writes it when first read.
    """

    covariance: FloatArray = field(default_factory=lambda: np.zeros((3, 3)))
    method: str = "paper"

    # ``message`` is held in ``__dict__["_message"]``: the text itself, or (a result made by
    # :meth:`explained_when_read`) the function that writes it, called when first read.
    @property  # type: ignore[misc]
    def message(self) -> str:
        """A human-readable explanation, empty when ok."""
        message: str | Callable[[], str] = self.__dict__["_message"]
        if not isinstance(message, str):
            message = message()
            self.__dict__["_message"] = message
        return message

    @message.setter
    def message(self, message: str) -> None:  # the dataclass's __init__ sets the field here
        self.__dict__["_message"] = message

    @classmethod
    def explained_when_read(
        cls, status: str, explain: Callable[[], str], covariance: FloatArray, method: str
    ) -> CorrectionResult:
        """A correction not made (``status`` not ``"ok"``, no pose) whose message is
        ``explain()``, written when first read: equal to ``CorrectionResult(status, None,
        explain(), covariance=covariance, method=method)``. ``explain`` must give the same text
        whenever called (and be picklable for the result to be)."""
        return unchecked_instance(
            cls, status=status, pose=None, _message=explain, covariance=covariance, method=method
        )


def _check_positive(value: float, name: str, unit: str) -> float:
    number = float(value)
    if not (math.isfinite(number) and number > 0.0):
        raise ValueError(f"{name} must be a positive finite {unit}, got {value!r}")
    return number


def symmetrized(matrix: FloatArray) -> FloatArray:
    """``(M + M^T) / 2``: the symmetric part of a float matrix."""
    return 0.5 * (matrix + matrix.T)


def validated_covariance(covariance: npt.ArrayLike) -> FloatArray:
    """``covariance`` as a symmetric positive-definite 3x3 float array, or ValueError."""
    matrix = np.asarray(covariance, dtype=np.float64)
    if matrix.shape != (3, 3) or not np.all(np.isfinite(matrix)):
        raise ValueError(f"covariance must be a finite 3x3 matrix, got shape {matrix.shape}")
    scale = float(np.max(np.abs(matrix)))
    if scale == 0.0 or np.max(np.abs(matrix - matrix.T)) > 1e-9 * scale:
        raise ValueError("covariance must be symmetric and non-zero")
    matrix = symmetrized(matrix)
    try:
        np.linalg.cholesky(matrix)
    except np.linalg.LinAlgError as error:
        raise ValueError("covariance must be positive definite (eq. 12 inverts it)") from error
    return matrix


def _readonly(matrix: FloatArray) -> FloatArray:
    matrix = np.array(matrix, dtype=np.float64, copy=True)
    matrix.setflags(write=False)
    return matrix


def information_vector(
    prior: FloatArray,
    line: tuple[float, float, float],
    r: float,
    xi: float,
    sigma_r: float,
    sigma_xi: float,
) -> FloatArray:
    """``J_PA^T Sigma_su^-1 P_su`` of eq. (13), with rows 1-2 as read in the module docstring.

    Args:
        prior: ``[x_A, y_A, theta_A]``, metres and radians.
        line: ``(a, b, c)`` of the wall line ``a x + b y + c = 0`` (any scale).
        r, xi: measured distance (m) and bearing (rad, robot frame).
        sigma_r, sigma_xi: variances of ``r`` (m^2) and ``xi`` (rad^2).
    """
    x, y, theta = prior
    a, b, c = line
    norm2 = a * a + b * b
    d = c + a * x + b * y
    u = xi + theta
    range_row = d * ((norm2 * r * r) - d * d) / (2.0 * r * r * norm2**2 * sigma_r)
    heading_row = (a * math.sin(u) - b * math.cos(u)) / (
        (-a * math.cos(u) - b * math.sin(u)) * sigma_xi
    )
    return np.array([a * range_row, b * range_row, heading_row])


def information_matrix(
    prior: FloatArray,
    line: tuple[float, float, float],
    r: float,
    sigma_r: float,
    sigma_xi: float,
) -> FloatArray:
    """``J_PA^T Sigma_su^-1 J_PA`` of eq. (14), with the xy block as read in the module docstring.

    Arguments as in :func:`information_vector`. The information in ``(x, y)`` lies along the
    wall normal ``(a, b)`` only; the heading's is ``1 / sigma_xi``; there is no cross term.
    """
    x, y, _ = prior
    a, b, c = line
    norm2 = a * a + b * b
    d = c + a * x + b * y
    weight = d * d / (r * r * norm2**2 * sigma_r)
    return np.array(
        [
            [a * a * weight, a * b * weight, 0.0],
            [a * b * weight, b * b * weight, 0.0],
            [0.0, 0.0, 1.0 / sigma_xi],
        ]
    )


def _paper_step(
    prior: FloatArray,
    covariance: FloatArray,
    wall: WallVector,
    r: float,
    xi: float,
    sigma_r: float,
    sigma_xi: float,
) -> tuple[str, FloatArray, FloatArray, str]:
    a, b, c = wall.line_coefficients
    x, y, theta = prior
    normal_length = math.hypot(a, b)
    distance_term = a * x + b * y + c
    if abs(distance_term) / normal_length <= ZERO_LENGTH_M:
        return (
            PRIOR_ON_WALL_LINE,
            prior,
            covariance,
            ("the prior position lies on the wall line: eq. (10) has no slope there"),
        )
    u = theta + xi
    cos_u, sin_u = math.cos(u), math.sin(u)
    normal_alignment = a * cos_u + b * sin_u
    if abs(normal_alignment) / normal_length < _MIN_NORMAL_ALIGNMENT:
        return (
            HEADING_DEGENERATE,
            prior,
            covariance,
            ("theta_A + xi is parallel to the wall: eq. (9) has no slope there"),
        )
    # Eqs (11)-(12) in gain form: with J = J_PA and W = Sigma_su^-1, the matrix inversion lemma
    # gives Sigma_f J^T W = Sigma_PA J^T (J Sigma_PA J^T + Sigma_su)^-1 = K and
    # Sigma_f = (I - K J) Sigma_PA, identical in exact arithmetic to eqs (11)-(14) (see
    # information_vector / information_matrix) and accurate when the wall's information
    # dwarfs the prior's.
    norm2 = a * a + b * b
    constraint_jacobian = np.array(  # d(eq. 10, eq. 9) / d(x_A, y_A, theta_A)
        [[2.0 * a * distance_term, 2.0 * b * distance_term, 0.0], [0.0, 0.0, -normal_alignment]]
    )
    constraint_covariance = np.array(  # Sigma_su = J_z diag(sigma_r, sigma_xi) J_z^T
        [[4.0 * r * r * norm2**2 * sigma_r, 0.0], [0.0, normal_alignment**2 * sigma_xi]]
    )
    constraint_residual = np.array(  # P_su = -(eq. 10, eq. 9) at the prior
        [-(distance_term**2 - r * r * norm2), -(b * cos_u - a * sin_u)]
    )
    # Products of two C-ordered operands are ndarray.dot: it makes the BLAS calls of ``@`` (the
    # same bits) at a fraction of its per-call cost. The others keep ``@``.
    c_ordered = covariance.flags.c_contiguous
    jacobian_covariance = (  # J Sigma_PA, used twice
        constraint_jacobian.dot(covariance) if c_ordered else constraint_jacobian @ covariance
    )
    gain = np.linalg.solve(
        jacobian_covariance @ constraint_jacobian.T + constraint_covariance, jacobian_covariance
    ).T
    corrected = prior + gain @ constraint_residual  # eq. (11)
    reduction = _IDENTITY_3 - gain @ constraint_jacobian
    reduced = reduction.dot(covariance) if c_ordered else reduction @ covariance
    corrected_covariance = (  # eq. (12), Joseph form: symmetric and PSD by construction
        reduced @ reduction.T + gain @ constraint_covariance @ gain.T
    )
    corrected_covariance = 0.5 * (corrected_covariance + corrected_covariance.T)
    return OK, corrected, corrected_covariance, ""


_IDENTITY_3 = np.eye(3)
_IDENTITY_3.flags.writeable = False


def _linear_step(
    prior: FloatArray,
    covariance: FloatArray,
    wall: WallVector,
    r: float,
    xi: float,
    sigma_r: float,
    sigma_xi: float,
) -> tuple[str, FloatArray, FloatArray, str]:
    a, b, c = wall.line_coefficients  # (a, b): unit outward normal, free side positive
    x, y, theta = prior
    inward_bearing_world = math.atan2(-b, -a)
    predicted = np.array([a * x + b * y + c, wrap_angle(inward_bearing_world - theta)])
    innovation = np.array([r - predicted[0], wrap_angle(xi - predicted[1])])
    jacobian = np.array([[a, b, 0.0], [0.0, 0.0, -1.0]])
    noise = np.diag([sigma_r, sigma_xi])
    innovation_covariance = jacobian @ covariance @ jacobian.T + noise
    gain = np.linalg.solve(innovation_covariance, jacobian @ covariance).T
    corrected = prior + gain @ innovation
    reduction = np.eye(3) - gain @ jacobian
    corrected_covariance = reduction @ covariance @ reduction.T + gain @ noise @ gain.T
    corrected_covariance = 0.5 * (corrected_covariance + corrected_covariance.T)
    return OK, corrected, corrected_covariance, ""


def correct_pose(
    pose: Pose,
    covariance: npt.ArrayLike,
    wall: WallVector,
    r: float,
    xi: float,
    sigma_r: float,
    sigma_xi: float,
    *,
    method: CorrectionMethod = "paper",
) -> CorrectionResult:
    """Correct a pose and its covariance with one matched map wall (eqs 7-14).

    Args:
        pose: the estimate ``P_A`` before correction (eq. 7), {W}.
        covariance: ``Sigma_PA`` (eq. 8), 3x3 over ``(x, y, theta)``, symmetric positive
            definite (eq. 12 inverts it).
        wall: the matched map wall; its line is ``a x + b y + c = 0`` of eqs (9)-(10).
        r: measured perpendicular distance from the robot's position to the wall, metres > 0.
        xi: measured bearing of the wall's normal through the robot (the foot of the
            perpendicular) in the robot frame {R}, radians (see :func:`observe_wall`).
        sigma_r: variance of ``r``, m^2 (the paper's ``sigma_r`` is a variance).
        sigma_xi: variance of ``xi``, rad^2 (likewise).
        method: ``"paper"`` (default), the single maximum-likelihood step of eqs (11)-(14);
            ``"linear"``, the exact update of the linear model ``r = signed distance``,
            ``xi = inward-normal bearing - theta`` (robot on the wall's free side).

    Returns:
        ``status "ok"`` with the corrected pose and covariance, or a status naming why no
        correction was made (``"prior_on_wall_line"``, ``"heading_degenerate"``,
        ``"numerical_failure"``) with the prior covariance.

    Raises:
        ValueError: on arguments of the wrong type, shape, sign or an unknown method.
    """
    if not isinstance(pose, Pose):
        raise ValueError(f"pose must be a Pose, got {type(pose).__name__}")
    if not isinstance(wall, WallVector):
        raise ValueError(f"wall must be a WallVector, got {type(wall).__name__}")
    prior_covariance = validated_covariance(covariance)
    r = _check_positive(r, "r", "distance in metres")
    xi = float(xi)
    if not math.isfinite(xi):
        raise ValueError(f"xi must be a finite angle in radians, got {xi!r}")
    sigma_r = _check_positive(sigma_r, "sigma_r", "variance of r in m^2")
    sigma_xi = _check_positive(sigma_xi, "sigma_xi", "variance of xi in rad^2")
    if method not in ("paper", "linear"):
        raise ValueError(f"method must be 'paper' or 'linear', got {method!r}")
    return corrected_pose(pose, prior_covariance, wall, r, xi, sigma_r, sigma_xi, method=method)


def corrected_pose(
    pose: Pose,
    prior_covariance: FloatArray,
    wall: WallVector,
    r: float,
    xi: float,
    sigma_r: float,
    sigma_xi: float,
    *,
    method: CorrectionMethod = "paper",
) -> CorrectionResult:
    """:func:`correct_pose` on checked inputs: ``prior_covariance`` as
    :func:`validated_covariance` returns it, ``r``, ``sigma_r``, ``sigma_xi`` positive floats,
    ``xi`` a finite float and ``method`` one of ``"paper"``, ``"linear"``."""
    step = _paper_step if method == "paper" else _linear_step
    status, corrected, corrected_covariance, message = step(
        pose.as_array(), prior_covariance, wall, r, xi, sigma_r, sigma_xi
    )
    if status == OK:
        # Plain floats: the finiteness test and the pose of a three-element vector cost less
        # than numpy's per-call overhead.
        x, y, theta = pose_values = corrected.tolist()
        if not (
            all(map(math.isfinite, pose_values))
            and all(map(math.isfinite, corrected_covariance.ravel().tolist()))
        ):
            status, corrected_covariance = NUMERICAL_FAILURE, prior_covariance
            message = "the correction overflowed"
    if status != OK:
        return CorrectionResult(
            status, None, message, covariance=_readonly(prior_covariance), method=method
        )
    corrected_covariance.setflags(write=False)  # the step's own new array: no copy needed
    return CorrectionResult(
        OK,
        Pose.unchecked(x, y, theta),  # finite floats: Pose.from_array's pose
        covariance=corrected_covariance,
        method=method,
    )
