"""The band of a run of FRFs imported with their coherence: the coherence is used (it
cuts the band where it is poor) and, where it limits neither edge, the reason says so
rather than that the run has no coherence."""

from __future__ import annotations

import numpy as np

from tests.cli_helpers import daq_json, invoke_daq


def _frf_table(path, coherence: np.ndarray, f: np.ndarray) -> None:
    w = 2 * np.pi * f
    h = sum(a * -(w**2) / ((2 * np.pi * fn) ** 2 - w**2 + 2j * 0.01 * (2 * np.pi * fn) * w)
            for a, fn in ((1.0, 42.0), (0.6, 155.0), (0.4, 388.0)))  # fmt: skip
    rows = ["Frequency (Hz),H11 Re [(m/s^2)/N],H11 Im [(m/s^2)/N],H11 coh"]
    rows += [f"{a:g},{z.real:.9g},{z.imag:.9g},{c:.4f}" for a, z, c in zip(f, h, coherence, strict=True)]
    path.write_text("\n".join(rows) + "\n")


def band_of(tmp_path, name: str, coherence: np.ndarray, f: np.ndarray) -> dict:
    path = tmp_path / name
    _frf_table(path, coherence, f)
    store = tmp_path / (name + "_runs")
    result = invoke_daq("import", str(path), "--store", str(store))
    assert result.returncode == 0, result.stderr
    (info,) = daq_json("analyze", store, "latest")
    return info["band"]


def test_a_good_coherence_is_named_as_limiting_neither_edge_not_called_absent(tmp_path):
    f = np.arange(0, 500.25, 0.25)
    band = band_of(tmp_path, "good.csv", np.full(f.size, 0.99), f)
    assert band["reason"] == (
        "the coherence (0.5 or more from the lowest line up to the top) limits neither edge; "
        "there is no force spectrum to limit the top"
    )
    assert "no coherence" not in band["reason"]
    assert band["low_hz"] == 0.25
    assert band["high_hz"] == 500.0


def test_a_coherence_that_falls_off_cuts_the_band_of_an_frf_run(tmp_path):
    f = np.arange(0, 500.25, 0.25)
    band = band_of(tmp_path, "falls.csv", np.where(f < 400, 0.99, 0.1), f)
    assert band["reason"].startswith("the coherence stays usable up to 399.")
    assert band["high_hz"] < 400
