"""Benchmark of the driver (not a test): `python bench/bench_driver.py [--repeat N]`.

Starts the simulated analyzer in its own process (`daq sim serve`, so the client
does not share a GIL with it), makes one measurement, then times fetching what a
capture fetches per hit: two 1024-point time records and the 401-line complex
FRF, over TCP (pyvisa-py SOCKET) and over the Prologix pty (pyserial).
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from drivers.hp_mnemonic import HPMnemonicAnalyzer as HP35660A
from drivers.settings import ImpactSettings

DAQ = Path(sys.executable).with_name("daq")


def serve(*args: str) -> tuple[subprocess.Popen, str]:
    proc = subprocess.Popen(
        [str(DAQ), "sim", "serve", "--time-scale", "0", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    assert proc.stdout is not None
    return proc, proc.stdout.readline().strip()


def measure(resource: str, repeat: int) -> tuple[float, float, float]:
    with HP35660A.open(resource, timeout_s=5.0) as dsa:
        dsa.configure(ImpactSettings(averages=1, preview=False))
        dsa.start()
        dsa.wait_until_done(timeout_s=10)

        def fetch() -> None:
            dsa.fetch_time_records()
            dsa.fetch_frf()

        fetch()
        rounds = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            fetch()
            rounds.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        for _ in range(repeat):
            dsa.query("ID?")
        query = (time.perf_counter() - t0) / repeat
    return statistics.median(rounds), min(rounds), query


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()
    os.environ.setdefault("DAQ_LOCK_DIR", tempfile.mkdtemp(prefix="daq-bench-locks-"))
    print("fetch = TIM1 + TIM2 (2 x 1024 float64) + FRSP (401 complex): 3 #A blocks, 25 kB")
    print(f"{'transport':<34} {'fetch median':>13} {'fetch best':>11} {'ID? query':>10}")
    for label, extra in (("TCP, pyvisa-py SOCKET", ["--tcp", "0"]), ("Prologix pty, pyserial", ["--pty"])):
        proc, resource = serve(*extra)
        try:
            med, best, query = measure(resource, args.repeat)
        finally:
            proc.send_signal(signal.SIGTERM)
            proc.wait(timeout=10)
            if proc.stdout is not None:
                proc.stdout.close()
        print(f"{label:<34} {med * 1e3:10.1f} ms {best * 1e3:8.1f} ms {query * 1e3:7.2f} ms")


if __name__ == "__main__":
    main()
