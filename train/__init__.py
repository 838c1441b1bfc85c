"""Command line and tooling around the environments: evaluate, train, benchmark, reproduce.

The console script ``sonar-gym`` (:mod:`sonar_gym.train.cli`) is a thin layer over
:mod:`sonar_gym.train.evaluation` (agents on envs over seeds, with statistics; spread over a
Ray cluster by :mod:`sonar_gym.train.distributed`), :mod:`sonar_gym.train.training`
(stable-baselines3 training with tuned configs; RLlib in :mod:`sonar_gym.train.rllib_backend`),
:mod:`sonar_gym.train.benchmark` (speed) and :mod:`sonar_gym.train.report` (tables, JSON/CSV
and plots).
"""

from __future__ import annotations


class UsageError(ValueError):
    """A request the user can fix: an unknown env id or agent, a bad ``--env-arg``, an algorithm
    the action space does not allow. The command line prints the message (which lists what is
    allowed) and exits with status 2, without a traceback."""
