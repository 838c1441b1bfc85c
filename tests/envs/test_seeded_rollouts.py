"""With default arguments every env replays the recorded seeded rollouts bit for bit.

The fixture of this machine's numerics family (:mod:`tests.envs.numerics`) was written by
``seeded_rollouts.py`` run on the tree before the argument renames, the reward terms and the
enforced info keys (see that module), never by the code under test.
"""

from __future__ import annotations

import pytest

from typing import Any

from tests.envs.numerics import missing_fixture_message
from tests.envs.seeded_rollouts import (
    AGENTS,
    ENV_IDS,
    FIXTURE,
    SEEDS,
    load_fixture,
    replay_digests,
)

RECORDED: dict[str, Any] = load_fixture() if FIXTURE.exists() else {}


@pytest.fixture(autouse=True)
def _recorded_for_this_family() -> None:
    if not RECORDED:
        pytest.fail(missing_fixture_message(FIXTURE))


def test_the_fixture_covers_every_id_agent_and_seed() -> None:
    expected = {f"{e}|{a}|{s}" for e in ENV_IDS for a in AGENTS for s in SEEDS}
    assert set(RECORDED) == expected


@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("agent_name", AGENTS)
@pytest.mark.parametrize("seed", SEEDS)
def test_default_rollouts_are_bit_identical_to_the_recorded_ones(
    env_id: str, agent_name: str, seed: int
) -> None:
    assert replay_digests(env_id, agent_name, seed, RECORDED[f"{env_id}|{agent_name}|{seed}"]) == []
