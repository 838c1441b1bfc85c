"""The simulated world: a pymunk space built from a :class:`~sonar_gym.scenario.Scenario`.

pymunk is the single source of truth for collisions. The room's walls, free walls and the four
sides of every box become static segments of radius 0; cylinders become static circles; the
robot is a dynamic circle of ``scenario.robot.radius``. The sonar does not query pymunk per
ping: it reads :attr:`World.geometry`, a flat numpy copy of the same static content
(:mod:`sonar_gym.geometry`), built once and rebuilt by :meth:`World.rebuild_geometry`.

The space is built on first use (:attr:`World.space`): a world whose robot is only teleported
and whose free-pose tests are decided far from every shape never needs it. Until then the robot
body has only been teleported, which leaves nothing of it but its pose, so the space built late
is the one an eager build would hold at that moment: the same shapes added in the same order,
the robot body at its pose.

Everything is in metres, radians and seconds, in the world frame {W}. The robot pose is the
pose of the robot frame {R}: the body's position and angle, the angle wrapped to (-pi, pi].

Motion (see :meth:`World.move_robot`) is executed by stepping the space in short substeps: the
robot's velocity is imposed from the body's ``velocity_func``, i.e. *after* collision detection
and *before* the contact solver, so a contact removes the approach velocity before the position
is integrated. Chipmunk has no speculative contacts, so a substep may end slightly inside a
surface it had not yet touched; the collision bias is set to remove such an overlap entirely in
the next substep, and a settle step at the end leaves the robot at most the collision slop
(1e-6 m) deep. Substeps shorter than the robot radius keep it from tunnelling through thin
walls. Frictionless contacts let the robot slide along a wall it is driven into; a contact never
turns it.

Determinism: every teleport and every motion starts from a fresh robot body, so no cached
contact or solver bias carries over; a motion's result depends only on the pose before it and
the commanded displacements. Pickling stores the scenario, the temperature and the robot pose,
and rebuilds the space from them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import pymunk

from sonar_gym.geometry import StaticGeometry, ring_shift, static_geometry
from sonar_gym.path_clearance import StaticShapeTable, arc_is_clear
from sonar_gym.pose import FloatArray, Pose, wrap_angle
from sonar_gym.scenario import Scenario

TEMPERATURE_RANGE_C = (-40.0, 60.0)
"""Allowed air temperature in degrees Celsius (inclusive)."""

MOTION_SUBSTEP_S = 0.01
"""Duration of one physics substep of a motion, seconds (it only scales the velocities)."""

STATIC_CATEGORY = 0b01
ROBOT_CATEGORY = 0b10
STATIC_ONLY = pymunk.ShapeFilter(mask=STATIC_CATEGORY)
"""Query filter that sees the static shapes and ignores the robot."""
_STATIC_FILTER = pymunk.ShapeFilter(categories=STATIC_CATEGORY)

_ROBOT_MASS_KG = 10.0
_COLLISION_SLOP_M = 1e-6
_CONTACT_IMPULSE_EPS = 1e-12
_ENDPOINT_TOLERANCE_M = 1e-6
OVERLAP_TOLERANCE_M = 1e-5
"""Overlap below which a footprint still counts as free (pymunk lets contacts rest ~1e-6 m deep)."""
_SETTLE_STEPS = 1


def _body_setter(name: str) -> Callable[[pymunk.Body, Any], None]:
    """The setter of ``pymunk.Body``'s property ``name``, to call directly:
    ``body.position = ...`` goes through pymunk's ``__setattr__`` hook first, which adds as much
    time again and changes nothing."""
    setter: Callable[[pymunk.Body, Any], None] = vars(pymunk.Body)[name].fset
    return setter


_SET_POSITION = _body_setter("position")
_SET_ANGLE = _body_setter("angle")
_SET_VELOCITY = _body_setter("velocity")
_SET_ANGULAR_VELOCITY = _body_setter("angular_velocity")

Region = tuple[tuple[float, float], tuple[float, float]]


class NoFreePoseError(ValueError):
    """No free robot pose could be found in the requested region with the requested clearance."""


@dataclass(frozen=True)
class MotionOutcome:
    """What happened to the robot body during :meth:`World.move_robot`.

    Attributes:
        pose: the robot pose afterwards ({W}; metres, radians).
        collided: whether any contact pushed back on the robot (a non-zero contact impulse).
        path_length_m: length of the path travelled by the robot centre, metres.
    """

    pose: Pose
    collided: bool
    path_length_m: float


def validate_temperature_c(temperature_c: float, name: str = "temperature_c") -> float:
    """``temperature_c`` as a float; ``ValueError`` naming ``name`` and the range if bad."""
    low, high = TEMPERATURE_RANGE_C
    try:
        value = float(temperature_c)
    except (TypeError, ValueError):
        raise ValueError(
            f"argument '{name}' must be a finite number of degrees Celsius in [{low}, {high}]; "
            f"got {temperature_c!r}"
        ) from None
    if not math.isfinite(value) or not low <= value <= high:
        raise ValueError(
            f"argument '{name}' must be a finite number of degrees Celsius in [{low}, {high}]; "
            f"got {temperature_c!r}"
        )
    return value


class World:
    """A scenario made physical: static pymunk shapes, a dynamic robot body and a geometry cache.

    Args:
        scenario: the world description.
        temperature_c: air temperature in degrees Celsius, finite, in [-40, 60]; the sonar
            derives the true speed of sound from it.
        robot_pose: initial robot pose; it must be free. When omitted, the robot starts at the
            origin (heading 0) if that is free, otherwise at the free point of a grid nearest to
            the centre of the scenario's bounds (still deterministic).

    Attributes:
        scenario: the scenario this world was built from.
        geometry: the :class:`~sonar_gym.geometry.StaticGeometry` of the static content.
        static_shape_table: the static pymunk shapes as arrays, for the compiled clearance
            test of planned motions (:mod:`sonar_gym.path_clearance`).
    """

    _body_behind = False
    """Whether the built space's body is not yet at the pose teleported to (set by
    :meth:`_teleport`, cleared by :meth:`_place_body`; here for a subclass's ``_build``)."""

    def __init__(
        self, scenario: Scenario, temperature_c: float = 20.0, robot_pose: Pose | None = None
    ) -> None:
        if not isinstance(scenario, Scenario):
            raise ValueError(
                f"argument 'scenario' must be a Scenario; got {type(scenario).__name__}"
            )
        self._temperature_c = validate_temperature_c(temperature_c)
        self._build(scenario)
        self._place_initial_robot(robot_pose)

    # --- construction --------------------------------------------------------------------

    def _build(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self.rebuild_geometry()
        self._index_static_content(scenario)
        self._space: pymunk.Space | None = None  # built on first use, see _build_space
        self._static_shapes: list[pymunk.Shape] = []
        self._robot_body: pymunk.Body | None = None
        self._robot_shape: pymunk.Circle | None = None

        self._commanded_velocity: tuple[float, float] = (0.0, 0.0)
        self._commanded_angular_velocity = 0.0
        self._robot_is_fresh = True  # not stepped by the space since it was made
        self._placed_pose: Pose | None = None  # the pose teleported to, until the body moves
        self._body_behind = False

    def _build_space(self) -> pymunk.Space:
        """Build the pymunk space as :meth:`_build` would have eagerly: the static shapes, then
        a new robot body at the origin, then the body teleported to the pose it was last
        teleported to (a body not yet in a space has been teleported only: see
        :meth:`_teleport`)."""
        space = pymunk.Space()
        space.gravity = (0.0, 0.0)
        space.damping = 1.0
        space.collision_slop = _COLLISION_SLOP_M
        # Chipmunk has no speculative contacts: a substep may end inside a wall it was not yet
        # touching. Remove the whole overlap in the next substep (the default corrects ~6 %).
        space.collision_bias = 0.0
        self._space = space
        self._add_static_shapes(space)
        body, shape = self._new_robot()
        space.add(body, shape)
        self._robot_body, self._robot_shape = body, shape
        if self._placed_pose is not None:
            _move_fresh_body(space, body, self._placed_pose)
        return space

    def _new_robot(self) -> tuple[pymunk.Body, pymunk.Circle]:
        radius = self.scenario.robot.radius
        body = pymunk.Body(_ROBOT_MASS_KG, pymunk.moment_for_circle(_ROBOT_MASS_KG, 0.0, radius))
        body.velocity_func = self._impose_velocity
        shape = pymunk.Circle(body, radius)
        shape.friction = 0.0
        shape.elasticity = 0.0
        shape.filter = pymunk.ShapeFilter(categories=ROBOT_CATEGORY, mask=STATIC_CATEGORY)
        return body, shape

    def _index_static_content(self, scenario: Scenario) -> None:
        # The geometry lists the segments (room, walls, box sides from each box's first corner)
        # and the cylinders in that order, as the same floats: the shape table, the box
        # polygons and the pymunk shapes (_add_static_shapes) are made from it.
        geometry = self.geometry
        self.static_shape_table = StaticShapeTable.of_outlines(
            geometry.segment_starts, geometry.segment_ends, geometry.circles
        )
        box_sides = geometry.segment_starts[geometry.n_segments - 4 * len(scenario.boxes) :]
        self._box_polygons = _ConvexPolygons(box_sides.reshape(-1, 4, 2))  # the boxes' corners

    def _add_static_shapes(self, space: pymunk.Space) -> None:
        # New pymunk shapes are already frictionless and inelastic; only their filter needs
        # setting.
        static_body = space.static_body
        geometry = self.geometry
        shapes: list[pymunk.Shape] = [
            pymunk.Segment(static_body, a, b, 0.0)
            for a, b in zip(
                geometry.segment_starts.tolist(), geometry.segment_ends.tolist(), strict=True
            )
        ]
        shapes += [
            pymunk.Circle(static_body, radius, (x, y)) for x, y, radius in geometry.circles.tolist()
        ]
        for shape in shapes:
            shape.filter = _STATIC_FILTER
        if shapes:
            space.add(*shapes)
        self._static_shapes = shapes

    def rebuild_geometry(self) -> None:
        """Rebuild :attr:`geometry` from :attr:`scenario` (after the static content changed).

        Worlds of equal scenarios share one read-only geometry
        (:func:`~sonar_gym.geometry.static_geometry`), so the analysis runs once per scenario.
        """
        self.geometry: StaticGeometry = static_geometry(self.scenario)

    def reset_episode(self, temperature_c: float, robot_pose: Pose | None = None) -> None:
        """Start a new episode in the same static world: new air temperature and robot pose.

        The pymunk space, its static shapes and :attr:`geometry` are kept; the robot gets a
        fresh body at ``robot_pose`` (which must be free) or at the default start (see the
        class docstring), so the result equals a newly built ``World(scenario, temperature_c,
        robot_pose)``.
        """
        self.temperature_c = temperature_c
        self._place_initial_robot(robot_pose)

    def set_scenario(self, scenario: Scenario, robot_pose: Pose | None = None) -> None:
        """Replace the static content by ``scenario``'s and rebuild the geometry cache.

        The robot moves to ``robot_pose`` (which must be free), or keeps its pose if that is
        still free, or goes to the default start (see the class docstring).
        """
        if not isinstance(scenario, Scenario):
            raise ValueError(
                f"argument 'scenario' must be a Scenario; got {type(scenario).__name__}"
            )
        previous_scenario, previous = self.scenario, self.robot_pose
        self._build(scenario)
        if robot_pose is None and self.is_free(previous.position):
            robot_pose = previous
        try:
            self._place_initial_robot(robot_pose)
        except ValueError:
            self._build(previous_scenario)
            self._teleport(previous)
            raise

    def _place_initial_robot(self, robot_pose: Pose | None) -> None:
        if robot_pose is not None:
            self.set_robot_pose(robot_pose)
            return
        self._teleport(self._default_start())

    def _default_start(self) -> Pose:
        if self.is_free((0.0, 0.0)):
            return Pose(0.0, 0.0, 0.0)
        (x0, y0), (x1, y1) = self.scenario.bounds
        centre = np.array([(x0 + x1) / 2.0, (y0 + y1) / 2.0])
        spacing = max(self.robot_radius / 2.0, 0.01)
        xs = np.arange(x0, x1 + spacing, spacing)
        ys = np.arange(y0, y1 + spacing, spacing)
        grid = np.round(np.stack(np.meshgrid(xs, ys, indexing="xy"), axis=-1).reshape(-1, 2), 9)
        order = np.argsort(np.linalg.norm(grid - centre, axis=1), kind="stable")
        for point in grid[order]:
            if self.is_free(point):
                return Pose(float(point[0]), float(point[1]), 0.0)
        return Pose(0.0, 0.0, 0.0)

    # --- state ---------------------------------------------------------------------------

    @property
    def temperature_c(self) -> float:
        """Air temperature in degrees Celsius."""
        return self._temperature_c

    @temperature_c.setter
    def temperature_c(self, value: float) -> None:
        self._temperature_c = validate_temperature_c(value)

    @property
    def robot_radius(self) -> float:
        """Radius of the robot's footprint, metres."""
        return self.scenario.robot.radius

    @property
    def space(self) -> pymunk.Space:
        """The ``pymunk.Space`` (static shapes in category :data:`STATIC_CATEGORY`, the robot in
        :data:`ROBOT_CATEGORY`), built on first use."""
        space = self._space
        if space is None:
            return self._build_space()
        if self._body_behind:
            self._place_body()
        return space

    @property
    def robot_body(self) -> pymunk.Body:
        """The robot's dynamic pymunk body (read it; move it only with the methods of this
        class, which keep :attr:`robot_pose` in step with it)."""
        return self._body()

    @property
    def static_shapes(self) -> tuple[pymunk.Shape, ...]:
        """The static pymunk shapes, in the order room, walls, box sides, cylinders."""
        self._body()
        return tuple(self._static_shapes)

    def _body(self) -> pymunk.Body:
        """The robot body at the robot pose, building the space first if it is not built yet."""
        if self._robot_body is None:
            self._build_space()
        elif self._body_behind:
            self._place_body()
        assert self._robot_body is not None
        return self._robot_body

    @property
    def robot_pose(self) -> Pose:
        """The true robot pose in {W}, from the pymunk body (metres, radians)."""
        if self._placed_pose is not None:  # the body holds exactly these floats
            return self._placed_pose
        body = self._body()
        x, y = body.position
        x, y, theta = float(x), float(y), float(body.angle)
        if math.isfinite(x) and math.isfinite(y) and math.isfinite(theta):
            return Pose.unchecked(x, y, theta)  # read many times a step: skip the checks
        return Pose(x, y, theta)  # raises, naming the non-finite field

    def set_robot_pose(self, pose: Pose) -> None:
        """Teleport the robot to ``pose``; raises ``ValueError`` if the footprint is not free."""
        if not isinstance(pose, Pose):
            raise ValueError(f"argument 'pose' must be a Pose; got {type(pose).__name__}")
        if not self.is_free(pose.position):
            raise ValueError(
                f"argument 'pose' must be a free pose (the robot of radius {self.robot_radius} m "
                f"overlaps an obstacle or leaves the room there); got {pose}"
            )
        self._teleport(pose)

    def place_robot_on_clear_path(self, pose: Pose) -> None:
        """Teleport the robot to ``pose`` without :meth:`is_free`: for a caller that has shown
        the robot's whole path to ``pose`` clear of every static shape (so it ends free)."""
        self._teleport(pose)

    def _teleport(self, pose: Pose) -> None:
        # The body follows only when it is next read (_body, space: _place_body): the queries
        # of the world ignore the robot, so a run of teleports between two motions leaves the
        # space as the last one alone would. Before the space is built, the pose is all there
        # is to keep (see _build_space).
        self._placed_pose = pose  # pose.theta is wrapped: the body reads back this very pose
        self._body_behind = self._space is not None

    def _place_body(self) -> None:
        """Put the body at the pose teleported to (:attr:`_placed_pose`)."""
        # A new body and shape carry no cached contacts and no solver bias velocity, so what
        # happens next depends only on the pose, never on the history of the space. A body
        # the space has not stepped since it was made is still in that state: it only moves.
        self._body_behind = False
        space, body, pose = self._space, self._robot_body, self._placed_pose
        assert space is not None and body is not None and pose is not None
        if self._robot_is_fresh:
            _move_fresh_body(space, body, pose)
            return
        old_shape = self._robot_shape
        assert old_shape is not None  # a body that has moved is in the built space
        space.remove(body, old_shape)
        body, shape = self._new_robot()
        _SET_POSITION(body, (pose.x, pose.y))
        _SET_ANGLE(body, pose.theta)
        space.add(body, shape)
        self._robot_body, self._robot_shape = body, shape
        self._robot_is_fresh = True

    # --- queries -------------------------------------------------------------------------

    def is_free(self, position_xy: npt.ArrayLike, radius: float | None = None) -> bool:
        """Whether a disc at ``position_xy`` (metres, {W}) is clear of every static shape.

        The disc (radius ``radius``, default the robot's) may touch but not overlap a wall,
        box side or cylinder (overlaps below :data:`OVERLAP_TOLERANCE_M`, where pymunk rests a
        contact, are ignored); its centre must not lie inside a box; when the scenario has a
        room, the disc must lie inside it. The robot's own body is ignored.
        """
        x, y = _as_point(position_xy, "position_xy")
        r = self.robot_radius if radius is None else float(radius)
        if not math.isfinite(r) or r < 0.0:
            raise ValueError(
                f"argument 'radius' must be a finite number >= 0 (metres); got {radius!r}"
            )
        return self.is_free_unchecked(x, y, r)

    def is_free_unchecked(self, x: float, y: float, r: float) -> bool:
        """:meth:`is_free` of the disc at ``(x, y)`` of radius ``r`` (metres, {W}) without
        the argument checks: finite Python floats, ``r >= 0``, are the caller's to ensure."""
        room = self.scenario.room
        inner = r - OVERLAP_TOLERANCE_M
        if room is not None and not (
            room.min[0] + inner <= x <= room.max[0] - inner
            and room.min[1] + inner <= y <= room.max[1] - inner
        ):
            return False
        if self._box_polygons.contain_strictly(x, y):
            return False
        space = self._space
        if space is None:
            table = self.static_shape_table
            # A disc farther than the clearance margin from every shape is free, which pymunk
            # would confirm: no need to build the space for it.
            if arc_is_clear(x, y, x, y, 0.0, 0.0, 1.0, r, table.bounds, table.kinds, table.shapes):
                return True
            space = self._build_space()
        return all(info.distance >= inner for info in space.point_query((x, y), r, STATIC_ONLY))

    def sample_free_pose(
        self,
        rng: np.random.Generator,
        clearance: float = 0.0,
        max_tries: int = 1000,
        region: Region | None = None,
    ) -> Pose:
        """Draw a pose uniformly over the free space (rejection sampling).

        The position is uniform over the room (or the scenario's bounds when there is no room),
        optionally intersected with ``region = ((x_min, y_min), (x_max, y_max))`` in metres,
        kept ``robot radius + clearance`` away from walls and obstacles; the heading is uniform
        in (-pi, pi]. Every draw comes from ``rng``: two coordinates per try, then the heading.

        Raises:
            NoFreePoseError: no free pose in ``max_tries`` tries (the message says why).
            ValueError: a bad argument.
        """
        if not isinstance(rng, np.random.Generator):
            raise ValueError(
                f"argument 'rng' must be a numpy.random.Generator; got {type(rng).__name__}"
            )
        clearance = float(clearance)
        if not math.isfinite(clearance) or clearance < 0.0:
            raise ValueError(
                f"argument 'clearance' must be a finite number >= 0 (metres); got {clearance!r}"
            )
        if int(max_tries) != max_tries or max_tries < 1:
            raise ValueError(f"argument 'max_tries' must be a positive integer; got {max_tries!r}")
        margin = self.robot_radius + clearance
        if self.scenario.room is not None:
            (x0, y0), (x1, y1) = self.scenario.room.min, self.scenario.room.max
        else:
            (x0, y0), (x1, y1) = self.scenario.bounds
        if region is not None:
            (rx0, ry0), (rx1, ry1) = _as_region(region)
            x0, y0, x1, y1 = max(x0, rx0), max(y0, ry0), min(x1, rx1), min(y1, ry1)
        x0, y0, x1, y1 = x0 + margin, y0 + margin, x1 - margin, y1 - margin
        if x0 > x1 or y0 > y1:
            raise NoFreePoseError(
                f"scenario {self.scenario.name!r}: the sampling area is empty once the robot "
                f"radius {self.robot_radius} m and clearance {clearance} m are kept from its edges "
                f"(region={region})"
            )
        for _ in range(int(max_tries)):
            x = float(rng.uniform(x0, x1))
            y = float(rng.uniform(y0, y1))
            # The tolerance is added so sampled poses are clear by the full margin.
            if self.is_free_unchecked(x, y, margin + OVERLAP_TOLERANCE_M):
                return Pose(x, y, float(rng.uniform(-math.pi, math.pi)))
        raise NoFreePoseError(
            f"scenario {self.scenario.name!r}: no free pose found in {max_tries} tries with "
            f"clearance {clearance} m (region={region}); lower the clearance or widen the region"
        )

    def line_of_sight(self, a_xy: npt.ArrayLike, b_xy: npt.ArrayLike) -> bool:
        """Whether the straight segment from ``a_xy`` to ``b_xy`` (metres, {W}) is unobstructed.

        Uses pymunk's ``segment_query_first`` on the static shapes (the robot is ignored).
        Contacts within 1 micrometre of either end point do not block, so a point *on* a
        surface (an echo point on a wall or a beacon) is visible from the free side.
        """
        return self.line_of_sight_unchecked(_as_point(a_xy, "a_xy"), _as_point(b_xy, "b_xy"))

    def line_of_sight_unchecked(self, a: tuple[float, float], b: tuple[float, float]) -> bool:
        """:meth:`line_of_sight` between points given as pairs of finite Python floats
        (metres, {W}), without the argument checks."""
        length = math.dist(a, b)
        if length <= 2.0 * _ENDPOINT_TOLERANCE_M:
            return True
        space = self.space
        hit = space.segment_query_first(a, b, 0.0, STATIC_ONLY)
        if hit is None:
            return True
        low, high = _ENDPOINT_TOLERANCE_M / length, 1.0 - _ENDPOINT_TOLERANCE_M / length
        if low < hit.alpha < high:
            return False
        return all(
            not low < info.alpha < high for info in space.segment_query(a, b, 0.0, STATIC_ONLY)
        )

    # --- motion --------------------------------------------------------------------------

    def move_robot(self, substep_displacements: npt.ArrayLike) -> MotionOutcome:
        """Drive the robot body through pymunk along planned per-substep displacements.

        Args:
            substep_displacements: ``(N, 3)`` planned ``[dx, dy, dtheta]`` of each substep in
                {W} (metres, radians). Substep ``k`` imposes the velocity
                ``displacement_k / MOTION_SUBSTEP_S``; contacts with static shapes remove the
                approach component (the robot slides along walls and never enters them).

        Returns:
            the pose afterwards, whether a contact pushed back, and the centre's path length.
            The body's velocity is zero afterwards; the result depends only on the pose before
            and the displacements (cached contacts are dropped first).
        """
        steps = np.asarray(substep_displacements, dtype=np.float64)
        if steps.ndim != 2 or steps.shape[1] != 3 or not np.all(np.isfinite(steps)):
            raise ValueError(
                "argument 'substep_displacements' must be a finite (N, 3) array of "
                "[dx, dy, dtheta]; "
                f"got shape {steps.shape}"
            )
        self._teleport(self.robot_pose)
        body = self._body()
        space = self.space
        collided = False
        path_length = 0.0
        previous = body.position
        velocities = steps / MOTION_SUBSTEP_S
        zero = np.zeros(3)
        # The velocity imposed in step k moves the body in step k + 1: one extra step applies the
        # last command, a settle step lets the contact bias remove any residual overlap.
        self._robot_is_fresh = False
        self._placed_pose = None
        for k in range(len(steps) + 1 + _SETTLE_STEPS):
            vx, vy, omega = velocities[k] if k < len(steps) else zero
            self._commanded_velocity = (float(vx), float(vy))
            self._commanded_angular_velocity = float(omega)
            space.step(MOTION_SUBSTEP_S)
            position = body.position
            path_length += math.dist(position, previous)
            previous = position
            if not collided:
                collided = _has_contact_impulse(body)
        self._commanded_velocity = (0.0, 0.0)
        self._commanded_angular_velocity = 0.0
        _SET_VELOCITY(body, (0.0, 0.0))
        _SET_ANGULAR_VELOCITY(body, 0.0)
        _SET_ANGLE(body, wrap_angle(body.angle))
        return MotionOutcome(self.robot_pose, collided, path_length)

    def _impose_velocity(self, body: pymunk.Body, gravity: Any, damping: float, dt: float) -> None:
        _SET_VELOCITY(body, self._commanded_velocity)
        _SET_ANGULAR_VELOCITY(body, self._commanded_angular_velocity)

    # --- pickling ------------------------------------------------------------------------

    def __getstate__(self) -> dict[str, Any]:
        pose = self.robot_pose
        return {
            "scenario": self.scenario,
            "temperature_c": self._temperature_c,
            "robot_pose": (pose.x, pose.y, pose.theta),
        }

    def __setstate__(self, state: dict[str, Any]) -> None:
        self._temperature_c = validate_temperature_c(state["temperature_c"])
        self._build(state["scenario"])
        self._teleport(Pose(*state["robot_pose"]))

    def __repr__(self) -> str:
        return (
            f"World(scenario={self.scenario.name!r}, temperature_c={self._temperature_c}, "
            f"robot_pose={self.robot_pose})"
        )


def _has_contact_impulse(body: pymunk.Body) -> bool:
    """Whether a contact of ``body`` pushed back on it in the last step."""
    found = False

    def visit(arbiter: pymunk.Arbiter) -> None:
        nonlocal found
        jx, jy = arbiter.total_impulse
        if abs(jx) + abs(jy) > _CONTACT_IMPULSE_EPS:
            found = True

    body.each_arbiter(visit)
    return found


def _move_fresh_body(space: pymunk.Space, body: pymunk.Body, pose: Pose) -> None:
    """Teleport ``body``, which ``space`` has not stepped since it was added, to ``pose``."""
    _SET_POSITION(body, (pose.x, pose.y))
    _SET_ANGLE(body, pose.theta)
    space.reindex_shapes_for_body(body)


def _as_point(value: Any, name: str) -> tuple[float, float]:
    if isinstance(value, np.ndarray) and value.shape == (2,) and value.dtype == np.float64:
        point = tuple(value.tolist())  # the common case, without numpy scalars
    else:
        try:
            x, y = value
            point = (float(x), float(y))
        except (TypeError, ValueError):
            point = (math.nan, math.nan)
    if not (math.isfinite(point[0]) and math.isfinite(point[1])):
        raise ValueError(
            f"argument '{name}' must be a finite point [x, y] in metres; got {value!r}"
        )
    return point


def _as_region(region: Region) -> Region:
    array = np.asarray(region, dtype=np.float64)
    if array.shape != (2, 2) or not np.all(np.isfinite(array)) or np.any(array[0] >= array[1]):
        raise ValueError(
            "argument 'region' must be ((x_min, y_min), (x_max, y_max)) in metres with "
            f"min < max; got {region!r}"
        )
    return ((float(array[0, 0]), float(array[0, 1])), (float(array[1, 0]), float(array[1, 1])))


class _ConvexPolygons:
    """Counter-clockwise convex polygons ``(P, K, 2)`` (metres, {W}), edges precomputed.

    A point is outside most polygons by its first or second edge, so a plain loop that stops
    there beats array arithmetic for the few boxes of a room.
    """

    def __init__(self, corners: FloatArray) -> None:
        previous = ring_shift(corners, -1, axis=1)
        edges = corners - previous
        self._polygons = [
            [(p[0], p[1], e[0], e[1]) for p, e in zip(ps, es, strict=True)]
            for ps, es in zip(previous.tolist(), edges.tolist(), strict=True)
        ]

    def contain_strictly(self, x: float, y: float) -> bool:
        """Whether ``(x, y)`` lies strictly inside any polygon: left of every one of its edges."""
        for polygon in self._polygons:
            for start_x, start_y, edge_x, edge_y in polygon:
                if edge_x * (y - start_y) - edge_y * (x - start_x) <= 0.0:
                    break
            else:
                return True
        return False
