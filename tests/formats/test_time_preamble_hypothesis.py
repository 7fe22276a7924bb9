"""A preamble of `key: value` / `key<TAB>value` lines before a time record's header row
(hypothesis), as acquisition programs write it: skipped as for FRF tables, each line
keeping its number, and named in a note. A sample rate it states is used when the
time column allows it, and refused, naming both, when not (before, the first preamble
line was read as the header: `line 2: 3 columns, expected 4`)."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError
from tests.cli_helpers import invoke_daq

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="time-preamble-"))
KEYS = ("Channels", "Operator", "Date", "Device", "Trigger level")


def meta(key: str, value: str, tab: bool) -> str:
    return f"{key}\t{value}" if tab else f"{key}: {value}"


@st.composite
def files(draw):
    """(text, rate Hz, stated rate Hz or None, line of the stated rate, preamble lines, n, sep)."""
    rate = draw(st.sampled_from([1000.0, 2048.0, 4000.0, 51200.0]))
    n = draw(st.integers(16, 200))
    sep = draw(st.sampled_from(["\t", ",", ";"]))
    lines: list[str] = []
    preamble: list[int] = []
    stated, at = None, None
    for key in draw(st.lists(st.sampled_from(KEYS), max_size=3)):
        if draw(st.booleans()):
            lines.append(draw(st.sampled_from(["", "# exported"])))
        lines.append(
            meta(key, draw(st.sampled_from(["3", "A. Smith", "2026-11-25", "x"])), draw(st.booleans()))
        )
        preamble.append(len(lines))
    if draw(st.booleans()) or not preamble:
        stated = rate * draw(st.sampled_from([1.0, 1.0, 1.05, 0.9, 2.0]))
        key = draw(st.sampled_from(["Sample rate", "Sampling frequency", "SampleRate", "fs"]))
        unit = draw(st.sampled_from(["", " Hz", "Hz"]))
        lines.append(meta(key, f"{stated:g}{unit}", draw(st.booleans())))
        preamble.append(len(lines))
        at = len(lines)
    lines.append(sep.join(["Time[s]", "Force[N]", "Accel[m/s^2]"]))
    lines += [sep.join([repr(i / rate), repr(float(i % 7)), repr(0.5 * i)]) for i in range(n)]
    return "\n".join(lines) + "\n", rate, stated, at, preamble, n, sep


@SETTINGS
@given(case=files())
def test_a_preamble_before_a_time_header_is_skipped_and_its_rate_checked(case):
    text, rate, stated, at, preamble, n, _ = case
    path = WORK / "preamble.txt"
    path.write_text(text, encoding="utf-8")
    if stated is not None and stated != rate:
        with pytest.raises(FormatError) as info:
            read_csv(path)
        message = str(info.value)
        assert "\n" not in message
        assert f"line {at} (" in message
        assert f"{stated:g} Hz" in message
        assert "the time column steps at" in message
        return
    data = read_csv(path)
    assert data.hits.n_samples == n
    if stated is not None:
        assert data.hits.sample_rate_hz == stated
    (said,) = [note for note in data.details["notes"] if note.startswith("preamble")]
    shown = ", ".join(str(k) for k in preamble)
    assert said.startswith(f"preamble line{'s' if len(preamble) > 1 else ''} {shown} skipped")


def test_the_trial_preamble_file_imports_at_its_stated_rate(tmp_path):
    rows = ["Sample rate: 4000 Hz", "Time[s]\tForce[N]\tAccel[m/s^2]"]
    rows += [f"{i / 4000!r}\t{100.0 if i == 3 else 0.0}\t{0.001 * i!r}" for i in range(64)]
    path = tmp_path / "preamble2.txt"
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    result = invoke_daq("import", str(path), "--store", str(tmp_path / "store"))
    assert result.returncode == 0, result.stderr
    assert "at 4000 Hz" in result.stdout
    assert "note: preamble line 1 skipped" in result.stdout
