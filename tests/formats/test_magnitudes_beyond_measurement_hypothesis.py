"""Values no instrument records (hypothesis): a channel scaled by 1e306 or 1e-300, or one
sample of 1e300, as a wrong unit or a broken export gives them (a new user's trial). The
import stored them without a word; `daq analyze` then printed ten numpy warnings and
"Singular matrix", or called the force "no force". Now the import refuses them in one line
naming the channel and where, and stores nothing; values within 1e-100..1e100 pass."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.imported import MAX_MAGNITUDE, MIN_MAGNITUDE
from daq.store import Store
from tests.analysis.impact_synth import impact_hits
from tests.cli_helpers import invoke_daq

SETTINGS = settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
RATE_HZ = 1024.0


def _write_hits(path, force, response):
    t = (np.arange(force.shape[1]) / RATE_HZ).tolist()
    rows = ["hit,time,force,response"]
    for k in range(force.shape[0]):
        f, r = force[k].tolist(), response[k].tolist()
        rows += [f"{k},{t[i]!r},{f[i]!r},{r[i]!r}" for i in range(len(t))]
    path.write_text("\n".join(rows) + "\n")


def _hits():
    return impact_hits([45.0, 120.0], [0.01, 0.01], [1.0, 0.5], RATE_HZ, 0.5, 2, 0.01, 0.003, 4)


@SETTINGS
@given(
    exponent=st.sampled_from([101, 150, 200, 306, -101, -200, -300]),
    channel=st.sampled_from(["force", "response"]),
    whole=st.booleans(),
)
def test_a_channel_beyond_any_measurement_is_refused_and_nothing_stored(
    tmp_path_factory, exponent, channel, whole
):
    work = tmp_path_factory.mktemp("mag")
    force, response = _hits()
    values = force if channel == "force" else response
    if whole or exponent < 0:
        values *= 10.0**exponent / np.max(np.abs(values))  # the whole channel scaled
    else:
        values[1, 300] = 10.0**exponent  # one sample of a hit
    _write_hits(work / "f.csv", force, response)
    result = invoke_daq("import", str(work / "f.csv"), "--store", str(work / "store"))
    assert result.returncode == 1
    (line,) = result.stderr.splitlines()
    assert f"the {channel} " in line
    assert ("beyond any measurement" if exponent > 0 else "below any measurement") in line
    if not whole and exponent > 0:
        assert "(hit 2, sample 301)" in line
    assert not (work / "store").exists() or Store(work / "store").list() == []


@pytest.mark.parametrize(
    "scale", [10.0 ** (np.log10(MAX_MAGNITUDE) - 1), 10.0 ** (np.log10(MIN_MAGNITUDE) + 1)]
)
def test_values_within_the_bounds_are_imported(tmp_path, scale):
    force, response = _hits()
    response *= scale / np.max(np.abs(response))
    _write_hits(tmp_path / "f.csv", force, response)
    result = invoke_daq("import", str(tmp_path / "f.csv"), "--store", str(tmp_path / "store"))
    assert result.returncode == 0, result.stderr


def test_an_frf_table_beyond_any_measurement_is_refused(tmp_path):
    freq = np.arange(1.0, 65.0)
    h = np.ones(64) * (1 + 1j)
    h[10] = 1e200
    rows = ["freq (Hz),H Re,H Im"] + [
        f"{f!r},{v.real!r},{v.imag!r}" for f, v in zip(freq.tolist(), h.tolist(), strict=True)
    ]
    (tmp_path / "h.csv").write_text("\n".join(rows) + "\n")
    result = invoke_daq("import", str(tmp_path / "h.csv"), "--store", str(tmp_path / "store"))
    assert result.returncode == 1
    (line,) = result.stderr.splitlines()
    assert "the FRF reaches 1e+200 in its form's SI unit (at 11 Hz)" in line
