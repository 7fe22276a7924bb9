"""Text tables without a header: frequency, Re, Im (as MATLAB's writematrix leaves them, or
the five receptances of the measured tool holder of tests/data/README.md) are FRFs, not a
time record sampled at 1 Hz; time records at a vibration test's rates stay time records
(hypothesis: steps, column counts, separators, decimal commas, printed precision)."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.cli.commands.import_file import detect_format
from tests.cli_helpers import invoke_daq

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="headerless-"))
#: (separator, decimal mark) pairs a lab's exports use.
STYLES = [("\t", "."), (" ", "."), (",", "."), (";", ","), ("\t", ",")]


def table_text(rows: np.ndarray, separator: str, decimal: str, digits: int) -> str:
    lines = []
    for row in rows:
        cells = [f"{v:.{digits}e}".replace(".", decimal) for v in row]
        lines.append(separator.join(cells))
    return "\n".join(lines) + "\n"


def put(text: str, name: str) -> Path:
    path = WORK / name
    path.write_text(text, encoding="utf-8")
    return path


@SETTINGS
@given(
    step=st.sampled_from([0.1, 0.125, 0.25, 0.5, 1.0, 2.0, 2.5, 5.0]),
    start_line=st.integers(0, 20),
    n_frf=st.integers(1, 4),
    style=st.sampled_from(STYLES),
    digits=st.integers(6, 10),
    seed=st.integers(0, 2**16),
)
def test_a_frequency_axis_of_a_tenth_and_more_is_an_frf_table(step, start_line, n_frf, style, digits, seed):
    rng = np.random.default_rng(seed)
    f = (start_line + np.arange(200)) * step
    values = rng.normal(size=(f.size, 2 * n_frf)) * 1e-6
    path = put(table_text(np.column_stack([f, values]), *style, digits), f"frf-{seed}.txt")
    chosen, why = detect_format(path)
    assert chosen == "frf-text", why
    assert f"steps by {step:g}" in why


@SETTINGS
@given(
    rate_hz=st.sampled_from([102.4, 256.0, 1024.0, 2560.0, 10240.0, 25600.0, 51200.0, 65536.0]),
    style=st.sampled_from(STYLES),
    digits=st.integers(7, 10),
    zero_start=st.booleans(),
    seed=st.integers(0, 2**16),
)
def test_time_records_at_a_vibration_tests_rates_stay_time_records(rate_hz, style, digits, zero_start, seed):
    rng = np.random.default_rng(seed)
    t = np.arange(300) / rate_hz
    force, response = rng.normal(size=(2, t.size))
    if zero_start:  # a record that starts at rest: both channels exactly 0 at t = 0
        force[0] = response[0] = 0.0
    path = put(table_text(np.column_stack([t, force, response]), *style, digits), f"time-{seed}.txt")
    chosen, why = detect_format(path)
    assert chosen == "csv", why


@SETTINGS
@given(step=st.sampled_from([0.01, 0.02, 0.025, 0.05]), n_frf=st.integers(1, 3), im_at_dc=st.booleans())
def test_between_a_hundredth_and_a_tenth_an_frf_is_told_by_its_real_value_at_0_hz(step, n_frf, im_at_dc):
    rng = np.random.default_rng(7)
    f = np.arange(200) * step
    values = rng.normal(size=(f.size, 2 * n_frf))
    values[0, 1::2] = 0.0  # Im at 0 Hz
    if im_at_dc:  # ... unless a column there is not an imaginary part
        values[0, 1] = 0.3
    path = put(table_text(np.column_stack([f, values]), "\t", ".", 7), f"dc-{step}-{n_frf}-{im_at_dc}.txt")
    chosen, why = detect_format(path)
    assert chosen == ("csv" if im_at_dc else "frf-text"), why


def test_the_tool_holders_receptance_as_its_source_wrote_it(tmp_path):
    """The layout of tool-holder's Point_1_Channel_1_CH1.txt (0-5000 Hz, 1 Hz, m/N), values
    made here: before, `daq import` stored it as one hit sampled at 1 Hz."""
    f = np.arange(5001.0)
    h = 1e-7 / (1 - (f / 1070.0) ** 2 + 0.066j * f / 1070.0)
    rows = [
        f"{x:.6e}\t{v.real:.6e}\t{v.imag:.6e}".replace("e+", "e+0").replace("e-", "e-0")
        for x, v in zip(f, h, strict=True)
    ]
    path = tmp_path / "Point_1_Channel_1_CH1.txt"
    path.write_text("\n".join(rows) + "\n")
    assert rows[0].startswith("0.000000e+000\t")
    result = invoke_daq("import", str(path), "--frf-form", "receptance", "--store", str(tmp_path / "runs"))
    assert result.returncode == 0, result.stderr
    assert "(frf-text: 1 FRF of 5001 points, receptance)" in result.stdout
    assert "no header, and its first column steps by 1" in result.stdout
    as_time = invoke_daq("import", str(path), "--format", "csv", "--store", str(tmp_path / "runs"))
    assert as_time.returncode == 1, as_time.stdout
    assert "a sampling rate of 1 Hz, which records no vibration" in as_time.stderr
    assert "import it with --format frf-text" in as_time.stderr
