"""The no-match message's list of rejections and the closest wall's reason, read from a match's
checks without building them, are those of the built checks (Yamamoto et al. sec. 4.3)."""

from __future__ import annotations

import numpy as np

from sonar_gym.localization.apcs_walls import WallMap, WallVector, match_wall


def _room() -> WallMap:
    corners = [(0.0, 0.0), (0.0, 4.0), (6.0, 4.0), (6.0, 0.0)]
    walls = [WallVector(corners[i], corners[(i + 1) % 4], name=f"wall_{i}") for i in range(4)] + [
        WallVector((2.0, 1.0), (2.0, 1.5), name="post"),
        WallVector((2.0, 1.5), (2.0, 1.0)),
    ]
    return WallMap(tuple(walls))


def test_rejection_summary_and_closest_reason_are_those_of_the_checks() -> None:
    rng = np.random.default_rng(8)
    reasons = set()
    for wall_map in (_room(), WallMap(())):
        for _ in range(3000):
            start = rng.uniform(-1.0, 7.0, 2)
            if rng.random() < 0.5:  # along a map wall, nearly: every condition in play
                wall = wall_map[int(rng.integers(len(wall_map)))] if len(wall_map) else None
                if wall is not None:
                    start = np.array(wall.start) + rng.normal(0.0, 0.05, 2)
                    direction = np.array(wall.end) - np.array(wall.start)
                    end = start + direction * rng.uniform(0.2, 1.2) + rng.normal(0.0, 0.01, 2)
                else:
                    end = start + rng.normal(0.0, 1.0, 2)
            else:
                end = start + rng.normal(0.0, 1.0, 2)
            detected = WallVector(tuple(start), tuple(end), name="detected")
            checks = match_wall(detected, wall_map).checks
            expected = ", ".join(
                f"{index}: {reason}" for index, reason in checks.rejections.items()
            )
            assert checks.rejection_summary() == expected
            closest = checks.closest
            assert checks.closest_reason == (None if closest is None else closest.reason)
            reasons.add(checks.closest_reason)
    assert {None, "orientation", "inclusion", "distance"} <= reasons
