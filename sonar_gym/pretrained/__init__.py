"""Where the shipped policies live, and the seeds every baseline number is measured on.

A shipped policy for ``SonarGym/<Name>`` is the directory ``<root>/<Name>/`` holding what
``sonar-gym train`` writes (``model.zip``, ``vecnormalize.pkl``, ``run.json``) plus
``learning_curve.csv`` (mean validation reward at checkpoints of every training seed) and
``training.json`` (how it was trained and selected). ``<root>`` is this package's directory,
or the directory named by the environment variable :data:`ROOT_VARIABLE` when it is set (to try
policies that are not installed, e.g. in tests).

Seeds (one home for them; training, selection and the baselines table import them):

- training: stable-baselines3 seeds :data:`TRAINING_SEEDS`;
- validation (checkpoint selection, learning curves): episode seeds from
  :data:`VALIDATION_SEED_START`;
- evaluation (the baselines table): episode seeds from :data:`EVALUATION_SEED_START`,
  :data:`DEFAULT_EVALUATION_EPISODES` of them by default, :data:`WIDE_EVALUATION_EPISODES`
  for the claims that 200 cannot decide (BeaconScan against the paper, Trilateration against
  its heuristic).

Plain paths only: nothing here imports torch, stable-baselines3 or an environment.
"""

from __future__ import annotations

import os
from pathlib import Path

ROOT_VARIABLE = "SONAR_GYM_PRETRAINED_DIR"
"""Environment variable: a directory to look for shipped policies in instead of this package."""

TRAINING_SEEDS: tuple[int, ...] = (0, 1, 2)
VALIDATION_SEED_START = 2_000_000
EVALUATION_SEED_START = 1_000_000
DEFAULT_VALIDATION_EPISODES = 100
DEFAULT_EVALUATION_EPISODES = 200
WIDE_EVALUATION_EPISODES = 5_000
"""Evaluation seeds for the claims 200 seeds cannot decide. BeaconScan against the paper's
procedure: both fail on mostly the same start poses, but each pose where only one of them fails
moves the paired difference by the failure penalty (20), so over 200 seeds its interval (about
+-0.5) is wider than anything a cheaper pan can gain (about the 0.68 the paper spends on
sensing). Trilateration against the adaptive planner: a gain of about 0.15 against an interval
of about +-0.4 over 200 seeds."""

MODEL_FILE = "model.zip"
VECNORMALIZE_FILE = "vecnormalize.pkl"
RUN_FILE = "run.json"
LEARNING_CURVE_FILE = "learning_curve.csv"
TRAINING_FILE = "training.json"
LEARNING_CURVE_COLUMNS = ("training_seed", "timesteps", "wall_time_s", "mean_reward", "ci95")


def pretrained_root() -> Path:
    """The directory searched for shipped policies: ``$SONAR_GYM_PRETRAINED_DIR`` if set (and
    not empty), else this package's directory."""
    override = os.environ.get(ROOT_VARIABLE, "").strip()
    return Path(override) if override else Path(__file__).resolve().parent


def policy_name(env_id: str) -> str:
    """The directory name of ``env_id``'s policy: the id after its namespace
    (``"SonarGym/BeaconScan-v0"`` -> ``"BeaconScan-v0"``)."""
    return env_id.rpartition("/")[2]


def policy_dir(env_id: str, root: Path | None = None) -> Path:
    """Where ``env_id``'s shipped policy is, or would be (``<root>/<policy_name>``)."""
    return (root or pretrained_root()) / policy_name(env_id)


def has_policy(env_id: str, root: Path | None = None) -> bool:
    """True when a policy for ``env_id`` ships (its ``model.zip`` exists)."""
    return bool(env_id) and (policy_dir(env_id, root) / MODEL_FILE).is_file()


def shipped_env_ids(namespace: str = "SonarGym", root: Path | None = None) -> list[str]:
    """The ``<namespace>/<Name>`` ids that have a shipped policy, sorted by name."""
    base = root or pretrained_root()
    if not base.is_dir():
        return []
    return [
        f"{namespace}/{entry.name}"
        for entry in sorted(base.iterdir())
        if entry.is_dir() and (entry / MODEL_FILE).is_file()
    ]


def find_policy(env_id: str, root: Path | None = None) -> Path:
    """The directory of ``env_id``'s shipped policy.

    Raises:
        ValueError: no policy ships for ``env_id`` (the message names the directory searched
            and the ids that have one).
    """
    if has_policy(env_id, root):
        return policy_dir(env_id, root)
    namespace = env_id.rpartition("/")[0] or "SonarGym"
    available = shipped_env_ids(namespace, root)
    hint = f"policies ship for {available}" if available else "no policy ships at all"
    raise ValueError(
        f"no shipped policy for env {env_id or '(unregistered env)'!r}: "
        f"{policy_dir(env_id or '?', root) / MODEL_FILE} does not exist ({hint}; "
        f"set {ROOT_VARIABLE} to look elsewhere)"
    )
