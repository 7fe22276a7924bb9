"""A UFF 58 time record's sample rate from its printed abscissa increment (hypothesis):
the header prints the increment to 6 significant digits (E13.5), so 4096 Hz comes back as
1/2.44141e-04 = 4095.99 Hz. Where the printed digits allow exactly one whole number of
hertz, that rate is stored, with a note saying why; a rate that is not whole and has no
whole number within the printed precision is stored as printed, without a note; our own
export's exact rate in the ID lines still wins. Before, 4095.99 Hz was stored silently."""

from __future__ import annotations

import gc
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pyuff
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.uff58 import read_uff

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="uff-increment-"))


def _record(kind: int, data: np.ndarray, rate: float, binary: int, id4: str) -> dict:
    dset = pyuff.prepare_58(
        binary=binary, id1="hit", id4=id4, func_type=1, rsp_node=1, rsp_dir=3, ref_node=1, ref_dir=3,
        abscissa_spacing=1, abscissa_spec_data_type=17, ordinate_spec_data_type=kind,
        orddenom_spec_data_type=0, z_axis_spec_data_type=0, data=data,
        x=np.arange(data.size) / rate,
    )  # fmt: skip
    dset["ordinate_axis_units_lab"] = "N" if kind == 13 else "m/s^2"
    return dset


def _write(rate: float, n: int, binary: int, id4: str = "NONE") -> Path:
    force = np.zeros(n)
    force[3] = 50.0
    response = np.sin(0.3 * np.arange(n))
    path = WORK / f"hits-{binary}.uff"
    path.unlink(missing_ok=True)
    with warnings.catch_warnings():
        # pyuff's binary writer leaves a file object for the garbage collector.
        warnings.simplefilter("ignore", ResourceWarning)
        pyuff.UFF(str(path)).write_sets(
            [_record(13, force, rate, binary, id4), _record(12, response, rate, binary, id4)], mode="add"
        )
        gc.collect()
    return path


def _printed(rate: float) -> float:
    """The increment as the header prints it, read back (s)."""
    return float(f"{1.0 / rate:.5e}")


def _notes(details: dict) -> list[str]:
    return [n for n in details["notes"] if n.startswith("sample rate ")]


@SETTINGS
@given(rate=st.integers(100, 50_000), n=st.integers(64, 600), binary=st.sampled_from([0, 1]))
def test_a_whole_rate_printed_to_6_digits_comes_back_whole(rate, n, binary):
    data = read_uff(_write(float(rate), n, binary))
    assert data.hits.sample_rate_hz == rate
    if 1.0 / _printed(rate) == rate:  # printed exactly (4000 Hz: 2.50000e-04): nothing to say
        assert _notes(data.details) == []
        return
    (note,) = _notes(data.details)
    assert note.startswith(f"sample rate {rate} Hz: the abscissa increment {1.0 / rate:.5e} s, printed to 6 ")
    assert note.endswith(f"{rate} Hz, the one whole number of hertz among them, is stored")


@SETTINGS
@given(
    whole=st.integers(100, 20_000),
    fraction=st.floats(0.25, 0.75),
    binary=st.sampled_from([0, 1]),
)
def test_a_rate_with_no_whole_number_in_reach_is_kept(whole, fraction, binary):
    rate = whole + fraction
    data = read_uff(_write(rate, 64, binary))
    assert data.hits.sample_rate_hz == 1.0 / _printed(rate)
    assert _notes(data.details) == []
    # Our export's exact rate in an ID line wins, whole or not.
    exact = read_uff(_write(rate, 64, binary, id4=f"sample_rate_hz={rate!r} start_s=0.0"))
    assert exact.hits.sample_rate_hz == rate
    assert _notes(exact.details) == []
    whole_exact = read_uff(
        _write(float(whole), 64, binary, id4=f"sample_rate_hz={float(whole)!r} start_s=0.0")
    )
    assert whole_exact.hits.sample_rate_hz == whole
    assert _notes(whole_exact.details) == []
    # ... and without it, the whole rate comes back whole: the same reader, the same file shape.
    assert read_uff(_write(float(whole), 64, binary)).hits.sample_rate_hz == whole
