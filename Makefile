# Two commands for a fresh machine (see README.md):
#   make evaluate   installs everything into .venv on first use, then runs the main job
#   make test       installs everything into .venv on first use, then runs lint and the test suite
# Another torch (e.g. a CUDA build): make TORCH_SPEC="torch==2.14.1" evaluate

PYTHON ?= python3
VENV ?= .venv
TORCH_SPEC ?= torch==2.13.0
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: install install-extras evaluate test test-slow lint benchmark baselines reproduce clean clean-compiled

# The slow group also covers the optional extras (RLlib on Ray, RL Zoo, video), installed in an
# environment of their own: ray[rllib] pins an older gymnasium than the main set-up installs.
EXTRAS_VENV ?= .venv-extras
EXTRAS_BIN := $(EXTRAS_VENV)/bin
EXTRAS_STAMP := $(EXTRAS_VENV)/.installed

# pip's own progress shows on the long steps (torch, then the dependencies); the editable link
# is made last and quietly, with setuptools' "Editable installation." notice (information,
# not a problem) filtered out; every other warning still shows. --progress-bar on keeps the
# bars when make's output is piped into a log.
PIP := $(BIN)/python -m pip --disable-pip-version-check
PIP_PROGRESS ?= --progress-bar on

$(STAMP): pyproject.toml
	@echo "==> creating $(VENV)"
	$(PYTHON) -m venv $(VENV)
	$(PIP) install --quiet --upgrade pip
	@echo "==> installing $(TORCH_SPEC) (the largest download)"
	$(PIP) install $(PIP_PROGRESS) "$(TORCH_SPEC)"
	@echo "==> installing sonar-gym's dependencies"
	$(PIP) install $(PIP_PROGRESS) ".[dev]"
	@echo "==> linking sonar-gym to this checkout (editable install)"
	PYTHONWARNINGS="ignore:Editable installation" $(PIP) install --quiet --no-deps -e .
	touch $(STAMP)
	@echo "==> ready: $(BIN)/sonar-gym (or $(BIN)/python -m sonar_gym)"

install: $(STAMP)

$(EXTRAS_STAMP): pyproject.toml
	@echo "==> creating $(EXTRAS_VENV) for the slow tests and the optional extras"
	$(PYTHON) -m venv $(EXTRAS_VENV)
	$(EXTRAS_BIN)/python -m pip --disable-pip-version-check install --quiet --upgrade pip
	$(EXTRAS_BIN)/python -m pip --disable-pip-version-check install $(PIP_PROGRESS) "$(TORCH_SPEC)"
	$(EXTRAS_BIN)/python -m pip --disable-pip-version-check install $(PIP_PROGRESS) ".[dev,ray,zoo,video]"
	PYTHONWARNINGS="ignore:Editable installation" $(EXTRAS_BIN)/python -m pip \
		--disable-pip-version-check install --quiet --no-deps -e .
	touch $(EXTRAS_STAMP)

install-extras: $(EXTRAS_STAMP)

evaluate: $(STAMP)
	$(BIN)/sonar-gym evaluate

# The test command runs the lint gate first: ruff (rules in pyproject.toml) and mypy over the
# four packages (envs/, agents/ and train/ are reached through sonar_gym/).
test: lint
	$(BIN)/python -m pytest -n 2 -q -m "not slow"

test-slow: $(EXTRAS_STAMP)
	$(EXTRAS_BIN)/python -m pytest -n 2 -q -m slow

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy sonar_gym

benchmark: $(STAMP)
	$(BIN)/sonar-gym benchmark

# The shipped policies against the papers' procedures, the heuristics and random, on evaluation
# seeds no training saw; rewrites README's table. Without --pretrained it trains them again.
baselines: $(STAMP)
	$(BIN)/sonar-gym baselines --pretrained --update-readme

reproduce: $(STAMP)
	$(BIN)/sonar-gym reproduce all

clean:
	rm -rf $(VENV) $(EXTRAS_VENV) runs .pytest_cache
	$(MAKE) clean-compiled

# numba checks a cached compiled loop against its own module's source only: after editing a
# helper that other modules' loops inline (compiled.py, drive_kernels.py), drop the caches.
clean-compiled:
	find sonar_gym envs agents train -name '*.nbi' -delete -o -name '*.nbc' -delete
