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
    expected_height = round(600 * (y1 - y0 + 2 * MARGIN_M) / (x1 - x0 + 2 * MARGIN_M))
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
