# Set-up and everyday commands. Plain pip on purpose: torch==2.13.0 must be installed before anything that
# depends on it (here it resolves to a local CPU wheel; any other resolution, or uv/poetry, pulls a multi-GB
# CUDA build).
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
PIP := $(BIN)/python -m pip --disable-pip-version-check
EXTRAS ?= render,train,graph,zoo,cluster,dev,docs,multi
comma := ,
STAMP := $(VENV)/.installed-$(subst $(comma),-,$(EXTRAS))
export OPENBLAS_NUM_THREADS := 1
export MKL_NUM_THREADS := 1
export NO_MKDOCS_2_WARNING := 1

.PHONY: install demo test test-fast test-rllib bench lint docs clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(BIN)/python
	$(PIP) install -q --progress-bar off torch==2.13.0
	$(PIP) install -q --progress-bar off -e ".[$(EXTRAS)]"
	touch $@

# The hot-path kernels are compiled ahead of time by setup.py (see ekfslam_gym/compiled.py); rebuild them in
# place whenever their sources change, or the package falls back to numba's JIT (correct, slower to start).
# The sources are compiled.SOURCES, printed by compiled.py run as a plain script (no package import).
KERNEL_SOURCES := setup.py ekfslam_gym/compiled.py $(shell $(PYTHON) ekfslam_gym/compiled.py)
AOT_STAMP := $(VENV)/.aot-kernels

$(AOT_STAMP): $(STAMP) $(KERNEL_SOURCES)
	$(BIN)/python -W ignore -c "from ekfslam_gym import compiled; raise SystemExit(compiled.backend() != 'aot')" \
		|| $(BIN)/python setup.py -q build_ext --inplace 2>&1 | grep -v -i "deprecat\|^ \|^!!\|^$$" || true
	@if [ -n "$$EKFSLAM_GYM_REQUIRE_AOT" ]; then $(BIN)/python -W ignore -c "from ekfslam_gym import compiled; \
		raise SystemExit(compiled.backend() != 'aot' and 'the ahead-of-time kernels are not built (EKFSLAM_GYM_REQUIRE_AOT=1)')"; fi
	touch $@

install: $(STAMP) $(AOT_STAMP)

demo: install
	$(BIN)/python demo.py --out out

test: install
	$(BIN)/python -m pytest -n auto  # pytest-xdist: one worker a core

test-fast: install
	$(BIN)/python -m pytest -m "not slow"

# RLlib pins its own gymnasium (Ray 2.60: 1.2.2), so it gets an environment of its own, torch first as above;
# the env's tests run there too, showing the package works on that gymnasium.
RLLIB_VENV ?= .venv-rllib
RLLIB_PIP := $(RLLIB_VENV)/bin/python -m pip --disable-pip-version-check
$(RLLIB_VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(RLLIB_VENV)
	$(RLLIB_PIP) install -q --progress-bar off torch==2.13.0
	$(RLLIB_PIP) install -q --progress-bar off -e ".[rllib]" "pytest>=8"
	touch $@

test-rllib: $(RLLIB_VENV)/.installed
	$(RLLIB_VENV)/bin/python -m pytest -p no:cacheprovider tests/training/test_rllib.py tests/envs/test_api.py tests/envs/test_step_limit.py tests/envs/test_golden_rollouts.py

bench: install  # bench/graph.py compares with GTSAM when the bench extra is installed (EXTRAS=...,bench)
	$(BIN)/python bench/startup.py
	$(BIN)/python bench/ekf.py
	$(BIN)/python bench/env.py
	$(BIN)/python bench/sim.py
	$(BIN)/python bench/train.py
	$(BIN)/python bench/graph.py
	$(BIN)/python bench/decisions.py
	$(BIN)/python bench/actions.py

# The documentation site, built offline from docs/ into site/ (strict: every warning is shown, and fails the build).
docs: install
	$(BIN)/python docs/generate.py --check
	$(BIN)/mkdocs build --strict

lint: install
	$(BIN)/ruff check . && $(BIN)/ruff format --check .

clean:
	rm -rf $(VENV) $(RLLIB_VENV) out site .pytest_cache
