"""n fixes at once (localize_repeated) against n calls of localize and average_fixes."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.localization.wu_tsai import (
    PAPER_RECEIVER_OFFSETS_M,
    average_fixes,
    localize,
    localize_repeated,
)
from sonar_gym.pose import Pose

A = 0.2
OFFSETS = np.array(PAPER_RECEIVER_OFFSETS_M)


def _distances(pose: Pose, z: float, rng: np.random.Generator, noise: float) -> np.ndarray:
    transmitters = np.array([[0.0, 0.0, 0.0], [A, 0.0, 0.0], [0.0, A, 0.0]])
    receivers = np.array([pose.transform_point(o) for o in OFFSETS])
    points = np.column_stack([receivers, np.full(len(receivers), z)])
    exact = np.linalg.norm(points[:, None, :] - transmitters[None, :, :], axis=2)
    return np.abs(exact + rng.normal(0.0, noise, exact.shape))


@pytest.mark.parametrize("noise", [0.0, 0.002, 0.05])
def test_repeated_fixes_match_one_by_one_localization(noise: float) -> None:
    rng = np.random.default_rng(3)
    tables = np.stack([_distances(Pose(0.4, -0.3, 0.7), -1.9, rng, noise) for _ in range(25)])
    tables[4, 1, 2] = np.nan  # a dropout
    tables[9, 0] = [0.1, 5.0, 5.0]  # no point (eq. (9) radicand < 0)
    batch = localize_repeated(tables, A, OFFSETS)
    singles = [localize(table, A, OFFSETS) for table in tables]
    assert batch.statuses.tolist() == [r.status for r in singles]
    assert batch.statuses[4] == "missing_distance"
    assert batch.statuses[9] == "inconsistent_distances"
    fixes = [r.fix for r in singles if r.fix is not None]
    for row, single in zip(np.flatnonzero(batch.ok), fixes, strict=True):
        assert batch.poses[row] == pytest.approx([single.x, single.y, single.heading], abs=1e-12)
        assert batch.z[row] == pytest.approx(single.z, abs=1e-12)
    averaged, expected = batch.average(), average_fixes(fixes)
    assert averaged is not None
    assert averaged.position == pytest.approx(expected.position, abs=1e-12)
    assert averaged.heading == pytest.approx(expected.heading, abs=1e-12)
    assert np.allclose(averaged.receiver_array, expected.receiver_array, atol=1e-12)


def test_no_fix_succeeding_averages_to_none() -> None:
    batch = localize_repeated(np.full((3, 2, 3), np.nan), A, OFFSETS)
    assert not batch.ok.any() and batch.average() is None
    assert np.isnan(batch.poses).all()


def _same_bits(left: object, right: object) -> bool:
    return bool(np.asarray(left).tobytes() == np.asarray(right).tobytes())


def _array_form(
    table: np.ndarray, a: float, offsets
) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
    """localize_repeated as whole-array numpy steps (distances whose squares stay finite)."""
    n, n_receivers = table.shape[:2]
    offsets = np.asarray(offsets, dtype=np.float64)
    mean_offset = offsets.mean(axis=0)
    spread = offsets - mean_offset
    observable = bool(np.any(np.hypot(spread[:, 0], spread[:, 1]) >= 1e-9))
    status = np.full(n, "ok", dtype=object)
    finite = np.all(np.isfinite(table), axis=(1, 2))
    status[~finite] = "missing_distance"
    clean = np.where(finite[:, None, None], table, 0.0)
    squares = clean * clean
    d0_sq, d1_sq, d2_sq = squares[..., 0], squares[..., 1], squares[..., 2]
    x = (d0_sq - d1_sq + a * a) / (2.0 * a)
    y = (d0_sq - d2_sq + a * a) / (2.0 * a)
    radicand = d0_sq - x * x - y * y
    assert np.isfinite(x + y + radicand).all()
    z = -1 * np.sqrt(np.maximum(radicand, 0.0))
    inconsistent = (radicand < -1e-9 * (d0_sq + a * a)).any(axis=1)
    status[finite & inconsistent] = "inconsistent_distances"
    if not observable:
        status[status == "ok"] = "heading_unobservable"
    receivers = np.stack([x, y, z], axis=-1)
    mean = np.add.reduce(receivers, axis=1) / n_receivers
    measured = receivers[:, :, :2] - mean[:, None, :2]
    cross = np.add.reduce(
        spread[None, :, 0] * measured[:, :, 1] - spread[None, :, 1] * measured[:, :, 0], axis=1
    )
    dot = np.add.reduce(spread[None] * measured, axis=(1, 2))
    heading = np.arctan2(cross, dot)
    c, s = np.cos(heading), np.sin(heading)
    poses = np.empty((n, 3))
    poses[:, 0] = mean[:, 0] - (c * mean_offset[0] - s * mean_offset[1])
    poses[:, 1] = mean[:, 1] - (s * mean_offset[0] + c * mean_offset[1])
    if np.all(mean_offset == 0.0):
        poses[:, :2] = mean[:, :2]
    poses[:, 2] = heading
    status[(status == "ok") & ~(np.hypot(cross, dot) >= 1e-18)] = "inconsistent_distances"
    good = (status == "ok") & np.isfinite(poses).all(axis=1) & np.isfinite(mean[:, 2])
    status[(status == "ok") & ~good] = "inconsistent_distances"
    z_fix = np.where(good, mean[:, 2], np.nan)
    poses[~good] = np.nan
    receivers[~good] = np.nan
    return status.tolist(), poses, z_fix, receivers


@pytest.mark.parametrize(
    "offsets",
    [
        PAPER_RECEIVER_OFFSETS_M,  # centred: the pose is the receivers' mean
        ((0.1, 0.2), (0.1, -0.2)),  # off the {AMR} origin: the mean offset is rotated away
        ((0.0, 0.2), (0.15, -0.1), (-0.15, -0.1)),  # three receivers
        ((0.05, 0.1),),  # one receiver: no heading
        ((0.0, 0.1), (0.1, 0.0), (0.0, -0.1), (-0.1, 0.0)),  # four: beyond the compiled loop
    ],
)
def test_repeated_fixes_give_the_bits_of_the_array_form(offsets) -> None:
    from sonar_gym.localization.wu_tsai import _localize_repeated_arrays, _receiver_layout

    rng = np.random.default_rng(8)
    n_receivers = len(offsets)
    transmitters = np.array([[0.0, 0.0, 0.0], [A, 0.0, 0.0], [0.0, A, 0.0]])
    tables = np.empty((400, n_receivers, 3))
    for table in tables:
        pose = Pose(*rng.uniform(-1.5, 1.5, 2), rng.uniform(-np.pi, np.pi))
        receivers = np.array([[*pose.transform_point(o), -1.9] for o in offsets])
        exact = np.linalg.norm(receivers[:, None, :] - transmitters[None, :, :], axis=2)
        table[:] = np.abs(exact + rng.normal(0.0, 0.01, exact.shape))
    tables[::7, 0, 1] = np.nan  # dropouts
    tables[3::11, -1, 2] = np.inf
    tables[5::13, 0] = [0.1, 5.0, 5.0]  # no point (eq. (9) radicand < 0)
    tables[6::17] = [[0.0, A, A]] * n_receivers  # every receiver below the first transmitter
    tables[8::19] = A  # equidistant: the receivers coincide in (x, y)
    statuses, poses, z, receivers = _array_form(tables, A, offsets)
    assert len(set(statuses)) >= (2 if n_receivers == 1 else 3)
    layout = _receiver_layout(tuple(map(tuple, offsets)), n_receivers)
    for fixes in (
        localize_repeated(tables, A, offsets),
        _localize_repeated_arrays(tables, A, -1, layout),
    ):
        assert fixes.statuses.tolist() == statuses
        assert _same_bits(fixes.poses, poses)
        assert _same_bits(fixes.z, z)
        assert _same_bits(fixes.receivers, receivers)
