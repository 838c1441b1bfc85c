"""Seeded rollouts at default arguments are bit-identical to the reference tree's.

The digests in ``fixtures/rollouts.<family>.json`` (this machine's numerics family,
:mod:`tests.envs.numerics`) were written by ``make_rollout_fixture.py`` run on the reference
tree (trained policies ship against its spaces, observations and rewards); this test replays
the same episodes with the code under test and compares every step.
"""

from __future__ import annotations

import json

import pytest

import sonar_gym  # noqa: F401  (registers the ids)
from tests.envs.make_rollout_fixture import CASES, FIXTURE, SEEDS, case_key, rollout
from tests.envs.numerics import missing_fixture_message

EXPECTED = json.loads(FIXTURE.read_text()) if FIXTURE.exists() else {}


@pytest.fixture(autouse=True)
def _recorded_for_this_family() -> None:
    if not EXPECTED:
        pytest.fail(missing_fixture_message(FIXTURE))


def test_the_fixture_holds_every_case() -> None:
    keys = {case_key(*case, seed) for case in CASES for seed in SEEDS}
    assert keys == set(EXPECTED)


@pytest.mark.parametrize("case", CASES, ids=lambda case: f"{case[0]}-{case[1]}-{case[2]}")
@pytest.mark.parametrize("seed", SEEDS)
def test_seeded_rollout_matches_the_reference(case: tuple, seed: int) -> None:
    env_id, kwargs, agent_name = case
    expected = EXPECTED[case_key(env_id, kwargs, agent_name, seed)]
    actual = rollout(env_id, kwargs, agent_name, seed)
    assert actual["observation_space"] == expected["observation_space"]
    assert actual["action_space"] == expected["action_space"]
    assert actual["actions"] == expected["actions"]
    for index, (got, want) in enumerate(zip(actual["steps"], expected["steps"], strict=False)):
        assert got == want, f"step {index} differs (0 is the reset)"
    assert len(actual["steps"]) == len(expected["steps"])
    assert actual["final_status"] == expected["final_status"]


def test_every_familys_fixture_holds_the_same_cases() -> None:
    """One file per numerics family, each recorded from the reference tree over the same cases;
    the cases no family-dependent function touches (BeaconScan's) are the same bits in all."""
    files = sorted(FIXTURE.parent.glob("rollouts.*.json"))
    assert {path.name for path in files} >= {"rollouts.x86-64-v3.json", "rollouts.x86-64-v4.json"}
    recorded = [json.loads(path.read_text()) for path in files]
    keys = {case_key(*case, seed) for case in CASES for seed in SEEDS}
    assert all(set(fixture) == keys for fixture in recorded)
    beacon = [key for key in keys if key.startswith("SonarGym/BeaconScan-v0 ")]
    assert all(fixture[key] == recorded[0][key] for fixture in recorded for key in beacon)
