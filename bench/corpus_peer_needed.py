"""Which of the peer's stable modes the data need: a leave-one-out of the peer's own modes.

For every corpus set (tests/data/README.md; the files live outside the repository), the
peer's modes of tests/data/corpus_reference.json are taken as poles (frequency, damping)
and their residues fitted to the set's FRF over the peer's band by least squares
(analysis.modal_id.lsfd, with residual terms: given the poles the residues are a
linear least-squares problem, the same whoever solves it). Printed per peer mode: the
misfit ||H - H_syn|| around it (LOCAL_HALF_WIDTHS half-power half-widths either side)
without that mode, the others refitted, over the misfit there with all of them. A mode
whose removal leaves the misfit where it was (x1.00-1.10) is a chain of the peer's
stability diagram that the data do not need: the spurious-pole rule of issue 20
(docs/analysis.md) applied to the peer. Whether our defaults found each mode is read
from ``daq analyze --json`` with default options.

Then, beside our own modes (their poles, residues fitted the same way): how well they
reproduce the FRF over the peer's band, and for each peer mode we miss, the misfit around
it with that mode added to ours, as a factor (x0.27: the data need it beside what we
found; x1.00: they do not).

Run: python bench/corpus_peer_needed.py --corpus CORPUS_DIR [--only tool-holder ...]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import corpus_reference as peer

from analysis.modal_id.lsfd import lsfd
from tests.corpus.test_corpus import near

#: The lines a mode is judged on: this many half-power half-widths (zeta f) either side.
LOCAL_HALF_WIDTHS = 3
REFERENCE = Path(__file__).resolve().parent.parent / "tests" / "data" / "corpus_reference.json"


def pole(frequency_hz: float, damping_ratio: float) -> complex:
    """The pole (rad/s) of an undamped natural frequency (Hz) and damping ratio."""
    w = 2 * np.pi * frequency_hz
    return complex(-damping_ratio * w, w * np.sqrt(1.0 - damping_ratio**2))


def frf_of(corpus: Path, spec) -> tuple[np.ndarray, np.ndarray]:
    """The set's FRF as the peer reference reads it: f (n_lines,) Hz, H (n_frf, n_lines)."""
    path = corpus / spec.path
    if spec.kind == "uff-frf":
        return peer.read_uff_frf(path)
    reader = peer.read_hits_csv if spec.kind == "csv-hits" else peer.read_text_hit
    f, h, _ = peer.h1_from_hits(*reader(path))
    return f, np.atleast_2d(h)


def ours(corpus: Path, spec) -> list[tuple[float, float]]:
    """Our modes' (frequency Hz, damping ratio), daq import and daq analyze with default options."""
    with tempfile.TemporaryDirectory() as store:
        run = [sys.executable, "-m", "daq"]
        subprocess.run(
            [*run, "import", str(corpus / spec.path), "--store", store], check=True, capture_output=True
        )
        out = subprocess.run([*run, "analyze", "latest", "--json", "--store", store], check=True,
                             capture_output=True, text=True).stdout  # fmt: skip
    return [(m["frequency_hz"], m["damping_ratio"]) for m in json.loads(out)[0]["modes"]]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--corpus", required=True, type=Path)
    parser.add_argument("--only", nargs="*", help="set names (default: all)")
    args = parser.parse_args(argv)
    sets = json.loads(REFERENCE.read_text())["sets"]
    for spec in peer.SETS:
        if (args.only and spec.name not in args.only) or not (args.corpus / spec.path).exists():
            continue
        ref = sets[spec.name]
        f, h = frf_of(args.corpus, spec)
        use = (f >= ref["band_hz"][0]) & (f <= ref["band_hz"][1]) & np.all(np.isfinite(h), axis=0)
        modes = ref["peer_modes"]
        poles = np.array([pole(m["frequency_hz"], m["damping_ratio"]) for m in modes])
        fu, hu = f[use], h[:, use]
        with_all = lsfd(fu, hu, poles, "accelerance")
        found = ours(args.corpus, spec)
        print(
            f"{spec.name}: the peer's {len(modes)} modes reproduce the FRF to "
            f"{100 * with_all.relative_error:.1f} %"
        )
        for k, m in enumerate(modes):
            fn, zeta = m["frequency_hz"], m["damping_ratio"]
            # Where the mode is: LOCAL_HALF_WIDTHS half-power half-widths, at least 3 lines, either side.
            there = np.abs(fu - fn) <= max(LOCAL_HALF_WIDTHS * zeta * fn, 3 * ref["frequency_step_hz"])
            without = lsfd(fu, hu, np.delete(poles, k), "accelerance")
            worse = np.linalg.norm((hu - without.synthesized)[:, there]) / np.linalg.norm(
                (hu - with_all.synthesized)[:, there]
            )
            hit = any(near(x, fn, ref["frequency_step_hz"], zeta) for x, _ in found)
            print(
                f"  {fn:10.2f} Hz {100 * zeta:5.2f} %: the misfit around it x{worse:.2f} without it"
                + ("" if hit else "   (not found by our defaults)")
            )
        _beside_ours(fu, hu, ref, modes, found)
    return 0


def _beside_ours(fu, hu, ref: dict, modes: list[dict], found: list[tuple[float, float]]) -> None:
    """Print how well our modes reproduce the FRF over the peer's band, and, for each peer
    mode we miss, how much adding it to ours lowers the misfit around it: whether the data
    still need it beside what we found."""
    line = ref["frequency_step_hz"]
    inside = [(f, z) for f, z in found if ref["band_hz"][0] <= f <= ref["band_hz"][1]]
    if not inside:
        return
    mine = np.array([pole(f, z) for f, z in inside])
    base = lsfd(fu, hu, mine, "accelerance")
    print(f"  our {len(inside)} modes in this band reproduce the FRF to {100 * base.relative_error:.1f} %")
    for m in modes:
        fn, zeta = m["frequency_hz"], m["damping_ratio"]
        if any(near(x, fn, line, zeta) for x, _ in inside):
            continue
        there = np.abs(fu - fn) <= max(LOCAL_HALF_WIDTHS * zeta * fn, 3 * line)
        more = lsfd(fu, hu, np.append(mine, pole(fn, zeta)), "accelerance")
        better = np.linalg.norm((hu - base.synthesized)[:, there]) / np.linalg.norm(
            (hu - more.synthesized)[:, there]
        )
        print(
            f"  {fn:10.2f} Hz {100 * zeta:5.2f} %, added to ours: the misfit around it x{1 / better:.2f}, "
            f"the whole {100 * more.relative_error:.1f} %"
        )


if __name__ == "__main__":
    raise SystemExit(main())
