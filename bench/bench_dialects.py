"""Benchmark of the dialects (not a test): `python bench/bench_dialects.py [--repeat N]`.

For each model (35660A and 3562A in HP mnemonics, 35670A in SCPI) the simulated
analyzer runs in its own process (`daq sim serve --model ...`, so the client does
not share a GIL with it); one measurement is made at each model's default lines,
then what a capture fetches per hit and at the end is timed: the hit's two time
records, then the FRF and the coherence. Over TCP (pyvisa-py SOCKET) and over the
Prologix pty (pyserial). Median (and best) of N rounds, after one warm-up round.
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

from drivers.family import open_analyzer
from drivers.settings import ImpactSettings

DAQ = Path(sys.executable).with_name("daq")
MODELS = ("35660A", "3562A", "35670A")
WIRES = (("TCP", ["--tcp", "0"]), ("pty", ["--pty"]))


def serve(model: str, *args: str) -> tuple[subprocess.Popen, str]:
    proc = subprocess.Popen(
        [str(DAQ), "sim", "serve", "--time-scale", "0", "--model", model, *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    assert proc.stdout is not None
    return proc, proc.stdout.readline().strip()


def measure(resource: str, repeat: int) -> dict[str, object]:
    """Times of one round, s: the two time records, the FRF and coherence, both."""
    with open_analyzer(resource, timeout_s=5.0) as dsa:
        settings = dsa.configure(ImpactSettings(averages=1, preview=False))
        dsa.start()
        dsa.wait_until_done(timeout_s=10)
        records: list[float] = []
        spectra: list[float] = []
        for i in range(repeat + 1):
            t0 = time.perf_counter()
            force, _ = dsa.fetch_time_records()
            t1 = time.perf_counter()
            frf, _ = dsa.fetch_frf(), dsa.fetch_coherence()
            t2 = time.perf_counter()
            if i:  # the first round warms up
                records.append(t1 - t0)
                spectra.append(t2 - t1)
        rounds = [a + b for a, b in zip(records, spectra, strict=True)]
        return {
            "dialect": dsa.dialect.name,
            "shape": f"{force.header.n_points} + {frf.header.n_points}",
            "lines": settings.lines,
            "records": statistics.median(records),
            "spectra": statistics.median(spectra),
            "round": statistics.median(rounds),
            "best": min(rounds),
        }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()
    os.environ.setdefault("DAQ_LOCK_DIR", tempfile.mkdtemp(prefix="daq-bench-locks-"))
    print(f"one hit's TIM1 + TIM2, then FRSP + COHR; median of {args.repeat} rounds (ms)")
    header = (
        f"{'model':<8} {'dialect':<8} {'wire':<5} {'points':>12} {'2 records':>10} {'FRF+COH':>9} "
        f"{'round':>8} {'best':>8}"
    )
    print(header)
    print("-" * len(header))
    for model in MODELS:
        for wire, extra in WIRES:
            proc, resource = serve(model, *extra)
            try:
                r = measure(resource, args.repeat)
            finally:
                proc.send_signal(signal.SIGTERM)
                proc.wait(timeout=10)
                if proc.stdout is not None:
                    proc.stdout.close()
            print(
                f"{model:<8} {r['dialect']:<8} {wire:<5} {r['shape']:>12} {r['records'] * 1e3:10.1f} "  # type: ignore[operator]
                f"{r['spectra'] * 1e3:9.1f} {r['round'] * 1e3:8.1f} {r['best'] * 1e3:8.1f}"  # type: ignore[operator]
            )


if __name__ == "__main__":
    main()
