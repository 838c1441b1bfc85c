"""``python -m sonar_gym ...`` runs the ``sonar-gym`` command line (for when the console
script is not on PATH, e.g. inside a virtual environment that is not activated)."""

import sys

from sonar_gym.train.cli import main

sys.exit(main())
