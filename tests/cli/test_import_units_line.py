"""The import's units line reads cleanly when an option wins over the header's unit:
one pair of brackets per column, not 'mV@10.2mV/g (option (the header says mV))'."""

from __future__ import annotations

from tests.cli_helpers import invoke_daq


def test_an_option_over_the_headers_unit_is_said_without_nested_brackets(tmp_path):
    path = tmp_path / "mv.csv"
    rows = ["Time (s),Force [N],acc [mV]"] + [
        f"{i / 1024:.9g},{1.0 if i == 2 else 0.0},{(-1) ** i}" for i in range(64)
    ]
    path.write_text("\n".join(rows) + "\n")
    result = invoke_daq(
        "import", str(path), "--response-unit", "mV@10.2mV/g", "--store", str(tmp_path / "runs")
    )
    assert result.returncode == 0, result.stderr
    (units,) = [line for line in result.stdout.splitlines() if line.startswith("units: ")]
    assert units == "units: time s, force N (header), response mV@10.2mV/g (option; the header says mV)"
    assert "((" not in units
    assert "))" not in units


def test_an_frf_form_option_over_the_units_row_is_said_without_nested_option_brackets(tmp_path):
    path = tmp_path / "frf.csv"
    rows = ["Frequency (Hz),H1 Re [(m/s^2)/N],H1 Im [(m/s^2)/N]"]
    rows += [f"{f},{1.0 / (1 + f)},{-0.5 / (1 + f)}" for f in range(0, 200, 2)]
    path.write_text("\n".join(rows) + "\n")
    result = invoke_daq("import", str(path), "--frf-form", "mobility", "--store", str(tmp_path / "runs"))
    assert result.returncode == 0, result.stderr
    (form,) = [line for line in result.stdout.splitlines() if line.startswith("form: ")]
    assert form.startswith("form: mobility (option; the header says ")
