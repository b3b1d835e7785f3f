# fenics-garment: the two commands of the README are `make demo` and `make test`.
# Both create .venv on first use (with a Python >= 3.12 found by .ci/find-python) and install the
# package editable; re-running them does not reinstall what is already there.

VENV      := .venv
PY        := $(VENV)/bin/python
MPIEXEC   := $(VENV)/bin/mpiexec
STAMP     := $(VENV)/.installed-stamp
DOCS_STAMP := $(VENV)/.docs-stamp
NP        ?= 2
PYTEST    := $(PY) -m pytest

.PHONY: demo test test-serial test-mpi test-slow chromium lint bench docs docker-check clean-venv help

help:
	@echo "make demo          run the main demo (creates .venv on first use)"
	@echo "make test          run the test suite: serial, then the mpi-marked subset on $(NP) ranks"
	@echo "                   (without the slow-marked verification runs: see test-slow)"
	@echo "make test-slow     the slow-marked runs (scenes, stress, long benchmarks); CI runs both"
	@echo "make lint          ruff check + format check"
	@echo "make bench         run the benchmark suite (writes benchmarks/results/)"
	@echo "make docs          build the documentation site offline into docs/_build/html"
	@echo "make docker-check  build the Docker image locally and run the tests inside it"

$(PY):
	@set -e; py=$$(./.ci/find-python); \
	echo "Creating $(VENV) with $$py"; \
	"$$py" -m venv $(VENV)

# Re-install only when the package metadata changes.
$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet -e ".[dev,plot]"
	@touch $(STAMP)

# The documentation tools (the `docs` extra), installed on first use of `make docs` or
# `make test-slow` (whose tests/test_docs.py builds the site).
$(DOCS_STAMP): pyproject.toml | $(STAMP)
	$(PY) -m pip install --quiet -e ".[dev,plot,docs]"
	@touch $(DOCS_STAMP)

demo: $(STAMP)
	$(MPIEXEC) -n $(NP) $(VENV)/bin/fenics-garment demo

test: test-serial test-mpi

test-serial: $(STAMP)
	$(PYTEST) -m "not mpi and not slow" tests

test-mpi: $(STAMP)
	$(MPIEXEC) -n $(NP) $(PY) -m pytest -m "mpi and not slow" -p no:cacheprovider tests

# The verification runs that take 20 s to 2 min each (full scenes, load-step and mesh stress
# tests, the long shell benchmarks): kept out of the default run's 15 minutes, run by CI after it.
test-slow: $(STAMP) $(DOCS_STAMP) chromium
	$(PYTEST) -m "slow and not mpi" tests

# Chromium and its driver for the report's browser test (tests/test_report_browser.py), from
# Debian's packages when run as root; otherwise that test skips and says why.
chromium:
	@if command -v chromium >/dev/null && command -v chromedriver >/dev/null; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
		echo "installing chromium and chromium-driver (apt-get)"; \
		apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
			chromium chromium-driver >/dev/null; \
	else echo "chromium/chromedriver missing (not root): the browser test will skip"; fi

lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

bench: $(STAMP)
	$(PY) -m benchmarks

# Offline (no intersphinx, no downloads), nitpicky, warnings as errors; pages and tables that
# come from the code and benchmarks/results/ are generated on the way (docs/_ext/garment_docs.py).
docs: $(DOCS_STAMP)
	$(PY) -m sphinx -b html -n -W --keep-going -q docs docs/_build/html
	@echo "docs: open docs/_build/html/index.html"

docker-check:
	bash .ci/docker-check

clean-venv:
	rm -rf $(VENV)
