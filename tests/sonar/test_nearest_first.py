"""The compiled ordering of echo candidates gives the bits and order of its array form."""

from __future__ import annotations

import numpy as np
import pytest

from sonar_gym.sonar import kernels
from tests.sonar.nearest_first_reference import nearest_first_reference


def _inputs(
    rng: np.random.Generator, n_candidates: int, n_kept: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    ranges = rng.uniform(0.01, 5.0, n_candidates)
    if n_candidates and rng.random() < 0.5:  # ties, as a corner's two walls give
        ranges[rng.integers(0, n_candidates, n_candidates // 2)] = ranges[0]
    if n_candidates and rng.random() < 0.1:
        ranges[rng.integers(0, n_candidates)] = np.nan
    keep = np.sort(rng.choice(n_candidates, n_kept, replace=False)).astype(np.int64)
    clear = rng.random(n_kept) < 0.7
    kept = rng.normal(0.0, 2.0, (n_kept, 3))
    amplitudes = rng.uniform(0.0, 10.0, n_candidates)
    return keep, clear, kept, ranges, amplitudes


@pytest.mark.parametrize("seed", range(4))
def test_nearest_first_matches_the_array_form_bit_for_bit(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(500):
        n_candidates = int(rng.integers(0, 40))
        n_kept = int(rng.integers(0, n_candidates + 1))
        inputs = _inputs(rng, n_candidates, n_kept)
        got = kernels.nearest_first(*inputs)
        want = nearest_first_reference(*inputs)
        for got_part, want_part in zip(got, want, strict=True):
            assert got_part.dtype == want_part.dtype
            assert got_part.shape == want_part.shape
            assert got_part.tobytes() == want_part.tobytes()
