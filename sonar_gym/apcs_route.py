"""Driving an APCS route leg by leg: the robot, its side sonars and the on-line APCS together.

One :class:`APCSRoute` holds what an APCS run needs in the world (the pymunk robot, its side
sonars, the two random streams) and the tracker
(:class:`~sonar_gym.localization.apcs_online.APCSTracker`)
that runs the paper's Fig. 2 loop. :meth:`APCSRoute.drive_to` drives towards a target in
straight commands, steering from the estimate every few commands; between two steering
corrections the commands, the readings taken along them and the tracker's work are arrays:
:func:`~sonar_gym.straight_drive.drive_commands` for the motion,
:meth:`~sonar_gym.sonar.swept.SideSonars.first_echoes_along` (of the sonars the leg runs) and
:meth:`~sonar_gym.sonar.swept.SideSonars.read_echoes` for the readings and
:meth:`~sonar_gym.localization.apcs_online.APCSTracker.run` for dead reckoning, ERPs, walls and
corrections. When a correction cuts a run short, the kept readings' noise is replayed from
their echoes, so the random streams stand where the shorter run would have left them.
"""

from __future__ import annotations

import bisect
import dataclasses
import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from sonar_gym import drive_kernels
from sonar_gym.frozen import unchecked_instance
from sonar_gym.localization.apcs import DetectedWall, MatchResult
from sonar_gym.localization.apcs_online import SIDE_NAMES, APCSTracker, RunResult
from sonar_gym.phase_timer import PhaseTimer
from sonar_gym.pose import FloatArray, Pose
from sonar_gym.robot import DifferentialDriveRobot
from sonar_gym.scenario import Box, Room, Scenario, Wall
from sonar_gym.sonar.pulse_echo import FirstEchoes
from sonar_gym.sonar.swept import SideSonars
from sonar_gym.straight_drive import CommandDraws, drive_commands
from sonar_gym.world import World

REAIM_TOLERANCE_RAD = math.radians(0.05)
"""Smallest heading correction the path follower commands (radians)."""


@dataclass(frozen=True)
class WallDetection:
    """One detected wall and what APCS did with it (Fig. 2).

    Attributes:
        leg: index of the leg during which the wall was detected.
        side: ``"left"`` or ``"right"``.
        wall: the detected wall (in the frame of the estimate at detection time).
        erp_points: ``(n, 2)`` the ERPs of its group, metres.
        match: the matching against the map (sec. 4.3).
        reason: ``None`` when matched, else why not
            (:func:`~sonar_gym.localization.apcs_online.rejection_reason`).
        correction_status: ``"ok"`` when the pose was corrected, else the reason.
        pose_before, pose_after: the estimate before and after (equal without a correction).
        true_pose: the true pose at detection time.
    """

    leg: int
    side: str
    wall: DetectedWall
    erp_points: FloatArray
    match: MatchResult
    reason: str | None
    correction_status: str
    pose_before: Pose
    pose_after: Pose
    true_pose: Pose

    @classmethod
    def unchecked(
        cls,
        leg: int,
        side: str,
        wall: DetectedWall,
        erp_points: FloatArray,
        match: MatchResult,
        reason: str | None,
        correction_status: str,
        pose_before: Pose,
        pose_after: Pose,
        true_pose: Pose,
    ) -> WallDetection:
        """``WallDetection(leg, side, ...)``, its fields set as its ``__init__`` sets them
        (frozen: straight into ``__dict__``) at a fraction of the cost."""
        return unchecked_instance(
            cls,
            leg=leg,
            side=side,
            wall=wall,
            erp_points=erp_points,
            match=match,
            reason=reason,
            correction_status=correction_status,
            pose_before=pose_before,
            pose_after=pose_after,
            true_pose=true_pose,
        )

    @property
    def matched(self) -> bool:
        """Whether exactly one map wall matched."""
        return self.match.matched


@dataclass(frozen=True)
class LegCommand:
    """What to do on one leg: which sonars, the sampling spacing and the lateral stand-off.

    Attributes:
        side: ``"none"``, ``"left"``, ``"right"`` or ``"both"``.
        spacing_cm: travel between two samples, centimetres.
        standoff_m: offset of the leg from the route's centre line, metres (positive: left).
    """

    side: str
    spacing_cm: int
    standoff_m: float

    @property
    def active_sides(self) -> tuple[str, ...]:
        """The side sonars that run: ``()``, ``("left",)``, ``("right",)`` or both."""
        return {"none": (), "left": ("left",), "right": ("right",), "both": SIDE_NAMES}[self.side]


@dataclass
class LegSummary:
    """What happened during one leg, per side (``left``, ``right``)."""

    detected: dict[str, int] = field(default_factory=lambda: {"left": 0, "right": 0})
    matched: dict[str, int] = field(default_factory=lambda: {"left": 0, "right": 0})
    rejected: dict[str, int] = field(default_factory=lambda: {"left": 0, "right": 0})
    dropped_groups: int = 0
    corrections: int = 0
    collided: bool = False
    sensing_time_s: float = 0.0
    samples: int = 0

    def add(self, other: LegSummary) -> None:
        """Add ``other``'s counts and times to these (``collided`` is left alone)."""
        for side in SIDE_NAMES:
            self.detected[side] += other.detected[side]
            self.matched[side] += other.matched[side]
            self.rejected[side] += other.rejected[side]
        self.dropped_groups += other.dropped_groups
        self.corrections += other.corrections
        self.sensing_time_s += other.sensing_time_s
        self.samples += other.samples


@dataclass
class EpisodeTrace:
    """Everything a route did, for rendering and the reproduction's plots.

    Attributes:
        true_path, estimated_path, odometry_path: ``[x, y, theta]`` after every command.
        erps: ``(x, y)`` of every ERP with its side, in the frame of the estimate when computed.
        detections: every detected wall with its match and correction.
        corrections: ``(true, before, after)`` poses of every correction made.
    """

    true_path: list[FloatArray] = field(default_factory=list)
    estimated_path: list[FloatArray] = field(default_factory=list)
    odometry_path: list[FloatArray] = field(default_factory=list)
    erps: list[tuple[float, float, str]] = field(default_factory=list)
    detections: list[WallDetection] = field(default_factory=list)
    corrections: list[tuple[Pose, Pose, Pose]] = field(default_factory=list)


@dataclass(frozen=True)
class _Plan:
    """Planned commands: ``(K, 2)`` ``(d_left, d_right)`` (metres), the ascending indices of
    the straight steps among them, the command counts at the steering points (``stops``) with
    the waypoint aimed at from each, the draws."""

    draws: CommandDraws
    commanded: FloatArray
    straight_indices: list[int]
    stops: list[int]
    next_waypoint: list[int]


def first_sample_step(counter: int, steps_per_sample: int) -> int:
    """Which straight step (0 = the first) takes the first reading, for a sampling sonar.

    Every straight step adds one to the count of steps since the last reading, ``counter``
    before the first; a step that brings it to ``steps_per_sample`` or more takes a reading
    and sets it to 0, so the readings fall on every ``max(steps_per_sample, 1)``-th straight
    step from this one on.
    """
    return max(steps_per_sample - counter - 1, 0)


def counter_after(counter: int, steps_per_sample: int, first: int, straight_steps: int) -> int:
    """The count of straight steps since the last reading after ``straight_steps`` straight
    steps, starting from ``counter``, with the readings from straight step ``first`` on every
    ``max(steps_per_sample, 1)``-th (``first`` past the steps: no reading, as without a
    sampling sonar)."""
    if straight_steps <= first:
        return counter + straight_steps
    return (straight_steps - 1 - first) % max(steps_per_sample, 1)


class APCSRoute:
    """A robot with side sonars driving through ``world`` while APCS corrects its estimate.

    Args:
        world: the world (its robot body is the true robot).
        robot: the differential drive (its odometry pose is plain dead reckoning).
        sonars: the side sonars.
        tracker: the on-line APCS (estimate, covariance, streams).
        motion_rng, sensor_rng: the random streams of the motion and of the readings.
        timing: optional dict to which the wall-clock seconds of ``"sensing"`` and
            ``"localization"`` are added.

    Attributes besides the arguments: ``trace`` (:class:`EpisodeTrace`), ``leg`` (legs
    done), ``last_leg`` and ``totals`` (:class:`LegSummary` of the last leg and of all),
    ``collisions`` (legs with a contact), ``sensing_time_s``.
    """

    def __init__(
        self,
        world: World,
        robot: DifferentialDriveRobot,
        sonars: SideSonars,
        tracker: APCSTracker,
        motion_rng: np.random.Generator,
        sensor_rng: np.random.Generator,
        timing: dict[str, float] | None = None,
    ) -> None:
        self.world = world
        self.robot = robot
        self.sonars = sonars
        self.tracker = tracker
        self.motion_rng = motion_rng
        self.sensor_rng = sensor_rng
        self.timing = {} if timing is None else timing
        self.trace = EpisodeTrace()
        self.leg = 0
        self.last_leg = LegSummary()
        self.totals = LegSummary()
        self.collisions = 0
        self.steps_since_sample = 0
        self.sensing_time_s = 0.0
        self._record(
            world.robot_pose.as_array()[None, :],
            tracker.estimate.as_array()[None, :],
            (robot.odometry_pose or tracker.estimate).as_array()[None, :],
        )

    def _timed(self, phase: str) -> PhaseTimer:
        return PhaseTimer(self.timing, phase)

    @property
    def true_pose(self) -> Pose:
        """The robot's true pose ({W})."""
        return self.world.robot_pose

    def end_leg(self, summary: LegSummary) -> None:
        """Book a finished leg: it becomes ``last_leg`` and adds to ``totals``."""
        self.leg += 1
        self.last_leg = summary
        self.totals.add(summary)
        self.collisions += int(summary.collided)

    def flush(self, side: str, summary: LegSummary) -> None:
        """Stop ``side``'s sonar: its open group is closed and handled (Fig. 2)."""
        with self._timed("localization"):
            result = self.tracker.flush(side)
        self._handled(result, np.zeros((0, 3)), summary)

    def drive_to(
        self,
        target: FloatArray,
        active_sides: Sequence[str],
        steps_per_sample: int,
        step_m: float,
        steps_per_aim: int,
        summary: LegSummary,
    ) -> None:
        """Drive to ``target`` ({W}) in straight commands of ``step_m``, steering from the estimate.

        Every ``steps_per_aim`` commands (and at the start) the remaining distance and the
        bearing to ``target`` are taken from the estimate and the robot turns in place when the
        heading is off by more than :data:`REAIM_TOLERANCE_RAD`. Every ``steps_per_sample``
        straight commands (counted across calls) the ``active_sides`` take a reading each.
        """
        self.drive_through([target], active_sides, steps_per_sample, step_m, steps_per_aim, summary)

    def drive_through(
        self,
        waypoints: Sequence[FloatArray],
        active_sides: Sequence[str],
        steps_per_sample: int,
        step_m: float,
        steps_per_aim: int,
        summary: LegSummary,
    ) -> None:
        """:meth:`drive_to` each of ``waypoints`` in turn.

        The commands to the last waypoint are planned at once from the estimate as dead
        reckoning carries it, then driven, sensed and handed to the tracker as arrays. When
        APCS corrects the estimate, the plan holds up to the next steering point; from there it
        is planned again from the corrected estimate (the random streams and the robot are
        put back where the first plan left them at that point).
        """
        targets = np.array(
            [np.asarray(target, dtype=np.float64).reshape(2) for target in waypoints]
        ).reshape(-1, 2)
        waypoint = 0
        while waypoint < len(targets):
            plan = self._plan(targets, waypoint, step_m, steps_per_aim)
            if not plan.stops:
                return
            waypoint = self._execute(plan, active_sides, steps_per_sample, summary)

    def _plan(self, targets: FloatArray, waypoint: int, step_m: float, steps_per_aim: int) -> _Plan:
        """The commands from the current estimate to the last target (see :meth:`drive_through`),
        planned in one compiled loop (:func:`sonar_gym.drive_kernels.plan_to_targets`)."""
        estimate = self.tracker.estimate
        rng = self.motion_rng
        draws = CommandDraws.start(rng)
        commanded, normals, uniforms, stops, _ = drive_kernels.plan_to_targets(
            rng,
            targets,
            waypoint,
            (estimate.x, estimate.y, estimate.theta),
            step_m,
            steps_per_aim,
            self.robot.wheel_base_for(self.world),
            self.robot.noise.encoder_std_m_per_sqrt_m,
            REAIM_TOLERANCE_RAD,
        )
        draws.extend(normals, uniforms)
        return _Plan(
            draws,
            commanded,
            # a turn in place rolls the wheels apart, a straight step both alike
            (commanded[:, 0] == commanded[:, 1]).nonzero()[0].tolist(),
            stops[:, 0].tolist(),
            stops[:, 1].tolist(),
        )

    def _execute(
        self, plan: _Plan, active_sides: Sequence[str], steps_per_sample: int, summary: LegSummary
    ) -> int:
        """Drive, sense and track ``plan``; returns the waypoint to plan for next."""
        commanded = plan.commanded
        motion = drive_commands(self.robot, self.world, commanded, plan.draws, self.motion_rng)
        straight = plan.straight_indices
        counter = self.steps_since_sample
        first = first_sample_step(counter, steps_per_sample) if active_sides else len(straight)
        samples = straight[first :: max(steps_per_sample, 1)]
        sensor_state = self.sensor_rng.bit_generator.state
        readings, echoes = self._read(motion.true_poses, samples, active_sides)
        with self._timed("localization"):
            # the increments and the readings come from the drive and the sonars, valid as run
            # requires them
            result = self.tracker.run_unchecked(
                motion.encoder_left_m,
                motion.encoder_right_m,
                np.asarray(samples, dtype=np.int64),
                readings,
                sensor_offset_m=self.sonars.lateral_offset_m,
                stops=plan.stops,
            )
        consumed = result.consumed
        kept = [index for index in samples if index < consumed]
        if consumed < len(commanded):  # a correction: the rest was planned from the old estimate
            self.world.set_robot_pose(Pose.unchecked(*motion.true_poses[consumed - 1].tolist()))
            self.robot.odometry_pose = Pose.unchecked(*motion.odometry_poses[consumed - 1].tolist())
            plan.draws.rewind(self.motion_rng, consumed)
            self.sensor_rng.bit_generator.state = sensor_state
            if kept and echoes is not None:  # the draws of the kept readings, in their order
                rows = 2 * len(kept)
                self.sonars.read_echoes(
                    self.world,
                    FirstEchoes(
                        echoes.detected[:rows], echoes.path_lengths[:rows], echoes.amplitudes[:rows]
                    ),
                    self.sensor_rng,
                )
        self.steps_since_sample = counter_after(
            counter, steps_per_sample, first, bisect.bisect_left(straight, consumed)
        )
        listen_s = self.sonars.transducer.listen_time_s * len(kept)  # both sonars fire together
        self.sensing_time_s += listen_s
        summary.sensing_time_s += listen_s
        summary.samples += len(active_sides) * len(kept)
        summary.collided = summary.collided or bool(motion.collided[:consumed].any())
        self._record(
            motion.true_poses[:consumed], result.estimated_path, motion.odometry_poses[:consumed]
        )
        self._handled(result, motion.true_poses, summary)
        return plan.next_waypoint[plan.stops.index(consumed)]

    def _read(
        self, true_poses: FloatArray, samples: Sequence[int], active_sides: Sequence[str]
    ) -> tuple[dict[str, FloatArray], FirstEchoes | None]:
        """Readings of the active sides at the commands ``samples`` (both sonars fire), and
        the first echoes they were read from (``None`` without samples)."""
        if not samples:
            return {}, None
        with self._timed("sensing"):
            echoes = self.sonars.first_echoes_along(
                self.world, true_poses[np.asarray(samples)], active_sides
            )
            side_readings = self.sonars.read_echoes(self.world, echoes, self.sensor_rng)
        all_readings = {"left": side_readings.left_m, "right": side_readings.right_m}
        return {side: all_readings[side] for side in active_sides}, echoes

    def _handled(self, result: RunResult, true_poses: FloatArray, summary: LegSummary) -> None:
        """Book the ERPs, walls and corrections of a tracker run into the trace and summary."""
        self.trace.erps.extend(result.erps)
        summary.dropped_groups += sum(result.dropped.values())
        for wall in result.walls:
            truth = (
                Pose.unchecked(*true_poses[wall.command_index].tolist())
                if wall.command_index >= 0
                else self.true_pose
            )
            summary.detected[wall.side] += 1
            if wall.match.matched:
                summary.matched[wall.side] += 1
            else:
                summary.rejected[wall.side] += 1
            if wall.pose_after is not wall.pose_before:
                summary.corrections += 1
                self.trace.corrections.append((truth, wall.pose_before, wall.pose_after))
            assert wall.group.fit.wall is not None
            self.trace.detections.append(
                WallDetection.unchecked(
                    self.leg,
                    wall.side,
                    wall.group.fit.wall,
                    wall.group.points,
                    wall.match,
                    wall.reason,
                    wall.correction.status,
                    wall.pose_before,
                    wall.pose_after,
                    truth,
                )
            )

    def _record(self, true: FloatArray, estimated: FloatArray, odometry: FloatArray) -> None:
        self.trace.true_path.extend(np.array(true, dtype=np.float64))
        self.trace.estimated_path.extend(np.array(estimated, dtype=np.float64))
        self.trace.odometry_path.extend(np.array(odometry, dtype=np.float64))


def check_route_clearance(
    scenario: Scenario,
    x_range_m: tuple[float, float],
    centre_line_y: float,
    standoffs_m: Sequence[float],
    clearance_m: float,
    temperature_c: float = 20.0,
    route_margin_m: float | None = None,
) -> None:
    """Raise ValueError unless every stand-off line of a route along ``+x`` clears the map.

    The route's two ends on the centre line must clear every *mapped* surface of ``scenario``
    by ``clearance_m`` (else the message blames ``route_margin_m``, the margin that placed
    them); then, for each of ``standoffs_m`` (metres from ``y = centre_line_y``), the robot's
    disc grown by ``clearance_m`` must be free of the mapped surfaces every 5 cm over
    ``x_range_m`` (metres in {W}); the route's start on the centre line must be free.
    """
    mapped = dataclasses.replace(
        scenario,
        walls=tuple(w for w in scenario.walls if w.mapped),
        boxes=tuple(b for b in scenario.boxes if b.mapped),
        cylinders=tuple(c for c in scenario.cylinders if c.mapped),
    )
    world = World(mapped, temperature_c=temperature_c)
    radius = mapped.robot.radius + clearance_m
    xs = np.arange(x_range_m[0], x_range_m[1] + 1e-9, 0.05)
    if not all(world.is_free((x, centre_line_y), radius) for x in x_range_m):
        raise ValueError(
            f"argument 'route_margin_m' puts the route's ends within {clearance_m:g} m of a "
            f"mapped surface of {scenario.name!r}; got {route_margin_m!r}"
        )
    for offset in standoffs_m:
        y = centre_line_y + offset
        if not all(world.is_free((x, y), radius) for x in xs):
            raise ValueError(
                f"argument 'standoffs_m': {offset:g} m brings the robot within "
                f"{clearance_m:g} m of a mapped surface of {scenario.name!r}; "
                f"got {tuple(standoffs_m)!r}"
            )
    if not world.is_free((x_range_m[0], centre_line_y)):
        raise ValueError(f"scenario {scenario.name!r}: the route's start is not free")


def render_route(
    route: APCSRoute, title: str, extra: dict[str, float], width_px: int = 900
) -> np.ndarray:
    """Top-down RGB image of ``route``'s world with its ERPs and its odometry (grey), true
    (green) and estimated (magenta) paths."""
    from sonar_gym.render import render_topdown, world_to_pixel

    scenario, trace = route.world.scenario, route.trace
    image = render_topdown(
        scenario,
        true_pose=route.true_pose,
        estimated_pose=route.tracker.estimate,
        scan_points=np.array([(x, y) for x, y, _ in trace.erps]).reshape(-1, 2),
        width_px=width_px,
        title=title,
        extra=extra,
    )
    height, width = image.shape[:2]
    for path, colour in (
        (trace.odometry_path, (150, 150, 150)),
        (trace.true_path, (20, 120, 20)),
        (trace.estimated_path, (216, 27, 156)),
    ):
        for x, y in np.array(path)[:, :2]:
            row, col = world_to_pixel(scenario, (x, y), width_px, height)
            if 0 <= row < height - 1 and 0 <= col < width - 1:
                image[row : row + 2, col : col + 2] = colour
    return image


def with_wall_obstacles(
    scenario: Scenario,
    rng: np.random.Generator,
    count: int,
    length_range_m: tuple[float, float],
    depth_range_m: tuple[float, float],
    x_range_m: tuple[float, float],
) -> Scenario:
    """``scenario`` plus ``count`` unmapped boxes standing against its room's long walls.

    Each box is drawn on a random long wall (left ``y = max``, right ``y = min``) with a length
    and a depth (metres) uniform in their ranges and a start uniform in ``x_range_m``; a box
    keeps 0.1 m from the other boxes and from the scenario's free walls near that wall, with
    50 attempts per box (a box that finds no place is left out).
    """
    room = scenario.room
    if room is None:
        raise ValueError(f"argument 'scenario': {scenario.name!r} has no room")
    boxes: list[Box] = []
    taken = {side: list(spans) for side, spans in _free_wall_spans(room, scenario.walls).items()}
    low_x, high_x = float(x_range_m[0]), float(x_range_m[1])
    for _ in range(count):
        for _attempt in range(50):
            side = SIDE_NAMES[int(rng.integers(2))]
            length = float(rng.uniform(*length_range_m))
            depth = float(rng.uniform(*depth_range_m))
            start_x = float(rng.uniform(low_x, max(low_x, high_x - length)))
            span = (start_x, start_x + length)
            if all(span[1] + 0.1 < a or span[0] - 0.1 > b for a, b in taken[side]):
                break
        else:
            continue
        taken[side].append(span)
        y_centre = room.max[1] - depth / 2.0 if side == "left" else room.min[1] + depth / 2.0
        boxes.append(Box((start_x + length / 2.0, y_centre), (length, depth), 0.0, mapped=False))
    return dataclasses.replace(scenario, boxes=scenario.boxes + tuple(boxes))


@functools.lru_cache(maxsize=8)
def _free_wall_spans(
    room: Room, walls: tuple[Wall, ...]
) -> dict[str, tuple[tuple[float, float], ...]]:
    """Per long wall of ``room`` (``"left"``: ``y = max``, ``"right"``: ``y = min``), the x
    spans ``(low, high)`` (metres) of the free walls with an end within 0.5 m of it, in
    scenario order; built once per room and walls, as every episode asks for the same."""
    taken: dict[str, list[tuple[float, float]]] = {"left": [], "right": []}
    for wall in walls:
        for side, y_wall in (("left", room.max[1]), ("right", room.min[1])):
            if min(abs(wall.a[1] - y_wall), abs(wall.b[1] - y_wall)) < 0.5:
                taken[side].append((min(wall.a[0], wall.b[0]), max(wall.a[0], wall.b[0])))
    return {side: tuple(spans) for side, spans in taken.items()}


__all__ = [
    "REAIM_TOLERANCE_RAD",
    "APCSRoute",
    "EpisodeTrace",
    "LegCommand",
    "LegSummary",
    "WallDetection",
    "check_route_clearance",
    "render_route",
    "with_wall_obstacles",
]
