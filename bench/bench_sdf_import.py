"""SDF import timings (not a test): a 1,000-trace file through the reader, the run
mapping and `daq import`.

    .venv/bin/python bench/bench_sdf_import.py [--traces 1000] [--samples 1024] [--kind hits|frf]

--kind hits (default): 1,000 hits of a force and a response record each (one time data
header, 1,000 scans, float64); --kind frf: 1,000 FRFs with coherence. The file is
written with `daq export`'s writer in a temporary folder, removed afterwards. Prints the
file size and, best of --repeat, the time of: the reader alone (read_sdf), the reader
plus the mapping to a run's parts (read_sdf_run), `daq import` in this process, and
`daq import` as a user runs it (a new process, interpreter start included).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from daq.cli.app import main
from daq.formats.sdf import read_sdf, read_sdf_run, write_sdf_run
from daq.store import Hits, MeasuredFrf, Run, new_run_id


def make_run(kind: str, n: int, samples: int, seed: int = 1) -> Run:
    rng = np.random.default_rng(seed)
    hits = frfs = None
    if kind == "hits":
        t = np.arange(samples) / 2560.0
        response = np.sin(2 * np.pi * 27.3 * t) * np.exp(-t / 0.4) * 20 + rng.normal(0, 0.05, (n, samples))
        force = rng.normal(0, 0.01, (n, samples))
        force[:, 32:40] += 150.0
        hits = Hits(
            force_n=force, response_m_s2=response, sample_rate_hz=2560.0, start_s=-32 / 2560.0, center_hz=0.0,
            accepted=np.ones(n, bool), reject_reason=[""] * n, overload=np.zeros((n, 2), bool),
            peak_force_n=force.max(axis=1), timestamp_utc=["2026-11-23T10:15:03.123Z"] * n, checks=[{}] * n,
        )  # fmt: skip
    else:
        lines = samples // 2 + 1
        frf = rng.normal(size=(n, lines)) + 1j * rng.normal(size=(n, lines))
        frfs = MeasuredFrf(
            np.linspace(0.0, 1000.0, lines), frf, rng.uniform(0, 1, (n, lines)), [f"H{k}" for k in range(n)]
        )
    return Run(
        new_run_id(), "simulated", True, "2026-11-23T10:15:03.123Z", "2026-11-23T10:16:03.123Z",
        hits=hits, analyzer=frfs,
    )  # fmt: skip


def best_of(repeat: int, fn) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main_cli(args: list[str]) -> None:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        status = main(args)
    if status != 0:
        raise SystemExit(f"daq {' '.join(args)} failed with status {status}")


def run(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--traces", type=int, default=1000, help="hits (2 records each) or FRFs")
    parser.add_argument(
        "--samples", type=int, default=1024, help="samples per record (FRFs: samples/2+1 lines)"
    )
    parser.add_argument("--kind", choices=("hits", "frf"), default="hits")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="daq-bench-sdf-") as folder:
        work = Path(folder)
        the_run = make_run(args.kind, args.traces, args.samples)
        path = work / "bench.sdf"
        written = best_of(1, lambda: write_sdf_run(the_run, path))
        size_mb = path.stat().st_size / 1e6
        what = f"{args.traces} hits x 2 records" if args.kind == "hits" else f"{args.traces} FRFs + coherence"
        print(f"SDF file: {what} of {args.samples} samples, {size_mb:.1f} MB (written in {written:.3f} s)")
        reader = best_of(args.repeat, lambda: read_sdf(path))
        mapping = best_of(args.repeat, lambda: read_sdf_run(path))
        stores = iter(range(10**6))
        in_process = best_of(
            args.repeat, lambda: main_cli(["import", str(path), "--store", str(work / f"s{next(stores)}")])
        )
        daq = Path(sys.executable).with_name("daq")

        def subprocess_import() -> None:
            command = [str(daq), "import", str(path), "--store", str(work / f"p{next(stores)}")]
            subprocess.run(command, check=True, capture_output=True)

        whole = best_of(args.repeat, subprocess_import)
        print(f"{'read_sdf (reader alone)':<40} {reader * 1000:9.1f} ms  {size_mb / reader:7.0f} MB/s")
        print(f"{'read_sdf_run (reader + run parts)':<40} {mapping * 1000:9.1f} ms")
        print(f"{'daq import, in this process':<40} {in_process * 1000:9.1f} ms  (with sealing the HDF5 run)")
        print(f"{'daq import, new process':<40} {whole * 1000:9.1f} ms  (with interpreter start and imports)")


if __name__ == "__main__":
    run()
