"""Reproductions of the papers' experiments in simulation: ``sonar-gym reproduce <paper>``."""
