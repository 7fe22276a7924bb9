"""A file of hits with a long pre-trigger: `daq analyze` cuts them at the impact and says
so in the text, the JSON and the report (analysis.pretrigger)."""

from __future__ import annotations

import json

import numpy as np

from tests.analysis.impact_synth import impact_hits
from tests.cli_helpers import invoke_daq


def _write_hits(path, pretrigger_s: float) -> None:
    fn, zeta, amp = [45.0, 120.0, 260.0], [0.015, 0.01, 0.008], [1.0, 0.7, 0.5]
    force, response = impact_hits(fn, zeta, amp, 1024.0, 0.5, 3, 0.02, 0.003, 7, pretrigger_s=pretrigger_s)
    t = np.arange(force.shape[1]) / 1024.0
    lines = ["hit,time,force,response"]
    for k in range(force.shape[0]):
        lines += [
            f"{k + 1},{ti!r},{fi!r},{ri!r}"
            for ti, fi, ri in zip(t.tolist(), force[k].tolist(), response[k].tolist(), strict=True)
        ]
    path.write_text("\n".join(lines) + "\n")


def test_a_long_pretrigger_is_cut_and_said_everywhere(tmp_path):
    store = str(tmp_path / "store")
    _write_hits(tmp_path / "hits.csv", 0.2)
    assert invoke_daq("import", str(tmp_path / "hits.csv"), "--store", store).returncode == 0
    text = invoke_daq("analyze", "latest", "--store", store)
    assert text.returncode == 0, text.stderr
    (line,) = [s for s in text.stdout.splitlines() if "pre-trigger" in s]
    assert line.startswith("  hits cut at their impacts: 0.19"), line
    (info,) = json.loads(invoke_daq("analyze", "latest", "--json", "--store", store).stdout)
    assert 0.195 <= info["pretrigger_cut_s"] <= 0.2
    (mode,) = [m for m in info["modes"] if abs(m["frequency_hz"] - 45) < 1]
    assert abs(mode["damping_ratio"] - 0.015) <= 3 * mode["damping_u"], mode
    report = invoke_daq("report", "latest", "-o", str(tmp_path / "r"), "--store", store)
    assert report.returncode == 0, report.stderr
    assert "Hits cut at their impacts: 0.19" in (tmp_path / "r" / "index.html").read_text()


def test_a_short_pretrigger_says_nothing(tmp_path):
    store = str(tmp_path / "store")
    _write_hits(tmp_path / "hits.csv", 0.002)
    assert invoke_daq("import", str(tmp_path / "hits.csv"), "--store", store).returncode == 0
    text = invoke_daq("analyze", "latest", "--store", store)
    assert "pre-trigger" not in text.stdout
    (info,) = json.loads(invoke_daq("analyze", "latest", "--json", "--store", store).stdout)
    assert info["pretrigger_cut_s"] == 0.0
