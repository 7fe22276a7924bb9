"""FRF exports whose preamble lines are quoted (Brüel & Kjær PULSE, Siemens Test.Lab) and
whose columns are named by their units alone ("Hz", "dB re 1 (m/s²)/N", "°").

A new user's PULSE-like export was refused as a time record with "1 data column", and a
Test.Lab-like one with "line 2: 3 columns, expected 2"; the same tables without quotes
imported."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.csv_text import is_number_text
from daq.formats.frf_text import read_frf_text
from tests.cli_helpers import daq_import, runs_in

LINES = 48
F = np.arange(1, LINES + 1) * 0.5
H = (1.0 + 0.2 * np.arange(LINES)) * np.exp(1j * np.linspace(-3.0, 3.0, LINES))


def pulse_like(path, phase_name: str = "°", phase_scale: float = 1.0) -> None:
    """Tab separated, decimal commas, quoted title and key/value lines, columns named by
    their units; magnitude in dB re 1 (m/s²)/N, phase in degrees (times phase_scale)."""
    head = [
        '"Frequency Response H1(Response,Hammer) - Mark 1 (Magnitude/Phase)"',
        '"Measurement:\tImpact test beam"',
        '"Averages:\t5"',
        "",
        f'"Hz"\t"dB re 1 (m/s²)/N"\t"{phase_name}"',
    ]
    db = 20 * np.log10(np.abs(H))
    phase = np.degrees(np.angle(H)) * phase_scale
    rows = [
        "\t".join(f"{v:.10f}".replace(".", ",") for v in (f, m, p))
        for f, m, p in zip(F, db, phase, strict=True)
    ]
    path.write_bytes(("\r\n".join(head + rows) + "\r\n").encode("latin-1"))


def write_testlab_like(path, preamble: list[tuple[str, ...]]) -> None:
    """Comma separated, each preamble line a row of quoted cells, then Re/Im in g/N."""
    head = [",".join(f'"{c}"' for c in cells) for cells in preamble]
    head += ["", '"Frequency (Hz)","FRF Real (g/N)","FRF Imaginary (g/N)"']
    rows = [f"{float(f)!r},{float(v.real)!r},{float(v.imag)!r}" for f, v in zip(F, H, strict=True)]
    path.write_text("\n".join(head + rows) + "\n", encoding="utf-8")


def test_a_pulse_like_export_reads_its_quoted_preamble_and_unit_named_columns(tmp_path):
    pulse_like(tmp_path / "h1.txt")
    data = read_frf_text(tmp_path / "h1.txt")
    assert data.measured_frfs.form == "accelerance"
    np.testing.assert_allclose(data.measured_frfs.frequency_hz, F)
    np.testing.assert_allclose(data.measured_frfs.frf[0], H, rtol=1e-8)
    assert "(m/s^2)/N" in data.details["form_from"]


def test_a_column_named_rad_alone_is_read_in_radians(tmp_path):
    pulse_like(tmp_path / "h1.txt", phase_name="rad", phase_scale=np.pi / 180)
    np.testing.assert_allclose(read_frf_text(tmp_path / "h1.txt").measured_frfs.frf[0], H, rtol=1e-8)


def test_a_testlab_like_export_is_detected_and_imported(tmp_path):
    path = tmp_path / "frf.csv"
    write_testlab_like(
        path, [("Name", "FRF Point1:+Z/Point1:+Z"), ("X axis", "Frequency", "Hz"), ("Averages", "5")]
    )
    store = tmp_path / "runs"
    result = daq_import(store, path)
    assert result.returncode == 0, result.stderr
    assert "frf-text" in result.stdout
    assert "3 preamble lines" in result.stdout
    assert len(runs_in(store)) == 1


def test_a_time_record_with_a_quoted_header_is_still_a_time_record(tmp_path):
    t = np.arange(256) / 256.0
    rows = [
        f"{x:.6f},{100.0 if k == 3 else 0.0},{np.exp(-3 * x) * np.sin(2 * np.pi * 20 * x):.6g}"
        for k, x in enumerate(t)
    ]
    path = tmp_path / "hit.csv"
    path.write_text('"Time (s)","Force (N)","Accel (m/s^2)"\n' + "\n".join(rows) + "\n", encoding="utf-8")
    result = daq_import(tmp_path / "runs", path)
    assert result.returncode == 0, result.stderr
    assert "csv: 1 hit of 256 samples" in result.stdout


#: A preamble cell: text, never a number ("INF" is one: a row of numbers is data).
CELL = st.text(
    st.characters(codec="latin-1", exclude_characters='"\r\n\t,;'), min_size=1, max_size=12
).filter(lambda s: s.strip() != "" and not s.strip()[0].isdigit() and not is_number_text(s))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(preamble=st.lists(st.lists(CELL, min_size=2, max_size=4).map(tuple), min_size=1, max_size=6))
def test_any_quoted_preamble_leaves_the_frf_as_without_it(tmp_path, preamble):
    path = tmp_path / "frf.csv"
    write_testlab_like(path, preamble)
    frfs = read_frf_text(path).measured_frfs
    np.testing.assert_allclose(frfs.frequency_hz, F)
    np.testing.assert_allclose(frfs.frf[0], H * 9.80665, rtol=1e-12)


@pytest.mark.parametrize("title", ['"Frequency Response H1"', '"Key:\tvalue"', '"Name","value"'])
def test_each_quoted_line_kind_alone_is_a_preamble(tmp_path, title):
    path = tmp_path / "frf.csv"
    rows = [f"{float(f)!r},{float(v.real)!r},{float(v.imag)!r}" for f, v in zip(F, H, strict=True)]
    path.write_text(
        f'{title}\n"Frequency (Hz)","Re (g/N)","Im (g/N)"\n' + "\n".join(rows) + "\n", encoding="utf-8"
    )
    np.testing.assert_allclose(read_frf_text(path).measured_frfs.frf[0], H * 9.80665, rtol=1e-12)


@pytest.mark.parametrize(
    ("unit", "factor"),
    [("((in/s²)/lbf)", 0.0254 / (0.45359237 * 9.80665)), ("((g)/N)", 9.80665), ("[(m/s²)/N]", 1.0)],
)
def test_a_unit_with_parentheses_inside_is_read(tmp_path, unit, factor):
    path = tmp_path / "frf.csv"
    write_testlab_like(path, [("Name", "FRF Point1:+Z/Point1:+Z")])
    text = path.read_text(encoding="utf-8").replace("(g/N)", unit)
    path.write_text(text, encoding="utf-8")
    frfs = read_frf_text(path).measured_frfs
    # Before: "nothing in the file says", the values stored as (m/s^2)/N, 175 times off in lbf.
    np.testing.assert_allclose(frfs.frf[0], H * factor, rtol=1e-12)


def _bare_columns(path, preamble: list[str]) -> None:
    rows = [f"{float(f) / 1000.0!r},{float(v.real)!r},{float(v.imag)!r}" for f, v in zip(F, H, strict=True)]
    path.write_text("\n".join([*preamble, '"Frequency","Real","Imaginary"', *rows]) + "\n", encoding="utf-8")


def test_units_only_the_preamble_states_are_used(tmp_path):
    path = tmp_path / "frf.csv"
    _bare_columns(
        path, ['"Name","FRF Point1:+Z/Point1:+Z"', '"X axis","Frequency","kHz"', '"Y axis","FRF","g/N"']
    )
    data = read_frf_text(path)
    # Before: a 120 Hz mode at 0.12 Hz, and g/N stored as (m/s^2)/N, with no word of either.
    np.testing.assert_allclose(data.measured_frfs.frequency_hz, F, rtol=1e-12)
    np.testing.assert_allclose(data.measured_frfs.frf[0], H * 9.80665, rtol=1e-12)
    assert data.details["form_from"] == "preamble's 'Y axis' (g/N)"
    assert "frequency in kHz, as the preamble's 'X axis' says" in data.details["notes"]
    assert data.details["preamble"]["Name"] == "FRF Point1:+Z/Point1:+Z"


def test_a_pulse_y_axis_unit_line_in_quotes_is_used(tmp_path):
    path = tmp_path / "h1.txt"
    rows = [f"{float(f)!r}\t{float(v.real)!r}\t{float(v.imag)!r}" for f, v in zip(F, H, strict=True)]
    head = ['"Frequency Response H1"', '"Y-Axis Unit:\tg/N"', "", '"Hz"\t"Real"\t"Imaginary"']
    path.write_text("\n".join(head + rows) + "\n", encoding="utf-8")
    data = read_frf_text(path)
    np.testing.assert_allclose(data.measured_frfs.frf[0], H * 9.80665, rtol=1e-12)
    assert data.details["form_from"] == "preamble's 'Y-Axis Unit' (g/N)"


def test_a_signalcalc_units_ratio_line_states_no_unit(tmp_path):
    path = tmp_path / "Hxysv.txt"
    rows = [f"{float(f)!r}\t{float(v.real)!r}\t{float(v.imag)!r}" for f, v in zip(F, H, strict=True)]
    path.write_text(
        "\n".join(["Units: Ratio", "", "Frequency\tReal\tImaginary", *rows]) + "\n", encoding="utf-8"
    )
    data = read_frf_text(path)
    np.testing.assert_allclose(data.measured_frfs.frf[0], H, rtol=1e-12)
    assert data.details["form_from"].startswith("default")


def test_pulse_columns_named_khz_and_by_a_linear_frf_unit(tmp_path):
    # Refused before: '"kHz"' as no frequency ("1 data column"), '"(m/s²)/N"' as no column kind.
    head = ['"Frequency Response H1"', '"Averages:\t5"', "", '"kHz"\t"(m/s²)/N"\t"°"']
    rows = [
        f"{float(f) / 1000.0!r}\t{float(abs(v))!r}\t{float(np.degrees(np.angle(v)))!r}"
        for f, v in zip(F, H, strict=True)
    ]
    path = tmp_path / "h1.txt"
    path.write_text("\n".join(head + rows) + "\n", encoding="utf-8")
    store = tmp_path / "runs"
    result = daq_import(store, path)
    assert result.returncode == 0, result.stderr
    data = read_frf_text(path)
    np.testing.assert_allclose(data.measured_frfs.frequency_hz, F, rtol=1e-12)
    np.testing.assert_allclose(data.measured_frfs.frf[0], H, rtol=1e-9)
    assert data.details["form_from"] == "header ((m/s^2)/N)"


def test_a_time_record_behind_a_quoted_title_and_key_line_is_read(tmp_path):
    t = np.arange(256) / 256.0
    rows = [f"{x:.6f},{100.0 if k == 3 else 0.0},{np.sin(2 * np.pi * 20 * x):.6g}" for k, x in enumerate(t)]
    head = ['"Impact test, beam 2"', '"Operator:\tme"', '"Time (s)","Force (N)","Accel (m/s^2)"']
    path = tmp_path / "hit.csv"
    path.write_text("\n".join(head + rows) + "\n", encoding="utf-8")
    result = daq_import(tmp_path / "runs", path)
    # Before: "has 1 data column", the title read as the header.
    assert result.returncode == 0, result.stderr
    assert "csv: 1 hit of 256 samples" in result.stdout
    assert "preamble lines 1, 2 skipped" in result.stdout
