"""Shared fixtures. Reference numbers live in tests/reference.py, computed before any
code existed (docs/method.md) or copied from the seed paper, never produced by our code."""

import gc
import os

# Before numpy loads (test modules import it before daq.cli.app, which sets the same):
# one BLAS thread, as `daq` runs. The analysis solves many small matrices, where BLAS
# threads cost more than they give; with a worker per core (pytest -n) they fight over
# the cores and the suite runs several times slower. A setting in the environment wins.
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

#: Skip reasons of the browser tests start with this; the summary counts them.
NO_BROWSER = "no Chromium"
#: Skip reasons of the real-data tests (tests/corpus) start with this.
NO_CORPUS = "measured data set not here"


def pytest_collection_finish(session):
    """Freeze what collection left alive (every test module and what it imported: numpy,
    scipy, h5py, dask, ...) out of the cyclic garbage collector's sight. Each full
    collection otherwise walks all of it again: a hypothesis test that allocates freely
    spent three quarters of its time there (16.7 s against 1.4 s). Only objects alive
    now are frozen, after a collection; whatever a test creates is collected as before,
    so an unclosed file or socket it leaves still warns."""
    gc.collect()
    gc.freeze()


def pytest_terminal_summary(terminalreporter):
    """Say loudly when the browser tests could not run (CI installs Chromium)."""
    skipped = [r for r in terminalreporter.stats.get("skipped", []) if NO_BROWSER in str(r.longrepr)]
    if skipped:
        terminalreporter.write_sep(
            "!",
            f"{len(skipped)} BROWSER TESTS SKIPPED: {NO_BROWSER} found (apt-get install chromium, or set "
            "DAQ_CHROMIUM to its path)",
            red=True,
            bold=True,
        )
    absent = [r for r in terminalreporter.stats.get("skipped", []) if NO_CORPUS in str(r.longrepr)]
    if absent:
        terminalreporter.write_sep(
            "!",
            f"{len(absent)} REAL-DATA TESTS SKIPPED: {NO_CORPUS} (set DAQ_CORPUS; tests/data/README.md)",
            red=True,
            bold=True,
        )
