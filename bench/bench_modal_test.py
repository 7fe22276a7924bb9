"""Benchmark (not a test): the analysis of a whole multi-point test beside a peer, sdypy-EMA.

    .venv/bin/python bench/bench_modal_test.py [--repeat 3] [--profile]
    DAQ_CORPUS=CORPUS_DIR .venv/bin/python bench/bench_modal_test.py   # with ModeLAB's beam

On the same stacked FRFs, side by side, in one run:

* ours, in-process: `analyze_test` (daq/workflows/test_analysis.py: the points' FRFs read
  from the store, one set of poles by LSCF over all of them, LSFD residues -> shapes with
  their bootstrap, MAC against the beam), default options, as `daq test analyze` calls it;
* ours, whole process: `python -m daq test analyze NAME` (interpreter and imports included);
* the peer: sdypy-EMA's LSCF (`Model.get_poles('lscf')`) on the same FRFs (those
  `analyze_test` reads, `gather`), over our band, at our LSCF order (pole pairs; ours is
  per frequency zone, the largest zone order is taken), its stable-pole selection
  (`select_closest_poles`) near our frequencies, and its LSFD modal constants
  (`get_constants('lsfd')`, lower and upper residuals), the mode shapes. The peer's timing
  starts from the arrays (reading the store is ours only).

Inputs: (1) ModeLAB's measured free-free beam, `$DAQ_CORPUS/modelab-beam/modelab_beam.uff`
(9 FRFs x 51,201 lines, `daq import --as-test`; skipped, with a message, when DAQ_CORPUS
is unset: the data are not in the repository, tests/data/README.md); (2) a simulated
7-point roving-hammer test of the seed's beam (`daq test new` + 7 x `daq capture --sim
--test NAME --next --hits 3 --yes --time-scale 0`, realistic scenario). On (2) `daq test
fit NAME` (least squares) is timed too: in-process `fit_test` alone and the whole process.

Every timed job runs in a child process of its own (this script with --worker, or `daq`),
so its peak RSS is its own: os.wait4's ru_maxrss of that child (what /usr/bin/time's %M
says), interpreter and imports included; "start" is the worker's RSS once its imports are
done and the input is read, before the first timed call. Wall times: median (and range)
of --repeat calls, one BLAS thread per process as `daq` sets (daq/cli/app.py). MAC: of the
complex vectors, ours (unit modal mass) against the peer's modal constants, per mode.

--profile prints cProfile's top 10 (own time and cumulative) of `analyze_test` on the
largest input.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
THREADS = {v: "1" for v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}
ENV = {**os.environ, **THREADS, "PYTHONPATH": str(REPO), "COLUMNS": "120"}
SIM_POINTS = "p1=0.1,p2=0.2,p3=0.3,p4=0.4,p5=0.5,p6=0.6,p7=0.7"
SIM_HITS = 3
MODELAB = Path("modelab-beam") / "modelab_beam.uff"


# --- child processes ------------------------------------------------------------------


def run_child(argv: list[str]) -> tuple[float, float, str]:
    """Run ``argv`` from the repository: (wall s, peak RSS MiB, stdout). Exit on failure."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        start = time.perf_counter()
        child = subprocess.Popen(argv, cwd=REPO, env=ENV, stdout=out, stderr=err, text=True)
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.perf_counter() - start
        child.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        if child.returncode != 0:
            raise SystemExit(f"{' '.join(argv)} failed ({child.returncode}):\n{err.read()[-3000:]}")
        return wall, usage.ru_maxrss / 1024, out.read()


def daq(*args: str) -> list[str]:
    return [sys.executable, "-m", "daq", *args]


def worker(job: str, store: str, name: str, repeat: int, extra: str) -> None:
    """One tool's timed calls in this process; prints JSON (times, start RSS, results)."""
    import resource

    from daq.workflows.test_analysis import analyze_test, gather

    out: dict = {}
    if job == "ours":
        analysis = None
        out["start_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        times = []
        for _ in range(repeat):
            start = time.perf_counter()
            analysis = analyze_test(Path(store), name)
            times.append(time.perf_counter() - start)
        zones = analysis.result.modal.zones
        out.update(
            times=times,
            frequency_hz=[m.frequency_hz for m in analysis.result.modes],
            band=[analysis.result.band.low_hz, analysis.result.band.high_hz],
            order=max(z.max_order if z.basis == "real" else max(1, z.max_order // 2) for z in zones),
            zones=[[z.low_hz, z.high_hz, z.max_order, z.basis] for z in zones],
            shapes=_complex(analysis.shapes.shapes),
            points=[p.name for p in analysis.data.points],
            shape_lines=int(analysis.data.frf.shape[1]),
        )
    elif job == "peer":
        from sdypy import EMA

        ours = json.loads(extra)
        data = gather(Path(store), name)
        f, frf = data.frequency_hz, data.frf
        out["start_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        times = []
        for _ in range(repeat):
            start = time.perf_counter()
            model = EMA.Model(
                frf=frf.copy(), freq=f.copy(), lower=ours["band"][0], upper=ours["band"][1],
                pol_order_high=int(ours["order"]), frf_form="accelerance",
            )  # fmt: skip
            model.get_poles(method="lscf", show_progress=False)
            model.select_closest_poles(list(ours["frequency_hz"]))
            unstable = _nearest_at_top(model, ours["frequency_hz"])
            _, constants = model.get_constants(method="lsfd")
            times.append(time.perf_counter() - start)
        out.update(
            times=times,
            unstable=unstable,
            frequency_hz=[float(x) for x in model.nat_freq],
            shapes=_complex(np.asarray(constants).T),
        )
    elif job == "fit":
        from daq.workflows.test_fit import fit_test

        analysis = analyze_test(Path(store), name)
        out["start_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        times = []
        for _ in range(repeat):
            start = time.perf_counter()
            fit_test(analysis, Path(store), "ls")
            times.append(time.perf_counter() - start)
        out["times"] = times
    elif job == "profile":
        import cProfile
        import pstats

        profile = cProfile.Profile()
        profile.runcall(analyze_test, Path(store), name)
        for key in ("tottime", "cumulative"):
            print(f"--- cProfile of analyze_test({name!r}), top 10 by {key} ---")
            pstats.Stats(profile, stream=sys.stdout).sort_stats(key).print_stats(10)
        return
    print(json.dumps(out))


def _nearest_at_top(model, frequency_hz: list[float]) -> list[int]:
    """Where the peer's stable-pole selection found no stable pole near one of our modes
    (it leaves a NaN pole there, which its LSFD cannot take), its pole nearest our
    frequency at its highest order instead, so the shapes can still be compared. Returns
    those modes' indices (marked in the table)."""
    top = len(model.all_poles) - 1
    poles = np.asarray(model.all_poles[top])
    missing = []
    for k, (row, col) in enumerate(model.pole_ind):
        if np.isfinite(model.all_poles[row][col]) and model.nat_freq[k] > 0:
            continue
        candidates = np.where(poles.imag > 0, np.abs(poles.imag / (2 * np.pi) - frequency_hz[k]), np.inf)
        j = int(np.argmin(candidates))
        model.pole_ind[k] = (top, j)
        model.nat_freq[k] = abs(poles[j]) / (2 * np.pi)
        model.nat_xi[k] = -poles[j].real / abs(poles[j])
        missing.append(k)
    return missing


def _complex(a: np.ndarray) -> list:
    a = np.asarray(a, dtype=complex)
    return [a.real.tolist(), a.imag.tolist()]


def _uncomplex(pair: list) -> np.ndarray:
    return np.asarray(pair[0]) + 1j * np.asarray(pair[1])


def call_worker(job: str, store: Path, name: str, repeat: int, extra: str = "") -> tuple[dict, float]:
    argv = [sys.executable, __file__, "--worker", job, str(store), name, str(repeat), extra]
    _, peak, text = run_child(argv)
    return json.loads(text.strip().splitlines()[-1]), peak


# --- inputs ---------------------------------------------------------------------------


def make_modelab(root: Path) -> tuple[Path, str] | None:
    corpus = os.environ.get("DAQ_CORPUS")
    if not corpus:
        print(f"SKIPPED ModeLAB beam: DAQ_CORPUS is unset (the data are not in the repository: {MODELAB})")
        return None
    path = Path(corpus) / MODELAB
    if not path.exists():
        print(f"SKIPPED ModeLAB beam: {path} does not exist (tests/data/README.md)")
        return None
    store = root / "modelab"
    run_child(daq("import", str(path), "--as-test", "modelab", "--store", str(store)))
    return store, "modelab"


def make_sim(root: Path) -> tuple[Path, str]:
    store = root / "sim7"
    run_child(daq("test", "new", "sim7", "--points", SIM_POINTS, "--store", str(store)))
    for _ in range(7):
        run_child(
            daq("capture", "--sim", "--test", "sim7", "--next", "--hits", str(SIM_HITS), "--yes",
                "--time-scale", "0", "--store", str(store))
        )  # fmt: skip
    return store, "sim7"


# --- figures --------------------------------------------------------------------------


def mac(a: np.ndarray, b: np.ndarray) -> float:
    return float(abs(np.vdot(a, b)) ** 2 / (np.vdot(a, a).real * np.vdot(b, b).real))


def timing(times: list[float]) -> str:
    median = statistics.median(times)
    unit, scale = ("s", 1.0) if median >= 1 else ("ms", 1e3)
    return f"{median * scale:.3g} {unit} ({min(times) * scale:.3g}-{max(times) * scale:.3g})"


def bench_input(label: str, store: Path, name: str, repeat: int, fit: bool, notes: list[str]) -> list[tuple]:
    rows = []
    ours, ours_peak = call_worker("ours", store, name, repeat)
    n_lines = ours["shape_lines"]
    zones = ", ".join(f"{lo:.4g}-{hi:.4g} Hz order {o} {b}" for lo, hi, o, b in ours["zones"])
    print(f"{label}: {len(ours['points'])} FRFs x {n_lines} lines; our zones: {zones}", flush=True)
    our_hz = np.asarray(ours["frequency_hz"])
    modes = ", ".join(f"{x:.5g}" for x in our_hz)
    rows.append((label, "ours: analyze_test (in-process)", timing(ours["times"]),
                 f"{ours_peak:.0f} ({ours['start_mib']:.0f})", f"{len(our_hz)}: {modes}", ""))  # fmt: skip
    times, peaks = [], []
    for _ in range(repeat):
        wall, peak, _ = run_child(daq("test", "analyze", name, "--store", str(store)))
        times.append(wall)
        peaks.append(peak)
    rows.append((label, "ours: daq test analyze (process)", timing(times), f"{max(peaks):.0f}", "same", ""))
    extra = json.dumps({k: ours[k] for k in ("band", "order", "frequency_hz")})
    peer, peer_peak = call_worker("peer", store, name, repeat, extra)
    peer_hz = np.asarray(peer["frequency_hz"])
    close = np.abs(peer_hz - our_hz) <= 0.01 * our_hz
    ours_shapes, peer_shapes = _uncomplex(ours["shapes"]), _uncomplex(peer["shapes"])
    macs = [mac(ours_shapes[k], peer_shapes[k]) for k in range(len(our_hz))]
    unstable = set(peer["unstable"])
    peer_modes = f"{int(close.sum())}/{len(our_hz)} within 1 %: " + ", ".join(
        f"{x:.5g}{'*' if k in unstable else ''}" for k, x in enumerate(peer_hz)
    )
    if unstable:
        notes.append(
            f"{label}: * no stable pole of the peer's (0.1 % frequency, 5 % damping between orders) near our "
            f"{', '.join(f'{our_hz[k]:.5g}' for k in sorted(unstable))} Hz: its nearest pole at order "
            f"{ours['order']} is used there"
        )
    rows.append((label, f"sdypy-EMA: LSCF order {ours['order']} + select + LSFD", timing(peer["times"]),
                 f"{peer_peak:.0f} ({peer['start_mib']:.0f})", peer_modes,
                 " ".join(f"{m:.6f}" for m in macs)))  # fmt: skip
    if fit:
        done, fit_peak = call_worker("fit", store, name, repeat)
        rows.append((label, "ours: fit_test ls (in-process)", timing(done["times"]),
                     f"{fit_peak:.0f} ({done['start_mib']:.0f})", "R 3x3", "no peer"))  # fmt: skip
        times, peaks = [], []
        for _ in range(repeat):
            wall, peak, _ = run_child(daq("test", "fit", name, "--store", str(store)))
            times.append(wall)
            peaks.append(peak)
        fit_row = (
            label,
            "ours: daq test fit (process, ls)",
            timing(times),
            f"{max(peaks):.0f}",
            "R 3x3",
            "no peer",
        )
        rows.append(fit_row)
    return rows


def print_table(rows: list[tuple]) -> None:
    head = ("input", "tool", "wall: median (min-max)", "peak RSS MiB (start)", "modes, Hz", "MAC ours-peer")
    widths = [max(len(str(r[i])) for r in [head, *rows]) for i in range(len(head))]
    print()
    for row in [head, tuple("-" * w for w in widths), *rows]:
        print("  ".join(f"{c!s:<{w}}" for c, w in zip(row, widths, strict=True)).rstrip())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="timed calls of each tool on each input")
    parser.add_argument("--profile", action="store_true", help="cProfile top 10: analyze_test, largest input")
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores; --repeat {args.repeat}; one BLAS thread per process", flush=True)
    with tempfile.TemporaryDirectory(prefix="bench-modal-test-") as tmp:
        root = Path(tmp)
        inputs = []
        modelab = make_modelab(root)
        if modelab is not None:
            inputs.append(("ModeLAB beam (9 x 51,201)", *modelab, False))
        inputs.append((f"sim 7 points x {SIM_HITS} hits", *make_sim(root), True))
        rows, notes = [], []
        for label, store, name, fit in inputs:
            rows += bench_input(label, store, name, args.repeat, fit, notes)
        print_table(rows)
        for note in notes:
            print(note)
        if args.profile:
            _, store, name, _ = inputs[0]
            print()
            print(run_child([sys.executable, __file__, "--worker", "profile", str(store), name, "1", ""])[2])


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        sys.path.insert(0, str(REPO))
        worker(sys.argv[2], sys.argv[3], sys.argv[4], int(sys.argv[5]), sys.argv[6])
    else:
        main()
