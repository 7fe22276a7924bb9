"""Any input gives ImportedData or a one-line FormatError naming the file: never anything else."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError
from daq.formats.imported import ImportedData
from daq.formats.uff58 import read_uff
from daq.formats.uff58_export import write_uff
from daq.store.ids import new_run_id
from daq.store.model import Hits, MeasuredFrf, Run

SETTINGS = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="formats-hypothesis-"))

# Text that looks like our CSV often enough to get past the first checks.
CSV_ALPHABET = st.sampled_from([*list("0123456789.,;-+eE \t\n#=:"), "nan", "inf", "hit", "time", "x", "\r"])
csv_like = st.lists(CSV_ALPHABET, max_size=200).map("".join)


def outcome(reader, path: Path, **kwargs) -> None:
    try:
        result = reader(path, **kwargs)
    except FormatError as exc:
        message = str(exc)
        assert "\n" not in message
        assert "\r" not in message
        assert str(path) in message
        return
    assert isinstance(result, ImportedData)
    if result.hits is not None:
        assert np.all(np.isfinite(result.hits.force_n))
        assert result.hits.sample_rate_hz > 0


def put(data: bytes, name: str) -> Path:
    path = WORK / name
    path.write_bytes(data)
    return path


@SETTINGS
@given(text=st.one_of(st.text(max_size=300), csv_like))
def test_read_csv_any_text(text):
    outcome(read_csv, put(text.encode("utf-8", "surrogatepass"), "t.csv"))


@SETTINGS
@given(
    data=st.binary(max_size=300),
    columns=st.one_of(st.none(), st.sampled_from(["0,1,2", "2,1,0", "t,F,a", "9,1,2"])),
)
def test_read_csv_any_bytes(data, columns):
    outcome(read_csv, put(data, "b.csv"), columns=columns)


@SETTINGS
@given(data=st.binary(max_size=600))
def test_read_uff_any_bytes(data):
    outcome(read_uff, put(data, "b.uff"))


def _valid_uff() -> bytes:
    rng = np.random.default_rng(0)
    n = 16
    hits = Hits(
        force_n=rng.normal(size=(2, n)),
        response_m_s2=rng.normal(size=(2, n)),
        sample_rate_hz=256.0,
        start_s=-0.125,
        center_hz=0.0,
        accepted=np.ones(2, dtype=bool),
        reject_reason=["", ""],
        overload=np.zeros((2, 2), dtype=bool),
        peak_force_n=np.ones(2),
        timestamp_utc=["2026-11-23T10:15:03Z"] * 2,
        checks=[{}, {}],
    )
    freq = np.arange(1.0, 9.0)
    frf = MeasuredFrf(freq, rng.normal(size=(1, 8)) + 1j, rng.uniform(size=(1, 8)), ["H21"])
    run = Run(
        new_run_id(),
        "captured",
        True,
        "2026-11-23T10:15:03Z",
        "2026-11-23T10:15:04Z",
        hits=hits,
        analyzer=frf,
    )
    path = WORK / "valid.uff"
    write_uff(run, path)
    return path.read_bytes()


VALID = _valid_uff()


def test_valid_uff_reads():
    assert read_uff(put(VALID, "v.uff")).hits.n_hits == 2


@SETTINGS
@given(cut=st.integers(min_value=1, max_value=len(VALID)))
def test_read_uff_truncated(cut):
    outcome(read_uff, put(VALID[:cut], "cut.uff"))


@SETTINGS
@given(
    flips=st.lists(
        st.tuples(
            st.integers(min_value=0, max_value=len(VALID) - 1), st.integers(min_value=0, max_value=255)
        ),
        min_size=1,
        max_size=8,
    )
)
def test_read_uff_mutated(flips):
    data = bytearray(VALID)
    for index, value in flips:
        data[index] = value
    outcome(read_uff, put(bytes(data), "flip.uff"))


@SETTINGS
@given(
    index=st.integers(min_value=0, max_value=len(VALID) - 1),
    text=st.sampled_from([b"nan", b"inf", b"-1", b"    -1\n", b"\n", b"58b", b"99999999", b"0"]),
)
def test_read_uff_spliced(index, text):
    # Header fields overwritten with edge values: NaN steps, negative counts, block markers.
    outcome(read_uff, put(VALID[:index] + text + VALID[index + len(text) :], "splice.uff"))
