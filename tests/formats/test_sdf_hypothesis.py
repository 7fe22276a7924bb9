"""Property tests: random valid SDF files (every revision, number type, x axis kind, scan
order) written and read back give the same headers and values; random damage to valid
files never raises anything but a one-line FormatError, from the reader or the import."""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.errors import FormatError
from daq.formats.sdf import (
    Channel,
    Comment,
    DataHeader,
    Scans,
    ScanVariable,
    SdfFile,
    Unit,
    Vector,
    Window,
    codes,
    parse_sdf,
    read_sdf_run,
)
from daq.formats.sdf.convert import integer_scaling, vector_factor
from daq.formats.sdf.run_export import sdf_of_run
from daq.formats.sdf.writer import encode_sdf
from tests.formats.sdf_builder import frf_file, full_file
from tests.store.store_helpers import make_frf, make_hits, make_run

REAL = Path(__file__).resolve().parents[1] / "data" / "sdf" / "SDF3KHZ.DAT"
TEXT = st.text(alphabet="abcXYZ 019_-/^", max_size=9)
POWERS_OF_TWO = st.sampled_from([1.0, 2.0, 0.5, 0.25, 4.0])


@st.composite
def channels(draw) -> Channel:
    corr = draw(st.sampled_from([0, 1, 2]))
    window = Window(1, corr, 1.5, 0.0, 0.0, draw(POWERS_OF_TWO), draw(POWERS_OF_TWO))
    return Channel(
        label=draw(TEXT),
        window=window,
        eng_unit=Unit(
            draw(TEXT), draw(POWERS_OF_TWO), tuple(draw(st.lists(st.integers(-6, 6), min_size=8, max_size=8)))
        ),
        int2engr=draw(st.sampled_from([1.0, 2.0, 0.5, -4.0])),
        scale=draw(st.sampled_from([1.0, 0.5, 2.0**-10])),
        offset=draw(st.sampled_from([0.0, 0.25, -8.0])),
    )


@st.composite
def sdf_files(draw) -> tuple[SdfFile, int]:
    rev = draw(st.sampled_from([1, 2, 3]))
    chans = draw(st.lists(channels(), min_size=1, max_size=3))
    if rev == 1:  # no channelScale / channelOffset fields in revision 1
        for channel in chans:
            channel.scale, channel.offset = 1.0, 0.0
    n_data = draw(st.integers(1, 3))
    scans = None
    scanned = [False] * n_data
    if draw(st.booleans()):
        n_scans = draw(st.integers(1, 3))
        scan_type = draw(st.sampled_from([codes.DEPTH, codes.SCAN]))
        if rev == 1:
            scanned = [True] * n_data
        else:
            a = draw(st.integers(0, n_data - 1))
            b = draw(st.integers(a + 1, n_data))
            scanned = [a <= k < b for k in range(n_data)]  # consecutive, as scan order needs
        variables = [
            ScanVariable(np.arange(n_scans, dtype=np.float64) * 2, draw(st.sampled_from([1, 2, 3, 4])))
        ]
        if rev == 3 and draw(st.booleans()):
            variables.append(
                ScanVariable(np.arange(n_scans) + 0.5, codes.FLOAT64, Unit("rpm"), "speed", 3, 1, 0)
            )
        scans = Scans(n_scans, n_scans - 1, scan_type, variables)
    shared = shared_x = None
    data = []
    for k in range(n_data):
        n_points = draw(st.integers(1, 5))
        x_resolution = draw(st.sampled_from([0, 1, 2, 3, 4]))
        xdata_type = draw(st.sampled_from([1, 2, 3, 4]))
        if x_resolution == 2:
            shared = shared or (n_points, xdata_type)
            n_points, xdata_type = shared
        n_vectors = draw(st.integers(1, 3))
        vectors = [
            Vector(
                draw(st.integers(-1, len(chans) - 1)), draw(st.integers(-1, len(chans) - 1)),
                draw(st.sampled_from([0, 48, -48, 96])), draw(st.sampled_from([0, 48, -48])),
            )
            for _ in range(n_vectors)
        ]  # fmt: skip
        dh = DataHeader(
            title=draw(TEXT), domain=draw(st.sampled_from([0, 1, 4])),
            data_type=draw(st.sampled_from([0, 2, 4, 8])), n_points=n_points, last_valid_index=n_points - 1,
            x_resolution=x_resolution, xdata_type=xdata_type, ydata_type=draw(st.sampled_from([1, 2, 3, 4])),
            y_per_point=draw(st.integers(1, 2)), y_is_complex=int(draw(st.booleans())), total_rows=n_vectors,
            first_x=float(draw(st.integers(-4, 4))), delta_x=draw(POWERS_OF_TWO), scan_data=int(scanned[k]),
            vectors=vectors,
        )  # fmt: skip
        dh.x = _x(draw, dh)
        if x_resolution == 2:  # one x vector for the whole file
            shared_x = dh.x if shared_x is None else shared_x
            dh.x = shared_x
        dh.y = _y(draw, dh, chans, scans.n_scans if scanned[k] else 1)
        data.append(dh)
    comments = [Comment(draw(TEXT) + "\r\n")] if rev == 3 and draw(st.booleans()) else []
    return SdfFile(data=data, channels=chans, scans=scans, comments=comments), rev


def _x(draw, dh: DataHeader) -> np.ndarray:
    if dh.x_resolution in (0, 1):
        return np.zeros(0)  # computed by the reader
    numbers = draw(st.lists(st.integers(-100, 100), min_size=dh.n_points, max_size=dh.n_points))
    x = np.array(numbers, dtype=np.float64)
    return np.stack([x + v for v in range(len(dh.vectors))]) if dh.x_resolution == 4 else x


def _y(draw, dh: DataHeader, chans: list[Channel], n_scans: int) -> np.ndarray:
    """EU values whose stored numbers are small integers: exact in every type."""
    parts = 2 if dh.y_is_complex else 1
    shape = (n_scans, len(dh.vectors), dh.n_points, dh.y_per_point, parts)
    stored = np.array(
        draw(st.lists(st.integers(-300, 300), min_size=math.prod(shape), max_size=math.prod(shape)))
    )
    values = stored.reshape(shape).astype(np.float64)
    for v, vector in enumerate(dh.vectors):
        if dh.ydata_type in (codes.INT16, codes.INT32):
            scale, offset = integer_scaling(vector, chans)
            values[:, v] = offset + scale * values[:, v]
        values[:, v] *= vector_factor(dh, vector, chans, "narrow")
    if parts == 2:
        values = values.view(np.complex128)
    values = values.reshape(shape[:4])
    return values[..., 0] if dh.y_per_point == 1 else values


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(sdf_files())
def test_random_valid_files_round_trip(case):
    sdf, rev = case
    data = encode_sdf(sdf, revision=rev)
    back = parse_sdf(data, "random.sdf")
    assert back.file.revision == rev
    for wrote, read in zip(sdf.data, back.data, strict=True):
        assert read.y.dtype == wrote.y.dtype
        np.testing.assert_array_equal(read.y, wrote.y)
        if wrote.x_resolution >= 2:
            np.testing.assert_array_equal(read.x, wrote.x)
        for name in ("title", "domain", "data_type", "n_points", "ydata_type", "y_per_point", "x_resolution"):
            assert getattr(read, name) == getattr(wrote, name), name
        assert read.vectors == wrote.vectors
    assert [c.label for c in back.channels] == [c.label for c in sdf.channels]
    assert [c.text for c in back.comments] == [c.text for c in sdf.comments]
    if sdf.scans is not None:
        assert back.scans.n_scans == sdf.scans.n_scans
        for wrote, read in zip(sdf.scans.variables, back.scans.variables, strict=True):
            np.testing.assert_array_equal(read.values, wrote.values)
    assert encode_sdf(back, revision=rev) == data  # and writing what was read changes nothing


def _bases() -> list[bytes]:
    """Valid files to damage: every record type, an FRF in each revision, the real
    35670A file, and our export of a run with hits, FRFs and coherence."""
    exported = make_run(hits=make_hits(n_hits=3, n_samples=16), analyzer=make_frf(n_frf=1, n_lines=9))
    return [
        full_file(),
        frf_file(1),
        frf_file(2),
        frf_file(3),
        REAL.read_bytes(),
        encode_sdf(sdf_of_run(exported)),
    ]


BASES = _bases()
MUTATION = st.one_of(
    st.tuples(st.just("cut"), st.integers(0, 10**6)),
    st.tuples(st.just("byte"), st.integers(0, 10**6), st.integers(0, 255)),
    st.tuples(
        st.just("int16"), st.integers(0, 10**6), st.sampled_from([0, 1, -1, 2, 4, 48, 96, 32767, -32768])
    ),
    st.tuples(
        st.just("int32"), st.integers(0, 10**6), st.sampled_from([0, -1, 7, 2**16, 2**31 - 1, -(2**31)])
    ),
    st.tuples(
        st.just("float32"),
        st.integers(0, 10**6),
        st.sampled_from([0.0, -1.0, 1e38, float("nan"), float("inf")]),
    ),
)


def mutate(data: bytes, mutations) -> bytes:
    out = bytearray(data)
    for kind, position, *value in mutations:
        if not out:
            break
        position %= len(out)
        if kind == "cut":
            del out[position:]
        elif kind == "byte":
            out[position] = value[0]
        else:
            fmt = {"int16": ">h", "int32": ">i", "float32": ">f"}[kind]
            packed = np.array([value[0]], dtype=fmt).tobytes()
            out[position : position + len(packed)] = packed
    return bytes(out)


@settings(max_examples=400, deadline=None)
@given(st.sampled_from(range(len(BASES))), st.lists(MUTATION, min_size=1, max_size=4))
def test_damage_gives_a_one_line_user_error_or_a_file(base, mutations):
    data = mutate(BASES[base], mutations)
    message = _refusal(lambda: parse_sdf(data, "damaged.sdf"))
    assert message is None or message.startswith("damaged.sdf: ")
    fd, name = tempfile.mkstemp(suffix=".sdf")
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
        imported = []
        _refusal(lambda: imported.append(read_sdf_run(Path(name))))
        if imported:
            json.dumps(imported[0].details, allow_nan=False)
    finally:
        os.unlink(name)


def _refusal(call) -> str | None:
    """None if ``call()`` returns, its one-line FormatError message if it raises one;
    anything else it raises fails the test."""
    try:
        call()
    except FormatError as exc:
        message = str(exc)
        assert "\n" not in message
        return message
    return None
