PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
# Exact versions of everything `make` installs (runtime, dev and docs extras), compiled from pyproject.toml.
LOCK := requirements-lock.txt
LATEST := .venv-latest
# The observers multiply many tiny matrices: BLAS threads only fight over the cores (10-20x slower under load).
export OPENBLAS_NUM_THREADS ?= 1
export OMP_NUM_THREADS ?= 1
export MKL_NUM_THREADS ?= 1

.PHONY: demo test test-slow test-latest lint bench docs notebooks lock clean

$(BIN)/python:
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml $(LOCK)
	$(BIN)/pip install --quiet -r $(LOCK)
	$(BIN)/pip install --quiet --no-deps -e .
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/intervalobs reproduce all

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks docs/conf.py
	$(BIN)/ruff format --check src tests benchmarks docs/conf.py
	$(BIN)/mypy

test: lint
	MPLBACKEND=Agg $(BIN)/python -m pytest -q -n 2

test-slow: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m pytest -q -n 2 -m slow

# The suite against the newest releases that pyproject.toml admits (not the lock): drift shows here first.
test-latest:
	$(PY) -m venv $(LATEST)
	$(LATEST)/bin/pip install --quiet --upgrade pip
	$(LATEST)/bin/pip install --quiet --upgrade --upgrade-strategy eager -e ".[dev,docs]"
	$(LATEST)/bin/pip freeze --exclude-editable > $(LATEST)/versions.txt
	INTERVALOBS_UNLOCKED=1 MPLBACKEND=Agg $(LATEST)/bin/python -m pytest -q -n 2

# Refresh the lock to the newest releases pyproject.toml admits (then run `make test` and commit both).
lock:
	$(PY) -m venv .venv-lock
	.venv-lock/bin/pip install --quiet --upgrade pip pip-tools
	.venv-lock/bin/pip-compile --quiet --upgrade --strip-extras --no-emit-index-url --no-emit-find-links \
		--extra dev --extra docs --extra notebooks -o $(LOCK) pyproject.toml

bench: $(STAMP)
	$(BIN)/python benchmarks/run.py
	$(BIN)/python benchmarks/campaign_scaling.py
	$(BIN)/python benchmarks/tightness.py
	$(BIN)/python benchmarks/robust_tightness.py
	$(BIN)/python benchmarks/scale.py
	$(BIN)/python benchmarks/shapes.py
	$(BIN)/python benchmarks/report.py

# API reference + pages into docs/_build/html; fresh environment (-E) and warnings as errors (-W).
docs: $(STAMP)
	MPLBACKEND=Agg $(BIN)/sphinx-build -E -W --keep-going -q -b html docs docs/_build/html
	@echo "docs: docs/_build/html/index.html"

# Execute docs/notebooks in place, outputs stored (a reader on the web sees them; the docs run them afresh).
notebooks: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python docs/notebooks/execute.py

clean:
	rm -rf $(VENV) $(LATEST) .venv-lock results build *.egg-info docs/_build docs/api
	find src -name '*.nbi' -delete -o -name '*.nbc' -delete
