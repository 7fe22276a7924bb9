"""Peer reference modal results for the public measured-data corpus (not a test; a bench tool).

The corpus itself lives outside the repository (data we did not make and may not commit); see
tests/data/README.md for each set's source, commit, licence and conversion. This script reads the
*converted* files (the ones `daq import` reads) and computes, with third-party tools only:

* time records: the H1 FRF and coherence with pyFRF (no window, linear averaging over the hits),
  taken as ACCELERANCE (acceleration over force, see "FRF form" below);
* every set: LSCF poles with sdypy-EMA (``Model(...).get_poles()``) for orders 2..2*ORDER_HIGH,
  reduced to "peer stable modes" by the rule below;
* half-power (-3 dB) frequency and damping on |H| for peer modes that are isolated.

Stability rule (documented, deterministic; no GUI picking):

1. Keep poles with 0 < zeta < 0.2 inside the band.
2. A pole of order n is *stable* when order n-2 (the previous LSCF order) has a pole within 1 %
   in frequency and 5 % (relative) in damping.
3. Stable poles of all orders are sorted by frequency and chained into clusters: a pole joins
   the current cluster when it is within 0.5 % of the cluster's running median frequency.
4. A cluster is a peer mode when it holds poles of at least 40 % of the orders computed (and at
   least 5 orders). Every cluster of at least 5 orders is listed in ``peer_supported_hz``: the
   features of the data the peer's diagram shows at all. ``resonance_peaks_hz`` lists the peaks
   of |H| standing 10 dB above their surroundings (where the coherence is >= 0.9): the
   half-power method's peak picking. A mode of ours that neither list supports is spurious.
   Reported: median frequency, median damping, damping spread (min, max and inter-quartile
   range over the cluster's orders), number of orders.

Half-power: the peak of |H| (sum over FRFs of |H|^2, square-rooted) nearest the peer frequency,
-3 dB crossings interpolated linearly; reported only when the peak lies within one bandwidth
(or 2 lines) of the peer frequency and no other peer mode lies within
+-5 half-power bandwidths, and flagged ``resolution_limited`` when the bandwidth spans < 4 lines.

FRF form. Every set is fitted as accelerance, (m/s^2)/N, and sdypy-EMA is told so
(``frf_form="accelerance"``), because that is what the data are and what ``daq analyze``
analyses: the time records' responses are accelerometer signals (``resp_type='a'``, pyFRF's
default) and the UFF sets store accelerance (ordinate data type 12, which is also what
sdypy-EMA's own ``read_uff`` maps to "accelerance"). pyFRF's ``get_H1()`` does NOT return that:
for ``resp_type='a'`` it multiplies H1 by (-j/omega)^2, i.e. returns receptance (displacement
over force, its docstring says "(receptance)"); only ``get_FRF(frf_estimator="H1",
frf_form="accelerance")`` multiplies back by (j omega)^2. Until issue 20 this script took
``get_H1()`` and fitted the receptance while telling sdypy "accelerance": the LSCF poles do not
depend on ``frf_form`` (it only selects the LSFD residual terms), but they do depend on which
FRF is fitted -- the 1/omega^2 weighting moves broad, peakless features (lvm-2ch m2's 214.5 Hz
becomes 215.1 Hz on the accelerance) and the damping of resolution-limited peaks -- and the
half-power and peak readings of |H| changed with it.

Usage::

    python bench/corpus_reference.py --corpus CORPUS_DIR [-o tests/data/corpus_reference.json]

Output: JSON with one entry per set (band, method settings, peer modes, half-power values,
published values where the source publishes any). Numbers only, no data.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ORDER_HIGH = 60  # sdypy pol_order_high: LSCF orders 2, 4, ..., 2*ORDER_HIGH
ZETA_MAX = 0.2
F_TOL = 0.01  # stability in frequency between consecutive orders (relative)
Z_TOL = 0.05  # stability in damping between consecutive orders (relative)
CLUSTER_TOL = 0.005  # clustering of stable poles in frequency (relative to running median)
MIN_SHARE = 0.4  # a peer mode is present in at least this share of the orders
MIN_ORDERS = 5
#: The form every set is fitted in and sdypy-EMA is told: the data's and daq analyze's own.
FRF_FORM = "accelerance"


@dataclass(frozen=True)
class SetSpec:
    """One converted file of the corpus and the band its peer reference uses."""

    name: str
    path: str  # relative to the corpus directory
    kind: str  # "csv-hits" (daq CSV layout), "text-hit" (time, force, response; no header) or "uff-frf"
    band: tuple[float, float]
    published: dict | None = None


SETS: tuple[SetSpec, ...] = (
    SetSpec("pyfrf-impact", "pyfrf-impact/pyfrf_impact.csv", "csv-hits", (500.0, 5500.0)),
    SetSpec("pyuff-3frf", "pyuff-3frf/pyuff_3frf.uff", "uff-frf", (20.0, 990.0)),
    SetSpec("lvm-2ch-m1", "lvm-2ch/lvm_m1.csv", "csv-hits", (5.0, 250.0)),
    SetSpec("lvm-2ch-m2", "lvm-2ch/lvm_m2.csv", "csv-hits", (5.0, 250.0)),
    SetSpec(
        "modelab-beam",
        "modelab-beam/modelab_beam.uff",
        "uff-frf",
        (65.0, 995.0),  # the source's own fMin 65 Hz, fMax 1000 Hz (Example/SignalCalc/setup.csv)
        published={
            "source": "github.com/alxhslm/ModeLAB @4a27c9822565ba9eb282d479333d3d920899182c",
            "where": "Example/modeshapes.png (subplot titles '%0.2f Hz' of modes.omega/2/pi, "
            "written by Example/run_example.m, method 'peak_fit'); README.md 'Example'",
            "method": "ModeLAB modal_analysis peak_fit in the bands fLMode..fHMode of setup.csv",
            "modes": [
                {"frequency_hz": 111.99, "band_hz": [108, 116]},
                {"frequency_hz": 306.86, "band_hz": [300, 312]},
                {"frequency_hz": 596.37, "band_hz": [590, 600]},
                {"frequency_hz": 974.14, "band_hz": [970, 980]},
            ],
            "damping": "not published",
        },
    ),
    SetSpec(
        "tool-holder",
        "tool-holder/tool_holder.uff",
        "uff-frf",
        (100.0, 3500.0),  # the source's own plots, Proj_3.m rows 101:3500 of each file
        published={
            "source": "github.com/leekunhwee/Vibration-Signal-Processing "
            "@d9edffe54f69bf34368cd47f9389b78fc3d360cf",
            "where": "ExperimentalModalAnalysis/README.md, the table of H11..H15 at R(1031), R(1104), "
            "I(1074), R(1914), R(2092), I(1961), R(2546), R(2783), I(2617)",
            "method": "by hand on the receptances: natural frequency at the peak of the imaginary part, "
            "damping (w2 - w1) / (2 wn) from the frequencies of the extrema of the real part",
            "modes": [
                {"frequency_hz": 1074.0, "real_extrema_hz": [1031, 1104]},
                {"frequency_hz": 1961.0, "real_extrema_hz": [1914, 2092]},
                {"frequency_hz": 2617.0, "real_extrema_hz": [2546, 2783]},
            ],
            "damping": "derived from the extrema: (1104-1031)/(2*1074) = 3.40 %, (2092-1914)/(2*1961) = "
            "4.54 %, (2783-2546)/(2*2617) = 4.53 %",
        },
    ),
    SetSpec(
        "tool-holder-impact",
        "tool-holder-impact/original/Point1_Channel1_CH1.txt",
        "text-hit",
        # From 50 Hz (ImpactSignalProcessing.m plots the FRF from 50 Hz) to where the hit's
        # force autospectrum has fallen 20 dB below its level up to 500 Hz (the hammer guidance
        # of analysis/band_choice.py; -22 dB at 1.4 kHz, -31 dB at 2 kHz, computed from the record).
        (50.0, 1400.0),
    ),
    SetSpec(
        "free-beam",
        "free-beam/poutre_Al_flexion.txt",
        "text-hit",
        # Our default band's ends (force within 20 dB up to 6 kHz), from the first line above 0 Hz.
        (9.0, 6000.0),
        published={
            "source": "github.com/lcharleux/numerical_analysis @794d4626f5a45a9003992755d52ef803e3943fcc",
            "where": "doc/Traitement_signal.rst, '2. Etude de la poutre': an aluminium beam "
            "600 x 30 x 15 mm, rho 2700 kg/m^3, struck by an impact hammer to vibrate in bending; "
            "f_n = C_n^2 / (2 pi l^2) sqrt(E / rho) sqrt(I / S), C_n^2 = 22.37, 61.67, "
            "((2n + 1) pi / 2)^2; E is the exercise's unknown",
            "method": "Euler-Bernoulli free-free bending; the frequencies' ratios to the first are exact",
            "modes": [],
            "damping": "not published",
        },
    ),
)

#: UFF 58 ordinate data types of the response, and the factor of (j omega)^k that turns
#: that FRF into accelerance: 8 displacement (receptance), 11 velocity, 12 acceleration.
UFF_FORMS = {8: 2, 11: 1, 12: 0}


def read_hits_csv(path: Path) -> tuple[float, np.ndarray, np.ndarray]:
    """Read the daq CSV layout (hit,time,force,response); returns fs, force and response (hits, n)."""
    fs = None
    with path.open() as handle:
        for line in handle:
            if not line.startswith("#"):
                break
            if "sample_rate_hz" in line:
                fs = float(line.split("=", 1)[1])
    table = np.loadtxt(path, delimiter=",", skiprows=_header_rows(path), usecols=(0, 2, 3), ndmin=2)
    hits = table[:, 0].astype(int)
    n_hits = hits.max() + 1
    force = table[:, 1].reshape(n_hits, -1)
    resp = table[:, 2].reshape(n_hits, -1)
    if fs is None:
        raise ValueError(f"{path}: no sample_rate_hz comment")
    return fs, force, resp


def _header_rows(path: Path) -> int:
    """Number of comment lines plus the header row."""
    with path.open() as handle:
        count = 0
        for line in handle:
            count += 1
            if not line.startswith("#"):
                return count
    return count


def h1_from_hits(fs: float, force: np.ndarray, resp: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """pyFRF H1 as accelerance and coherence, no window, linear averaging over the hits.

    Returns f, H (1, nf), coh. ``get_H1()`` alone would be receptance (module docstring); the
    0 Hz line comes back NaN (pyFRF divides by omega = 0), as get_H1's did; lscf_poles zeroes it,
    and it lies below every band.
    """
    import pyFRF

    fs_int = round(fs)  # pyFRF takes an int rate; the corpus rates are whole numbers of Hz
    if abs(fs - fs_int) > 1e-6 * fs:
        raise ValueError(f"sample rate {fs} Hz is not a whole number of Hz")
    frf = pyFRF.FRF(
        fs_int, exc=force, resp=resp, exc_type="f", resp_type="a", window="none", weighting="linear"
    )
    with np.errstate(invalid="ignore"):  # inf * 0 at 0 Hz
        h = np.atleast_2d(np.squeeze(frf.get_FRF(frf_estimator="H1", frf_form=FRF_FORM)))
    coh = np.squeeze(frf.get_coherence())
    return np.asarray(frf.get_f_axis()), h, np.atleast_1d(coh)


def read_uff_frf(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """All dataset-58 FRFs (function type 4) of a UFF file on one axis: f, H (n_frf, nf)."""
    import pyuff

    uff = pyuff.UFF(str(path))
    types = list(uff.get_set_types())
    sets = uff.read_sets([i for i, t in enumerate(types) if t == 58])
    sets = sets if isinstance(sets, list) else [sets]
    frfs = [s for s in sets if s["func_type"] == 4]
    forms = {s.get("ordinate_spec_data_type") for s in frfs}
    if len(forms) != 1 or not forms <= set(UFF_FORMS):
        raise ValueError(f"{path}: ordinate data types {sorted(forms)}, not one of {sorted(UFF_FORMS)}")
    f = np.asarray(frfs[0]["x"], dtype=float)
    h = np.array([np.asarray(s["data"], dtype=complex) for s in frfs])
    # To accelerance, the form fitted (FRF_FORM): times (j omega)^k.
    return f, h * (2j * np.pi * f) ** UFF_FORMS[forms.pop()]


def read_text_hit(path: Path) -> tuple[float, np.ndarray, np.ndarray]:
    """One hit in a text table of time [s], force, response (a header row of names, or none):
    fs and (1, n) arrays. The rate comes from the time column's mean step."""
    with path.open(encoding="latin-1") as handle:
        first = handle.readline().split()
    try:
        [float(cell) for cell in first]
        skip = 0
    except ValueError:
        skip = 1  # "T[s] F[N] A[g]"
    table = np.loadtxt(path, ndmin=2, skiprows=skip)
    fs = (table.shape[0] - 1) / (table[-1, 0] - table[0, 0])
    return float(fs), table[None, :, 1], table[None, :, 2]


def lscf_poles(
    f: np.ndarray, h: np.ndarray, band: tuple[float, float]
) -> list[tuple[np.ndarray, np.ndarray]]:
    """sdypy-EMA LSCF poles per order: list of (frequency Hz, damping ratio) arrays, ascending order."""
    from sdypy import EMA

    keep = f <= band[1]
    h = np.where(np.isfinite(h), h, 0.0)  # e.g. H1 at 0 Hz; LSCF needs finite lines below the band
    model = EMA.Model(
        frf=h[:, keep],
        freq=f[keep],
        lower=band[0],
        upper=band[1],
        pol_order_high=ORDER_HIGH,
        frf_form=FRF_FORM,  # what the FRF handed over is (module docstring, "FRF form")
    )
    model.get_poles(method="lscf", show_progress=False)
    out = []
    for fp, zp in zip(model.pole_freq, model.pole_xi, strict=True):
        fp = np.asarray(fp, dtype=float)
        zp = np.asarray(zp, dtype=float)
        ok = (fp >= band[0]) & (fp <= band[1]) & (zp > 0) & (zp < ZETA_MAX)
        out.append((fp[ok], zp[ok]))
    return out


def stable_modes(orders: list[tuple[np.ndarray, np.ndarray]], need: int | None = None) -> list[dict]:
    """Apply the stability and clustering rule of the module docstring; ``need``: orders a
    cluster must hold (default: MIN_SHARE of the orders computed, at least MIN_ORDERS)."""
    stable = []  # (frequency, damping, order index)
    for k in range(1, len(orders)):
        f_prev, z_prev = orders[k - 1]
        for fp, zp in zip(*orders[k], strict=True):
            if f_prev.size == 0:
                continue
            df = np.abs(f_prev - fp) / fp
            dz = np.abs(z_prev - zp) / zp
            if np.any((df < F_TOL) & (dz < Z_TOL)):
                stable.append((fp, zp, k))
    stable.sort()
    clusters: list[list[tuple[float, float, int]]] = []
    for pole in stable:
        if clusters and abs(pole[0] - np.median([p[0] for p in clusters[-1]])) <= CLUSTER_TOL * pole[0]:
            clusters[-1].append(pole)
        else:
            clusters.append([pole])
    if need is None:
        need = max(MIN_ORDERS, int(np.ceil(MIN_SHARE * len(orders))))
    modes = []
    for cluster in clusters:
        by_order: dict[int, tuple[float, float]] = {}
        for fp, zp, k in cluster:  # one pole per order: the one nearest the cluster median
            fm = np.median([p[0] for p in cluster])
            if k not in by_order or abs(fp - fm) < abs(by_order[k][0] - fm):
                by_order[k] = (fp, zp)
        if len(by_order) < need:
            continue
        fr = np.array([v[0] for v in by_order.values()])
        zr = np.array([v[1] for v in by_order.values()])
        modes.append(
            {
                "frequency_hz": round(float(np.median(fr)), 4),
                "damping_ratio": round(float(np.median(zr)), 6),
                "damping_min": round(float(zr.min()), 6),
                "damping_max": round(float(zr.max()), 6),
                "damping_iqr": round(float(np.subtract(*np.percentile(zr, [75, 25]))), 6),
                "frequency_spread_hz": round(float(np.ptp(fr)), 4),
                "orders": len(by_order),
            }
        )
    return modes


#: A resonance peak of |H| stands this far above the valleys either side, dB.
PEAK_PROMINENCE_DB = 10.0
#: ... where the coherence (time records) is at least this.
PEAK_MIN_COHERENCE = 0.9


def resonance_peaks(f: np.ndarray, h: np.ndarray, band: tuple[float, float], coh=None) -> list[float]:
    """Frequencies of the peaks of |H| (RMS over the FRFs, dB) that stand PEAK_PROMINENCE_DB
    above their surroundings inside ``band`` (and where the coherence is good): the peak
    picking of the half-power method, the seed's own reading of an FRF."""
    from scipy.signal import find_peaks

    mag = np.sqrt(np.mean(np.abs(np.atleast_2d(h)) ** 2, axis=0))
    level = 20 * np.log10(np.maximum(mag, np.finfo(float).tiny))
    peaks, _ = find_peaks(level, prominence=PEAK_PROMINENCE_DB)
    keep = (f[peaks] >= band[0]) & (f[peaks] <= band[1])
    if coh is not None:
        keep &= np.atleast_2d(coh).mean(axis=0)[peaks] >= PEAK_MIN_COHERENCE
    return [round(float(x), 4) for x in f[peaks[keep]]]


def half_power(f: np.ndarray, h: np.ndarray, modes: list[dict]) -> list[dict]:
    """Half-power frequency and damping of isolated peer modes on the combined |H|."""
    mag = np.sqrt(np.sum(np.abs(h) ** 2, axis=0))
    df = f[1] - f[0]
    out = []
    freqs = [m["frequency_hz"] for m in modes]
    for fm, mode in zip(freqs, modes, strict=True):
        bw_guess = max(2 * mode["damping_ratio"] * fm, df)
        if any(abs(o - fm) < 5 * bw_guess for o in freqs if o != fm):
            continue
        lo = np.searchsorted(f, fm - 3 * bw_guess - 2 * df)
        hi = np.searchsorted(f, fm + 3 * bw_guess + 2 * df)
        if hi - lo < 3:
            continue
        i = lo + int(np.argmax(mag[lo:hi]))
        if abs(f[i] - fm) > max(bw_guess, 2 * df):  # no peak of |H| at this pole: not isolated
            continue
        level = mag[i] / np.sqrt(2)
        a = i
        while a > 0 and mag[a] > level:
            a -= 1
        b = i
        while b < len(mag) - 1 and mag[b] > level:
            b += 1
        if a == 0 or b == len(mag) - 1:
            continue
        f1 = f[a] + (level - mag[a]) * (f[a + 1] - f[a]) / (mag[a + 1] - mag[a])
        f2 = f[b - 1] + (level - mag[b - 1]) * (f[b] - f[b - 1]) / (mag[b] - mag[b - 1])
        out.append(
            {
                "peer_frequency_hz": fm,
                "peak_frequency_hz": round(float(f[i]), 4),
                "damping_ratio": round(float((f2 - f1) / (2 * f[i])), 6),
                "bandwidth_lines": round(float((f2 - f1) / df), 2),
                "resolution_limited": bool((f2 - f1) / df < 4),
            }
        )
    return out


def reference(corpus: Path, spec: SetSpec) -> dict:
    """Peer reference of one set."""
    path = corpus / spec.path
    entry: dict = {"file": spec.path, "band_hz": list(spec.band)}
    if spec.kind in ("csv-hits", "text-hit"):
        fs, force, resp = read_hits_csv(path) if spec.kind == "csv-hits" else read_text_hit(path)
        f, h, coh = h1_from_hits(fs, force, resp)
        sel = (f >= spec.band[0]) & (f <= spec.band[1])
        entry.update(
            {
                "sample_rate_hz": fs,
                "hits": int(force.shape[0]),
                "samples_per_hit": int(force.shape[1]),
                "frf_method": "pyFRF H1 (get_FRF frf_form='accelerance'), window none, "
                "linear averaging over all hits",
                "coherence_in_band": {
                    "min": round(float(coh[sel].min()), 4),
                    "median": round(float(np.median(coh[sel])), 4),
                },
            }
        )
    else:
        f, h = read_uff_frf(path)
        entry.update(
            {
                "frfs": int(h.shape[0]),
                "lines": int(h.shape[1]),
                "frf_method": "as stored (UFF 58, function type 4), times (j omega)^k to accelerance "
                "from its ordinate type (8 receptance, 11 mobility, 12 accelerance)",
            }
        )
    entry["frequency_step_hz"] = round(float(f[1] - f[0]), 6)
    peaks = resonance_peaks(f, h, spec.band, coh if spec.kind != "uff-frf" else None)
    orders = lscf_poles(f, h, spec.band)
    modes = stable_modes(orders)
    entry["frf_form"] = FRF_FORM
    entry["lscf"] = {
        "tool": "sdypy-EMA Model(frf_form='accelerance').get_poles(method='lscf')",
        "pol_order_high": ORDER_HIGH,
        "orders_computed": len(orders),
        "rule": {
            "freq_tol": F_TOL,
            "damping_tol": Z_TOL,
            "cluster_tol": CLUSTER_TOL,
            "min_share_of_orders": MIN_SHARE,
            "min_orders": MIN_ORDERS,
            "zeta_max": ZETA_MAX,
        },
    }
    entry["peer_modes"] = modes
    # The looser reading: every chain of the peer's diagram stable over MIN_ORDERS orders. A
    # mode of ours that none of these supports is counted spurious (tests/test_corpus.py).
    entry["peer_supported_hz"] = [m["frequency_hz"] for m in stable_modes(orders, MIN_ORDERS)]
    entry["resonance_peaks_hz"] = peaks
    entry["half_power"] = half_power(f, h, modes)
    entry["published"] = spec.published
    return entry


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--corpus", required=True, type=Path, help="the corpus directory (outside the repo)")
    parser.add_argument(
        "-o",
        "--output",
        type=Path,
        default=Path(__file__).resolve().parent.parent / "tests" / "data" / "corpus_reference.json",
    )
    parser.add_argument("--only", nargs="*", help="set names to compute (default: all)")
    args = parser.parse_args(argv)
    result = {"generator": "bench/corpus_reference.py", "sets": {}}
    if args.only and args.output.exists():  # the other sets' entries stay as they were
        result = json.loads(args.output.read_text())
    for spec in SETS:
        if args.only and spec.name not in args.only:
            continue
        if not (args.corpus / spec.path).exists():
            print(f"{spec.name}: {spec.path} not found under {args.corpus}; skipped", file=sys.stderr)
            continue
        result["sets"][spec.name] = reference(args.corpus, spec)
        print(f"{spec.name}: {len(result['sets'][spec.name]['peer_modes'])} peer modes", file=sys.stderr)
    args.output.write_text(json.dumps(result, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
