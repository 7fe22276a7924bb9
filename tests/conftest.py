"""Shared fixtures. Reference numbers live in tests/reference.py, computed before any
code existed (docs/method.md) or copied from the seed paper, never produced by our code."""

#: Skip reasons of the browser tests start with this; the summary counts them.
NO_BROWSER = "no Chromium"


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
