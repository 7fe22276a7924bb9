"""Whatever follows LabVIEW's signature line, the reader gives hits or one FormatError
line: never another exception (hypothesis, over the rows and cells LabVIEW writes,
shuffled, cut and mixed with junk)."""

from __future__ import annotations

import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.errors import FormatError
from daq.formats.lvm import read_lvm

WORK = Path(tempfile.mkdtemp(prefix="lvm-fuzz-"))
KEYS = ["Channels", "Samples", "Y_Unit_Label", "X_Dimension", "X0", "Delta_X", "X_Value", "Comment",
        "Separator", "Decimal_Separator", "X_Columns", "***End_of_Header***", "Multi_Headings"]  # fmt: skip
CELLS = st.one_of(
    st.sampled_from([*KEYS, "", "Tab", "Comma", "No", "One", "Multi", ".", ",", "N", "g", "Volts", "m/s^2"]),
    st.integers(-3, 70).map(str),
    st.floats(-1e3, 1e3, allow_nan=False).map(repr),
    st.sampled_from(["0.000977", "0,000977", "1.953125E-5", "0", "-1", "nan", "1e999", "abc"]),
    st.text(max_size=6),
)


def hits_or_one_line(path: Path):
    """read_lvm's hits, or None after checking its refusal is one line."""
    try:
        return read_lvm(path)
    except FormatError as exc:
        message = str(exc)
    assert "\n" not in message
    return None


def _real_layout() -> bytes:
    from tests.formats.test_lvm import hammer_hit, lvm_text

    force, a1, _ = hammer_hit(300, 1024.0, 87.5)
    return lvm_text([[("F", "N", force), ("a1", "m/s^2", a1)]] * 2).encode()


REAL = _real_layout()
ROWS = st.lists(st.lists(CELLS, max_size=7).map("\t".join), max_size=40)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(rows=ROWS, end=st.booleans())
def test_any_rows_after_the_signature_give_hits_or_one_line(rows, end):
    path = WORK / "fuzz.lvm"
    text = "LabVIEW Measurement\t\n" + "\n".join(rows) + ("\n" if end else "")
    path.write_bytes(text.encode("utf-8", "surrogatepass"))
    data = hits_or_one_line(path)
    if data is not None:
        assert data.hits.force_n.shape == data.hits.response_m_s2.shape


@settings(max_examples=100, deadline=None)
@given(cut=st.integers(20, 2000), junk=st.binary(max_size=20))
def test_a_real_layout_cut_anywhere_or_ended_in_junk_gives_hits_or_one_line(cut, junk):
    path = WORK / "cut.lvm"
    path.write_bytes(REAL[: len(REAL) * cut // 2000] + junk)
    hits_or_one_line(path)
