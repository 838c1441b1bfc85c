"""sonar_gym: a Gymnasium suite for active localization research with ultrasonic sensing.

``import sonar_gym`` registers the ``SonarGym/...`` environment ids (their entry points are
strings, so the environment modules load only when an environment is made).
"""

from sonar_gym.pose import Pose
from sonar_gym.registration import register_environments
from sonar_gym.scenario import Scenario, ScenarioError, builtin_names, load_scenario

register_environments()

__all__ = ["Pose", "Scenario", "ScenarioError", "builtin_names", "load_scenario"]
