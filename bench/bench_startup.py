"""Start-up of the `daq` command line (not a test): whole processes, interpreter included.

    .venv/bin/python bench/bench_startup.py [--repeat 20] [--repo DIR]

Runs each of `daq --help`, `daq runs list --store <small store>` and `daq model`
--repeat times as `python -m daq ...` subprocesses and prints the min and median wall
time of each; and `daq serve --sim --port 0` (a fifth as many times, at least 3: each
call takes seconds), timed from the start to the line that prints the page's address,
then stopped. The small store (5 runs of 10 hits) and the service's store and token are
made in a temporary folder and removed afterwards; one untimed call of each command
comes first (page cache, .pyc files, the store's index).

--repo DIR times the code in DIR instead of this checkout (PYTHONPATH=DIR, run from
DIR), e.g. an older commit checked out with `git worktree add /tmp/wt-before <commit>`.

The same figures by hand, with /usr/bin/time (GNU time; "%e" is elapsed seconds):

    for i in $(seq 20); do /usr/bin/time -f %e .venv/bin/python -m daq --help >/dev/null; done
    for i in $(seq 20); do /usr/bin/time -f %e .venv/bin/python -m daq runs list --store DIR >/dev/null; done

and what the imports cost, largest last:

    .venv/bin/python -X importtime -m daq --help 2>&1 >/dev/null | sort -t'|' -k2 -n | tail -30
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def make_store(folder: Path, runs: int = 5) -> None:
    """``runs`` small sealed runs in ``folder`` (bench_store's runs: 10 hits of 1,024 samples)."""
    from bench_store import make_run

    from daq.store import seal

    for seed in range(runs):
        seal(make_run(10, 1024, seed), folder)


def timed(argv: list[str], repo: Path) -> float:
    """Wall seconds of the process ``argv``, run from ``repo`` with its code first on the path."""
    env = {**os.environ, "PYTHONPATH": str(repo), "COLUMNS": "120"}
    start = time.perf_counter()
    done = subprocess.run(
        argv, cwd=repo, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    elapsed = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed ({done.returncode}):\n{done.stderr[-2000:]}")
    return elapsed


def timed_serve(argv: list[str], repo: Path, token_file: Path) -> float:
    """Wall seconds from starting the service ``argv`` to its line with the page's
    address (http://...), after which it is stopped with SIGTERM."""
    env = {**os.environ, "PYTHONPATH": str(repo), "COLUMNS": "120", "DAQ_TOKEN_FILE": str(token_file)}
    start = time.perf_counter()
    proc = subprocess.Popen(
        argv, cwd=repo, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    try:
        seen = []
        for line in proc.stderr:
            seen.append(line)
            if "http://" in line:
                return time.perf_counter() - start
        raise SystemExit(f"{' '.join(argv)} ended before printing its address:\n{''.join(seen)[-2000:]}")
    finally:
        proc.terminate()
        proc.wait(30)
        proc.stderr.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20, help="timed calls of each command")
    parser.add_argument("--repo", type=Path, default=REPO, help="the checkout whose daq is timed")
    args = parser.parse_args()
    repo = args.repo.resolve()
    root = Path(tempfile.mkdtemp(prefix="bench-startup-"))
    try:
        store = root / "store"
        make_store(store)
        daq = [sys.executable, "-m", "daq"]
        commands = {
            "daq --help": [*daq, "--help"],
            "daq runs list --store <5 runs>": [*daq, "runs", "list", "--store", str(store)],
            "daq model": [*daq, "model"],
        }
        rows = []
        for label, argv in commands.items():
            timed(argv, repo)  # warm-up: page cache, .pyc files, the store's index
            times = [timed(argv, repo) for _ in range(args.repeat)]
            rows.append((label, min(times), statistics.median(times)))
        serve = [*daq, "serve", "--sim", "--port", "0", "--jobs", "1", "--store", str(root / "served")]
        label = "daq serve --sim: start to its address"
        token = root / "token"
        timed_serve(serve, repo, token)  # warm-up
        times = [timed_serve(serve, repo, token) for _ in range(max(3, args.repeat // 5))]
        rows.append((label, min(times), statistics.median(times)))
    finally:
        shutil.rmtree(root, ignore_errors=True)
    width = max(len(label) for label, *_ in rows)
    print(f"code: {repo}   calls per command: {args.repeat}")
    print(f"{'command':<{width}}  {'min':>8}  {'median':>8}")
    for label, low, middle in rows:
        print(f"{label:<{width}}  {low * 1e3:6.0f} ms  {middle * 1e3:6.0f} ms")


if __name__ == "__main__":
    main()
