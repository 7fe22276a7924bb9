"""A SIGINT that lands while `daq serve` starts stops it, even when the process was
started with SIGINT ignored (a background job of a script), as it does once serving."""

from __future__ import annotations

import signal
import subprocess
import time

import pytest

from tests.service.service_helpers import DAQ, service_env

pytestmark = pytest.mark.slow


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.parametrize("delay_s", [1.5, 3.0])
def test_one_sigint_during_start_up_stops_the_service(tmp_path, delay_s):
    proc = subprocess.Popen(
        [str(DAQ), "serve", "--sim", "--port", "0", "--jobs", "1", "--store", str(tmp_path / "store")],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=service_env(tmp_path),
        preexec_fn=_ignore_sigint, start_new_session=True,
    )  # fmt: skip
    try:
        time.sleep(delay_s)
        proc.send_signal(signal.SIGINT)
        proc.wait(20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
            proc.stderr.close()
            pytest.fail(f"daq serve ignored one SIGINT {delay_s} s after its start")
    with proc.stderr:
        assert "Traceback" not in proc.stderr.read()
