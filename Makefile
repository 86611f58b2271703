# The two entry points of the README. Each creates .venv if it is missing.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test test-fast test-estimate-coverage bench clean

# The first run installs into .venv and shows pip's own output; later runs skip it. pip
# byte-compiles what it installs on one core; here compileall does it on every core instead
# (the same bytecode; in a fresh clone on 2 cores, pip's warm download cache, one run each:
# pip install -e '.[test,sweep]' 24.8 s, with --no-compile 8.4 s, then compileall 8.7 s),
# desmon's own modules included, the installed packages' own test folders and the
# installers (pip, setuptools) left out: nothing imports them (5.0 s instead of 8.3 s, one
# run each). As with pip, a file that does not compile, or is imported after all, is
# compiled at import, and the install goes on.
$(STAMP): pyproject.toml
	@test -x $(BIN)/python || { echo "==> creating $(VENV) with $$($(PY) --version)"; $(PY) -m venv $(VENV); }
	@echo "==> installing desmon and its test and sweep extras into $(VENV) (first run only; pip's output follows)"
	@$(BIN)/python -m pip install --upgrade pip
	@$(BIN)/python -m pip install --no-compile -e '.[test,sweep]'
	@echo "==> byte-compiling the installed packages and desmon on every core"
	@$(BIN)/python -m compileall -q -j 0 -x '/tests?/|/site-packages/(pip|setuptools|pkg_resources|_distutils_hack)/' $(VENV)/lib desmon || true
	@touch $(STAMP)
	@echo "==> installed: $(BIN)/desmon"

demo: $(STAMP)
	@echo "==> running the coffee-mug case study in the SimPy world: $(BIN)/desmon run scenarios/coffee_handover.py"
	@$(BIN)/desmon run scenarios/coffee_handover.py
	@echo "==> done. To type plain 'desmon ...' in this shell: . $(BIN)/activate"

# The whole suite in one pytest run on $(JOBS) processes (pytest-xdist; JOBS: one more than the
# cores this process may use, at most 4 of them: a test waiting for a command, a timeout or a
# Dask worker leaves its core to the extra process (on 2 cores, one fresh-clone run each: the
# tests' CPU seconds summed by DESMON_TEST_CPU over make test's wall time were 1.64 cores with
# 2 processes, 1.91 with 3); make test JOBS=1 for one). The longest tests start first
# (tests/conftest.py's LONGEST, then the other tests marked slow), --dist loadgroup hands
# each process its next test as it finishes one (an xdist_group stays in one process), and
# --no-loadscope-reorder keeps that order. One dot per test, a line with its name and time
# for each slow test as it ends, the ten slowest at the end; the target fails if a test did.
JOBS ?= $(shell $(PY) -c "import os; n = len(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity') else os.cpu_count(); print(max(1, min(4, n or 1)) + 1)" 2>/dev/null || echo 3)

# The suite starts a few hundred Python processes (the docs' commands, the benches, Dask's
# workers): they load desmon's compiled bytecode (__pycache__, which git ignores) instead of
# compiling it again each time, also where the environment sets PYTHONDONTWRITEBYTECODE.
test test-fast: export PYTHONDONTWRITEBYTECODE :=

test: $(STAMP)
	@echo "==> the whole test suite on $(JOBS) processes, 7 to 13 min on 2 cores by the machine, more at a busy hour (README.md): one dot per test, a line for each slow test as it ends, the ten slowest at the end"
	$(BIN)/python -m pytest -n $(JOBS) --dist loadgroup --no-loadscope-reorder --durations=10

# The maintainer's loop: the tests marked fast (tests/conftest.py's FAST list; pytest -m fast
# selects the same from any command line), only their files collected. About 13 CPU-seconds
# (time make test-fast, 2026-12-05: 13 s wall at load 2 to 3).
FAST_FILES = $(shell $(BIN)/python -c "import sys; sys.path.insert(0, 'tests'); from conftest import FAST; print(' '.join(sorted({'tests/' + e.split('::')[0] for e in FAST})))" 2>/dev/null)

test-fast: $(STAMP)
	@echo "==> the fast subset, under a minute: every layer touched; make test runs everything"
	$(BIN)/python -m pytest -m fast -q $(FAST_FILES)

# The coverage self-test's full count (tests/test_estimate_coverage.py, docs/estimate.md):
# 200 estimations on each analysable scenario, where make test runs the first 40.
test-estimate-coverage: $(STAMP)
	DESMON_COVERAGE_ESTIMATIONS=200 $(BIN)/python -m pytest -q tests/test_estimate_coverage.py

bench: $(STAMP)
	$(BIN)/python -m bench

clean:
	rm -rf $(VENV) build *.egg-info
