"""Top-down pictures of a scenario and polar-style plots of a sonar pan.

:func:`render_topdown` returns an RGB ``uint8`` array ``(H, W, 3)``: the room, walls, boxes,
cylinders (small beacon red, large beacon blue, clutter grey; objects missing from the map
drawn dashed), emitters (green triangles), the robot at its true pose (green disc with a
heading line), the estimated pose (magenta outline with heading line) and scan points (orange
dots), all in the world frame {W}, with a 0.5 m grid as in Beom & Cho Fig. 7. A legend (lower
right) names the robot, the estimate, the beacons or emitters present and the range dots
(ranges placed along the beam axis: the paper's way of drawing RCD arcs, Beom & Cho Fig. 8),
and a scale bar (lower left) gives 1 m (0.5 m in small images).

Image size: ``W = width_px`` and ``H = height_px`` if given, else
``H = max(16, 2 * round(width_px * (span_y + 2 m) / (span_x + 2 m) / 2))`` (even, so video
encoders take the frames as they are) with ``span`` the extent of ``scenario.bounds`` and
``m`` = :data:`MARGIN_M`. The world is drawn at equal scale in x and
y, centred; :func:`world_to_pixel` gives the pixel of a world point.

matplotlib (Agg) is imported inside the functions. The static part of a picture is drawn once
per ``(scenario, width, height)`` and kept (a few are cached), each frame then restores it and
draws only the robot, estimate, scan and text.

:func:`plot_scan_polar` writes a PNG of one pan in the robot frame {R}, the style of Beom & Cho
Fig. 8(a)/(b): range dots around the robot (an octagon) and, if given, RCDs as arcs.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from sonar_gym.pose import Pose
from sonar_gym.scenario import Scenario

if TYPE_CHECKING:
    from matplotlib.artist import Artist

MARGIN_M = 0.25
"""Space drawn around ``scenario.bounds`` on each side, metres."""

GRID_SPACING_M = 0.5
"""Spacing of the background grid, metres (Beom & Cho Fig. 7)."""

SCALE_BAR_M = 1.0
"""Length of the scale bar, metres (shorter when 1 m would take over a quarter of the width)."""

_DPI = 64  # a power of two, so width_px / dpi * dpi is exact
_CACHE_SIZE = 4

COLOURS: dict[str, str] = {
    "outside": "#d9d9d9",
    "floor": "#ffffff",
    "grid": "#ececec",
    "wall": "#222222",
    "unmapped": "#b5651d",
    "box": "#a6a6a6",
    "box_edge": "#4d4d4d",
    "clutter": "#595959",
    "small_beacon": "#d62728",
    "large_beacon": "#1f77b4",
    "emitter": "#2ca02c",
    "robot": "#2ca02c",
    "robot_edge": "#145214",
    "estimate": "#d81b9c",
    "scan": "#ff7f0e",
    "text": "#111111",
}
"""Colours of the picture's elements (matplotlib colour strings)."""


def image_size(
    scenario: Scenario, width_px: int = 600, height_px: int | None = None
) -> tuple[int, int]:
    """``(H, W)`` of :func:`render_topdown`'s image (see the module docstring for the formula)."""
    width = _positive_int(width_px, "width_px")
    if height_px is not None:
        return _positive_int(height_px, "height_px"), width
    (x0, y0), (x1, y1) = scenario.bounds
    span_x, span_y = x1 - x0 + 2 * MARGIN_M, y1 - y0 + 2 * MARGIN_M
    return max(16, 2 * round(width * span_y / span_x / 2.0)), width


def _view(scenario: Scenario, height: int, width: int) -> tuple[float, float, float]:
    """``(x_left, y_bottom, pixels_per_metre)`` of the equal-scale view."""
    (x0, y0), (x1, y1) = scenario.bounds
    span_x, span_y = x1 - x0 + 2 * MARGIN_M, y1 - y0 + 2 * MARGIN_M
    scale = min(width / span_x, height / span_y)
    cx, cy = (x0 + x1) / 2.0, (y0 + y1) / 2.0
    return cx - width / (2.0 * scale), cy - height / (2.0 * scale), scale


def world_to_pixel(
    scenario: Scenario, xy: npt.ArrayLike, width_px: int = 600, height_px: int | None = None
) -> tuple[int, int]:
    """``(row, col)`` of the pixel of :func:`render_topdown`'s image holding world point ``xy``."""
    height, width = image_size(scenario, width_px, height_px)
    left, bottom, scale = _view(scenario, height, width)
    x, y = np.asarray(xy, dtype=np.float64).reshape(2)
    col = math.floor((x - left) * scale)
    row = math.floor(height - (y - bottom) * scale)
    return row, col


class _TopDownCanvas:
    """A figure with the static scenario drawn once and animated artists for each frame."""

    def __init__(self, scenario: Scenario, height: int, width: int) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.height, self.width = height, width
        self.figure = Figure(figsize=(width / _DPI, height / _DPI), dpi=_DPI)
        self.canvas = FigureCanvasAgg(self.figure)
        ax = self.figure.add_axes((0.0, 0.0, 1.0, 1.0))
        ax.set_axis_off()
        left, bottom, scale = _view(scenario, height, width)
        ax.set_xlim(left, left + width / scale)
        ax.set_ylim(bottom, bottom + height / scale)
        ax.set_aspect("auto")
        self.ax = ax
        self.points_per_metre = scale * 72.0 / _DPI
        self.px = 72.0 / _DPI  # one pixel in points
        self.figure.patch.set_facecolor(COLOURS["outside"] if scenario.room else COLOURS["floor"])
        self._draw_static(scenario)
        self._draw_legend(scenario)
        self._draw_scale_bar(scale)
        self.canvas.draw()
        self.background = self.canvas.copy_from_bbox(self.figure.bbox)
        self._make_animated(scenario.robot.radius)

    def _draw_static(self, scenario: Scenario) -> None:
        from matplotlib.patches import Circle, Polygon, Rectangle

        ax, px = self.ax, self.px
        line_width = max(1.0, self.width / 300.0) * px
        (x0, y0), (x1, y1) = scenario.bounds
        if scenario.room is not None:
            (rx0, ry0), (rx1, ry1) = scenario.room.min, scenario.room.max
            ax.add_patch(
                Rectangle(
                    (rx0, ry0),
                    rx1 - rx0,
                    ry1 - ry0,
                    facecolor=COLOURS["floor"],
                    edgecolor="none",
                    zorder=0,
                )
            )
        grid_x = (
            np.arange(math.ceil(x0 / GRID_SPACING_M), math.floor(x1 / GRID_SPACING_M) + 1)
            * GRID_SPACING_M
        )
        grid_y = (
            np.arange(math.ceil(y0 / GRID_SPACING_M), math.floor(y1 / GRID_SPACING_M) + 1)
            * GRID_SPACING_M
        )
        for gx in grid_x:
            ax.plot([gx, gx], [y0, y1], color=COLOURS["grid"], linewidth=px, zorder=1)
        for gy in grid_y:
            ax.plot([x0, x1], [gy, gy], color=COLOURS["grid"], linewidth=px, zorder=1)
        if scenario.room is not None:
            corners = list(scenario.room.corners) + [scenario.room.corners[0]]
            ax.plot(
                *zip(*corners, strict=True),
                color=COLOURS["wall"],
                linewidth=2 * line_width,
                zorder=3,
            )
        for wall in scenario.walls:
            ax.plot(
                [wall.a[0], wall.b[0]],
                [wall.a[1], wall.b[1]],
                color=COLOURS["wall"] if wall.mapped else COLOURS["unmapped"],
                linestyle="-" if wall.mapped else "--",
                linewidth=2 * line_width,
                zorder=3,
            )
        for box in scenario.boxes:
            ax.add_patch(
                Polygon(
                    box.corners,
                    closed=True,
                    facecolor=COLOURS["box"],
                    edgecolor=COLOURS["box_edge"] if box.mapped else COLOURS["unmapped"],
                    linestyle="-" if box.mapped else "--",
                    linewidth=line_width,
                    zorder=2,
                )
            )
        for cylinder in scenario.cylinders:
            colour = COLOURS.get(cylinder.role, COLOURS["clutter"])
            # A beacon a few centimetres wide would vanish; draw it at least 3 pixels across.
            radius = max(cylinder.radius, 1.5 * px / self.points_per_metre)
            ax.add_patch(
                Circle(
                    cylinder.center,
                    radius,
                    facecolor=colour,
                    edgecolor=colour if cylinder.mapped else COLOURS["unmapped"],
                    linestyle="-" if cylinder.mapped else "--",
                    linewidth=px,
                    zorder=4,
                )
            )
        if scenario.emitters:
            font = max(6.0, self.width / 75.0) * px
            for emitter in scenario.emitters:
                x, y, _ = emitter.position
                ax.plot(
                    [x],
                    [y],
                    marker="^",
                    color=COLOURS["emitter"],
                    markersize=max(5.0, self.width / 80.0) * px,
                    zorder=5,
                )
                ax.annotate(
                    emitter.name,
                    (x, y),
                    xytext=(4, 4),
                    textcoords="offset points",
                    fontsize=font,
                    color=COLOURS["emitter"],
                    zorder=5,
                )

    def _draw_legend(self, scenario: Scenario) -> None:
        from matplotlib.lines import Line2D

        px = self.px
        size = max(4.0, self.width / 90.0) * px
        # (label, marker, face colour, edge colour)
        entries = [
            ("robot", "o", COLOURS["robot"], COLOURS["robot_edge"]),
            ("estimate", "o", "none", COLOURS["estimate"]),
        ]
        roles = {cylinder.role for cylinder in scenario.cylinders}
        for role, label in (("small_beacon", "small beacon"), ("large_beacon", "large beacon")):
            if role in roles:
                entries.append((label, "o", COLOURS[role], COLOURS[role]))
        if scenario.emitters:
            entries.append(("emitter", "^", COLOURS["emitter"], COLOURS["emitter"]))
        entries.append(("range dots (beam axis)", "o", COLOURS["scan"], COLOURS["scan"]))
        handles = [
            Line2D(
                [],
                [],
                linestyle="none",
                marker=marker,
                markersize=size,
                markerfacecolor=face,
                markeredgecolor=edge,
                label=label,
            )
            for label, marker, face, edge in entries
        ]
        self.ax.legend(
            handles=handles,
            loc="lower right",
            fontsize=max(5.0, self.width / 85.0) * px,
            framealpha=0.8,
            borderpad=0.3,
            handletextpad=0.3,
            labelspacing=0.25,
        )

    def _draw_scale_bar(self, pixels_per_metre: float) -> None:
        length_m = SCALE_BAR_M if pixels_per_metre * SCALE_BAR_M <= self.width / 4 else 0.5
        if pixels_per_metre * length_m > self.width / 4:
            length_m = 0.1
        self.scale_bar_m = length_m
        x_left, x_right = self.ax.get_xlim()
        y_bottom, y_top = self.ax.get_ylim()
        # in the margin band below the scene, clear of the bottom wall
        x0, y0 = x_left + 0.02 * (x_right - x_left), y_bottom + 0.45 * MARGIN_M
        self.scale_bar_start = (x0, y0)
        self.ax.plot(
            [x0, x0 + length_m],
            [y0, y0],
            color=COLOURS["text"],
            linewidth=max(2.0, self.width / 200.0) * self.px,
            solid_capstyle="butt",
            zorder=11,
        )
        self.ax.annotate(
            f"{length_m:g} m",
            (x0 + length_m, y0),
            xytext=(3, 0),
            textcoords="offset points",
            ha="left",
            va="center",
            fontsize=max(5.0, self.width / 85.0) * self.px,
            color=COLOURS["text"],
            zorder=11,
        )

    def _make_animated(self, robot_radius: float) -> None:
        from matplotlib.lines import Line2D
        from matplotlib.patches import Circle

        ax, px = self.ax, self.px
        line_width = max(1.5, self.width / 250.0) * px
        self.robot_disc = Circle(
            (0.0, 0.0),
            robot_radius,
            facecolor=COLOURS["robot"],
            alpha=0.35,
            edgecolor=COLOURS["robot_edge"],
            linewidth=line_width,
            animated=True,
            zorder=6,
        )
        self.robot_heading = Line2D(
            [], [], color=COLOURS["robot_edge"], linewidth=line_width, animated=True, zorder=7
        )
        self.estimate_disc = Circle(
            (0.0, 0.0),
            robot_radius,
            facecolor="none",
            edgecolor=COLOURS["estimate"],
            linewidth=line_width,
            linestyle="--",
            animated=True,
            zorder=8,
        )
        self.estimate_heading = Line2D(
            [], [], color=COLOURS["estimate"], linewidth=line_width, animated=True, zorder=8
        )
        self.scan = Line2D(
            [],
            [],
            linestyle="none",
            marker="o",
            markersize=max(2.0, self.width / 250.0) * px,
            markerfacecolor=COLOURS["scan"],
            markeredgecolor="none",
            animated=True,
            zorder=9,
        )
        font = max(7.0, self.width / 60.0) * px
        self.text = ax.text(
            0.01,
            0.99,
            "",
            transform=ax.transAxes,
            ha="left",
            va="top",
            fontsize=font,
            color=COLOURS["text"],
            animated=True,
            zorder=10,
            bbox={"facecolor": "white", "alpha": 0.75, "edgecolor": "none", "pad": 2.0},
        )
        ax.add_patch(self.robot_disc)
        ax.add_patch(self.estimate_disc)
        for artist in (self.robot_heading, self.estimate_heading, self.scan):
            ax.add_line(artist)

    def frame(
        self,
        true_pose: Pose | None,
        estimated_pose: Pose | None,
        scan_points: np.ndarray | None,
        text: str,
    ) -> np.ndarray:
        self.canvas.restore_region(self.background)
        drawn: list[Artist] = []
        if scan_points is not None and len(scan_points):
            self.scan.set_data(scan_points[:, 0], scan_points[:, 1])
            drawn.append(self.scan)
        for pose, disc, heading in (
            (true_pose, self.robot_disc, self.robot_heading),
            (estimated_pose, self.estimate_disc, self.estimate_heading),
        ):
            if pose is None:
                continue
            disc.center = (pose.x, pose.y)
            reach = 1.3 * disc.radius
            heading.set_data(
                [pose.x, pose.x + reach * math.cos(pose.theta)],
                [pose.y, pose.y + reach * math.sin(pose.theta)],
            )
            drawn += [disc, heading]
        if text:
            self.text.set_text(text)
            drawn.append(self.text)
        renderer = self.canvas.get_renderer()
        for artist in sorted(drawn, key=lambda a: a.get_zorder()):
            artist.draw(renderer)
        rgba = np.asarray(self.canvas.buffer_rgba())
        image = np.ascontiguousarray(rgba[: self.height, : self.width, :3])
        if image.shape != (self.height, self.width, 3):  # guard against backend rounding
            padded = np.full((self.height, self.width, 3), 255, dtype=np.uint8)
            padded[: image.shape[0], : image.shape[1]] = image
            image = padded
        return image

    def close(self) -> None:
        self.figure.clear()


_CANVASES: OrderedDict[tuple[Scenario, int, int], _TopDownCanvas] = OrderedDict()


def _canvas_for(scenario: Scenario, height: int, width: int) -> _TopDownCanvas:
    key = (scenario, height, width)
    canvas = _CANVASES.get(key)
    if canvas is None:
        canvas = _TopDownCanvas(scenario, height, width)
        _CANVASES[key] = canvas
        while len(_CANVASES) > _CACHE_SIZE:
            _, old = _CANVASES.popitem(last=False)
            old.close()
    else:
        _CANVASES.move_to_end(key)
    return canvas


def render_topdown(
    scenario: Scenario,
    true_pose: Pose | None = None,
    estimated_pose: Pose | None = None,
    scan_points: npt.ArrayLike | None = None,
    *,
    width_px: int = 600,
    height_px: int | None = None,
    title: str | None = None,
    extra: Mapping[str, Any] | Sequence[str] | str | None = None,
) -> np.ndarray:
    """Draw the scenario from above; return an RGB image ``(H, W, 3)`` of ``uint8``.

    Args:
        scenario: what to draw.
        true_pose: the robot's true pose ({W}); a green disc of the robot radius with a
            heading line.
        estimated_pose: an estimate ({W}); a dashed magenta circle with a heading line.
        scan_points: ``(N, 2)`` points in {W}, metres (e.g. sonar ranges placed along their
            beams); non-finite rows are skipped.
        width_px, height_px: image size; see the module docstring for the height formula.
        title: a line of text at the top left.
        extra: more text below the title: a mapping (drawn as ``key: value`` lines, floats
            with 3 decimals), a sequence of lines, or one string.
    """
    if not isinstance(scenario, Scenario):
        raise ValueError(f"argument 'scenario' must be a Scenario; got {type(scenario).__name__}")
    for name, pose in (("true_pose", true_pose), ("estimated_pose", estimated_pose)):
        if pose is not None and not isinstance(pose, Pose):
            raise ValueError(f"argument '{name}' must be a Pose or None; got {type(pose).__name__}")
    height, width = image_size(scenario, width_px, height_px)
    points = None
    if scan_points is not None:
        points = np.asarray(scan_points, dtype=np.float64)
        if points.size == 0:
            points = None
        elif points.ndim != 2 or points.shape[1] != 2:
            raise ValueError(
                "argument 'scan_points' must be an (N, 2) array of [x, y] in metres; "
                f"got shape {points.shape}"
            )
        else:
            points = points[np.all(np.isfinite(points), axis=1)]
    canvas = _canvas_for(scenario, height, width)
    return canvas.frame(true_pose, estimated_pose, points, _text_block(title, extra))


def _text_block(title: str | None, extra: Mapping[str, Any] | Sequence[str] | str | None) -> str:
    lines: list[str] = []
    if title:
        lines.append(str(title))
    if isinstance(extra, str):
        lines.append(extra)
    elif isinstance(extra, Mapping):
        for key, value in extra.items():
            shown = f"{value:.3f}" if isinstance(value, float) else str(value)
            lines.append(f"{key}: {shown}")
    elif isinstance(extra, Iterable):
        lines.extend(str(line) for line in extra)
    elif extra is not None:
        raise ValueError(
            "argument 'extra' must be a mapping, a sequence of strings or a string; "
            f"got {type(extra).__name__}"
        )
    return "\n".join(lines)


def save_png(image: npt.ArrayLike, path: str | Path) -> Path:
    """Write an ``(H, W, 3)`` ``uint8`` RGB image as a PNG file; return the path."""
    from PIL import Image

    array = np.asarray(image)
    if array.ndim != 3 or array.shape[2] != 3 or array.dtype != np.uint8:
        raise ValueError(
            "argument 'image' must be an (H, W, 3) uint8 array; "
            f"got shape {array.shape}, dtype {array.dtype}"
        )
    path = Path(path)
    Image.fromarray(array, mode="RGB").save(path, format="PNG")
    return path


def plot_scan_polar(
    angles: npt.ArrayLike,
    ranges: npt.ArrayLike,
    path: str | Path,
    rcds: Iterable[Any] | None = None,
    *,
    robot_radius_m: float = 0.3,
    max_range_m: float | None = None,
    title: str | None = None,
    size_px: int = 600,
) -> Path:
    """Write a PNG of one pan in the robot frame {R} (Beom & Cho Fig. 8(a)/(b) style).

    Args:
        angles: pan angles, radians in {R} (0 = robot forward, counter-clockwise positive).
        ranges: measured ranges from the pan axis, metres; NaN (a dropout) is not drawn.
        path: the PNG file to write.
        rcds: regions of constant depth to draw as arcs of radius ``delta`` from
            ``beta - eta/2`` to ``beta + eta/2``, numbered in order: each a tuple
            ``(delta_m, beta_rad, eta_rad)`` or an object with attributes ``delta_m``,
            ``beta_rad``, ``eta_rad`` (or ``delta``, ``beta``, ``eta``; metres and radians).
        robot_radius_m: radius of the octagon that stands for the robot, metres.
        max_range_m: half the plotted extent, metres (default: the largest range + 0.3 m).
        title: a title above the plot.
        size_px: width and height of the PNG in pixels.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Arc, RegularPolygon

    theta = np.asarray(angles, dtype=np.float64).reshape(-1)
    rho = np.asarray(ranges, dtype=np.float64).reshape(-1)
    if theta.shape != rho.shape:
        raise ValueError(
            "arguments 'angles' and 'ranges' must have the same length; "
            f"got {theta.size} and {rho.size}"
        )
    size = _positive_int(size_px, "size_px")
    hit = np.isfinite(rho) & np.isfinite(theta)
    xs, ys = rho[hit] * np.cos(theta[hit]), rho[hit] * np.sin(theta[hit])
    parsed = [_rcd_tuple(rcd, i) for i, rcd in enumerate(rcds or [])]
    if max_range_m is None:
        candidates = [float(np.max(rho[hit])) if hit.any() else 1.0] + [d for d, _, _ in parsed]
        max_range_m = max(candidates) + 0.3
    extent = float(max_range_m)

    dpi = 100
    figure = Figure(figsize=(size / dpi, size / dpi), dpi=dpi)
    FigureCanvasAgg(figure)
    ax = figure.add_subplot(1, 1, 1)
    ax.set_aspect("equal")
    ax.set_xlim(-extent, extent)
    ax.set_ylim(-extent, extent)
    ax.grid(True, color="#e0e0e0", linewidth=0.6)
    ax.set_xlabel("x_R [m]")
    ax.set_ylabel("y_R [m]")
    ax.add_patch(
        RegularPolygon(
            (0.0, 0.0),
            8,
            radius=robot_radius_m,
            orientation=math.pi / 8,
            facecolor="none",
            edgecolor=COLOURS["robot_edge"],
            linewidth=1.2,
        )
    )
    ax.plot([0.0, 1.3 * robot_radius_m], [0.0, 0.0], color=COLOURS["robot_edge"], linewidth=1.2)
    ax.plot(xs, ys, linestyle="none", marker="o", markersize=2.0, color=COLOURS["wall"])
    for number, (delta, beta, eta) in enumerate(parsed, start=1):
        start, end = math.degrees(beta - eta / 2.0), math.degrees(beta + eta / 2.0)
        ax.add_patch(
            Arc(
                (0.0, 0.0),
                2 * delta,
                2 * delta,
                theta1=start,
                theta2=end,
                color=COLOURS["small_beacon"],
                linewidth=2.0,
            )
        )
        label_r = delta + 0.08 * extent
        ax.annotate(
            str(number),
            (label_r * math.cos(beta), label_r * math.sin(beta)),
            ha="center",
            va="center",
            color=COLOURS["small_beacon"],
            fontsize=9,
        )
    if title:
        ax.set_title(title)
    path = Path(path)
    figure.savefig(path, format="png")
    figure.clear()
    return path


def _rcd_tuple(rcd: Any, index: int) -> tuple[float, float, float]:
    for names in (("delta_m", "beta_rad", "eta_rad"), ("delta", "beta", "eta")):
        if all(hasattr(rcd, n) for n in names):
            values = tuple(float(getattr(rcd, n)) for n in names)
            break
    else:
        try:
            delta, beta, eta = rcd
            values = (float(delta), float(beta), float(eta))
        except (TypeError, ValueError):
            raise ValueError(
                f"argument 'rcds'[{index}] must be (delta_m, beta_rad, eta_rad) or have those "
                f"attributes; got {rcd!r}"
            ) from None
    if not all(math.isfinite(v) for v in values) or values[0] < 0 or values[2] < 0:
        raise ValueError(
            f"argument 'rcds'[{index}] must have finite delta >= 0 and eta >= 0; got {values}"
        )
    return values  # type: ignore[return-value]


def _positive_int(value: Any, name: str) -> int:
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, np.integer))
        or not 16 <= value <= 8192
    ):
        raise ValueError(
            f"argument '{name}' must be an integer number of pixels in [16, 8192]; got {value!r}"
        )
    return int(value)
