"""Gymnasium environments of sonar_gym: one module per task over the shared base in ``base.py``,
with spaces built from the action types of ``action_types.py`` and the observation features of
``features.py``.

The ids are registered by ``import sonar_gym`` (see :mod:`sonar_gym.registration`).
"""
