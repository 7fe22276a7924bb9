"""`daq import FILE --test T --point P | head -0`: stdout closed before the first line is
printed. The run is sealed and must still join its test (it used to be joined after the
lines were printed, so the broken pipe left it outside the test). A real process and a
real pipe, closed by the reader."""

from __future__ import annotations

import os
import subprocess

from tests.cli_helpers import DAQ, ENV, invoke_daq
from tests.formats.test_record_cut import record


def test_an_import_whose_output_pipe_is_closed_still_joins_its_test(tmp_path):
    store = tmp_path / "runs"
    assert invoke_daq("test", "new", "t", "--points", "p1=0.5,p2=0.3", "--store", str(store)).returncode == 0
    force, response = record([600, 600 + 4096], 600 + 8192, freq_hz=150.0)
    pairs = enumerate(zip(force, response, strict=True))
    rows = [f"{k / 2048!r},{float(f)!r},{float(a)!r}" for k, (f, a) in pairs]
    path = tmp_path / "hits.csv"
    path.write_text("time,force,response\n" + "\n".join(rows) + "\n")
    proc = subprocess.Popen(
        [str(DAQ), "import", str(path), "--test", "t", "--point", "p1", "--store", str(store)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, env={**os.environ, **ENV},
    )  # fmt: skip
    proc.stdout.close()  # as `| head -0` does: every line printed meets a closed pipe
    proc.wait(60)
    said = proc.stderr.read().decode()
    proc.stderr.close()
    shown = invoke_daq("test", "show", "t", "--store", str(store))
    assert shown.returncode == 0, shown.stderr
    assert "1 of 2 points measured" in shown.stdout, (shown.stdout, said)
