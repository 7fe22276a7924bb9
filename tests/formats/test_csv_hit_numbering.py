"""A CSV export says how its hit numbers count (from 0, the run's index), since people read
hits from 1 everywhere else; the line is prose to the reader, so the file still reads back."""

from __future__ import annotations

from daq.formats.csv_text import read_csv, write_csv
from tests.formats.test_csv_text import make_run


def test_the_export_says_its_hits_count_from_0_and_still_reads_back(tmp_path):
    run = make_run(n=4)
    path = tmp_path / "run.csv"
    write_csv(run, path)
    lines = path.read_text().splitlines()
    (said,) = [line for line in lines if line.startswith("# hit numbering:")]
    assert "count from 0" in said
    assert "# rejected hit 1: double hit" in lines  # hit 2 to a person
    got = read_csv(path)
    assert got.hits.accepted.tolist() == run.hits.accepted.tolist()
    assert "hit numbering" not in got.details.get("comments", {})
