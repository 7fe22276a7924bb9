"""Public measured data, nobody's here: `daq import` and `daq analyze` with DEFAULT options
against the peer references of bench/corpus_reference.py (tests/data/corpus_reference.json).

The data sets themselves are not in the repository (tests/data/README.md: their sources,
commits and licences, and how to convert them); the tests read them from $DAQ_CORPUS, else
tests/data/corpus/, and are skipped, loudly (tests/conftest.py), where they are absent.

What must hold on every set (the issue's figures):
  * at least 90 % of the peer's stable modes found, each within 0.2 % in frequency (or one
    line, on a grid coarser than that; or, for a heavily damped mode, a quarter of its
    half-power half-width, HALF_WIDTH_SHARE);
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

import numpy as np
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


#: A heavily damped mode's frequency is defined to a fraction of its half-power half-width
#: zeta f, not to 0.2 %: on tool-holder the peer's own LSCF puts mode 1 at 1064.8-1068.3 Hz
#: as its band moves (0.1 zeta f) and the source's peak of the imaginary part at 1074 Hz
#: (0.2 zeta f from the peer). Above zeta = 0.8 % this share of zeta f is the tolerance.
HALF_WIDTH_SHARE = 0.25


def near(f_ours: float, f_ref: float, line_hz: float, zeta_ref: float = 0.0) -> bool:
    """Within 0.2 % of the reference, one line, or HALF_WIDTH_SHARE of its half-width."""
    return abs(f_ours - f_ref) <= max(
        FREQUENCY_TOLERANCE * f_ref, line_hz, HALF_WIDTH_SHARE * zeta_ref * f_ref
    )


#: Where the defaults fall short today, said and kept visible (strict: a fix makes them pass
#: and the mark must then go). lvm-2ch is two hits of a LabVIEW log; the evidence for each
#: entry (the peer's own tools re-run on the same hits) is in docs/analysis.md, "On
#: measured data nobody here made".
KNOWN_SHORT = {
    ("found", "lvm-2ch-m1"): "the peer's 146.2 and 182.9 Hz (2.3 %, 1.2 %, no peak in m1) move with the band "
    "by more than 0.2 %: the peer's own LSCF gives 147.06 and 181.57 Hz on 5-400 Hz (ours: 1.75-400 Hz); "
    "the close pairs' poles, refined on the FRF (analysis/modal_id/refine.py), read 163.2 Hz at "
    "0.666 +- 0.013 % and 233.67 Hz at 0.129 +- 0.016 %, below the peer's LSCF spreads "
    "(0.77-0.85 %, 0.155-0.30 %), which carry LSCF's noise bias on overlapping modes",
    ("found", "lvm-2ch-m2"): "7 of 10: on 5-250 Hz the peer splits the one 160.8 Hz peak (half power 0.48 %) "
    "into 159.92 and 160.75 Hz from order 38 up (one mode, 160.1-160.3 Hz 0.43-0.45 %, on 5-300 and "
    "5-400 Hz); ours, 160.45 Hz 0.44 +- 0.13 %, is matched to 160.75 Hz (0.27-0.37 %); 143.7 Hz "
    "(2.8 %) and 215.1 Hz (gone on 5-300 Hz; a possible mode left out, 215.6 Hz) have no peak in m2; "
    "the close pair refined on the FRF: 233.68 Hz 0.132 +- 0.003 % against the peer's LSCF 0.141-0.244 %, "
    "235.83 Hz 0.182 +- 0.006 % against 0.201-0.416 %",
    ("spurious", "lvm-2ch-m1"): "8.05 Hz (poor coherence at low frequency, band-edge caution) and "
    "40.03 Hz (on a notch of the force spectrum; a peak m2 confirms, the peer a mode on m2 only)",
    ("found", "tool-holder"): "3 of 11: the peer's LSCF keeps 11 chains in 100-3500 Hz (792 Hz at 9.9 %, "
    "1227, 1503, 1813, 2313, 2771, 3002, 3405 Hz at 1-4 %, 1-4 % of |H|); the source publishes 3 modes "
    "and half-power peak picking finds 3 peaks, all 3 found (test_defaults_reproduce_published_frequencies)",
    ("found", "tool-holder-impact"): "2 of 7: one hit; the peer's LSCF keeps 685, 807 (11 %), 904, 998 and "
    "1209 Hz (7 %) beside 297 and 1074 Hz; 685, 807 and 998 Hz are named as possible modes left out (below); "
    "ours 1231.5 +- 9.5 Hz for 1209 Hz, 22 Hz away, 1 Hz beyond a "
    "quarter of its half-width; peak picking finds one peak (1058 Hz)",
    ("spurious", "tool-holder"): "2724 Hz (2.1 +- 0.7 %) between the peer's chains at 2679 and 2771 Hz: "
    "the shoulder above the 2610 Hz mode, one mode in ours, two in the peer's",
    ("spurious", "tool-holder-impact"): "1231.5 Hz (7.6 +- 2.3 %): the peer's 1209 Hz (7.1 %) and 1219 Hz "
    "chains, 12-22 Hz away",
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
        match = [
            m for m in ours if near(m["frequency_hz"], peer["frequency_hz"], line, peer["damping_ratio"])
        ]
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
        [(m["frequency_hz"], m["damping_ratio"]) for m in ref["peer_modes"]]
        + [(f, 0.0) for f in ref["peer_supported_hz"] + ref["resonance_peaks_hz"]]
        + [(m["frequency_hz"], _published_damping(m)) for m in (ref.get("published") or {}).get("modes", [])]
    )
    inside = [m["frequency_hz"] for m in info["modes"] if low <= m["frequency_hz"] <= high]
    spurious = [f for f in inside if not any(near(f, s, line, z) for s, z in support)]
    assert len(spurious) <= MAX_SPURIOUS * len(inside), spurious


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(n for n in SETS if SETS[n].get("published")))
def test_defaults_reproduce_published_frequencies(name, analysed):
    published = SETS[name]["published"]
    line = SETS[name]["frequency_step_hz"]
    ours = [m["frequency_hz"] for m in analysed(name)["modes"]]
    for mode in published["modes"]:
        f = mode["frequency_hz"]
        assert any(near(x, f, line, _published_damping(mode)) for x in ours), (f, ours)


def _published_damping(mode: dict) -> float:
    """The damping a source's mode was published with, or read from the frequencies of the
    extrema of its real part ((w2 - w1) / (2 wn)); 0 when it publishes none."""
    if "damping_ratio" in mode:
        return mode["damping_ratio"]
    if "real_extrema_hz" in mode:
        low, high = mode["real_extrema_hz"]
        return (high - low) / (2 * mode["frequency_hz"])
    return 0.0


@pytest.mark.slow
def test_one_hit_of_a_51_2_khz_text_export_reads_at_its_rate_and_gives_the_peers_first_mode(
    analysed, tmp_path
):
    """tool-holder-impact: a headerless, tab-separated record whose time column is printed to 7
    significant digits (1.953125e-05, ..., 9.999805e-01) reads as 51.2 kHz, and its dominant
    mode (79 % of the synthesis) lies within a quarter half-width of the peer's LSCF mode,
    with its damping inside the peer's spread. (The peak of |H|, 1058 Hz, is no reading of
    a 3.7 % mode's frequency: the neighbours' skirts move it by half a half-width.)"""
    name = "tool-holder-impact"
    ref, info = SETS[name], analysed(name)
    imported = daq("import", str(corpus_dir() / ref["file"]), "--store", str(tmp_path))
    assert "(csv: 1 hit of 51200 samples at 51200 Hz)" in imported.stdout, imported.stdout
    (peer,) = [m for m in ref["peer_modes"] if abs(m["frequency_hz"] - 1074) < 20]
    zeta = peer["damping_ratio"]
    (ours,) = [m for m in info["modes"] if near(m["frequency_hz"], peer["frequency_hz"], 1.0, zeta)]
    u = ours["damping_u"]
    assert peer["damping_min"] - 2 * u <= ours["damping_ratio"] <= peer["damping_max"] + 2 * u, (peer, ours)
    assert info["n_averages"] == 1
    assert any("one hit" in c for c in info["cautions"]), info["cautions"]


@pytest.mark.slow
def test_the_broad_modes_the_defaults_drop_are_named_and_kept_when_asked_for(analysed, tmp_path):
    """tool-holder-impact: the defaults drop three stable chains whose terms do not stand 3
    times above the misfit around them; the caution names them, and its --frequencies
    gives the peer's 685, 807 and 998 Hz, each within its tolerance and damping spread."""
    name = "tool-holder-impact"
    ref, info = SETS[name], analysed(name)
    line = ref["frequency_step_hz"]
    dropped = [p for p in ref["peer_modes"] if round(p["frequency_hz"]) in (685, 807, 998)]
    aside = [a["frequency_hz"] for a in info["set_aside"]]
    for peer in dropped:
        assert not any(
            near(m["frequency_hz"], peer["frequency_hz"], line, peer["damping_ratio"]) for m in info["modes"]
        )
        assert any(near(f, peer["frequency_hz"], line, peer["damping_ratio"]) for f in aside), (peer, aside)
    (caution,) = [c for c in info["cautions"] if "left out" in c]
    asked = caution.rsplit("--frequencies ", 1)[1].split()[0]
    imported = daq("import", str(corpus_dir() / ref["file"]), "--store", str(tmp_path))
    assert imported.returncode == 0, imported.stderr
    result = daq("analyze", "latest", "--store", str(tmp_path), "--json", "--frequencies", asked)
    assert result.returncode == 0, result.stderr
    (kept,) = json.loads(result.stdout)
    for peer in dropped:
        (m,) = [
            m
            for m in kept["modes"]
            if near(m["frequency_hz"], peer["frequency_hz"], line, peer["damping_ratio"])
        ]
        u = m["damping_u"] or 0.0
        assert peer["damping_min"] - 2 * u <= m["damping_ratio"] <= peer["damping_max"] + 2 * u, (peer, m)


@pytest.mark.slow
def test_on_averaged_hits_only_chains_above_the_scatter_over_hits_are_named(analysed):
    """pyfrf-impact (5 hits) and lvm-2ch m2 (2 hits): the noise a possible mode is named
    against is the scatter over the hits. pyfrf-impact's 4700.7 Hz chain (which the peer's
    diagram does not hold) stood 18 times above the line-to-line noise and is no longer
    named; what is named stands on a peak the peer's peak picking lists (823.4 Hz, the
    middle of the 810/824/851 Hz triple, seen in the zone of its own its clear peak gets).
    lvm-2ch m2 still names 215.6 Hz, the peer's 215.1 Hz."""
    ref, info = SETS["pyfrf-impact"], analysed("pyfrf-impact")
    line = ref["frequency_step_hz"]
    aside = [a["frequency_hz"] for a in info["set_aside"]]
    assert not any(abs(f - 4700.7) < 5 for f in aside), aside
    assert all(any(near(f, p, line) for p in ref["resonance_peaks_hz"]) for f in aside), aside
    name = "lvm-2ch-m2"
    ref, info = SETS[name], analysed(name)
    (peer,) = [p for p in ref["peer_modes"] if round(p["frequency_hz"]) == 215]
    aside = [a["frequency_hz"] for a in info["set_aside"]]
    assert any(near(f, peer["frequency_hz"], ref["frequency_step_hz"], peer["damping_ratio"]) for f in aside)


@pytest.mark.slow
def test_close_lightly_damped_modes_do_not_lend_each_other_their_poles(analysed):
    """pyfrf-impact's 4092.1 and 4127.6 Hz (0.05 %, 35 Hz apart, 0.85 %: inside the 1 %
    stability tolerance): a chain stepped to the neighbour for an order or two, and its
    spread over the top orders made u_f 15 and 14 Hz against a hit-to-hit scatter of
    0.1 Hz. Every mode's u_f now stays under a quarter of the gap to its neighbour."""
    modes = sorted(analysed("pyfrf-impact")["modes"], key=lambda m: m["frequency_hz"])
    f = np.array([m["frequency_hz"] for m in modes])
    gap = np.minimum(np.diff(f, prepend=-np.inf), np.diff(f, append=np.inf))
    for m, g in zip(modes, gap, strict=True):
        assert m["frequency_u_hz"] < g / 4, (m["frequency_hz"], m["frequency_u_hz"], g)


@pytest.mark.slow
@pytest.mark.parametrize(("channel", "name"), [("m_1", "lvm-2ch-m1"), ("m_2", "lvm-2ch-m2")])
def test_the_labview_file_itself_reads_as_the_converted_csv_does(channel, name, analysed, tmp_path):
    """lvm-2ch: the source's own LabVIEW file (one record of two taps, its force channel
    labelled g, Delta_X 0.000977) imported as it is, --force-unit N and the channel, is cut
    into the two hits the conversion made by hand (8191 samples at 1024 Hz) and gives every
    mode the converted CSV gives within 0.05 % (its pre-trigger is 83 samples, the
    conversion's 84)."""
    path = corpus_dir() / "lvm-2ch" / "original" / "long_single_header_multi_ch.lvm"
    if not path.exists():
        pytest.skip(f"{NO_CORPUS}: {path} (tests/data/README.md)")
    imported = daq(
        "import", str(path), "--force-unit", "N", "--columns", f"F,{channel}", "--store", str(tmp_path)
    )
    assert imported.returncode == 0, imported.stderr
    assert "(lvm: 2 hits of 8191 samples at 1024 Hz)" in imported.stdout, imported.stdout
    assert "one record holding 2 taps" in imported.stdout
    result = daq("analyze", "latest", "--store", str(tmp_path), "--json")
    assert result.returncode == 0, result.stderr
    (lvm,) = json.loads(result.stdout)
    ours = [m["frequency_hz"] for m in lvm["modes"]]
    for mode in analysed(name)["modes"]:
        assert min(abs(f - mode["frequency_hz"]) for f in ours) <= 5e-4 * mode["frequency_hz"], (mode, ours)
    assert len(ours) == len(analysed(name)["modes"])


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(SETS))
def test_every_mode_carries_a_standard_uncertainty(name, analysed):
    """Every mode found with default options has a finite ± for its frequency and damping.
    On the tool holder, a pole added beside the heavily damped 1073 Hz mode
    (refine.missing_beside_heavy) settled at 1300 Hz and, refined again from there as each
    bootstrap replicate is, ran to the 1968 Hz mode: it was reported with no ± until a
    pole that does not hold was left out (identify._holding)."""
    for m in analysed(name)["modes"]:
        assert np.isfinite(m["frequency_u_hz"]), m
        assert m["damping_u"] is not None, m
        assert np.isfinite(m["damping_u"]), m


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(SETS))
def test_no_measured_set_is_called_skewed(name, analysed):
    """Every measured set's response is timed with its force (analysis/hit_checks.py
    response_timing): its hits start within 0-3 ms of the force, far inside the limits,
    and the caution a skewed file gets must never come on them."""
    cautions = analysed(name)["cautions"]
    assert not [c for c in cautions if "not timed with the force" in c], cautions


@pytest.mark.slow
def test_the_free_beams_first_bending_mode_is_found_by_default(analysed):
    """free-beam's first bending mode, a clear peak at 224.6 Hz narrower than a line (9.77
    Hz), which neither LSCF reading holds: the third pass keeps it for its peak
    (identify._kept_for_peaks). Exact free-free theory (beta L = 4.7300 and 7.8532, the
    formula the source's course publishes) puts it at the second mode / 2.7565; ours lies
    within 2 u of that, marked as kept for a peak."""
    modes = analysed("free-beam")["modes"]
    second = min(modes, key=lambda m: abs(m["frequency_hz"] - 605.1))
    theory_hz = second["frequency_hz"] / (7.8532 / 4.7300) ** 2
    (first,) = [m for m in modes if abs(m["frequency_hz"] - 224.6) < 9.77]
    assert first["quality"]["for_peak"], first
    assert abs(first["frequency_hz"] - theory_hz) <= 2 * first["frequency_u_hz"], (first, theory_hz)
    assert any("kept for a clear peak" in c for c in analysed("free-beam")["cautions"])
