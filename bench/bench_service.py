"""Benchmark: `daq serve` under 50 clients, and how fast a hit reaches the page.

Run: .venv/bin/python bench/bench_service.py [--runs 100] [--folder /tmp/daq-bench-service]

1. A store of N runs: one simulated capture, cloned under new ids (the same
   records, so every run is analysable), then analysed and fitted with
   `daq fit --all` (timed).
2. `daq serve --sim` on that store; 50 asyncio clients (httpx) for 5 s each:
   GET /api/runs (the whole listing with each run's results) and
   GET /api/runs/<id>/analysis; requests per second and latency percentiles.
3. Hit to page: with the live page open in headless Chromium (Playwright, Debian's
   /usr/bin/chromium), an auto capture of 5 hits; for each hit, the time from the
   service taking its records off the analyzer (the hit's timestamp_utc) to its
   row appearing in the page's hits table, drawn in the same handler as its
   traces. Same machine, same clock.
"""

from __future__ import annotations

import argparse
import asyncio
import dataclasses
import json
import os
import re
import shutil
import signal
import statistics
import subprocess
import sys
import time
from datetime import datetime
from pathlib import Path

import httpx

ROOT = Path(__file__).resolve().parents[1]
DAQ = Path(sys.executable).with_name("daq")
CLIENTS = 50
SECONDS = 5.0


def make_store(folder: Path, n_runs: int, env: dict[str, str]) -> Path:
    from daq.store import Store, new_run_id

    store = folder / "store"
    marker = folder / f"ready-{n_runs}"
    if marker.exists():
        return store
    shutil.rmtree(folder, ignore_errors=True)
    store.mkdir(parents=True)
    subprocess.run(
        [str(DAQ), "capture", "--sim", "--hits", "5", "--yes", "--store", str(store), "--time-scale", "0"],
        check=True, env=env, capture_output=True,
    )  # fmt: skip
    the_store = Store(store)
    (original,) = the_store.list()
    run = the_store.open(original.run_id)
    for _ in range(n_runs - 1):
        the_store.seal(dataclasses.replace(run, run_id=new_run_id()))
    t0 = time.perf_counter()
    subprocess.run(
        [str(DAQ), "fit", "--all", "--store", str(store)], check=True, env=env, capture_output=True
    )
    seconds = time.perf_counter() - t0
    print(f"analyse + fit {n_runs} runs (daq fit --all, {os.cpu_count()} cores): {seconds:.1f} s")
    marker.touch()
    return store


def start_service(store: Path, env: dict[str, str]) -> tuple[subprocess.Popen, str, str]:
    proc = subprocess.Popen(
        [str(DAQ), "serve", "--sim", "--port", "0", "--store", str(store), "--time-scale", "0.05"],
        stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True, env=env, start_new_session=True,
    )  # fmt: skip
    for line in proc.stderr:
        match = re.search(r"open (http://\S+)/#token=([0-9a-f]+)", line)
        if match:
            return proc, match.group(1), match.group(2)
    raise SystemExit("daq serve did not start")


async def load(url: str, path: str) -> tuple[int, list[float]]:
    latencies: list[float] = []
    deadline = time.perf_counter() + SECONDS

    async def client() -> None:
        async with httpx.AsyncClient(base_url=url, timeout=60) as c:
            while time.perf_counter() < deadline:
                t0 = time.perf_counter()
                r = await c.get(path)
                r.raise_for_status()
                latencies.append(time.perf_counter() - t0)

    t0 = time.perf_counter()
    await asyncio.gather(*(client() for _ in range(CLIENTS)))
    return int(len(latencies) / (time.perf_counter() - t0)), latencies


def hit_to_page(url: str, token: str) -> list[float]:
    from playwright.sync_api import sync_playwright

    chromium = os.environ.get("DAQ_CHROMIUM", "/usr/bin/chromium")
    args = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update"]
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=args)
        page = browser.new_page()
        page.goto(f"{url}/#token={token}")
        page.wait_for_selector("#hits-table")
        page.evaluate(
            """() => { window.__rows = {};
            new MutationObserver(() => {
              for (const tr of document.querySelectorAll('#hits-table tr[data-index]')) {
                const i = tr.dataset.index; if (!(i in window.__rows)) window.__rows[i] = Date.now();
              }
            }).observe(document.querySelector('#hits-table'), {childList: true, subtree: true}); }"""
        )
        with httpx.Client(base_url=url, headers={"Authorization": f"Bearer {token}"}) as c:
            c.post("/api/capture", json={"hits": 5, "auto": True}).raise_for_status()
            while c.get("/api/capture").json()["state"] != "idle":
                time.sleep(0.1)
            hits = c.get("/api/capture").json()["hits"]
        shown = page.evaluate("() => window.__rows")
        browser.close()
    out = []
    for hit in hits:
        taken = datetime.fromisoformat(hit["timestamp_utc"].replace("Z", "+00:00")).timestamp()
        out.append(shown[str(hit["index"])] / 1000.0 - taken)
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--folder", type=Path, default=Path("/tmp/daq-bench-service"))
    args = parser.parse_args()
    env = {
        **os.environ,
        "DAQ_TOKEN_FILE": str(args.folder / "token"),
        "DAQ_LOCK_DIR": str(args.folder / "locks"),
    }
    env["DAQ_CONFIG"] = str(args.folder / "none.toml")
    store = make_store(args.folder, args.runs, env)
    proc, url, token = start_service(store, env)
    try:
        with httpx.Client(base_url=url) as c:
            runs = c.get("/api/runs").json()
            some = runs[len(runs) // 2]["run_id"]
            print(f"{len(runs)} runs in the store; listing is {len(json.dumps(runs)) / 1024:.0f} KiB of JSON")
        for name, path in (("list runs", "/api/runs"), ("one run's analysis", f"/api/runs/{some}/analysis")):
            rate, lat = asyncio.run(load(url, path))
            q = statistics.quantiles(lat, n=100)
            print(
                f"{name:20s}: {rate:6d} requests/s with {CLIENTS} clients; "
                f"latency p50 {q[49] * 1e3:.0f} ms, p99 {q[98] * 1e3:.0f} ms"
            )
        try:
            delays = hit_to_page(url, token)
            print("hit to page (records taken -> row and traces drawn): "
                  + ", ".join(f"{d * 1e3:.0f}" for d in delays) + " ms")  # fmt: skip
        except Exception as exc:  # the browser part is optional
            print(f"hit to page: not measured ({type(exc).__name__}: {exc})")
    finally:
        proc.send_signal(signal.SIGINT)
        proc.wait(30)


if __name__ == "__main__":
    main()
