"""A format given with --format follows the rule auto-detection uses (daq/cli/commands/
import_file.py, frequency_axis_why): a headerless table whose first column steps by 0.1 or
more, or by 0.01 or more from a real value at 0 Hz, is a frequency axis, anything finer is
time. Forced frf-text is refused below that boundary and taken above it, exactly where
detection says frf-text; forced csv is refused from a step of 0.1 s (10 samples/s, no
vibration) and taken below. And the import's count of lines above 0 Hz is the analysis's
(hypothesis: steps on both sides of the boundaries, column counts, record lengths)."""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from analysis import spectra
from analysis.windows import WindowSpec
from daq.cli.commands.import_file import MIN_FREQUENCY_STEP, MIN_FREQUENCY_STEP_AT_DC, detect_format
from daq.formats import imported
from tests.cli_helpers import invoke_daq

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="forced-"))
#: Steps around both boundaries, and the steps of real records and FRFs.
STEPS = [
    1 / 51200,
    1 / 25600,
    1 / 1024,
    0.001,
    0.005,
    0.00999,
    0.01,
    0.02,
    0.05,
    0.0999,
    0.1,
    0.125,
    0.5,
    1.0,
    2.5,
]
steps = st.one_of(
    st.sampled_from(STEPS),
    # Away from the boundaries by more than the rule's slack (1e-9 of the step).
    st.floats(1e-5, 5.0).filter(lambda s: all(abs(s / b - 1) > 1e-6 for b in (0.1, 0.01))),
)


def headerless(name: str, step: float, n_frf: int, start_line: int, real_at_zero: bool, seed: int) -> Path:
    """frequency (or time), then n_frf Re/Im pairs, 64 rows, tab-separated, repr-printed."""
    rng = np.random.default_rng(seed)
    axis = (start_line + np.arange(64)) * step
    values = rng.normal(size=(axis.size, 2 * n_frf))
    if real_at_zero:
        values[0, 1::2] = 0.0
    path = WORK / name
    rows = np.column_stack([axis, values])
    path.write_text("".join("\t".join(repr(float(v)) for v in row) + "\n" for row in rows))
    return path


def is_frequency_axis(step: float, first: float, real_at_zero: bool) -> bool:
    """The documented rule, written out here independently of the code."""
    return step >= MIN_FREQUENCY_STEP or (step >= MIN_FREQUENCY_STEP_AT_DC and first == 0 and real_at_zero)


@SETTINGS
@given(
    step=steps,
    n_frf=st.integers(1, 3),
    start_line=st.sampled_from([0, 0, 1, 7]),
    real_at_zero=st.booleans(),
    seed=st.integers(0, 2**16),
)
# Found in a full run: the mean step 0.0009765625 (1 + 1e-9) prints as 0.000976563, not ...62.
@example(step=0.0009765625, n_frf=1, start_line=0, real_at_zero=False, seed=0)
def test_forced_frf_text_is_taken_exactly_where_detection_says_frf_text(
    step, n_frf, start_line, real_at_zero, seed
):
    path = headerless(f"frf-{seed}.txt", step, n_frf, start_line, real_at_zero, seed)
    store = Path(tempfile.mkdtemp(dir=WORK)) / "runs"  # one per example: a refusal stores nothing
    expected = is_frequency_axis(step, start_line * step, real_at_zero)
    assert (detect_format(path)[0] == "frf-text") == expected
    result = invoke_daq("import", str(path), "--format", "frf-text", "--store", str(store))
    if expected:
        assert result.returncode == 0, result.stderr
        assert f"(frf-text: {n_frf} FRF" in result.stdout
    else:
        assert result.returncode == 1, result.stdout
        (line,) = result.stderr.splitlines()
        said = re.search(r"its first column steps by (\S+), which as frequency would be FRFs from", line)
        # The step as printed (6 digits) of the mean step read back: 0.0009765625 may print ...63.
        assert said is not None, line
        assert float(said.group(1)) == pytest.approx(step, rel=1e-5)
        assert "import it with --format csv" in line
        assert not store.exists() or not any(store.glob("*.h5"))


@SETTINGS
@given(step=steps, n_cols=st.integers(3, 6), seed=st.integers(0, 2**16))
def test_forced_csv_is_refused_from_a_tenth_of_a_second(step, n_cols, seed):
    path = headerless(f"csv-{seed}.txt", step, 1, 0, False, seed)
    if n_cols != 3:  # more columns: the note names them, the rule is the same
        rows = [line + "\t1.5" * (n_cols - 3) for line in path.read_text().splitlines()]
        path.write_text("\n".join(rows) + "\n")
    store = Path(tempfile.mkdtemp(dir=WORK)) / "runs"
    result = invoke_daq("import", str(path), "--format", "csv", "--store", str(store))
    if step >= MIN_FREQUENCY_STEP:
        assert result.returncode == 1, result.stdout
        (line,) = result.stderr.splitlines()
        assert "which records no vibration" in line
        assert "import it with --format frf-text" in line
        assert not store.exists() or not any(store.glob("*.h5"))
    else:
        assert result.returncode == 0, result.stderr
        assert "(csv: 1 hit of 64 samples" in result.stdout
        assert ("note: column" in result.stdout) == (n_cols > 3)


@settings(max_examples=200, deadline=None)
@given(
    n=st.integers(2, 400),
    rate=st.sampled_from([256.0, 1024.0, 51200.0]),
    zoom=st.sampled_from([0.0, 3.0, 500.0]),
)
def test_the_lines_the_import_counts_are_the_lines_the_analysis_gets(n, rate, zoom):
    records = np.ones((1, n), dtype=complex if zoom else float)
    uniform = WindowSpec("uniform")
    try:
        got = spectra.linear_spectra(records, records, rate, uniform, uniform, center_hz=zoom)
    except ValueError:  # a zoom band reaching below 0 Hz: no analysis at all
        assume(False)
    assert imported.lines_above_zero(n, zoom, rate) == int(np.count_nonzero(got.frequency_hz > 0))


def test_the_import_uses_the_analysiss_alias_free_factor():
    assert imported.ALIAS_FREE_FACTOR == spectra.ALIAS_FREE_FACTOR


def test_the_import_uses_the_analysiss_least_lines():
    from analysis import run_analysis

    assert imported.MIN_ANALYSIS_LINES == run_analysis.MIN_LINES
