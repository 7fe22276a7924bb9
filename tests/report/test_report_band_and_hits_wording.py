"""The report's analysis note writes the band as `daq analyze` does (four significant
digits: the edges are frequency lines such as 0.999997 Hz), and the hit-quality note
says "hit 4" for one hit not drawn."""

from __future__ import annotations

import html
import re

from tests.cli_helpers import invoke_daq


def test_the_report_writes_the_terminals_band_and_one_hit_not_drawn_in_the_singular(tmp_path):
    from tests.analysis.impact_synth import impact_hits

    fs = 2048.0
    force, response = impact_hits([45.0, 132.0, 310.0], [0.015, 0.008, 0.02], [1.0, -0.6, 0.4], fs, 2.0, 4,
                                  0.01, 2e-3, 7)  # fmt: skip
    path = tmp_path / "four.csv"
    rows = ["hit,time,force,response"]
    for k in range(4):
        rows += [f"{k},{i / fs:.9g},{force[k, i]:.9g},{response[k, i]:.9g}" for i in range(force.shape[1])]
    path.write_text("\n".join(rows) + "\n")
    store = tmp_path / "runs"
    assert invoke_daq("import", str(path), "--store", str(store)).returncode == 0
    analyzed = invoke_daq("analyze", "latest", "--store", str(store))
    assert analyzed.returncode == 0, analyzed.stderr
    (band,) = re.findall(r"^  band (\S+ Hz):", analyzed.stdout, re.M)
    for edge in band.removesuffix(" Hz").split("-"):
        assert len(edge.replace(".", "").lstrip("0")) <= 4  # four digits at most
    out = tmp_path / "report"
    result = invoke_daq("report", "latest", "-o", str(out), "--store", str(store))
    assert result.returncode == 0, result.stderr
    page = html.unescape((out / "index.html").read_text())
    assert f" Band {band}: " in page
    assert not re.search(r"Band \d+\.\d{5,}", page)
    assert "Drawn: hits 1-3 (" in page
    assert "; not drawn: hit 4, listed in the Hits table." in page
