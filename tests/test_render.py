"""Top-down rendering and scan plots."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sonar_gym.pose import Pose
from sonar_gym.render import (
    MARGIN_M,
    image_size,
    plot_scan_polar,
    render_topdown,
    save_png,
    world_to_pixel,
)
from sonar_gym.scenario import load_scenario, scenario_from_dict

LAB = load_scenario("beom_cho_lab")


def test_image_shape_and_dtype_follow_the_formula() -> None:
    image = render_topdown(LAB)
    (x0, y0), (x1, y1) = LAB.bounds
    exact_height = 600 * (y1 - y0 + 2 * MARGIN_M) / (x1 - x0 + 2 * MARGIN_M)
    expected_height = 2 * round(exact_height / 2)  # even: video encoders need even sizes
    assert abs(expected_height - exact_height) <= 1.0
    assert image.shape == (expected_height, 600, 3) == (*image_size(LAB), 3)
    assert image.dtype == np.uint8


@pytest.mark.parametrize(("width", "height"), [(29, None), (333, None), (257, 97), (640, 480)])
def test_any_requested_size_is_exact(width: int, height: int | None) -> None:
    image = render_topdown(LAB, Pose(0, 0, 0), width_px=width, height_px=height)
    assert image.shape == (*image_size(LAB, width, height), 3)
    if height is not None:
        assert image.shape[:2] == (height, width)


def test_robot_pixels_are_drawn_at_the_true_pose() -> None:
    pose = Pose(-0.5, 1.0, 0.0)
    background = render_topdown(LAB)
    with_robot = render_topdown(LAB, true_pose=pose)
    row, col = world_to_pixel(LAB, pose.position)
    assert not np.array_equal(with_robot[row, col], background[row, col])
    # Inside the disc (0.2 m behind the centre, clear of the heading line) it is greenish.
    row, col = world_to_pixel(LAB, (pose.x - 0.2, pose.y))
    r, g, b = with_robot[row, col].astype(int)
    assert g > r and g > b
    # Far from the robot nothing changed.
    row, col = world_to_pixel(LAB, (2.0, 1.0))
    assert np.array_equal(with_robot[row, col], background[row, col])


def test_heading_line_points_along_theta() -> None:
    up = render_topdown(LAB, true_pose=Pose(0.0, 0.0, math.pi / 2))
    right = render_topdown(LAB, true_pose=Pose(0.0, 0.0, 0.0))
    ahead_up = world_to_pixel(LAB, (0.0, 0.25))
    ahead_right = world_to_pixel(LAB, (0.25, 0.0))
    assert up[ahead_up].sum() < right[ahead_up].sum()  # the dark line darkens it
    assert right[ahead_right].sum() < up[ahead_right].sum()


def test_estimate_is_drawn_in_its_own_colour() -> None:
    estimate = Pose(1.5, 0.5, 0.0)
    image = render_topdown(LAB, estimated_pose=estimate)
    row, col = world_to_pixel(LAB, (estimate.x + 0.15, estimate.y))
    r, g, b = image[row, col].astype(int)
    assert r > g and b > g  # magenta


def test_scan_points_are_drawn_in_world_coordinates() -> None:
    point = np.array([[1.0, -1.0]])
    background = render_topdown(LAB)
    image = render_topdown(LAB, scan_points=point)
    row, col = world_to_pixel(LAB, point[0])
    assert not np.array_equal(image[row, col], background[row, col])
    # Non-finite rows are skipped, empty arrays are fine.
    render_topdown(LAB, scan_points=np.array([[math.nan, 0.0]]))
    render_topdown(LAB, scan_points=np.zeros((0, 2)))
    with pytest.raises(ValueError, match="scan_points"):
        render_topdown(LAB, scan_points=np.zeros((3, 3)))


def test_beacons_are_coloured() -> None:
    image = render_topdown(LAB, width_px=800)
    r, g, b = image[world_to_pixel(LAB, LAB.beacon("large_beacon").center, 800)].astype(int)
    assert b > r + 60
    r, g, b = image[world_to_pixel(LAB, LAB.beacon("small_beacon").center, 800)].astype(int)
    assert r > b + 60


def test_title_and_extra_text_change_the_image_only_there() -> None:
    plain = render_topdown(LAB)
    titled = render_topdown(LAB, title="BeaconScan", extra={"E_xy": 0.031, "status": "ok"})
    changed = np.argwhere(np.any(plain != titled, axis=2))
    assert len(changed)
    assert changed[:, 0].max() < plain.shape[0] // 3 and changed[:, 1].max() < plain.shape[1] // 2


def test_frames_do_not_leak_into_each_other() -> None:
    first = render_topdown(LAB, true_pose=Pose(1.0, 1.0, 0.0))
    render_topdown(
        LAB, true_pose=Pose(-1.0, -1.0, 1.0), scan_points=np.array([[0.0, 0.0]]), title="x"
    )
    again = render_topdown(LAB, true_pose=Pose(1.0, 1.0, 0.0))
    assert np.array_equal(first, again)


def test_scenario_without_room_and_with_emitters_renders() -> None:
    roh = load_scenario("roh_beacons")
    image = render_topdown(roh, title="Roh")
    assert image.shape == (*image_size(roh), 3)
    walls_only = scenario_from_dict({"walls": [{"a": [0, 0], "b": [2, 0]}]})
    assert render_topdown(walls_only, Pose(1.0, 1.0)).shape[1] == 600


def test_bad_arguments_are_rejected() -> None:
    with pytest.raises(ValueError, match="width_px"):
        render_topdown(LAB, width_px=0)
    with pytest.raises(ValueError, match="true_pose"):
        render_topdown(LAB, true_pose=(0, 0, 0))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="scenario"):
        render_topdown("beom_cho_lab")  # type: ignore[arg-type]


def test_save_png_round_trips(tmp_path: Path) -> None:
    from PIL import Image

    image = render_topdown(LAB, Pose(0, 0, 0), width_px=300)
    path = save_png(image, tmp_path / "frame.png")
    with Image.open(path) as loaded:
        assert np.array_equal(np.asarray(loaded.convert("RGB")), image)
    with pytest.raises(ValueError, match="image"):
        save_png(image.astype(np.float32), tmp_path / "bad.png")


def test_plot_scan_polar_writes_a_png(tmp_path: Path) -> None:
    from PIL import Image

    angles = np.radians(np.arange(-180, 180, 1.0))
    ranges = np.full(angles.shape, 2.0)
    ranges[::5] = np.nan
    table_two = [
        (2.8542, math.radians(-10.3), math.radians(22.0)),
        (1.4401, math.radians(-78.3), math.radians(24.0)),
    ]
    path = plot_scan_polar(
        angles, ranges, tmp_path / "pan.png", rcds=table_two, title="Table II", size_px=400
    )
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with Image.open(path) as loaded:
        assert loaded.size == (400, 400)
    with pytest.raises(ValueError, match="angles"):
        plot_scan_polar(angles[:3], ranges, tmp_path / "x.png")
    with pytest.raises(ValueError, match="rcds"):
        plot_scan_polar(angles, ranges, tmp_path / "x.png", rcds=[("a", 0.0)])


def test_importing_render_does_not_import_matplotlib() -> None:
    code = "import sys, sonar_gym.render; print('matplotlib' in sys.modules)"
    output = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert output.stdout.strip() == "False"


def test_every_env_renders_frames_of_even_size() -> None:
    import gymnasium as gym

    from sonar_gym.registration import ENVIRONMENTS

    for env_id in ENVIRONMENTS:
        env = gym.make(env_id, render_mode="rgb_array")
        env.reset(seed=0)
        frame = env.render()
        env.close()
        assert frame.ndim == 3 and frame.shape[0] % 2 == 0 and frame.shape[1] % 2 == 0, env_id


def test_scale_bar_is_one_metre_long_in_the_bottom_margin() -> None:
    from sonar_gym.render import SCALE_BAR_M, _view

    image = render_topdown(LAB)
    height, width = image.shape[:2]
    left, bottom, scale = _view(LAB, height, width)
    x0 = left + 0.02 * width / scale
    y = bottom + 0.45 * MARGIN_M

    def dark(x: float) -> bool:
        row, col = world_to_pixel(LAB, (x, y))
        return bool(np.all(image[row, col] < 80))

    assert SCALE_BAR_M == 1.0
    assert all(dark(x0 + f * SCALE_BAR_M) for f in (0.1, 0.5, 0.9))
    assert not dark(x0 + 1.05 * SCALE_BAR_M + 0.4)  # past the bar and its label's start


def test_legend_names_the_beacons_only_where_the_scenario_has_them() -> None:
    from sonar_gym.render import _TopDownCanvas

    def labels(scenario) -> list[str]:
        height, width = image_size(scenario)
        canvas = _TopDownCanvas(scenario, height, width)
        legend = canvas.ax.get_legend()
        return [text.get_text() for text in legend.get_texts()]

    lab = labels(LAB)
    assert lab[:2] == ["robot", "estimate"]
    assert "small beacon" in lab and "large beacon" in lab
    assert "range dots (beam axis)" in lab
    corridor = labels(load_scenario("apcs_corridor"))
    assert "small beacon" not in corridor and "range dots (beam axis)" in corridor
    assert "emitter" in labels(load_scenario("roh_beacons"))


def test_legend_is_drawn_in_the_lower_right_corner() -> None:
    image = render_topdown(LAB)
    height, width = image.shape[:2]
    corner = image[int(0.85 * height) :, int(0.8 * width) :]
    # the legend's entries carry the robot green and the range-dot orange
    greens = np.all(np.abs(corner.astype(int) - (0x2C, 0xA0, 0x2C)) < 30, axis=-1)
    oranges = np.all(np.abs(corner.astype(int) - (0xFF, 0x7F, 0x0E)) < 30, axis=-1)
    assert greens.any() and oranges.any()


@pytest.mark.slow  # needs the [video] extra, which make test-slow installs
def test_record_video_writes_a_video_for_every_env(tmp_path: Path) -> None:
    import gymnasium as gym
    from gymnasium.wrappers import RecordVideo

    from sonar_gym.registration import ENVIRONMENTS

    for index, env_id in enumerate(ENVIRONMENTS):
        folder = tmp_path / str(index)
        env = RecordVideo(
            gym.make(env_id, render_mode="rgb_array"),
            str(folder),
            episode_trigger=lambda episode: episode == 0,
            disable_logger=True,
        )
        env.reset(seed=0)
        env.action_space.seed(0)
        for _ in range(3):
            _, _, terminated, truncated, _ = env.step(env.action_space.sample())
            if terminated or truncated:
                break
        env.close()
        videos = list(folder.glob("*.mp4"))
        assert len(videos) == 1 and videos[0].stat().st_size > 1000, env_id
