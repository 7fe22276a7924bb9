"""Benchmark: our automatic modal identification on a wide-band impact test, beside sdypy-EMA's LSCF.

Input (fixed seed): a simulated 5-hit impact test, 25.6 kHz, 1 s records, 26 lightly
damped modes (damping 0.02-0.2 %, 800 Hz-9.3 kHz), a 0.1 ms half-sine force pulse with
a little noise on both channels. The response is a linear (not circular) convolution of
the force with the accelerance's impulse response, computed 4 s long and cut to the
1 s record: the record truncates the decay, as a real one does (leakage, no window).
Or, with ``--csv FILE``, the hits of a file in our CSV layout (daq/formats/csv_text.py);
there is no truth then, only the counts of modes / stable poles.

Ours: analysis.run_analysis.analyze_hits with the default AnalysisOptions() and uniform
windows (it chooses the band, cuts frequency zones, fits each zone's LSCF, the per-hit
scatter and the uncertainties).

Peer: sdypy-EMA ``Model(frf=H1, freq=f, lower, upper, pol_order_high=N).get_poles('lscf')``
on the same H1 (linear_spectra / frf_estimate, uniform windows, 0..fs/2 at 1 Hz lines)
over the band ours chose:
  * zones: one model per zone of ours over that zone's lines, pol_order_high = the zone's
    max_order. sdypy's N yields models of 1..N pole pairs (real denominator of degree
    2, 4, .., 2N), the count of our real-basis zones; our complex-basis zones (bands away
    from 0 Hz) count one pole per denominator degree, so there sdypy fits twice the degree
    for the same number of positive-frequency poles. sdypy has no complex (zoomed) basis:
    every model spans 0..upper with the lines below ``lower`` left out.
  * whole band at pol_order_high = 100 and 200, as a user would run it without zones.
sdypy picks no modes by itself; the simple automatic reading used here: keep the poles
with 0 < damping < 1 inside the band (per zone: inside the zone's core, as ours keeps
them); a pole is stable when the nearest pole of the previous order lies within 1 % in
frequency and 5 % (relative) in damping; a pole stable over at least 5 consecutive
orders (4 stable links) counts. A true mode is found when such a pole lies within 0.2 %
of its frequency at any order; spurious = such poles at the top order (of each zone)
within 0.2 % of no true mode.

Figures: wall time, best of 3; tracemalloc peak of one more run (numpy buffers, not
BLAS/LAPACK workspace); the process max RSS (resource.getrusage) of a subprocess that
builds the data and runs one tool only, beside its RSS before the tool ran.
OMP/OPENBLAS/MKL threads are set to 1 before numpy loads (as daq/cli/app.py does): one core.

Run: .venv/bin/python bench/bench_wideband.py [--csv FILE] [--json]
With --json the table goes to stderr and the figures, as JSON, to stdout.
"""

from __future__ import annotations

import os

# As `daq` itself does (daq/cli/app.py), before numpy loads: one BLAS thread, one core.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse
import contextlib
import io
import json
import resource
import subprocess
import sys
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np
import scipy.signal

from analysis.run_analysis import AnalysisOptions, analyze_hits
from analysis.spectra import frf_estimate, linear_spectra
from analysis.windows import WindowSpec

ROOT = Path(__file__).resolve().parent.parent

SEED = 20261201
FS = 25600.0
N_SAMPLES = 25600  # 1 s: 1 Hz lines
N_HITS = 5
N_MODES = 26
F_RANGE = (800.0, 9300.0)
ZETA_RANGE = (0.0002, 0.002)
PULSE_S = 1e-4
NOISE = 1e-3  # noise std over each channel's peak
LONG = 4  # the response is computed this many records long, then cut

#: Truth match (relative frequency) and the sdypy stability reading.
MATCH_REL = 0.002
STABLE_F_REL = 0.01
STABLE_ZETA_REL = 0.05
STABLE_ORDERS = 5
WHOLE_BAND_ORDERS = (100, 200)
REPEAT = 3
UNIFORM = WindowSpec("uniform")
TOOLS = ("ours", "sdypy-zones", *(f"sdypy-{n}" for n in WHOLE_BAND_ORDERS))


# ---------------------------------------------------------------------------- input
def simulated_test(seed: int = SEED) -> dict:
    """Hits (n_hits, n_samples) force N and response m/s^2, and the true modes."""
    rng = np.random.default_rng(seed)
    fn = np.geomspace(*F_RANGE, N_MODES) * (1 + rng.uniform(-0.015, 0.015, N_MODES))
    fn[0], fn[-1] = F_RANGE
    zeta = np.exp(rng.uniform(*np.log(ZETA_RANGE), N_MODES))
    # Unit modal masses; phi_in * phi_out with either sign (a transfer FRF).
    r = rng.choice([-1.0, 1.0], N_MODES) * rng.uniform(0.3, 1.0, N_MODES)
    wn = 2 * np.pi * fn
    lam = -zeta * wn + 1j * wn * np.sqrt(1 - zeta**2)
    n_long = LONG * N_SAMPLES
    t = np.arange(n_long) / FS
    # Displacement impulse response sum r Im(e^{lam t}) / wd; acceleration = its second
    # derivative: sum r Im(lam^2 e^{lam t}) / wd for t > 0 plus (sum r) delta(t).
    h_acc = np.zeros(n_long)
    for rk, lk in zip(r, lam, strict=True):
        h_acc += rk * np.imag(lk**2 * np.exp(lk * t)) / lk.imag
    direct = float(r.sum())
    force = np.zeros((N_HITS, N_SAMPLES))
    response = np.zeros((N_HITS, N_SAMPLES))
    for k in range(N_HITS):
        amplitude = rng.uniform(80.0, 120.0)
        t0 = (8 + rng.uniform(0.0, 1.0)) / FS
        s = t - t0
        f_long = np.where((s >= 0) & (s <= PULSE_S), amplitude * np.sin(np.pi * s / PULSE_S), 0.0)
        a_long = scipy.signal.fftconvolve(f_long, h_acc)[:n_long] / FS + direct * f_long  # linear
        f_rec, a_rec = f_long[:N_SAMPLES], a_long[:N_SAMPLES]  # the record cuts the decay
        force[k] = f_rec + NOISE * np.abs(f_rec).max() * rng.standard_normal(N_SAMPLES)
        response[k] = a_rec + NOISE * np.abs(a_rec).max() * rng.standard_normal(N_SAMPLES)
    return {
        "force": force,
        "response": response,
        "sample_rate_hz": FS,
        "accepted": np.ones(N_HITS, bool),
        "true_hz": np.sort(fn),
        "source": f"simulated: {N_HITS} hits, {FS:g} Hz, {N_SAMPLES / FS:g} s, {N_MODES} modes, seed {SEED}",
    }


def csv_test(path: Path) -> dict:
    from daq.formats.csv_text import read_csv

    hits = read_csv(path).hits
    if hits is None or np.iscomplexobj(hits.force_n):
        raise SystemExit(f"{path}: no baseband hits to analyse")
    return {
        "force": hits.force_n,
        "response": hits.response_m_s2,
        "sample_rate_hz": float(hits.sample_rate_hz),
        "accepted": np.asarray(hits.accepted, bool),
        "true_hz": None,
        "source": f"{path}: {int(hits.accepted.sum())} hits, {hits.sample_rate_hz:g} Hz, "
        f"{hits.force_n.shape[1] / hits.sample_rate_hz:g} s",
    }


def h1_to_nyquist(data: dict) -> tuple[np.ndarray, np.ndarray]:
    """H1 (n_lines,) on 0..fs/2 with uniform windows, the FRF sdypy is given."""
    acc = data["accepted"]
    spectra = linear_spectra(
        data["force"][acc], data["response"][acc], data["sample_rate_hz"], UNIFORM, UNIFORM,
        max_frequency_hz=data["sample_rate_hz"] / 2,
    )  # fmt: skip
    est = frf_estimate(spectra)
    return est.frequency_hz, np.nan_to_num(est.h1)


# ---------------------------------------------------------------------------- tools
def run_ours(data: dict):
    return analyze_hits(
        data["force"], data["response"], data["sample_rate_hz"], data["accepted"], UNIFORM, UNIFORM,
        options=AnalysisOptions(),
    )  # fmt: skip


def sdypy_poles(f: np.ndarray, h: np.ndarray, lower: float, upper: float, order: int) -> list[np.ndarray]:
    """sdypy's LSCF poles (rad/s) of every order 1..order."""
    from sdypy import EMA

    with contextlib.redirect_stderr(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = EMA.Model(frf=h, freq=f, lower=lower, upper=upper, pol_order_high=int(order))
        model.get_poles(method="lscf", show_progress=False)
    return [np.asarray(p) for p in model.all_poles]


def run_sdypy_zones(f, h, zones) -> list[tuple[dict, list[np.ndarray]]]:
    return [(z, sdypy_poles(f, h, z["low_hz"], z["high_hz"], z["max_order"])) for z in zones]


def run_sdypy_band(f, h, band, order) -> list[tuple[dict, list[np.ndarray]]]:
    zone = {"low_hz": band[0], "high_hz": band[1], "core_low_hz": band[0], "core_high_hz": band[1]}
    return [(zone, sdypy_poles(f, h, band[0], band[1], order))]


# ---------------------------------------------------------------------------- reading
def stable_poles(per_order: list[np.ndarray], low: float, high: float) -> list[np.ndarray]:
    """Per order, (n, 2) (frequency Hz, damping) of the poles stable over >= STABLE_ORDERS orders."""
    out, prev, prev_run = [], np.empty((0, 2)), np.empty(0, int)
    for poles in per_order:
        wn = np.abs(poles)
        with np.errstate(all="ignore"):
            fz = np.column_stack([wn / (2 * np.pi), -poles.real / wn])
        keep = (poles.imag > 0) & np.isfinite(fz).all(axis=1) & (fz[:, 1] > 0) & (fz[:, 1] < 1)
        keep &= (fz[:, 0] >= low) & (fz[:, 0] <= high)
        fz = fz[keep]
        run = np.ones(len(fz), int)
        if len(prev) and len(fz):
            j = np.argmin(np.abs(fz[:, 0, None] - prev[None, :, 0]), axis=1)
            ok = np.abs(fz[:, 0] - prev[j, 0]) <= STABLE_F_REL * fz[:, 0]
            ok &= np.abs(fz[:, 1] - prev[j, 1]) <= STABLE_ZETA_REL * fz[:, 1]
            run[ok] = prev_run[j[ok]] + 1
        out.append(fz[run >= STABLE_ORDERS])
        prev, prev_run = fz, run
    return out


def near(values: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """For each value, whether a target lies within MATCH_REL of it."""
    if values.size == 0 or targets.size == 0:
        return np.zeros(values.size, bool)
    return (np.abs(values[:, None] - targets[None, :]) <= MATCH_REL * targets[None, :]).any(axis=1)


def read_sdypy(fits, true_hz: np.ndarray | None) -> dict:
    found_any, top, top_all = [], [], []
    for zone, per_order in fits:
        stable = stable_poles(per_order, zone["core_low_hz"], zone["core_high_hz"])
        last = per_order[-1]
        with np.errstate(all="ignore"):
            f_last = np.abs(last) / (2 * np.pi)
        top_all.append(
            f_last[(last.imag > 0) & (f_last >= zone["core_low_hz"]) & (f_last <= zone["core_high_hz"])]
        )
        found_any.append(np.concatenate([s[:, 0] for s in stable]) if stable else np.empty(0))
        top.append(stable[-1][:, 0] if stable else np.empty(0))
    found_any, top = np.concatenate(found_any), np.concatenate(top)
    out = {"stable_poles_top_order": int(top.size)}
    if true_hz is not None:
        out["true_found"] = int(near(true_hz, found_any).sum())
        out["spurious"] = int((~near(top, true_hz)).sum())
        out["true_near_top_order"] = int(near(true_hz, np.concatenate(top_all)).sum())
    return out


def read_ours(result, true_hz: np.ndarray | None) -> dict:
    fn = np.array([m.frequency_hz for m in result.modes])
    out = {"modes": int(fn.size)}
    if true_hz is not None:
        out["true_found"] = int(near(true_hz, fn).sum())
        out["spurious"] = int((~near(fn, true_hz)).sum())
    return out


# ---------------------------------------------------------------------------- measuring
def max_rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # Linux: KiB


def measure(fn) -> dict:
    """Best-of-REPEAT wall time, max RSS after those runs, tracemalloc peak of one more run."""
    times, out = [], None
    for _ in range(REPEAT):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    rss = max_rss_mib()
    tracemalloc.start()
    fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return {"time_s": min(times), "tracemalloc_peak_mib": peak / 2**20, "max_rss_mib": rss, "out": out}


def worker(tool: str, csv: str | None, band: list | None, zones: list | None) -> dict:
    """One tool in this process: data, RSS before, then measure(); a JSON-able row."""
    data = csv_test(Path(csv)) if csv else simulated_test()
    true_hz = data["true_hz"]
    if tool == "ours":
        rss_before = max_rss_mib()
        m = measure(lambda: run_ours(data))
        result = m.pop("out")
        row = {
            "band_hz": [result.band.low_hz, result.band.high_hz],
            "zones": [
                {"low_hz": z.low_hz, "high_hz": z.high_hz, "core_low_hz": z.core_low_hz,
                 "core_high_hz": z.core_high_hz, "max_order": z.max_order, "basis": z.basis}
                for z in result.modal.zones
            ],
            **read_ours(result, _in_band(true_hz, result.band.low_hz, result.band.high_hz)),
        }  # fmt: skip
    else:
        f, h = h1_to_nyquist(data)
        from sdypy import EMA  # noqa: F401  (its import is not the tool's memory)

        rss_before = max_rss_mib()
        if tool == "sdypy-zones":
            m = measure(lambda: run_sdypy_zones(f, h, zones))
        else:
            order = int(tool.split("-")[1])
            m = measure(lambda: run_sdypy_band(f, h, band, order))
        row = read_sdypy(m.pop("out"), _in_band(true_hz, *band))
    return {"tool": tool, "rss_before_mib": rss_before, **m, **row}


def _in_band(true_hz, low, high):
    return None if true_hz is None else true_hz[(true_hz >= low) & (true_hz <= high)]


def spawn(tool: str, args, band=None, zones=None) -> dict:
    """Run worker(tool) in a fresh interpreter, so that its max RSS is its own."""
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", tool]
    if args.csv:
        cmd += ["--csv", args.csv]
    if band is not None:
        cmd += ["--band", json.dumps(band), "--zones", json.dumps(zones)]
    done = subprocess.run(cmd, capture_output=True, text=True, check=False, cwd=ROOT)
    if done.returncode != 0:
        raise SystemExit(f"worker {tool} failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


# ---------------------------------------------------------------------------- report
def table(summary: dict) -> str:
    lines = [
        f"input: {summary['source']}",
        f"band (chosen by ours): {summary['band_hz'][0]:.0f}-{summary['band_hz'][1]:.0f} Hz; "
        + ("no truth" if summary["true_in_band"] is None else f"true modes in it: {summary['true_in_band']}"),
        "ours zones: " + ", ".join(f"{z['low_hz']:.0f}-{z['high_hz']:.0f} Hz n={z['max_order']}"
                                   f"{'c' if z['basis'] == 'complex' else 'r'}" for z in summary["zones"]),
        "",
        f"{'tool':<40}{'time s':>8}{'tracemalloc MiB':>17}{'max RSS MiB':>13}{'(before)':>10}"
        f"{'found':>7}{'spurious':>10}{'near@top':>10}",
    ]  # fmt: skip
    for row in summary["rows"]:
        found = row.get("true_found", row.get("modes", row.get("stable_poles_top_order")))
        lines.append(
            f"{row['label']:<40}{row['time_s']:>8.2f}{row['tracemalloc_peak_mib']:>17.1f}"
            f"{row['max_rss_mib']:>13.0f}{row['rss_before_mib']:>10.0f}{found!s:>7}"
            f"{row.get('spurious', '-')!s:>10}{row.get('true_near_top_order', '-')!s:>10}"
        )
    lines += [
        "",
        f"found: true modes within {100 * MATCH_REL:g} % (sdypy: poles stable {100 * STABLE_F_REL:g} % in "
        f"frequency, {100 * STABLE_ZETA_REL:g} % in damping over >= {STABLE_ORDERS} orders); spurious: "
        "ours' modes / sdypy's stable poles at the top order matching no true mode; "
        "near@top: true modes with any sdypy pole within "
        f"{100 * MATCH_REL:g} % at the top order, stable or not; time: best of {REPEAT}, 1 BLAS thread; "
        "max RSS of a process running that tool only, (before): the same before its first run; "
        "n=..r/c: our zone order, real/complex basis; without truth (--csv), found = ours' modes / "
        "sdypy's stable poles at the top order",
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--csv", help="hits from a file in our CSV layout instead of the simulation")
    parser.add_argument("--json", action="store_true", help="figures as JSON on stdout, the table on stderr")
    parser.add_argument("--worker", choices=TOOLS, help=argparse.SUPPRESS)
    parser.add_argument("--band", help=argparse.SUPPRESS)
    parser.add_argument("--zones", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        band = json.loads(args.band) if args.band else None
        zones = json.loads(args.zones) if args.zones else None
        print(json.dumps(worker(args.worker, args.csv, band, zones)))
        return

    ours = spawn("ours", args)
    band, zones = ours["band_hz"], ours["zones"]
    ours["label"] = f"ours analyze_hits ({len(zones)} zones, per-hit)"
    rows = [ours]
    peer = spawn("sdypy-zones", args, band, zones)
    peer["label"] = "sdypy lscf, our zones & orders"
    rows.append(peer)
    for n in WHOLE_BAND_ORDERS:
        row = spawn(f"sdypy-{n}", args, band, zones)
        row["label"] = f"sdypy lscf, whole band, N={n}"
        rows.append(row)
    data = csv_test(Path(args.csv)) if args.csv else simulated_test()
    true_in = _in_band(data["true_hz"], *band)
    summary = {
        "source": data["source"],
        "band_hz": band,
        "zones": zones,
        "true_total": None if data["true_hz"] is None else int(data["true_hz"].size),
        "true_in_band": None if true_in is None else int(true_in.size),
        "rows": rows,
    }
    text = table(summary)
    if args.json:
        print(text, file=sys.stderr)
        print(json.dumps(summary, indent=1))
    else:
        print(text)


if __name__ == "__main__":
    main()
