# Two commands for a fresh machine (see README.md):
#   make evaluate   installs everything into .venv on first use, then runs the main job
#   make test       installs everything into .venv on first use, then runs the test suite
# Another torch (e.g. a CUDA build): make TORCH_SPEC="torch==2.14.1" evaluate

PYTHON ?= python3
VENV ?= .venv
TORCH_SPEC ?= torch==2.13.0
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: install evaluate test test-slow lint benchmark reproduce clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet "$(TORCH_SPEC)"
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

install: $(STAMP)

evaluate: $(STAMP)
	$(BIN)/sonar-gym evaluate

test: $(STAMP)
	$(BIN)/python -m pytest -n 2 -q -m "not slow"

test-slow: $(STAMP)
	$(BIN)/python -m pytest -n 2 -q -m slow

lint: $(STAMP)
	$(BIN)/ruff check .

benchmark: $(STAMP)
	$(BIN)/sonar-gym benchmark

reproduce: $(STAMP)
	$(BIN)/sonar-gym reproduce all

clean:
	rm -rf $(VENV) runs .pytest_cache
