"""`daq serve --scheduler`: the service hands its analyses to a running Dask cluster
(a real `dask scheduler` and `dask worker` on loopback, separate processes), and the
results land in the store as the local workers would store them."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from daq.store import Store
from tests.service.hardening_helpers import free_port
from tests.service.service_helpers import EventReader, serving, wait_for

DASK = Path(sys.executable).with_name("dask")

pytestmark = pytest.mark.slow


@contextlib.contextmanager
def dask_cluster(tmp_path: Path):
    """A scheduler and one worker process; the scheduler's address."""
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
    log = (tmp_path / "dask.log").open("w")
    scheduler = subprocess.Popen(
        [str(DASK), "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
        stdout=log, stderr=subprocess.STDOUT, env=env, start_new_session=True,
    )  # fmt: skip
    worker = subprocess.Popen(
        [str(DASK), "worker", address, "--nworkers", "1", "--nthreads", "1", "--no-dashboard"],
        stdout=log, stderr=subprocess.STDOUT, env=env, start_new_session=True,
    )  # fmt: skip
    try:
        yield address
    finally:
        for proc in (worker, scheduler):
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(10)
        log.close()


def test_the_service_hands_its_analyses_to_a_dask_cluster(tmp_path):
    with dask_cluster(tmp_path) as address, serving(tmp_path, "--sim", "--scheduler", address) as served:
        assert f"on {address}" in "".join(served.stderr_lines)
        events = EventReader(served)
        run_id = served.post("/api/capture", {"hits": 2, "auto": True}).json()["run_id"]
        fit = events.wait_for_kind("fit_done", run_id, 180)
        assert fit["method"] == "ls"
        assert "analysis_failed" not in events.kinds(run_id)
        (row,) = served.get("/api/runs").json()
        assert (row["analysis"], row["fit"]) == ("done", "done")
        # Stored beside the run, readable as any local result.
        store = Store(served.store)
        assert store.read_result(run_id, "analysis")["summary"]["run_id"] == run_id
        assert store.read_result(run_id, "fit-ls")["summary"]["method"] == "ls"
        wait_for(lambda: served.get("/api/health").json()["jobs"]["done"] == 1, 30, "the job count")
        events.close()
