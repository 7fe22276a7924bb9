# `make demo` and `make test` work on a fresh machine with Python 3.11+ and make:
# each creates .venv and installs what it needs on first use.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin

.PHONY: demo test lint format bench clean

$(BIN)/python:
	@$(PYTHON) -c 'import sys; sys.exit(0 if sys.version_info >= (3, 11) else "make: Python 3.11+ is needed; run make PYTHON=/path/to/python3.11")'
	$(PYTHON) -m venv $(VENV)

# The stamps depend on pyproject.toml so that a changed dependency list reinstalls.
$(VENV)/.installed-run: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet --disable-pip-version-check -e .
	@touch $@

$(VENV)/.installed-dev: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet --disable-pip-version-check -e '.[dev]'
	@touch $@ $(VENV)/.installed-run

# The demo's runs go to a store of their own, not the lab's.
DEMO_STORE ?= $(VENV)/demo-runs
DEMO_TEST_STORE ?= $(VENV)/demo-test-runs

demo: $(VENV)/.installed-run
	$(BIN)/daq model
	$(BIN)/daq demo
	# --seed 1: the run docs/damping.md measured (a capture without --seed plays a fresh one).
	$(BIN)/daq capture --sim --seed 1 --hits 5 --yes --operator demo --note "make demo" --store $(DEMO_STORE)
	$(BIN)/daq runs list --store $(DEMO_STORE)
	$(BIN)/daq runs verify --store $(DEMO_STORE)
	$(BIN)/daq analyze latest --store $(DEMO_STORE)
	$(BIN)/daq fit latest --store $(DEMO_STORE)
	$(BIN)/daq report latest --store $(DEMO_STORE) -o $(VENV)/demo-report --force
	# The same beam on a simulated SCPI 35670A, its run through an SDF file and back.
	$(BIN)/daq capture --sim --seed 1 --analyzer 35670A --hits 3 --yes --note "make demo, 35670A" --store $(DEMO_STORE)
	$(BIN)/daq analyze latest --store $(DEMO_STORE)
	$(BIN)/daq export latest --format sdf --force -o $(VENV)/demo-35670A.sdf --store $(DEMO_STORE)
	$(BIN)/daq import $(VENV)/demo-35670A.sdf --store $(DEMO_STORE)
	# A five-point roving-hammer test of the beam: shapes, MAC, Table 2 and its report.
	rm -rf $(DEMO_TEST_STORE)
	$(BIN)/daq test new demo-beam --points p1=0.14,p2=0.28,p3=0.42,p4=0.56,p5=0.7 --store $(DEMO_TEST_STORE)
	for seed in 1 2 3 4 5; do \
	  $(BIN)/daq capture --sim --seed $$seed --test demo-beam --next --hits 3 --yes --time-scale 0 \
	    --note "make demo, test" --store $(DEMO_TEST_STORE) > /dev/null || exit 1; \
	done
	$(BIN)/daq test analyze demo-beam --store $(DEMO_TEST_STORE)
	$(BIN)/daq test report demo-beam -o $(VENV)/demo-test-report --force --store $(DEMO_TEST_STORE)

test: lint
	# One worker more than the cores: the service, browser and kill tests spend much of
	# their time waiting on real time. worksteal: an idle worker takes queued tests from
	# a busy one, so the slow tests at the end do not leave a core waiting.
	$(BIN)/python -m pytest -n $$($(BIN)/python -c 'import os; print((os.cpu_count() or 1) + 1)') --dist worksteal

lint: $(VENV)/.installed-dev
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

format: $(VENV)/.installed-dev
	$(BIN)/ruff check --fix .
	$(BIN)/ruff format .

bench: $(VENV)/.installed-dev
	$(BIN)/python bench/bench_model.py
	$(BIN)/python bench/bench_driver.py
	$(BIN)/python bench/bench_dialects.py
	$(BIN)/python bench/sim_frf_accuracy.py
	$(BIN)/python bench/bench_store.py
	$(BIN)/python bench/bench_sdf_import.py
	$(BIN)/python bench/bench_spectra.py
	$(BIN)/python bench/bench_modal.py
	$(BIN)/python bench/bench_wideband.py
	$(BIN)/python bench/bench_analysis.py
	$(BIN)/python bench/bench_damping.py
	$(BIN)/python bench/bench_ga_seeds.py
	$(BIN)/python bench/bench_modal_test.py

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache .hypothesis
