"""The form of stored FRFs (receptance, mobility, accelerance): sealed and read back,
checked by verify(), shown by `daq runs show`, and accelerance for runs written before
FRFs had a form."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from daq.store import SCHEMA_VERSION, MeasuredFrf, open_run, seal, verify
from daq.store.layout import SCHEMA_VERSION_FRF_FORMS
from tests.cli_helpers import invoke_daq
from tests.store.store_helpers import make_frf, make_run


def with_form(form: str) -> MeasuredFrf:
    frf = make_frf(n_frf=2, n_lines=51)
    return MeasuredFrf(frf.frequency_hz, frf.frf, frf.coherence, frf.labels, form=form)


@pytest.mark.parametrize(
    ("form", "units"), [("receptance", "m/N"), ("mobility", "(m/s)/N"), ("accelerance", "(m/s^2)/N")]
)
def test_form_round_trips_with_its_unit(tmp_path, form, units):
    run = make_run(kind="imported", measured=with_form(form))
    path = seal(run, tmp_path / "store")
    assert verify(path) == []
    back = open_run(path)
    assert back.measured_frfs.form == form
    np.testing.assert_array_equal(back.measured_frfs.frf, run.measured_frfs.frf)
    with h5py.File(path, "r") as f:
        assert f["entry/measured_frf"].attrs["form"] == form.encode()
        assert f["entry/measured_frf/frf"].attrs["units"] == units.encode()
        # Only a run an older reader would misread (not accelerance) gets the new version.
        want = SCHEMA_VERSION if form == "accelerance" else SCHEMA_VERSION_FRF_FORMS
        assert int(f.attrs["schema_version"]) == want


def test_a_run_without_form_reads_as_accelerance(tmp_path):
    path = seal(make_run(kind="imported", measured=with_form("accelerance")), tmp_path / "store")
    copy = tmp_path / path.name
    copy.write_bytes(path.read_bytes())
    with h5py.File(copy, "a") as f:
        del f["entry/measured_frf"].attrs["form"]
    assert open_run(copy).measured_frfs.form == "accelerance"


def test_unknown_form_refused():
    frf = make_frf(n_frf=1, n_lines=5)
    with pytest.raises(ValueError, match="inertance"):
        MeasuredFrf(frf.frequency_hz, frf.frf, None, frf.labels, form="inertance")


def test_damaged_form_attribute_is_reported(tmp_path):
    path = seal(make_run(kind="imported", measured=with_form("mobility")), tmp_path / "store")
    copy = tmp_path / path.name
    copy.write_bytes(path.read_bytes())
    with h5py.File(copy, "a") as f:
        f["entry/measured_frf"].attrs["form"] = np.bytes_(b"inertance")
    problems = verify(copy)
    assert problems
    assert "inertance" in problems[0]


def test_runs_show_says_the_form(tmp_path):
    store = tmp_path / "store"
    run = make_run(kind="imported", measured=with_form("receptance"))
    seal(run, store)
    result = invoke_daq("runs", "show", run.run_id, "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert "receptance (m/N)" in result.stdout
