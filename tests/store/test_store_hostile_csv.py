"""A legal CSV of a million tiny hits is refused in one line, in bounded time and memory
(issue item 9, CSV part: it once took 4.3 GB to import)."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

DAQ = Path(sys.executable).with_name("daq")


def _tiny_hits(path: Path, n_hits: int, hit_column: bool) -> Path:
    with open(path, "w") as out:
        out.write("hit,time,force,response\n" if hit_column else "time,force,response\n")
        row = "{k},0,1,2\n{k},0.001,3,4\n" if hit_column else "0,1,2\n0.001,3,4\n"
        block = "".join(row.format(k=k) for k in range(1000)) if not hit_column else None
        for start in range(0, n_hits, 1000):
            if hit_column:
                out.write("".join(row.format(k=k) for k in range(start, min(start + 1000, n_hits))))
            else:
                out.write(block)
    return path


@pytest.mark.timeout(120)
@pytest.mark.parametrize("hit_column", [True, False], ids=["hit-column", "time-restarts"])
def test_a_million_tiny_hits_are_refused_in_bounded_memory(tmp_path, hit_column):
    csv = _tiny_hits(tmp_path / "tiny.csv", 1_000_000, hit_column)
    assert csv.stat().st_size < 40 * 2**20

    def cap() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (1536 * 2**20,) * 2)

    env = {**os.environ, "COLUMNS": "200", "NO_COLOR": "1"}
    env.pop("DAQ_DEBUG", None)
    store = tmp_path / "store"
    result = subprocess.run(
        [str(DAQ), "import", str(csv), "--format", "csv", "--store", str(store)],
        capture_output=True, text=True, timeout=90, env=env, preexec_fn=cap,
    )  # fmt: skip
    lines = result.stderr.splitlines()
    assert result.returncode == 1, result.stderr[-2000:]
    assert len(lines) == 1, result.stderr[-2000:]
    assert "holds 1000000 hits, more than the 10000 one import may hold" in lines[0]
    assert not list(store.glob("*.h5")) if store.exists() else True


def test_ten_thousand_hits_still_import(tmp_path):
    from daq.formats.csv_text import read_csv

    data = read_csv(_tiny_hits(tmp_path / "ok.csv", 10_000, True))
    assert data.hits.force_n.shape == (10_000, 2)
