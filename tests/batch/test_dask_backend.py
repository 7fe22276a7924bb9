"""`daq analyze|fit --scheduler`: the batch on a Dask cluster (a LocalCluster of two
worker processes on loopback) stores what the local pool stores, so that a local
run afterwards is a cache hit; a failing run fails as locally; a scheduler that is
malformed, unreachable, without workers or without the extra is one error line.
"""

from __future__ import annotations

import json
import logging
import shutil
import socket
import sys
import warnings
from dataclasses import replace
from pathlib import Path
from unittest import mock

import distributed
import numpy as np
import pytest
from store.store_helpers import make_frf, make_run

from daq.batch import dask_backend as dask_batch
from daq.store import Run, Store, seal
from daq.store.ids import RUN_ID_LENGTH
from tests.cli_helpers import assert_one_line_error, capture_sim, invoke_daq, run_daq

#: Summary fields that time the computation: the only ones two runs may differ in.
TIMING = ("seconds",)


@pytest.fixture(scope="module")
def cluster():
    # The scheduler of a LocalCluster lives in this process: its INFO records (clients
    # coming and going) would reach the handler `daq` puts on the root logger and read
    # as daq's own stderr. A real scheduler runs elsewhere.
    logger = logging.getLogger("distributed")
    level = logger.level
    logger.setLevel(logging.ERROR)
    # No dashboard; the scheduler's HTTP server (metrics, health) on a free port rather
    # than 8787, which another cluster on this machine may hold (distributed then warns).
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None,
        scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
    )  # fmt: skip
    yield cluster
    # Shutting the worker processes down, distributed may warn about the connections
    # it closes (a ResourceWarning of an unclosed socket, or a RuntimeWarning of a
    # coroutine never awaited); nothing of that is about daq.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ResourceWarning)
        warnings.filterwarnings("ignore", category=RuntimeWarning, module=r"(distributed|tornado|asyncio)\b")
        cluster.close()
    logger.setLevel(level)


@pytest.fixture(scope="module")
def store(tmp_path_factory) -> Path:
    """Three captured runs (two beams), never analysed: the tests work on copies."""
    path = tmp_path_factory.mktemp("batch") / "runs"
    capture_sim(path, "realistic", seed=11)
    capture_sim(path, "realistic", seed=12)
    capture_sim(path, "seed", seed=13)
    return path


def copy_store(source: Path, target: Path) -> Path:
    # copy2 keeps the mtimes to the nanosecond: the cache keys hash them.
    return Path(shutil.copytree(source, target, copy_function=shutil.copy2))


def batch(command: str, store: Path, *args: str, env: dict | None = None) -> list[dict]:
    """`daq COMMAND --all --json` in this process (the cluster computes, or nothing does)."""
    result = invoke_daq(command, "--all", "--json", "--store", str(store), *args, env=env)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    return json.loads(result.stdout)


def local_batch(command: str, store: Path, *args: str) -> list[dict]:
    """`daq COMMAND --all --json` on the local pool, as the real console script: its
    worker processes then use one BLAS thread each, as `daq` sets before numpy loads
    and as Dask's workers do. Forked from this process instead, they would inherit
    the BLAS threads of the numpy pytest loaded, and differ in the last bits."""
    result = run_daq(command, "--all", "--json", "--store", str(store), *args)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    return json.loads(result.stdout)


def without_timing(summary: dict) -> dict:
    return {k: v for k, v in summary.items() if k not in TIMING}


def results(store: Path) -> dict[str, int]:
    """Every result file of the store (``<run id>.<result>.h5``): its mtime (ns)."""
    return {p.name: p.stat().st_mtime_ns for p in sorted(store.glob("*.h5")) if p.name.count(".") == 3}


def no_accepted_hit() -> Run:
    run = make_run(kind="captured")
    n = run.hits.n_hits
    run.hits = replace(run.hits, accepted=np.zeros(n, bool), reject_reason=["double impact"] * n)
    return run


def assert_same_results(a: Path, b: Path) -> None:
    """The two stores hold the same result files with the same content: arrays bit
    for bit, cache keys and summaries equal (the time taken aside)."""
    assert list(results(a)) == list(results(b))
    for name in results(a):
        run_id, result = name[:RUN_ID_LENGTH], name[RUN_ID_LENGTH + 1 : -len(".h5")]
        x, y = Store(a).read_result(run_id, result), Store(b).read_result(run_id, result)
        assert sorted(x) == sorted(y), name
        for key, value in x.items():
            if isinstance(value, np.ndarray):
                assert value.dtype == y[key].dtype, (name, key)
                assert value.shape == y[key].shape, (name, key)
                assert value.tobytes() == y[key].tobytes(), (name, key)
            elif key == "summary":
                assert without_timing(value) == without_timing(y[key]), name
            else:
                assert value == y[key], (name, key)


def test_the_cluster_stores_what_the_local_pool_stores(cluster, store, tmp_path):
    local = copy_store(store, tmp_path / "local")
    remote = copy_store(store, tmp_path / "remote")
    address = ("--scheduler", cluster.scheduler_address)
    for command in ("analyze", "fit"):
        here = local_batch(command, local)
        there = batch(command, remote, *address)
        assert [without_timing(s) for s in there] == [without_timing(s) for s in here]
        assert not any(s["cached"] for s in there)
    assert len(results(remote)) == 6  # an analysis and a least-squares fit per run
    assert_same_results(local, remote)

    # Locally afterwards, all of it is a cache hit: nothing is computed or written.
    before = results(remote)
    for command in ("analyze", "fit"):
        assert all(s["cached"] for s in batch(command, remote))
    assert results(remote) == before

    # And the cluster reads its cache too, sending nothing.
    with mock.patch.object(dask_batch, "_analyze_task", side_effect=AssertionError("sent")):
        assert all(s["cached"] for s in batch("analyze", remote, *address))
    assert results(remote) == before


def test_a_fit_on_the_cluster_analyses_first_when_it_must(cluster, store, tmp_path):
    """No analysis stored: the fit's task computes it first, and both are stored."""
    local = copy_store(store, tmp_path / "local")
    remote = copy_store(store, tmp_path / "remote")
    here = local_batch("fit", local, "--method", "modal")
    there = batch("fit", remote, "--method", "modal", "--scheduler", cluster.scheduler_address)
    assert [without_timing(s) for s in there] == [without_timing(s) for s in here]
    assert sorted(name[RUN_ID_LENGTH + 1 :] for name in results(remote)) == (
        ["analysis.h5"] * 3 + ["fit-modal.h5"] * 3
    )
    assert_same_results(local, remote)


def test_daq_scheduler_gives_the_address_and_an_explicit_jobs_wins(cluster, store, tmp_path):
    remote = copy_store(store, tmp_path / "remote")
    env = {"DAQ_SCHEDULER": cluster.scheduler_address}
    calls = []
    original = dask_batch.run_on_cluster

    def spy(address, *args):
        calls.append(address)
        return original(address, *args)

    with mock.patch.object(dask_batch, "run_on_cluster", side_effect=spy):
        (first, *_) = batch("analyze", remote, env=env)
        assert calls == [cluster.scheduler_address]
        assert first["cached"] is False
        batch("analyze", remote, "--recompute", "--jobs", "1", env=env)  # the local pool
        assert calls == [cluster.scheduler_address]
    result = invoke_daq("analyze", "--all", "--jobs", "2", "--scheduler", cluster.scheduler_address)
    assert_one_line_error(result, "not both")
    assert result.returncode == 2


def test_a_failing_run_fails_on_the_cluster_as_it_does_locally(cluster, store, tmp_path):
    """One good run, one damaged file, one run without an accepted hit: the same
    lines on stderr, the same exit status, the good run's results stored."""
    base = tmp_path / "base"
    base.mkdir()
    good = Path(shutil.copy2(sorted(store.glob("*.h5"))[0], base))
    data = bytearray(good.read_bytes())
    data[len(data) // 2 : len(data) // 2 + 64] = bytes(64)
    (base / "20261123T130000.000Z-deadbeef.h5").write_bytes(bytes(data))
    seal(no_accepted_hit(), base)
    local = copy_store(base, tmp_path / "local")
    remote = copy_store(base, tmp_path / "remote")
    for command in ("analyze", "fit"):
        here = run_daq(command, "--all", "--store", str(local))
        there = invoke_daq(command, "--all", "--store", str(remote), "--scheduler", cluster.scheduler_address)
        assert here.returncode == there.returncode == 1
        lines = sorted(there.stderr.replace(str(remote), "STORE").splitlines())
        assert lines == sorted(here.stderr.replace(str(local), "STORE").splitlines())
        assert len(lines) == 3, lines  # two runs, then the summary line
        # Every line starts `daq: error:`, so sorting them does not keep the summary last.
        assert there.stderr.splitlines()[-1].startswith("daq: error: 2 of 3 runs"), there.stderr
        assert "damaged or not an HDF5 run file" in there.stderr
        assert "no accepted hit" in there.stderr
    assert_same_results(local, remote)


def test_one_failing_run_is_the_one_error_line(cluster, tmp_path):
    empty = no_accepted_hit()
    seal(empty, tmp_path)
    result = invoke_daq(
        "fit", empty.run_id, "--store", str(tmp_path), "--scheduler", cluster.scheduler_address
    )
    assert_one_line_error(result, empty.run_id, "no accepted hit")


@pytest.mark.parametrize(
    "address",
    ["10.0.0.9:8786", "http://10.0.0.9:8786", "tcp://10.0.0.9", "tcp://10.0.0.9:0", "tcp://a b:1", ""],
)
def test_a_malformed_address_is_one_line(tmp_path, address):
    result = invoke_daq("analyze", "--all", "--store", str(tmp_path), "--scheduler", address)
    assert_one_line_error(result, "--scheduler", "tcp://HOST:PORT")
    result = invoke_daq("fit", "--all", "--store", str(tmp_path), env={"DAQ_SCHEDULER": address or "x"})
    assert_one_line_error(result, "$DAQ_SCHEDULER", "tcp://HOST:PORT")


def test_the_addresses_it_takes():
    assert dask_batch.scheduler_address(None, {}) is None
    assert dask_batch.scheduler_address(None, {"DAQ_SCHEDULER": ""}) is None
    assert dask_batch.scheduler_address(None, {"DAQ_SCHEDULER": "tcp://h:1"}) == "tcp://h:1"
    assert (
        dask_batch.scheduler_address("tls://[::1]:8786", {"DAQ_SCHEDULER": "tcp://h:1"}) == "tls://[::1]:8786"
    )
    assert (
        dask_batch.scheduler_address("tcp://node-7.lab.example:65535", {}) == "tcp://node-7.lab.example:65535"
    )


def test_an_unreachable_scheduler_is_one_line(store, tmp_path, monkeypatch):
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    monkeypatch.setattr(dask_batch, "CONNECT_TIMEOUT_S", 1.0)
    address = f"tcp://127.0.0.1:{port}"
    result = invoke_daq("analyze", "--all", "--store", str(store), "--scheduler", address)
    assert_one_line_error(result, f"cannot reach the Dask scheduler at {address} (timed out after 1 s)")


def test_a_scheduler_without_workers_is_one_line(store, monkeypatch):
    monkeypatch.setattr(dask_batch, "CONNECT_TIMEOUT_S", 1.0)
    with distributed.LocalCluster(
        n_workers=0, processes=False, protocol="tcp", host="127.0.0.1", dashboard_address=None,
        scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
    ) as empty:  # fmt: skip
        result = invoke_daq("fit", "--all", "--store", str(store), "--scheduler", empty.scheduler_address)
    assert_one_line_error(result, "has no worker", f"dask worker {empty.scheduler_address}")


def test_without_the_extra_the_option_says_what_to_install(store, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed fails
    result = invoke_daq("analyze", "--all", "--store", str(store), "--scheduler", "tcp://10.0.0.9:8786")
    assert_one_line_error(result, "pip install 'cantilever-daq[dask]'")
    assert result.returncode == 1


def test_a_worker_of_another_version_refuses_the_task():
    reason = dask_batch._analyze_task(b"", "x.h5", None, "cantilever-daq 0.0.0")
    assert "cantilever-daq 0.0.0" in reason
    assert "the same version" in reason


def test_a_worker_decodes_the_run_as_the_store_reads_a_run_file(tmp_path):
    """The bytes sent go through daq.store.open_run_bytes: what the store refuses in a
    file on disk is refused, as a one-line reason naming the file."""
    from analysis.run_analysis import AnalysisOptions
    from daq.workflows.fit import FitOptions

    software = dask_batch._software()
    run = make_run(kind="imported", measured=make_frf(n_frf=1))
    path = seal(run, tmp_path)
    info, _ = dask_batch._analyze_task(path.read_bytes(), str(path), AnalysisOptions(), software)
    assert info["run_id"] == run.run_id
    reason = dask_batch._analyze_task(b"not hdf5", "somewhere/x.h5", AnalysisOptions(), software)
    assert reason.startswith("somewhere/x.h5: damaged or not an HDF5 run file")
    reason = dask_batch._fit_task(b"not hdf5", "somewhere/x.h5", FitOptions(), None, True, software)
    assert reason.startswith("somewhere/x.h5: damaged or not an HDF5 run file")
    # An external link inside the file is refused, as in a file opened from disk.
    import h5py

    linked = tmp_path / "linked.h5"
    shutil.copy2(path, linked)
    with h5py.File(linked, "a") as f:
        f["entry/outside"] = h5py.ExternalLink("/etc/passwd", "/")
    reason = dask_batch._analyze_task(linked.read_bytes(), str(linked), AnalysisOptions(), software)
    assert "external link" in reason
    assert str(linked) in reason
