"""The real HP 35670A file (tests/data/sdf/README.md) against the analyzer's own ASCII
export of the same trace: the numbers on the right-hand side come from the analyzer."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from daq.formats.sdf import read_sdf
from daq.formats.sdf.convert import vector_unit
from daq.store import Store
from tests.cli_helpers import invoke_daq

DATA = Path(__file__).resolve().parents[1] / "data" / "sdf"
REAL = DATA / "SDF3KHZ.DAT"


@pytest.fixture(scope="module")
def real():
    return read_sdf(REAL)


def _screen(power_v2_peak: np.ndarray) -> np.ndarray:
    """The analyzer showed V rms: the auto-power spectrum is in V^2 (peak), so
    sqrt(P / 2). This is the screen's unit choice, not part of the file."""
    return np.sqrt(power_v2_peak / 2)


def test_the_reader_gives_the_analyzers_numbers_to_their_printed_precision(real):
    shown = np.loadtxt(DATA / "ASCII3KH.TXT")
    hz = np.loadtxt(DATA / "ASCII3KH.X")
    (dh,) = real.data
    index = np.searchsorted(dh.x, hz)
    assert np.array_equal(dh.x[index], hz)  # every printed frequency is a line of the file
    ours = _screen(dh.y[0, 0, index])
    nonzero = shown != 0
    assert np.array_equal(ours[~nonzero], shown[~nonzero])
    # The export prints 7 significant digits (%e with 6 decimals): one unit of the last
    # digit is 10 ** (exponent - 6). The analyzer rounds its own float32 arithmetic, so
    # allow one unit, not half.
    unit = 10.0 ** (np.floor(np.log10(np.abs(shown[nonzero]))) - 6)
    error = np.abs(ours[nonzero] - shown[nonzero]) / unit
    assert error.max() <= 1.0, f"worst: {error.max():.3f} units of the last printed digit"
    assert np.mean(error <= 0.5) > 0.9  # most agree to half a unit, as correct rounding would
    # The 3 kHz line: 10 mV rms, as the source was set.
    assert ours[375] == pytest.approx(0.0100988, abs=1e-7)
    assert hz[375] == 3000.0


def test_the_headers_as_the_analyzer_wrote_them(real):
    assert (real.file.revision, real.file.applic, real.file.instrument) == (2, 10, "HP 35670A")
    assert real.file.applic_version == "A.01.11"
    assert real.file.stamp == "2013-02-13 09:08"
    assert (real.meas.center_freq, real.meas.span_freq, real.meas.block_size) == (8192.0, 16384.0, 4096)
    assert (real.meas.start_freq_index, real.meas.stop_freq_index) == (0, 1600)
    (dh,) = real.data
    assert (dh.title, dh.domain, dh.data_type, dh.n_points, dh.last_valid_index) == (
        "Pwr Spec",
        0,
        2,
        2049,
        2048,
    )
    assert (dh.ydata_type, dh.y_is_complex, dh.y_is_power, dh.first_x, dh.delta_x) == (3, 0, 1, 0.0, 8.0)
    assert dh.y.shape == (1, 1, 2049)
    assert dh.x_unit.label == "Hz"
    (vector,) = dh.vectors
    assert (vector.row_channel, vector.col_channel, vector.row_power, vector.col_power) == (0, -1, 96, 0)
    assert vector_unit(dh, vector, real.channels).label == "V^2"
    channel = real.channels[0]
    assert (channel.label, channel.module_id, channel.serial) == ("Chan  1", "HP35670A", "MY42506778")
    assert (channel.window.type, channel.window.corr_mode) == (2, 0)  # flat top, no correction applied
    assert channel.window.narrow_band_corr == pytest.approx(4.6869145)  # SDF_basi.h FLATTOP_NARROW_CORR
    assert (channel.eng_unit.label, channel.int2engr, channel.input_impedance) == ("V", 1.0, 50.0)
    assert len(real.channels) == 2
    assert real.unique == [(1013, 522)]
    assert real.scans is not None
    assert (real.scans.n_scans, real.scans.scan_type) == (1, 1)


def test_window_policies_differ_by_the_square_of_the_corrections(real):
    none = read_sdf(REAL, window="none").data[0].y
    wide = read_sdf(REAL, window="wide").data[0].y
    window = real.channels[0].window
    np.testing.assert_allclose(real.data[0].y, none * window.narrow_band_corr**2, rtol=1e-15)
    np.testing.assert_allclose(wide, none * window.wide_band_corr**2, rtol=1e-15)


def test_sdfascii_reads_the_same_numbers(real):
    sdfascii = pytest.importorskip("sdfascii")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        header, values = sdfascii.read_sdf_file(str(REAL))
    # sdfascii applies the same corrections, then sqrt(P) / sqrt(2) for a 35670A file,
    # and keeps lines start..stop of the measurement header, in float32.
    assert header["file_hdr"]["sdf_revision"] == 2
    np.testing.assert_allclose(values, _screen(real.data[0].y[0, 0, :1601]), rtol=2e-7)


def test_importing_it_makes_a_run_of_its_one_power_spectrum(tmp_path):
    # The whole story (values, export, analysis) is tests/formats/test_sdf_spectra_import.py.
    store = tmp_path / "store"
    copy = tmp_path / "SDF3KHZ.DAT"
    shutil.copyfile(REAL, copy)
    result = invoke_daq("import", str(copy), "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert "(sdf: 1 spectra of 1601 points)" in result.stdout
    (run,) = [Store(store).open(s.run_id) for s in Store(store).list()]
    assert (run.hits, run.analyzer, run.measured_frfs) == (None, None, None)
    assert run.spectra.kinds == ["power"]
