"""A preamble of delimited ``key,value`` rows before a time record's header (hypothesis), as
oscilloscopes and acquisition programs write their settings above the data
(``"Sample rate","2048 Hz"``, quoted or not, ``,`` or ``;``, padded with empty cells to
the table's width as a spreadsheet saves it). Before, the first such row was read as the
header and the file refused with `has 2 data columns; need time, force and response`.
Now the rows are skipped as the `key: value` preamble is, each line keeping its number,
and a sample rate they state is checked against the time column."""

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
WORK = Path(tempfile.mkdtemp(prefix="time-preamble-delimited-"))
KEYS = ("Instrument", "Operator", "Date", "Record length", "Trigger level", "Probe")
VALUES = ("Test rig 3", "A. Smith", "2026-12-08 10:41:07", "4096", "0.5 V", "x10")


def row(cells: list[str], sep: str, quoted: bool, width: int, padded: bool) -> str:
    shown = [f'"{c}"' if quoted else c for c in cells]
    if padded:
        shown += [""] * (width - len(cells))
    return sep.join(shown)


@st.composite
def files(draw):
    """(text, rate Hz, stated rate Hz or None, line of the stated rate, preamble lines, n)."""
    rate = draw(st.sampled_from([1000.0, 2048.0, 4000.0, 51200.0]))
    n = draw(st.integers(16, 200))
    sep = draw(st.sampled_from([",", ";"]))
    width = draw(st.sampled_from([3, 4]))
    quoted, padded = draw(st.booleans()), draw(st.booleans())
    lines: list[str] = []
    preamble: list[int] = []
    stated, at = None, None
    for k in draw(st.lists(st.integers(0, len(KEYS) - 1), min_size=1, max_size=4)):
        if draw(st.booleans()):
            lines.append(draw(st.sampled_from(["", "# exported"])))
        lines.append(row([KEYS[k], VALUES[k]], sep, quoted, width, padded))
        preamble.append(len(lines))
    if draw(st.booleans()):
        stated = rate * draw(st.sampled_from([1.0, 1.0, 1.05, 0.9]))
        key = draw(st.sampled_from(["Sample rate", "Sampling frequency", "fs"]))
        unit = draw(st.sampled_from(["", " Hz"]))
        lines.append(row([key, f"{stated:g}{unit}"], sep, quoted, width, padded))
        preamble.append(len(lines))
        at = len(lines)
    names = ["Time (s)", "Force (N)", "Acceleration (m/s^2)", "Spare (V)"][:width]
    lines.append(row(names, sep, quoted, width, False))
    lines += [sep.join([repr(i / rate), repr(float(i % 7)), repr(0.5 * i), "0.0"][:width]) for i in range(n)]
    return "\n".join(lines) + "\n", rate, stated, at, preamble, n


@SETTINGS
@given(case=files())
def test_delimited_preamble_rows_before_a_time_header_are_skipped(case):
    text, rate, stated, at, preamble, n = case
    path = WORK / "scope.csv"
    path.write_text(text, encoding="utf-8")
    if stated is not None and stated != rate:
        with pytest.raises(FormatError, match=rf"line {at} \(.*the time column steps at") as info:
            read_csv(path)
        assert "\n" not in str(info.value)
        return
    data = read_csv(path)
    assert data.hits.n_samples == n
    assert data.hits.sample_rate_hz == pytest.approx(stated if stated is not None else rate, rel=1e-9)
    (said,) = [note for note in data.details["notes"] if note.startswith("preamble")]
    shown = ", ".join(str(k) for k in preamble)
    assert said.startswith(f"preamble line{'s' if len(preamble) > 1 else ''} {shown} skipped")


def scope_file(path: Path, stated_hz: float) -> None:
    rows = ['"Instrument","Test rig 3"', '"Date","2026-12-08 10:41:07"', f'"Sample rate","{stated_hz:g} Hz"']
    rows.append('"Time (s)","Force (N)","Acceleration (m/s^2)"')
    rows += [f"{i / 2048:.7g},{100.0 if i == 3 else 0.0},{0.001 * i:.7g}" for i in range(256)]
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")


def test_a_quoted_scope_preamble_imports_at_its_stated_rate(tmp_path):
    path = tmp_path / "scope.csv"
    scope_file(path, 2048)
    result = invoke_daq("import", str(path), "--store", str(tmp_path / "store"))
    assert result.returncode == 0, result.stderr
    assert "1 hit of 256 samples at 2048 Hz" in result.stdout
    assert "note: preamble lines 1, 2, 3 skipped" in result.stdout
    assert "header's first column 'Time (s)'" in result.stdout


def test_a_scope_preamble_rate_the_time_column_denies_is_refused_in_one_line(tmp_path):
    path = tmp_path / "scope.csv"
    scope_file(path, 2000)
    store = tmp_path / "store"
    result = invoke_daq("import", str(path), "--store", str(store))
    assert result.returncode != 0
    assert result.stderr.count("\n") == 1
    assert "Traceback" not in result.stderr
    assert "line 3 (Sample rate: 2000 Hz)" in result.stderr
    assert not store.exists() or not list(store.glob("*.h5"))


@SETTINGS
@given(
    sep=st.sampled_from([",", ";"]),
    quoted=st.booleans(),
    key=st.sampled_from(["Sample rate", "Sampling frequency", "fs"]),
    rate=st.sampled_from([1000.0, 2048.0, 51200.0]),
)
def test_a_rate_row_as_wide_as_force_and_response_gives_their_rate(sep, quoted, key, rate):
    # Two cells, as many as the data: a header but for its key (before, the file was refused
    # with "Sample rate" read as the force column's name).
    lines = [
        row([key, f"{rate:g}"], sep, quoted, 2, False),
        row(["Force (N)", "Acc (m/s^2)"], sep, quoted, 2, False),
    ]
    lines += [f"{100.0 if i == 3 else 0.0}{sep}{0.001 * (-1) ** i * (64 - i):.6g}" for i in range(64)]
    path = WORK / "two.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    data = read_csv(path)
    assert data.hits.sample_rate_hz == rate
    assert data.hits.n_samples == 64
    assert any(note.startswith("preamble line 1 skipped") for note in data.details["notes"])
