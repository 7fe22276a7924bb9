"""Shared fixtures. Reference numbers live in tests/reference.py, computed before any
code existed (docs/method.md) or copied from the seed paper, never produced by our code."""

#: Skip reasons of the browser tests start with this; the summary counts them.
NO_BROWSER = "no Chromium"
#: Skip reasons of the real-data tests (tests/corpus) start with this.
NO_CORPUS = "measured data set not here"


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
