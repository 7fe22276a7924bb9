"""FRF tables after a preamble, generated at random (hypothesis): preamble lines of
``key: value`` and ``key<TAB>value`` with blank lines between, tab / ``;`` / whitespace
separators, CRLF or LF, UTF-8 or Latin-1, with or without a ``Units:`` line and a units
row. Each is detected as frf-text and reads back as written, in the form the units row says."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.cli.commands.import_file import detect_format
from daq.formats.frf_text import read_frf_text

SETTINGS = settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="frf-preamble-"))
KEYS = [
    "Units",
    "Ref Chan:Resp Chan",
    "Channel Name",
    "Channel Comment",
    "Averages",
    "Window",
    "Date",
    "Ü-Kanal",
]
VALUES = ["Ratio", "0-Z:0-Z", "", "Hanning", "10", "16.01.2021 12:00", "µ-Wert"]
# (units row cell, form, factor)
UNITS = [
    ("(m/s²)(N)", "accelerance", 1.0),
    ("(m/s^2)/N", "accelerance", 1.0),
    ("(m/s)(N)", "mobility", 1.0),
    ("m/N", "receptance", 1.0),
    ("(mm)(N)", "receptance", 1e-3),
    ("g/N", "accelerance", 9.80665),
    ("Ratio", "accelerance", 1.0),
    (None, "accelerance", 1.0),  # no units row at all
]


@st.composite
def preamble_lines(draw):
    lines = []
    for _ in range(draw(st.integers(0, 8))):
        key, value = draw(st.sampled_from(KEYS)), draw(st.sampled_from(VALUES))
        style = draw(st.sampled_from(["colon", "tab", "tab-colon", "blank"]))
        if style == "colon":
            lines.append(f"{key}: {value}")
        elif style == "tab":
            lines.append(f"{key}\t{value}")
        elif style == "tab-colon":
            lines.append(f"{key}\t : {value}")
        else:
            lines.append("")
    return lines


@SETTINGS
@given(
    preamble=preamble_lines(),
    sep=st.sampled_from(["\t", ";", "   "]),
    eol=st.sampled_from(["\r\n", "\n"]),
    encoding=st.sampled_from(["utf-8", "latin-1"]),
    unit=st.sampled_from(UNITS),
    marker=st.booleans(),
    blank_after_header=st.booleans(),
    names=st.sampled_from(
        [("Frequency", "Real", "Imaginary"), ("Frequency (Hz)", "Re", "Im"), ("freq", "re", "im")]
    ),
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(2, 30),
)
def test_a_table_after_a_preamble_reads_back(
    preamble, sep, eol, encoding, unit, marker, blank_after_header, names, seed, n
):
    rng = np.random.default_rng(seed)
    freq = np.arange(n) * 0.01953125
    frf = rng.normal(size=n) + 1j * rng.normal(size=n)
    cell, form, factor = unit
    if sep == "   ":  # whitespace-separated: no spaces inside a name
        names = tuple(name.replace(" ", "") for name in names)
    rows = [*preamble, sep.join(names)]
    if blank_after_header:
        rows.append("")
    if cell is not None:
        if marker:
            rows.append("Units:")
        rows.append(sep.join(["Hz", cell, ""]) if sep != "   " else f"Hz{sep}{cell}")
    comma = sep == ";"
    for f, h in zip(freq, frf, strict=True):
        cells = [repr(float(f)), repr(float(h.real)), repr(float(h.imag))]
        rows.append(sep.join(c.replace(".", ",") if comma else c for c in cells))
    path = WORK / "h.txt"
    path.write_bytes(eol.join(rows).encode(encoding) + eol.encode())
    assert detect_format(path)[0] == "frf-text"
    got = read_frf_text(path)
    np.testing.assert_array_equal(got.measured_frfs.frequency_hz, freq)
    if factor == 1.0:
        np.testing.assert_array_equal(got.measured_frfs.frf[0], frf)
    else:
        np.testing.assert_allclose(got.measured_frfs.frf[0], frf * factor, rtol=1e-15)
    assert got.measured_frfs.form == form
    said = got.details["form_from"]
    assert said.startswith("units row" if cell not in (None, "Ratio") else "default")
    assert said.count("(") == said.count(")")
    kept = [line for line in preamble if line]
    assert bool(got.details.get("preamble")) == bool(kept)
