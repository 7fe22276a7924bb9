"""A text file whose last line has no line end may have been cut short mid-number
(hypothesis): it still reads, with a note naming that line; a file whose last line ends
gets none. Time records (csv) and FRF tables (frf-text) alike."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError
from daq.formats.frf_text import read_frf_text
from tests.cli_helpers import invoke_daq

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="unended-"))


def notes(details: dict) -> list[str]:
    return [n for n in details.get("notes") or [] if "no line end" in n]


@SETTINGS
@given(
    n=st.integers(3, 300),
    end=st.sampled_from(["\n", "\r\n"]),
    cut=st.integers(0, 12),
    ended=st.booleans(),
    comment_after=st.booleans(),
)
def test_a_time_record_cut_short_is_noted_with_its_line(n, end, cut, ended, comment_after):
    rows = ["t,F,a"] + [f"{i / 4000!r},{i * 0.5!r},{-0.066120503 * i!r}" for i in range(n)]
    text = end.join(rows)
    # Cut inside the last row's last number, never into its separator.
    last = rows[-1]
    text = text[: len(text) - min(cut, len(last) - last.rindex(",") - 3)]
    if comment_after:
        text += end + "# end of export"
    if ended:
        text += end
    path = WORK / "cut.csv"
    path.write_bytes(text.encode())
    said = notes(read_csv(path).details)
    if ended or comment_after:
        assert said == []
    else:
        assert said == [
            f"line {n + 1}, the last, has no line end: the file may be cut short and that row incomplete; "
            "compare its end with the source"
        ]


@SETTINGS
@given(n=st.integers(3, 80), ended=st.booleans())
def test_an_frf_table_cut_short_is_noted_with_its_line(n, ended):
    rows = ["Frequency (Hz),H Re,H Im"] + [f"{i * 0.5!r},{1.0 / (i + 1)!r},{-0.25 * i!r}" for i in range(n)]
    path = WORK / "frf.csv"
    path.write_text("\n".join(rows) + ("\n" if ended else ""), encoding="utf-8")
    said = notes(read_frf_text(path).details)
    assert said == ([] if ended else [said[0]])
    assert ended or said[0].startswith(f"line {n + 1}, the last, has no line end")


def test_the_trial_file_cut_mid_number_imports_with_the_note(tmp_path):
    rows = ["t,F,a"] + [f"{i / 4000!r},{100.0 if i == 3 else 0.0},{0.001 * i!r}" for i in range(100)]
    path = tmp_path / "truncated_midline.csv"
    path.write_text("\n".join(rows) + "\n0.025,0,-0.06612", encoding="utf-8")
    result = invoke_daq("import", str(path), "--store", str(tmp_path / "store"))
    assert result.returncode == 0, result.stderr
    assert "note: line 102, the last, has no line end: the file may be cut short" in result.stdout


@SETTINGS
@given(
    n=st.integers(3, 200),
    end=st.sampled_from(["\n", "\r\n"]),
    kept_cells=st.integers(1, 2),
    frf=st.booleans(),
)
def test_a_last_row_cut_into_its_cells_is_refused_as_cut_short(n, end, kept_cells, frf):
    """Cut before its last cells (a new user's truncated files): refused with the line, as
    before, and now also said to be the file's last line without a line end."""
    header = "freq (Hz),H Re,H Im" if frf else "t,F,a"
    rows = [header] + [f"{(i + 1) / 4!r},{1.0 + i!r},{0.5 * i + 0.25!r}" for i in range(n)]
    cells = rows[-1].split(",")
    rows[-1] = ",".join(cells[:kept_cells]) + ("," if kept_cells == 2 else "")
    path = WORK / ("cut.frf.csv" if frf else "cut.csv")
    path.write_text(end.join(rows), encoding="utf-8")  # no line end after the last row
    with pytest.raises(FormatError, match=f"line {n + 1}.*it is the file's last line and has no line end"):
        (read_frf_text if frf else read_csv)(path)
    path.write_text(end.join(rows) + end, encoding="utf-8")  # ended: not called cut short
    with pytest.raises(FormatError) as refused:
        (read_frf_text if frf else read_csv)(path)
    assert "cut short" not in str(refused.value)


@pytest.mark.parametrize(
    "last",
    ["End of data", "0.002,3,0.1,7", "0.002,3,NaN", "0.002,3,n/a"],
    ids=["footer", "extra", "nan", "word"],
)
def test_a_last_line_that_is_no_cut_row_is_not_called_cut_short(last):
    """A footer, an extra cell or a word is refused as before, without the cut-short
    sentence, which is for a row cut into its cells (review of the first version)."""
    path = WORK / "footer.csv"
    path.write_text("t,F,a\n0,1,0.5\n0.001,2,0.25\n" + last, encoding="utf-8")
    with pytest.raises(FormatError) as refused:
        read_csv(path)
    assert "cut short" not in str(refused.value)
