# The two entry points of the README. Each creates .venv if it is missing.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test test-fast bench clean

# The first run installs into .venv and shows pip's own output; later runs skip it.
$(STAMP): pyproject.toml
	@test -x $(BIN)/python || { echo "==> creating $(VENV) with $$($(PY) --version)"; $(PY) -m venv $(VENV); }
	@echo "==> installing desmon and its test and sweep extras into $(VENV) (first run only; pip's output follows)"
	@$(BIN)/python -m pip install --upgrade pip
	@$(BIN)/python -m pip install -e '.[test,sweep]'
	@touch $(STAMP)
	@echo "==> installed: $(BIN)/desmon"

demo: $(STAMP)
	@echo "==> running the coffee-mug case study in the SimPy world: $(BIN)/desmon run scenarios/coffee_handover.py"
	@$(BIN)/desmon run scenarios/coffee_handover.py
	@echo "==> done. To type plain 'desmon ...' in this shell: . $(BIN)/activate"

# Fast tests first (one dot each), then the tests marked slow, each by name with its time.
# The slow phase runs even when the fast one fails; the target fails if either did.
test: $(STAMP)
	@echo "==> the whole test suite, about 15 min on 2 cores (fast tests 5 min, slow tests 10 min; README.md): the fast tests first, one dot each, then the slow ones by name"
	@fast=0; slow=0; \
	echo '$(BIN)/python -m pytest -m "not slow"'; \
	$(BIN)/python -m pytest -m "not slow" || fast=$$?; \
	echo '$(BIN)/python -m pytest -m slow -v --durations=10'; \
	$(BIN)/python -m pytest -m slow -v --durations=10 || slow=$$?; \
	if [ $$fast -ne 0 ] || [ $$slow -ne 0 ]; then \
	  echo "==> make test FAILED: fast tests exit $$fast, slow tests exit $$slow (0 = passed)"; exit 1; \
	fi; \
	echo "==> make test: the fast and the slow tests passed"

# The maintainer's loop: the tests marked fast (tests/conftest.py's FAST list; pytest -m fast
# selects the same from any command line), only their files collected. About 15 CPU-seconds.
FAST_FILES = $(shell $(BIN)/python -c "import sys; sys.path.insert(0, 'tests'); from conftest import FAST; print(' '.join(sorted({'tests/' + e.split('::')[0] for e in FAST})))" 2>/dev/null)

test-fast: $(STAMP)
	@echo "==> the fast subset, under a minute: every layer touched; make test runs everything"
	$(BIN)/python -m pytest -m fast -q $(FAST_FILES)

bench: $(STAMP)
	$(BIN)/python -m bench

clean:
	rm -rf $(VENV) build *.egg-info
