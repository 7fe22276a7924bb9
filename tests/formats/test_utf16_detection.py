"""UTF-16 text with no byte-order mark (as some Windows tools save a CSV) is told apart
from binary data: `daq import` says what it is and how to fix it, and stores nothing."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from daq.cli.commands.import_file import _utf16_without_bom, not_readable
from daq.store import Store
from tests.cli_helpers import assert_one_line_error, invoke_daq

#: What a text export holds: printable ASCII, separators, line ends, a few units' letters.
TEXT = (
    st.lists(
        st.sampled_from([*"0123456789.,;-+eE tf()[]NgsHzm/\t\n", "\r\n", "°", "µ", "Ω"]),
        min_size=2,
        max_size=400,
    )
    .map("".join)
    .filter(lambda s: sum(c in "°µΩ" for c in s) <= len(s) // 20)
)


@settings(max_examples=200, deadline=None)
@given(text=TEXT, codec=st.sampled_from(["utf-16-le", "utf-16-be"]))
def test_utf16_without_a_byte_order_mark_is_named(text, codec):
    head = text.encode(codec)
    assert _utf16_without_bom(head)
    assert "text in UTF-16 (no byte-order mark)" in not_readable(Path("x.csv"), head)


@settings(max_examples=200, deadline=None)
@given(values=st.lists(st.floats(allow_nan=False, allow_infinity=False, width=64), min_size=2, max_size=64))
def test_binary_numbers_are_not_taken_for_utf16(values):
    head = np.asarray(values, dtype="<f8").tobytes()
    assert not _utf16_without_bom(head)


@given(text=TEXT)
def test_utf8_text_is_not_taken_for_utf16(text):
    assert not _utf16_without_bom(text.encode("utf-8"))


def test_daq_import_refuses_it_in_one_line_and_stores_nothing(tmp_path):
    path = tmp_path / "hits.csv"
    path.write_bytes("time,force,response\r\n0,1,2\r\n0.001,2,3\r\n".encode("utf-16-be"))
    store = tmp_path / "runs"
    result = invoke_daq("import", str(path), "--store", str(store))
    assert_one_line_error(result, "text in UTF-16 (no byte-order mark)", "save it as UTF-8")
    assert result.returncode == 1
    assert "Traceback" not in result.stderr
    assert not store.exists() or Store(store).list() == []
