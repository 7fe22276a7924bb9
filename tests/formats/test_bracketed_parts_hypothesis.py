"""FRF table headers that bracket the part a column holds (hypothesis): `Signal 2 (Real)`,
`Signal 2 (Imag.)`, as a building-model course's export wrote them (matos1396/Vibes
`dados/FRF.csv`). The bracket stood where a unit stands, so the column was refused as
"not frequency, re, im, mag, phase or coherence". Now the bracketed part names the kind,
the rest of the cell labels the FRF, and a bracketed unit is still a unit."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.errors import FormatError
from daq.formats.frf_text import read_frf_text

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="bracketed-parts-"))
RE = ["(Real)", "(real)", "(Re)", "[Real]", "(REAL)"]
IM = ["(Imag.)", "(Imag)", "(Imaginary)", "(Im)", "[Imag.]"]


def _write(header: list[str], columns: list[np.ndarray], delimiter: str, name: str = "frf.csv") -> Path:
    rows = [delimiter.join(header)]
    rows += [delimiter.join(f"{c[k]:.9g}" for c in columns) for k in range(columns[0].size)]
    path = WORK / name
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


@SETTINGS
@given(
    n=st.integers(8, 120),
    seed=st.integers(0, 2**16),
    n_frf=st.integers(1, 3),
    re_part=st.sampled_from(RE),
    im_part=st.sampled_from(IM),
    delimiter=st.sampled_from([",", ";", "\t"]),
    name=st.sampled_from(["Signal {k}", "H{k}1", "Point {k}"]),
)
def test_a_bracketed_real_and_imaginary_part_is_read_as_re_and_im(
    n, seed, n_frf, re_part, im_part, delimiter, name
):
    rng = np.random.default_rng(seed)
    freq = 0.5 * np.arange(n)
    header, columns, frfs = ["freq (Hz)"], [freq], []
    for k in range(n_frf):
        h = rng.normal(size=n) + 1j * rng.normal(size=n)
        label = name.format(k=k + 2)
        header += [f"{label} {re_part}", f"{label} {im_part}"]
        columns += [h.real, h.imag]
        frfs.append(h)
    data = read_frf_text(_write(header, columns, delimiter))
    got = data.measured_frfs
    assert got.frf.shape == (n_frf, n)
    for k, h in enumerate(frfs):
        np.testing.assert_allclose(got.frf[k], h, rtol=1e-8, atol=1e-12)
    assert [lab.strip() for lab in got.labels] == [name.format(k=k + 2) for k in range(n_frf)]
    assert data.details["form"] == "accelerance"  # nothing says otherwise: the default


def test_a_bracketed_unit_is_still_a_unit():
    freq = np.arange(1.0, 11.0)
    h = np.linspace(1, 2, 10) * (1 + 1j)
    path = _write(
        ["freq (Hz)", "H11 Re ((m/s^2)/N)", "H11 Im ((m/s^2)/N)"], [freq, h.real, h.imag], ",", "u.csv"
    )
    data = read_frf_text(path)
    np.testing.assert_allclose(data.measured_frfs.frf[0], h)
    path = _write(["freq (Hz)", "H11 Re (g/N)", "H11 Im (g/N)"], [freq, h.real, h.imag], ",", "g.csv")
    np.testing.assert_allclose(read_frf_text(path).measured_frfs.frf[0], 9.80665 * h)


def test_a_bracket_that_names_no_kind_is_still_refused():
    freq = np.arange(1.0, 11.0)
    path = _write(["freq (Hz)", "Signal 2 (Left)", "Signal 2 (Right)"], [freq, freq, freq], ",", "bad.csv")
    with pytest.raises(FormatError, match="is not frequency, re, im, mag, phase or coherence"):
        read_frf_text(path)
