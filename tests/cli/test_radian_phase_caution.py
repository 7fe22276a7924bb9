"""A phase the import says looks like radians is said again by `daq analyze`, where the
modes it spoils are read: a new user's table of magnitude and phase in radians gave one
mode at 2624 Hz under generic cautions, the import's note long scrolled away."""

from __future__ import annotations

import json

import numpy as np

from tests.cli_helpers import invoke_daq


def table(path, phase_header: str) -> None:
    f = np.arange(1, 2001) * 0.5
    w, wn = 2 * np.pi * f, 2 * np.pi * 300.0
    h = -(w**2) / (wn**2 - w**2 + 2j * 0.02 * wn * w)
    rows = [f"{float(x)!r},{float(abs(v))!r},{float(np.angle(v))!r}" for x, v in zip(f, h, strict=True)]
    path.write_text(f"Frequency (Hz),H11 mag,{phase_header}\n" + "\n".join(rows) + "\n")


def cautions(tmp_path, phase_header: str) -> list[str]:
    path = tmp_path / "magphase.csv"
    table(path, phase_header)
    store = tmp_path / "runs"
    assert invoke_daq("import", str(path), "--store", str(store)).returncode == 0
    result = invoke_daq("analyze", "latest", "--store", str(store), "--json")
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)[0]["cautions"]


def test_a_phase_in_radians_read_as_degrees_is_cautioned_in_the_analysis(tmp_path):
    said = [c for c in cautions(tmp_path, "H11 phase") if "looks like radians" in c]
    assert len(said) == 1
    assert "[rad]" in said[0]


def test_a_phase_said_in_radians_is_not(tmp_path):
    assert not [c for c in cautions(tmp_path, "H11 phase [rad]") if "radians" in c]
