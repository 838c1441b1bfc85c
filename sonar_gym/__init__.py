"""sonar_gym: a Gymnasium suite for active localization research with ultrasonic sensing.

``import sonar_gym`` registers the ``SonarGym/...`` environment ids (their entry points are
strings, so the environment modules load only when an environment is made).
"""

from importlib import metadata as _metadata

from sonar_gym.pose import Pose
from sonar_gym.registration import register_environments
from sonar_gym.scenario import Scenario, ScenarioError, builtin_names, load_scenario

try:
    __version__ = _metadata.version("sonar-gym")
except _metadata.PackageNotFoundError:  # a source tree on PYTHONPATH, not installed
    __version__ = "0.0.0+unknown"

register_environments()

__all__ = ["Pose", "Scenario", "ScenarioError", "__version__", "builtin_names", "load_scenario"]
