"""Gymnasium environments of sonar_gym: one module per task over the shared base in ``base.py``.

The ids are registered by ``import sonar_gym`` (see :mod:`sonar_gym.registration`).
"""
