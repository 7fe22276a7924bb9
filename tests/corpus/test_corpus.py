"""Public measured data, nobody's here: `daq import` and `daq analyze` with DEFAULT options
against the peer references of bench/corpus_reference.py (tests/data/corpus_reference.json).

The data sets themselves are not in the repository (tests/data/README.md: their sources,
commits and licences, and how to convert them); the tests read them from $DAQ_CORPUS, else
tests/data/corpus/, and are skipped, loudly (tests/conftest.py), where they are absent.

What must hold on every set (the issue's figures):
  * at least 90 % of the peer's stable modes found, each within 0.2 % in frequency (or one
    line, on a grid coarser than that);
  * damping within the peer's spread over its orders, widened by our own 2 u;
  * at most one spurious mode per ten found: a mode of ours inside the peer's band that
    neither the peer's stability diagram (chains stable over 5 orders) nor the peak picking
    of the half-power method (peaks standing 10 dB above their surroundings) supports.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import NO_CORPUS

REFERENCE = Path(__file__).resolve().parents[1] / "data" / "corpus_reference.json"
SETS = json.loads(REFERENCE.read_text())["sets"]
FREQUENCY_TOLERANCE = 0.002
MIN_FOUND = 0.9
MAX_SPURIOUS = 0.1


def corpus_dir() -> Path:
    return Path(os.environ.get("DAQ_CORPUS") or Path(__file__).resolve().parents[1] / "data" / "corpus")


def daq(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "daq", *args], capture_output=True, text=True, timeout=300)


def near(f_ours: float, f_ref: float, line_hz: float) -> bool:
    return abs(f_ours - f_ref) <= max(FREQUENCY_TOLERANCE * f_ref, line_hz)


#: Where the defaults fall short today, said and kept visible (strict: a fix makes them pass
#: and the mark must then go). lvm-2ch is two hits of a LabVIEW log; the evidence for each
#: entry (the peer's own tools re-run on the same hits) is in docs/analysis.md, "On
#: measured data nobody here made".
KNOWN_SHORT = {
    ("found", "lvm-2ch-m1"): "the peer's 146.2 and 182.9 Hz (2.3 %, 1.2 %, no peak in m1) move with the band "
    "by more than 0.2 %: the peer's own LSCF gives 147.06 and 181.57 Hz on 5-400 Hz (ours: 1.75-400 Hz)",
    ("found", "lvm-2ch-m2"): "7 of 10: on 5-250 Hz the peer splits the one 160.8 Hz peak (half power 0.48 %) "
    "into 159.92 and 160.75 Hz from order 38 up (one mode, 160.1-160.3 Hz 0.43-0.45 %, on 5-300 and "
    "5-400 Hz); ours, 160.45 Hz 0.444 %, is matched to 160.75 Hz and outside its 0.27-0.37 %; 143.7 Hz "
    "(2.8 %) and 215.1 Hz (gone on 5-300 Hz) have no peak in m2; 233.66 Hz 0.133 +- 0.003 % against "
    "the peer's 0.141-0.244 %",
    ("spurious", "lvm-2ch-m1"): "8.05 Hz (poor coherence at low frequency, band-edge caution) and "
    "40.03 Hz (on a notch of the force spectrum; a peak m2 confirms, the peer a mode on m2 only)",
}


def known(kind: str, name: str):
    reason = KNOWN_SHORT.get((kind, name))
    return pytest.param(name, marks=pytest.mark.xfail(reason=reason, strict=True)) if reason else name


@pytest.fixture(scope="module")
def analysed(tmp_path_factory):
    """Each set imported and analysed once with default options: name -> daq analyze --json."""
    cache: dict[str, dict] = {}

    def get(name: str) -> dict:
        if name not in cache:
            path = corpus_dir() / SETS[name]["file"]
            if not path.exists():
                pytest.skip(f"{NO_CORPUS}: {path} (tests/data/README.md)")
            store = tmp_path_factory.mktemp(name)
            imported = daq("import", str(path), "--store", str(store))
            assert imported.returncode == 0, imported.stderr
            result = daq("analyze", "latest", "--store", str(store), "--json")
            assert result.returncode == 0, result.stderr
            (cache[name],) = json.loads(result.stdout)
        return cache[name]

    return get


@pytest.mark.slow
@pytest.mark.parametrize("name", [known("found", n) for n in sorted(SETS)])
def test_defaults_find_the_peers_modes(name, analysed):
    ref, info = SETS[name], analysed(name)
    line = ref["frequency_step_hz"]
    ours = info["modes"]
    found = 0
    for peer in ref["peer_modes"]:
        match = [m for m in ours if near(m["frequency_hz"], peer["frequency_hz"], line)]
        if not match:
            continue
        found += 1
        m = min(match, key=lambda m: abs(m["frequency_hz"] - peer["frequency_hz"]))
        u = m["damping_u"] or 0.0
        assert peer["damping_min"] - 2 * u <= m["damping_ratio"] <= peer["damping_max"] + 2 * u, (peer, m)
    assert found >= MIN_FOUND * len(ref["peer_modes"]), (found, len(ref["peer_modes"]))


@pytest.mark.slow
@pytest.mark.parametrize("name", [known("spurious", n) for n in sorted(SETS)])
def test_defaults_add_no_spurious_modes(name, analysed):
    ref, info = SETS[name], analysed(name)
    line = ref["frequency_step_hz"]
    low, high = ref["band_hz"]
    support = (
        [m["frequency_hz"] for m in ref["peer_modes"]] + ref["peer_supported_hz"] + ref["resonance_peaks_hz"]
    )
    inside = [m["frequency_hz"] for m in info["modes"] if low <= m["frequency_hz"] <= high]
    spurious = [f for f in inside if not any(near(f, s, line) for s in support)]
    assert len(spurious) <= MAX_SPURIOUS * len(inside), spurious


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(n for n in SETS if SETS[n].get("published")))
def test_defaults_reproduce_published_frequencies(name, analysed):
    published = SETS[name]["published"]
    line = SETS[name]["frequency_step_hz"]
    ours = [m["frequency_hz"] for m in analysed(name)["modes"]]
    for f in (m["frequency_hz"] for m in published["modes"]):
        assert any(near(x, f, line) for x in ours), (f, ours)
