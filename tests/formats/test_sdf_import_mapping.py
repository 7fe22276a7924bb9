"""What `daq import` makes of SDF files an analyzer could have written (built by hand
with the test builder): which channel is the force, units to SI, alias-protected lines,
coherence pairing, the exponential window, spectra, and what is refused."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from daq.formats.errors import FormatError
from daq.formats.sdf import read_sdf_run
from daq.formats.units import POUND_FORCE_N
from tests.cli_helpers import invoke_daq
from tests.formats.sdf_builder import (
    YDATA,
    assemble,
    block,
    channel_hdr,
    data_hdr,
    meas_hdr,
    scan_struct,
    unit,
    values,
    vector_hdr,
    window,
)

VOLT = unit("V", 1.0, (2, 4, -6, -2, 0, 0, 0, 0))
EXPONENTIAL = window(5, 0, 1.0, 0.25, 0.0, 1.0, 1.0)  # time constant 0.25 s


def write(tmp_path: Path, data: bytes) -> Path:
    path = tmp_path / "ANALYZER.DAT"
    path.write_bytes(data)
    return path


def test_an_frf_with_coherence_on_the_alias_protected_lines(tmp_path):
    rev = 2
    channels = [
        channel_hdr(rev, "Hammer", eng=unit("lbf", 4.4482, (2, 2, -4, 0, 0, 0, 0, 0)), attribute=2),
        channel_hdr(rev, "Accel", win=EXPONENTIAL, eng=unit("g", 9.80665, (0, 2, -4, 0, 0, 0, 0, 0))),
    ]
    data = [
        data_hdr(rev, n_points=4, first_vector=0, title="Freq Resp", complex=1, data_type=4, delta_x=2.0),
        data_hdr(rev, n_points=4, first_vector=1, title="Coherence", data_type=8, delta_x=2.0),
    ]
    vectors = [vector_hdr(1, 0, 48, -48), vector_hdr(1, 0, 0, 0)]
    y = values([1, 1, 2, 0, 0, -2, 3, 3], ">f4") + values([0.5, 0.75, 1.0, 0.25], ">f4")
    meas = meas_hdr(rev, start=1, stop=3)  # line 0 (DC) is not alias-protected
    imported = read_sdf_run(write(tmp_path, assemble(rev, meas, data, vectors, channels, block(YDATA, y))))
    frfs = imported.measured_frfs
    np.testing.assert_array_equal(frfs.frequency_hz, [2.0, 4.0, 6.0])
    # g / lbf to (m/s^2) / N: 9.80665 / 4.4482216152605 (the labels' exact factors).
    factor = 9.80665 / POUND_FORCE_N
    np.testing.assert_allclose(frfs.frf, [[2 * factor, -2j * factor, (3 + 3j) * factor]], rtol=1e-15)
    np.testing.assert_array_equal(frfs.coherence, [[0.75, 1.0, 0.25]])
    assert list(frfs.labels) == ["Freq Resp"]
    assert imported.hits is None
    assert imported.details["frf_units"] == ["g/lbf"]
    assert imported.details["exp_decay_s"] == 0.25  # the accelerometer's exponential window
    assert imported.details["sdf_revision"] == 2


def _time_file(unit1: bytes, unit2: bytes, reference: int) -> bytes:
    """Two channels of time records in 2 scans; channel ``reference`` is marked as the
    reference channel. Stored float32: scan s, channel c: [10 s + c, 10 s + c + 0.5]."""
    rev = 3
    channels = [
        channel_hdr(rev, "Ch1", eng=unit1, attribute=2 if reference == 0 else 0),
        channel_hdr(rev, "Ch2", eng=unit2, attribute=2 if reference == 1 else 0),
    ]
    dh = data_hdr(rev, n_points=2, rows=2, domain=1, data_type=0, first_x=-0.5, delta_x=0.25, scan_data=1)
    y = values([0, 0.5, 1, 1.5, 10, 10.5, 11, 11.5], ">f4")
    scans = scan_struct(2, 1, 0, 3, values([1, 2], ">f4"), unit("count"))
    return assemble(
        rev, meas_hdr(rev), [dh], [vector_hdr(0), vector_hdr(1)], channels, block(YDATA, y), scans=scans
    )


def test_time_records_in_volts_take_the_reference_channel_as_force(tmp_path):
    imported = read_sdf_run(write(tmp_path, _time_file(VOLT, VOLT, reference=1)))
    hits = imported.hits
    # Force = channel 2 (the reference): [1, 1.5], [11, 11.5]; response = channel 1.
    np.testing.assert_array_equal(hits.force_n, [[1.0, 1.5], [11.0, 11.5]])
    np.testing.assert_array_equal(hits.response_m_s2, [[0.0, 0.5], [10.0, 10.5]])
    assert (hits.sample_rate_hz, hits.start_s, hits.center_hz) == (4.0, -0.5, 0.0)
    assert hits.accepted.all()
    assert "values kept" in imported.details["time_units"]["force"]
    assert imported.details["force_channel"] == "Ch2"


@pytest.mark.parametrize(
    ("label", "factor"),
    [
        # HP's label for g, known as g by its label: exactly 9.80665 m/s^2.
        ("g's", 9.80665),
        # A label no reader knows: the SDF unit's dimensions and its own factor, a float32.
        ("EU", float(np.float32(9.80665))),
    ],
)
def test_time_records_in_force_and_acceleration_units_become_si(tmp_path, label, factor):
    g_unit = unit(label, 9.80665, (0, 2, -4, 0, 0, 0, 0, 0))
    imported = read_sdf_run(write(tmp_path, _time_file(g_unit, unit("lbf", 4.4482), reference=0)))
    hits = imported.hits
    # Force is the lbf channel (2) although channel 1 is marked as reference: units first.
    np.testing.assert_array_equal(hits.force_n, np.array([[1.0, 1.5], [11.0, 11.5]]) * POUND_FORCE_N)
    np.testing.assert_array_equal(hits.response_m_s2, np.array([[0.0, 0.5], [10.0, 10.5]]) * factor)


def test_spectra_alone_become_the_runs_spectra_not_frfs(tmp_path):
    rev = 2
    data = [
        data_hdr(rev, n_points=2, title="Pwr Spec 1", data_type=2),
        data_hdr(rev, n_points=2, first_vector=1, title="Cross Spec", data_type=3, complex=1),
        data_hdr(rev, n_points=2, first_vector=2, title="Coherence", data_type=8),
    ]
    vectors = [vector_hdr(0, -1, 96, 0), vector_hdr(1, 0, 48, 48), vector_hdr(1, 0, 0, 0)]
    y = values([1, 2], ">f4") + values([1, 0, 0, 1], ">f4") + values([0.5, 0.25], ">f4")
    channels = [channel_hdr(rev), channel_hdr(rev, eng=unit("g", 9.80665, (0, 2, -4, 0, 0, 0, 0, 0)))]
    path = write(
        tmp_path, assemble(rev, meas_hdr(rev, start=0, stop=1), data, vectors, channels, block(YDATA, y))
    )
    imported = read_sdf_run(path)
    assert imported.hits is None
    assert imported.measured_frfs is None
    spectra = imported.spectra
    assert spectra.kinds == ["power", "cross", "coherence"]
    # Channel 1 in V, channel 2 in g: the cross spectrum becomes V * m/s^2.
    assert spectra.units == ["V^2", "(m/s^2)*V", ""]
    assert spectra.labels == ["Pwr Spec 1", "Cross Spec", "Coherence"]
    assert spectra.values.dtype == np.complex128  # one cross spectrum: every trace complex
    np.testing.assert_array_equal(spectra.frequency_hz, [0.0, 1.0])
    np.testing.assert_allclose(spectra.values, [[1, 2], [9.80665, 9.80665j], [0.5, 0.25]], rtol=1e-15)


def test_a_file_with_nothing_a_run_holds_is_refused_with_what_it_holds(tmp_path):
    rev = 2
    data = [data_hdr(rev, n_points=2, domain=1, title="Auto Corr", data_type=5)]
    path = write(
        tmp_path,
        assemble(rev, meas_hdr(rev), data, [vector_hdr(0, -1, 96, 0)], [channel_hdr(rev)],
                 block(YDATA, values([1, 2], ">f4"))),
    )  # fmt: skip
    with pytest.raises(FormatError) as info:
        read_sdf_run(path)
    message = str(info.value)
    assert message.startswith(f"{path}: nothing to import as a run")
    assert "auto-correlation data header ('Auto Corr')" in message


def test_one_channel_of_time_records_is_refused(tmp_path):
    rev = 2
    dh = data_hdr(rev, n_points=2, domain=1, data_type=0)
    path = write(
        tmp_path,
        assemble(rev, meas_hdr(rev), [dh], [vector_hdr(0)], [channel_hdr(rev)], block(YDATA, bytes(8))),
    )
    with pytest.raises(FormatError, match="time records are of 1 channel"):
        read_sdf_run(path)


def test_time_records_in_volts_are_said_on_stderr_when_imported(tmp_path):
    path = write(tmp_path, _time_file(VOLT, VOLT, reference=1))
    result = invoke_daq("import", str(path), "--format", "sdf", "--store", str(tmp_path / "store"))
    assert result.returncode == 0, result.stderr
    warnings = result.stderr.splitlines()
    assert len(warnings) == 2, result.stderr  # force and response, each in volts
    assert all(w.startswith("warning: channel ") and "(stored under the SI label)" in w for w in warnings)
