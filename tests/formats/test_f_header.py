"""A header "f, Re, Im" names an FRF table; "f" beside time-record columns does not.

"f" alone is the frequency only where every other column names an FRF quantity: in a time
record's header "F" is the force (`t,F,a`), so the rule looks at the whole header.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.cli.commands.import_file import detect_format
from daq.formats.frf_text import read_frf_text

FRF_PAIRS = [
    ("Re", "Im"),
    ("re", "im"),
    ("real", "imag"),
    ("mag (dB)", "phase (deg)"),
    ("Mag", "Phase [deg]"),
]
TIME_NAMES = ["Force", "acc", "a", "response", "force (N)", "acc (g)"]


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    f_name=st.sampled_from(["f", "F", "f [Hz]", "F (kHz)"]),
    pairs=st.lists(st.sampled_from(FRF_PAIRS), min_size=1, max_size=3),
    delimiter=st.sampled_from([",", ";", "\t"]),
)
def test_f_then_frf_columns_is_an_frf_table(tmp_path_factory, f_name, pairs, delimiter):
    path = Path(tmp_path_factory.mktemp("f")) / "table.txt"
    header = [f_name] + [name for pair in pairs for name in pair]
    rows = [[str(1.0 + k)] + ["1"] * (len(header) - 1) for k in range(10)]
    path.write_text("\n".join(delimiter.join(r) for r in [header, *rows]) + "\n")
    kind, why = detect_format(path)
    assert kind == "frf-text", why
    data = read_frf_text(path, "accelerance")
    scale = 1000.0 if "kHz" in f_name else 1.0
    np.testing.assert_allclose(data.measured_frfs.frequency_hz, scale * (1.0 + np.arange(10)))
    assert data.measured_frfs.frf.shape == (len(pairs), 10)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(names=st.lists(st.sampled_from(TIME_NAMES), min_size=2, max_size=3))
def test_f_beside_time_record_columns_is_no_frequency(tmp_path_factory, names):
    path = Path(tmp_path_factory.mktemp("f")) / "hits.csv"
    path.write_text(
        ",".join(["F", *names]) + "\n" + "".join(f"{k},1,2{',3' * (len(names) - 1)}\n" for k in range(3))
    )
    assert detect_format(path)[0] == "csv"


def test_f_with_a_unit_that_is_no_frequency_is_no_frequency(tmp_path):
    path = tmp_path / "table.csv"
    path.write_text("f (N),re,im\n" + "".join(f"{k},1,0\n" for k in range(1, 10)))
    assert detect_format(path)[0] == "csv"
