"""The numerics family names the pair of numpy's loop level and OpenBLAS's kernel level."""

from __future__ import annotations

import pytest

from tests.envs.numerics import BLAS_KERNEL_LEVELS, NUMERICS_FAMILY, numerics_family


@pytest.mark.parametrize(
    ("level", "blas", "family"),
    [
        ("x86-64-v4", "v4", "x86-64-v4"),
        ("x86-64-v3", "v3", "x86-64-v3"),
        ("x86-64-v4", "v3", "x86-64-v4-blas-v3"),
        ("x86-64-v3", "v4", "x86-64-v3-blas-v4"),
        ("aarch64-other", "neoversen1", "aarch64-other-blas-neoversen1"),
    ],
)
def test_a_family_is_the_level_unless_the_kernels_differ(
    level: str, blas: str, family: str
) -> None:
    assert numerics_family(level, blas) == family


def test_openblas_kernel_families_map_to_their_instruction_level() -> None:
    assert BLAS_KERNEL_LEVELS["skylakex"] == "v4"
    assert BLAS_KERNEL_LEVELS["haswell"] == "v3"
    assert set(BLAS_KERNEL_LEVELS.values()) == {"v3", "v4"}


def test_this_machine_has_a_family_name_usable_in_a_file_name() -> None:
    assert NUMERICS_FAMILY and "/" not in NUMERICS_FAMILY and " " not in NUMERICS_FAMILY
