"""Replay mode: the simulated analyzer serving recorded hits (sims.sources.ReplaySource),
the HDF5 reader behind ``daq sim serve --replay`` (daq.workflows.recorded_hits) and the two
together in a real subprocess.

The hits are made here; what the analyzer must return is computed here with numpy
from docs/instrument.md (1024 samples at 2.56 x span, 400 lines, H1 = G21 / G11),
never taken from a previous reply of the simulator.
"""

from __future__ import annotations

import os
import re
import select
import signal
import socket
import subprocess
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from daq.workflows.errors import WorkflowError
from daq.workflows.recorded_hits import load_recorded_hits
from sims.command_table import ERRORS
from sims.inprocess import InProcessConnection
from sims.instrument import Analyzer
from sims.sources import RecordedHit, ReplaySource
from tests.cli_helpers import DAQ, assert_one_line_error, run_daq
from tests.sims.wire import HEADER_LENGTH, decode_trace

SPAN_HZ = 200.0
FS_HZ = 2.56 * SPAN_HZ  # 512 Hz
N = 1024
N_LINES = 400
START_S = -10e-3  # the first sample, relative to the trigger (a 10 ms pre-trigger)
TIME_BLOCK = 4 + 8 * (HEADER_LENGTH + N)
STATUS_DONE, STATUS_WAITING, STATUS_ERROR, STATUS_PENDING = 1, 2, 16, 32


# ---------------------------------------------------------------- recorded hits
def make_hits(n_hits: int, seed: int = 0) -> list[RecordedHit]:
    """Hammer pulses and a two-mode response, with noise, so that H1 differs from
    other estimators; a few odd float64 values check that the replay is bit-exact."""
    rng = np.random.default_rng(seed)
    t = START_S + np.arange(N) / FS_HZ
    tau = np.arange(N) / FS_HZ
    impulse = np.exp(-3.0 * tau) * np.sin(2 * np.pi * 17.0 * tau) + 0.5 * np.exp(-5.0 * tau) * np.sin(
        2 * np.pi * 63.0 * tau
    )
    hits = []
    for i in range(n_hits):
        width = 0.004 + 0.002 * i
        pulse = np.where((t >= 0) & (t < width), np.sin(np.pi * np.clip(t, 0, None) / width), 0.0)
        force = (80.0 + 15.0 * i) * pulse + 0.5 * rng.standard_normal(N)
        response = np.convolve(force, impulse)[:N] / FS_HZ + 0.3 * rng.standard_normal(N)
        force[-1] = -0.0
        response[-1] = 5e-324  # the smallest subnormal
        response[-2] = -0.0
        hits.append(RecordedHit(force, response, FS_HZ, START_S))
    return hits


def be64(values: np.ndarray) -> bytes:
    return np.asarray(values, dtype=">f8").tobytes()


def h1(hits: list[RecordedHit]) -> np.ndarray:
    """H1 on lines 0..400 of a uniform-window FFT: sum conj(X1) X2 / sum |X1|^2."""
    x1 = np.fft.rfft(np.stack([h.force_n for h in hits]), axis=1)[:, : N_LINES + 1]
    x2 = np.fft.rfft(np.stack([h.acceleration_m_s2 for h in hits]), axis=1)[:, : N_LINES + 1]
    return (np.conj(x1) * x2).sum(axis=0) / (np.abs(x1) ** 2).sum(axis=0)


class Client:
    """An in-process connection with the replies decoded test-side."""

    def __init__(self, analyzer: Analyzer) -> None:
        self.conn = InProcessConnection(analyzer)

    def send(self, text: str) -> None:
        self.conn.write(text.encode("ascii") + b"\n")

    def query(self, text: str) -> bytes:
        self.send(text)
        return self.conn.read(timeout_s=2.0)

    def status(self) -> int:
        return int(self.query("STA?"))

    def error(self) -> tuple[int, str]:
        match = re.fullmatch(rb'(\d+),"(.*)"\r\n', self.query("ERR?"))
        assert match
        return int(match.group(1)), match.group(2).decode("ascii")

    def trace(self, function: str) -> tuple[np.ndarray, np.ndarray, bytes]:
        """(header, values, raw data bytes) of ``function``'s DDAN dump."""
        raw = self.query(f"TRCA;{function};DDAN")
        header, values = decode_trace(raw)
        return header, values, raw[4 + 8 * HEADER_LENGTH :]


def replay(hits: list[RecordedHit], loop: bool = False) -> Client:
    return Client(Analyzer(ReplaySource(hits, loop=loop), time_scale=0.0))


def assert_serves(client: Client, hit: RecordedHit) -> None:
    """The analyzer's time records are ``hit``'s, bit for bit."""
    for function, samples in (("TIM1", hit.force_n), ("TIM2", hit.acceleration_m_s2)):
        header, _, raw = client.trace(function)
        assert raw == be64(samples), function
        assert int(header[1]) == N


# ---------------------------------------------------------------- ReplaySource
@pytest.mark.timeout(5)
def test_time_records_are_the_recorded_hit_bit_for_bit():
    hits = make_hits(1)
    client = replay(hits)
    client.send("FRS 200 HZ;UNIF;STRT")
    assert client.query("SMSD") == b"1\r\n"
    assert client.error() == (0, "No error")
    assert_serves(client, hits[0])
    header, _, _ = client.trace("TIM2")
    assert header[7] == 0  # time domain
    assert header[36] == 1  # real
    assert header[52] == header[53] == FS_HZ / 2
    assert header[55] == 1 / FS_HZ
    assert header[64] == START_S


@pytest.mark.timeout(5)
def test_frequency_response_is_h1_of_the_recorded_hits():
    hits = make_hits(3)
    client = replay(hits)
    client.send("FRS 200 HZ;UNIF;NAVG 3;STBL;STRT")
    assert client.query("SMSD") == b"1\r\n"
    assert client.query("AVG?") == b"3\r\n"
    header, frsp, _ = client.trace("FRSP")
    expected = h1(hits)
    assert frsp.shape == (N_LINES + 1,)
    np.testing.assert_allclose(frsp, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())
    # The check can tell H1 from its usual mistakes.
    x1 = np.fft.rfft(np.stack([h.force_n for h in hits]), axis=1)[:, : N_LINES + 1]
    x2 = np.fft.rfft(np.stack([h.acceleration_m_s2 for h in hits]), axis=1)[:, : N_LINES + 1]
    for wrong in (np.conj(expected), (x2 / x1).mean(axis=0), h1(hits[-1:])):
        assert np.abs(wrong - expected).max() > 1e-3 * np.abs(expected).max()
    assert header[1] == N_LINES + 1
    assert header[3] == 3  # averages
    assert header[7] == 1  # frequency domain
    assert header[36] == 0  # complex
    assert header[55] == SPAN_HZ / N_LINES
    assert header[64] == 0.0
    # The last hit is the one on show.
    assert_serves(client, hits[-1])


@pytest.mark.timeout(5)
def test_frequency_response_averages_only_the_accepted_hits():
    hits = make_hits(3, seed=4)
    client = replay(hits)
    client.send("FRS 200 HZ;UNIF;NAVG 2;STBL;PRVW 1;STRT")
    assert client.status() & STATUS_PENDING
    assert_serves(client, hits[0])
    client.send("RJCT")
    assert_serves(client, hits[1])
    client.send("ACPT")
    assert client.query("SMSD") == b"0\r\n"
    assert_serves(client, hits[2])
    client.send("ACPT")
    assert client.query("SMSD") == b"1\r\n"
    assert client.error() == (0, "No error")
    _, frsp, _ = client.trace("FRSP")
    expected = h1(hits[1:])
    np.testing.assert_allclose(frsp, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())


@pytest.mark.timeout(5)
def test_recorded_overload_flags_are_reported():
    hits = make_hits(2)
    hits[1].overload = (False, True)
    client = replay(hits)
    client.send("FRS 200 HZ;STRT")
    assert client.query("OVLD?") == b"0,0\r\n"
    client.send("STRT")
    assert client.query("OVLD?") == b"0,1\r\n"
    assert client.trace("TIM1")[0][5] == 0
    assert client.trace("TIM2")[0][5] == 1


@pytest.mark.timeout(5)
@pytest.mark.parametrize("span", ["400 HZ", "100 HZ", "12.5 HZ"])
def test_a_span_other_than_the_recording_is_error_6_naming_the_recorded_span(span):
    hits = make_hits(2)
    client = replay(hits)
    client.send(f"FRS {span};STRT")
    sta = client.status()
    assert sta & STATUS_ERROR
    assert not sta & (STATUS_DONE | STATUS_WAITING)
    code, message = client.error()
    assert code == 6
    assert message.startswith(ERRORS[6] + ": ")
    assert re.search(r"\b200 Hz\b", message), message
    assert client.query("SMSD") == b"0\r\n"
    # Nothing was used up: with the right span the first hit comes.
    client.send("FRS 200 HZ;STRT")
    assert client.query("SMSD") == b"1\r\n"
    assert_serves(client, hits[0])


@pytest.mark.timeout(5)
def test_when_the_hits_run_out_the_analyzer_waits_for_a_trigger():
    hits = make_hits(2)
    client = replay(hits)
    client.send("FRS 200 HZ")
    for hit in hits:
        client.send("STRT")
        assert client.query("SMSD") == b"1\r\n"
        assert_serves(client, hit)
    client.send("STRT")
    sta = client.status()
    assert sta & STATUS_WAITING
    assert not sta & (STATUS_DONE | STATUS_ERROR)
    assert client.query("SMSD") == b"0\r\n"
    assert client.error() == (0, "No error")


@pytest.mark.timeout(5)
def test_a_looping_replay_starts_over():
    hits = make_hits(2)
    client = replay(hits, loop=True)
    client.send("FRS 200 HZ")
    for i in range(5):
        client.send("STRT")
        assert client.query("SMSD") == b"1\r\n"
        assert_serves(client, hits[i % 2])
    client.send("UNIF;NAVG 4;STBL;STRT")  # hits 1, 0, 1, 0
    assert client.query("SMSD") == b"1\r\n"
    _, frsp, _ = client.trace("FRSP")
    expected = h1([hits[1], hits[0], hits[1], hits[0]])
    np.testing.assert_allclose(frsp, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())


@pytest.mark.timeout(5)
def test_a_baseband_recording_is_refused_in_zoom():
    hits = make_hits(1)
    client = replay(hits)
    client.send("FRS 200 HZ;CF 500 HZ;STRT")
    code, _ = client.error()
    assert code != 0
    assert not client.status() & (STATUS_DONE | STATUS_WAITING)
    assert client.query("SMSD") == b"0\r\n"
    client.send("CF 100 HZ;STRT")  # span / 2: baseband again
    assert client.query("SMSD") == b"1\r\n"
    assert_serves(client, hits[0])


def zoom_hit(center_hz: float, seed: int = 3) -> RecordedHit:
    """A complex record of 512 samples at 1.28 x 200 Hz (docs/instrument.md), with odd
    values in both the real and the imaginary parts."""
    rng = np.random.default_rng(seed)
    fs = 1.28 * SPAN_HZ
    force = rng.standard_normal(N // 2) + 1j * rng.standard_normal(N // 2)
    response = rng.standard_normal(N // 2) + 1j * rng.standard_normal(N // 2)
    force[-1] = complex(-0.0, 5e-324)
    return RecordedHit(force, response, fs, START_S, center_hz=center_hz)


@pytest.mark.timeout(5)
def test_a_zoom_recording_is_served_bit_for_bit_at_its_center():
    hit = zoom_hit(500.0)
    client = replay([hit])
    client.send("FRS 200 HZ;CF 500 HZ;UNIF;STRT")
    assert client.query("SMSD") == b"1\r\n"
    assert client.error() == (0, "No error")
    for function, samples in (("TIM1", hit.force_n), ("TIM2", hit.acceleration_m_s2)):
        header, _, raw = client.trace(function)
        assert header[36] == 0  # complex
        assert int(header[1]) == N // 2
        # A complex trace is (re, im) pairs, big-endian float64.
        pairs = np.stack([samples.real, samples.imag], axis=1).ravel()
        assert raw == be64(pairs), function


@pytest.mark.timeout(5)
@pytest.mark.parametrize("setup", ["FRS 200 HZ;CF 600 HZ", "FRS 200 HZ;CF 100 HZ", "FRS 400 HZ;CF 500 HZ"])
def test_a_zoom_recording_elsewhere_is_refused(setup):
    client = replay([zoom_hit(500.0)])
    client.send(f"{setup};STRT")
    code, _ = client.error()
    assert code != 0
    assert client.query("SMSD") == b"0\r\n"


def test_replay_source_refuses_hits_that_are_not_1024_real_or_512_complex_samples():
    good = make_hits(1)[0]
    with pytest.raises(ValueError, match="1024"):
        ReplaySource([good, RecordedHit(np.zeros(512), np.zeros(512), FS_HZ)])
    with pytest.raises(ValueError, match="1024"):
        ReplaySource([RecordedHit(good.force_n, good.acceleration_m_s2[:-1], FS_HZ)])
    with pytest.raises(ValueError, match="512"):
        ReplaySource([RecordedHit(np.zeros(1024, complex), np.zeros(1024, complex), FS_HZ, center_hz=5.0)])
    with pytest.raises(ValueError, match="center_hz"):
        ReplaySource([RecordedHit(np.zeros(512, complex), np.zeros(512, complex), FS_HZ)])


# ---------------------------------------------------------------- HDF5 runs
def write_run(path: Path, hits: list[RecordedHit], skip: tuple[str, ...] = (), **datasets) -> Path:
    """A run laid out as docs/run-format.md: /entry/hits/{force,response,time}
    plus whatever ``datasets`` add or replace; ``skip`` leaves datasets (or "hits",
    the whole group) out."""
    fields = {
        "force": np.stack([h.force_n for h in hits]) if hits else np.zeros((0, N)),
        "response": np.stack([h.acceleration_m_s2 for h in hits]) if hits else np.zeros((0, N)),
        "time": START_S + np.arange(N) / FS_HZ,
    }
    fields.update(datasets)
    with h5py.File(path, "w") as f:
        f.attrs["default"] = "entry"
        entry = f.create_group("entry")
        entry.attrs["NX_class"] = "NXentry"
        if "hits" in skip:
            return path
        group = entry.create_group("hits")
        group.attrs["NX_class"] = "NXdata"
        for name, value in fields.items():
            if name in skip or value is None:
                continue
            value = np.asarray(value)
            options = (
                {"compression": "gzip", "shuffle": True, "fletcher32": True, "chunks": True}
                if value.ndim
                else {}
            )
            group.create_dataset(name, data=value, **options)
        if "force" in group:
            group["force"].attrs["units"] = "N"
    return path


@pytest.mark.timeout(10)
def test_load_recorded_hits_reads_a_run(tmp_path):
    hits = make_hits(3)
    path = write_run(
        tmp_path / "run.h5",
        hits,
        accepted=np.array([True, False, True]),
        overload=np.array([[False, False], [False, True], [True, False]]),
    )
    loaded = load_recorded_hits(path)
    assert len(loaded) == 3
    for got, made, over in zip(loaded, hits, [(False, False), (False, True), (True, False)], strict=True):
        assert be64(got.force_n) == be64(made.force_n)
        assert be64(got.acceleration_m_s2) == be64(made.acceleration_m_s2)
        assert got.sample_rate_hz == pytest.approx(FS_HZ, rel=1e-9)
        assert got.start_s == START_S
        assert got.overload == over
    accepted = load_recorded_hits(path, accepted_only=True)
    assert [be64(h.force_n) for h in accepted] == [be64(hits[0].force_n), be64(hits[2].force_n)]


@pytest.mark.timeout(10)
def test_a_run_without_flags_replays_every_hit(tmp_path):
    hits = make_hits(2)
    loaded = load_recorded_hits(write_run(tmp_path / "run.h5", hits), accepted_only=True)
    assert len(loaded) == 2
    assert all(h.overload == (False, False) for h in loaded)
    # What it reads, the analyzer serves: at FRS 200 HZ, bit for bit.
    client = replay(loaded)
    client.send("FRS 200 HZ;UNIF;NAVG 2;STBL;STRT")
    assert client.query("SMSD") == b"1\r\n"
    assert_serves(client, hits[1])
    _, frsp, _ = client.trace("FRSP")
    np.testing.assert_allclose(frsp, h1(hits), rtol=1e-9, atol=1e-12 * np.abs(h1(hits)).max())


def _uneven_time() -> np.ndarray:
    t = START_S + np.arange(N) / FS_HZ
    t[500] += 0.3 / FS_HZ
    return t


def _with(value: float, where: str) -> dict:
    hits = make_hits(2)
    arrays = {
        "force": np.stack([h.force_n for h in hits]),
        "response": np.stack([h.acceleration_m_s2 for h in hits]),
    }
    arrays[where][1, 10] = value
    return arrays


MALFORMED = {
    "no hits group": ({"skip": ("hits",)}, r"no /entry/hits group"),
    "no force": ({"skip": ("force",)}, r"/entry/hits/force is missing"),
    "no response": ({"skip": ("response",)}, r"/entry/hits/response is missing"),
    "no time": ({"skip": ("time",)}, r"/entry/hits/time is missing"),
    "500 samples": (
        {"force": np.zeros((2, 500)), "response": np.zeros((2, 500))},
        r"n_hits x one of 256, 512, 1024, 2048, 4096 \(a record of the family\), got \(2, 500\)",
    ),
    "one hit as a vector": ({"force": np.zeros(N), "response": np.zeros(N)}, r"n_hits x one of"),
    "hit counts differ": (
        {"response": np.zeros((1, N))},
        r"force and response .* \(2, 1024\) and \(1, 1024\)",
    ),
    "short time": ({"time": np.arange(512) / FS_HZ}, r"/entry/hits/time must hold 1024"),
    "NaN time": ({"time": np.full(N, np.nan)}, r"/entry/hits/time must hold 1024 finite"),
    "uneven time": ({"time": _uneven_time()}, r"/entry/hits/time is not evenly spaced"),
    "time backwards": ({"time": -np.arange(N) / FS_HZ}, r"/entry/hits/time is not evenly spaced"),
    "NaN force": (_with(np.nan, "force"), r"non-finite"),
    "inf response": (_with(np.inf, "response"), r"non-finite"),
    "no hits": ({"force": np.zeros((0, N)), "response": np.zeros((0, N))}, r"no hits to replay"),
}


@pytest.mark.timeout(10)
@pytest.mark.parametrize("case", list(MALFORMED))
def test_a_malformed_run_is_a_user_error_naming_the_problem(tmp_path, case):
    datasets, message = MALFORMED[case]
    datasets = dict(datasets)
    skip = datasets.pop("skip", ())
    path = write_run(tmp_path / "bad.h5", make_hits(2), skip=skip, **datasets)
    with pytest.raises(WorkflowError, match=message) as info:
        load_recorded_hits(path)
    assert str(path) in str(info.value)


def test_accepted_only_leaving_nothing_is_a_user_error(tmp_path):
    path = write_run(tmp_path / "run.h5", make_hits(2), accepted=np.array([False, False]))
    assert len(load_recorded_hits(path)) == 2
    with pytest.raises(WorkflowError, match="no hits to replay"):
        load_recorded_hits(path, accepted_only=True)


def test_a_file_that_is_not_hdf5_is_a_user_error(tmp_path):
    path = tmp_path / "run.h5"
    path.write_text("force,response\n1,2\n")
    with pytest.raises(WorkflowError, match="not a readable HDF5 file"):
        load_recorded_hits(path)
    with pytest.raises(WorkflowError, match="no such run file"):
        load_recorded_hits(tmp_path / "missing.h5")
    with pytest.raises(WorkflowError, match="no such run file"):
        load_recorded_hits(tmp_path)  # a folder


@pytest.mark.parametrize(
    ("datasets", "name"),
    [
        ({"overload": np.array([True, False])}, "overload"),  # (n_hits,), not (n_hits, 2)
        ({"overload": np.zeros((1, 2), bool)}, "overload"),  # one row for two hits
        ({"accepted": np.array([True])}, "accepted"),  # one flag for two hits
    ],
    ids=["overload-1d", "overload-short", "accepted-short"],
)
def test_misshapen_flags_are_a_user_error(tmp_path, datasets, name):
    """Flags shaped unlike the hits (overload (n_hits, 2), accepted (n_hits,)) are a
    WorkflowError naming the dataset, which `daq sim serve --replay` reports as the user's
    mistake, not an IndexError it would turn into "internal error" (exit 70)."""
    path = write_run(tmp_path / "run.h5", make_hits(2), **datasets)
    with pytest.raises(WorkflowError, match=name):
        load_recorded_hits(path, accepted_only=True)


def test_a_group_where_a_dataset_belongs_is_a_user_error(tmp_path):
    """A group where the force dataset belongs is a WorkflowError naming it, not the
    TypeError h5py raises on reading a group as an array."""
    path = write_run(tmp_path / "run.h5", make_hits(2), skip=("force",))
    with h5py.File(path, "a") as f:
        f.create_group("entry/hits/force")
    with pytest.raises(WorkflowError, match="force"):
        load_recorded_hits(path)


# ---------------------------------------------------------------- daq sim serve --replay
def _recv_exactly(sock: socket.socket, n: int) -> bytes:
    data = bytearray()
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        assert chunk, f"connection closed after {len(data)} of {n} bytes"
        data += chunk
    return bytes(data)


def _recv_line(sock: socket.socket) -> bytes:
    data = bytearray()
    while not data.endswith(b"\r\n"):
        chunk = sock.recv(1)
        assert chunk, f"connection closed after {bytes(data)!r}"
        data += chunk
    return bytes(data)


@pytest.mark.timeout(30)
def test_daq_sim_serve_replays_a_run_over_tcp(tmp_path):
    hits = make_hits(3, seed=9)
    path = write_run(tmp_path / "run.h5", hits)
    env = {**os.environ, "NO_COLOR": "1", "COLUMNS": "120"}
    env.pop("DAQ_DEBUG", None)
    proc = subprocess.Popen(
        [str(DAQ), "sim", "serve", "--replay", str(path), "--tcp", "0", "--time-scale", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
        # A child of a shell or CI runner that ignores SIGINT would inherit that and
        # never see the Ctrl-C this test sends.
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        assert proc.stdout is not None
        ready, _, _ = select.select([proc.stdout], [], [], 20.0)
        assert ready, "no resource printed"
        first = proc.stdout.readline().decode("ascii")
        match = re.fullmatch(r"TCPIP::127\.0\.0\.1::(\d+)::SOCKET\n", first)
        assert match, first
        with socket.create_connection(("127.0.0.1", int(match.group(1))), timeout=5.0) as sock:
            sock.sendall(b"ID?\n")
            assert _recv_line(sock) == b"HP35660A\r\n"
            sock.sendall(b"FRS 200 HZ;STRT\nSMSD\n")
            assert _recv_line(sock) == b"1\r\n"
            for function, samples in (("TIM1", hits[0].force_n), ("TIM2", hits[0].acceleration_m_s2)):
                sock.sendall(f"TRCA;{function};DDAN\n".encode())
                block = _recv_exactly(sock, TIME_BLOCK)
                header, _ = decode_trace(block)
                assert block[4 + 8 * HEADER_LENGTH :] == be64(samples), function
                assert header[55] == pytest.approx(1 / FS_HZ, rel=1e-9)
            sock.sendall(b"STRT;SMSD\n")  # the next hit is the next recorded one
            assert _recv_line(sock) == b"1\r\n"
            sock.sendall(b"TIM1;DDAN\n")
            assert _recv_exactly(sock, TIME_BLOCK)[4 + 8 * HEADER_LENGTH :] == be64(hits[1].force_n)
        time.sleep(0.05)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=10)
        assert proc.returncode == 0, err
        assert out == b"", out  # the resource alone on stdout
        assert b"Traceback" not in err
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


@pytest.mark.timeout(30)
def test_daq_sim_serve_refuses_a_malformed_run(tmp_path):
    path = write_run(tmp_path / "run.h5", make_hits(2), time=_uneven_time())
    result = run_daq("sim", "serve", "--replay", str(path), "--tcp", "0", "--time-scale", "0", timeout=20)
    assert_one_line_error(result, "not evenly spaced")
    assert result.returncode == 1
    assert result.stdout == ""
