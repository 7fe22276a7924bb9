"""Convert the public measured data sets in CORPUS_DIR/<set>/original/ to files `daq import` reads.

Run with the project's venv:  .venv/bin/python bench/corpus_convert.py CORPUS_DIR

The corpus lives outside the repository (tests/data/README.md: each set's source,
commit and licence; the originals are fetched from there into CORPUS_DIR/<set>/original/).
Every original is kept untouched; converted files go to CORPUS_DIR/<set>/. Then
`python bench/corpus_reference.py --corpus CORPUS_DIR` computes the peers' readings and
`DAQ_CORPUS=CORPUS_DIR python -m pytest tests/corpus` runs our defaults against them.
Sets:

pyfrf-impact   ladisk/pyFRF @55431fd data/measurements_{1..5}.npy: each (3, 25600) float64,
               rows = time [s], excitation, response; 25.6 kHz, 1 s, 5 hits.
               -> pyfrf_impact.csv (hit,time,force,response). Units are not stated by the
               source; imported as N and m/s^2 (the daq defaults).
pyuff-3frf     ladisk/pyuff data/meas_point_{1,2,3}.txt: 1001 complex accelerances written as
               Python complex literals "(a+bj)", one per line, 0..1000 Hz step 1 Hz, roving
               reference (ref nodes 1,2,3), fixed response node 1 (pyuff README).
               -> pyuff_3frf.uff (UFF 58 ASCII, function type 4, m/s^2 / N assumed).
lvm-2ch        ladisk/lvm_read data/long_single_header_multi_ch.lvm: LabVIEW text, 16383 rows,
               channels F ("g" label), m_1, m_2 (m/s^2), Delta_X 0.000977 s (= 1/1024 rounded);
               two impacts (samples 84 and 8275) -> two hits of 8191 samples each.
               -> lvm_m1.csv and lvm_m2.csv (force with m_1 / m_2), 1024 Hz, start 0 s.
modelab-beam   alxhslm/ModeLAB @4a27c98 Example/SignalCalc/ASCII0000{1..9}/Hxysv0000{1..9}.txt:
               DataPhysics SignalCalc ASCII FRF exports (CRLF, latin-1 unit label "(m/s\xb2)(N)"),
               9 header lines then 51,201 rows "Frequency Real Imaginary", 0..1000 Hz step
               1000/51200 Hz. Roving hammer (9 points along a beam, z = 0.1..1.2 m, setup.csv),
               one accelerometer at z = 0.5 m (= hammer point 4), direction -x (hammer +x).
               -> modelab_beam.uff (UFF 58b binary, function type 4, ref nodes 1..9 +x,
               response node 4 -x; x stored as doubles so the 1000/51200 Hz step is exact).
tool-holder    leekunhwee/Vibration-Signal-Processing @d9edffe ExperimentalModalAnalysis/
               Point_{1..5}_Channel_1_CH1.txt: five roving-hammer receptances of a milling tool
               in its holder (m/N, the source's README), no header, three columns
               frequency, Re, Im, 0..5000 Hz step 1 Hz; hammer at points 1..5 (0, 55, 90, 130,
               165 mm from the tool tip), accelerometer at point 1 (the tip).
               -> tool_holder.uff (UFF 58 ASCII, function type 4, ordinate data type 8:
               displacement over force, receptance; ref nodes 1..5, response node 1).
tool-holder-impact  the same repository, ImpactTesting/Point1_Channel1_CH1.txt: one hit,
               time [s], force [N], acceleration [m/s^2] (ImpactSignalProcessing.m), tab
               separated, no header, 51,200 rows at 51.2 kHz, time printed to 7 significant
               digits. Not converted: `daq import` reads the original.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pyuff


def write_hits_csv(
    path: Path, fs: float, time: np.ndarray, force: np.ndarray, resp: np.ndarray, comments: list[str]
) -> None:
    """Write hits (n_hits, n) to the daq CSV layout: comments, header, hit,time,force,response."""
    lines = [f"# {c}" for c in comments]
    lines.append(f"# sample_rate_hz = {float(fs)!r}")
    lines.append(f"# start_s = {float(time[0])!r}")
    lines.append("hit,time,force,response")
    for k in range(force.shape[0]):
        for t, f, a in zip(time, force[k], resp[k], strict=True):
            lines.append(f"{k},{float(t)!r},{float(f)!r},{float(a)!r}")
    path.write_text("\n".join(lines) + "\n")


#: UFF 58 ordinate data type and unit label of each FRF form (the response over force).
ORDINATE = {"receptance": (8, "m"), "accelerance": (12, "m/s^2")}


def frf_record(
    frf: np.ndarray,
    freq: np.ndarray,
    ids: tuple[str, str],
    nodes: tuple[int, int, int, int],
    form: str,
    entity: str,
    binary: bool = False,
) -> dict:
    """A dataset-58 FRF record (function type 4) for pyuff: ``nodes`` = (response node,
    its direction, reference node, its direction); abscissa in Hz, evenly spaced unless
    ``binary`` (then the x values are stored as they are)."""
    ordinate, unit = ORDINATE[form]
    rsp_node, rsp_dir, ref_node, ref_dir = nodes
    return pyuff.prepare_58(
        binary=int(binary), func_type=4, rsp_node=rsp_node, rsp_dir=rsp_dir, ref_node=ref_node,
        ref_dir=ref_dir, id1=ids[0], id2=ids[1], rsp_ent_name=entity, ref_ent_name=entity, data=frf,
        x=freq, abscissa_spacing=0 if binary else 1, abscissa_spec_data_type=18,
        abscissa_axis_units_lab="Hz", ordinate_spec_data_type=ordinate, ordinate_axis_units_lab=unit,
        orddenom_spec_data_type=13, orddenom_axis_units_lab="N",
    )  # fmt: skip


def convert_pyfrf(root: Path) -> None:
    d = root / "pyfrf-impact"
    m = np.array([np.load(d / "original" / f"measurements_{i}.npy") for i in range(1, 6)])
    time = m[0, 0]
    for k in range(1, 5):  # every hit shares the time axis; hit 0's is written for all
        assert np.allclose(m[k, 0], time, rtol=0, atol=1e-12)  # same axis up to float round-off
    fs = float((len(time) - 1) / (time[-1] - time[0]))  # 1 / mean step, as daq computes it
    write_hits_csv(
        d / "pyfrf_impact.csv",
        fs,
        time,
        m[:, 1],
        m[:, 2],
        [
            "source: github.com/ladisk/pyFRF @55431fd3 data/measurements_1..5.npy",
            "rows 1 (excitation) and 2 (response) of each file; units not stated (N, m/s^2 assumed)",
        ],
    )


def convert_pyuff(root: Path) -> None:
    d = root / "pyuff-3frf"
    out = d / "pyuff_3frf.uff"
    if out.exists():
        out.unlink()
    freq = np.arange(0, 1001, dtype=float)
    uff = pyuff.UFF(str(out))
    for i in range(3):
        frf = np.genfromtxt(d / "original" / f"meas_point_{i + 1}.txt", dtype=complex)
        assert frf.shape == freq.shape
        ids = (f"pyuff meas_point_{i + 1} accelerance", "ladisk/pyuff data/meas_point_N.txt")
        data = frf_record(frf, freq, ids, (1, 1, i + 1, 1), "accelerance", "TestCase")
        uff.write_sets(data, mode="add")


def convert_lvm(root: Path) -> None:
    d = root / "lvm-2ch"
    src = d / "original" / "long_single_header_multi_ch.lvm"
    lines = src.read_text().splitlines()
    start = next(i for i, s in enumerate(lines) if s.startswith("X_Value")) + 1
    rows = np.array([[float(v) for v in s.split("\t")[1:4]] for s in lines[start:] if s.strip()])
    n = 8191  # impacts at samples 84 and 8275: two records of 8191 samples, 84 samples pre-trigger
    fs = 1024.0  # header Delta_X 0.000977 is 1/1024 rounded to 6 decimals
    force = np.array([rows[:n, 0], rows[n : 2 * n, 0]])
    time = np.arange(n) / fs
    for ch, name in ((1, "m1"), (2, "m2")):
        resp = np.array([rows[:n, ch], rows[n : 2 * n, ch]])
        write_hits_csv(
            d / f"lvm_{name}.csv",
            fs,
            time,
            force,
            resp,
            [
                "source: github.com/ladisk/lvm_read data/long_single_header_multi_ch.lvm",
                f"force column F (labelled 'g' in the file), response m_{ch} (m/s^2); "
                "two impacts split into hits of 8191 samples; fs 1024 Hz assumed",
            ],
        )


def convert_modelab(root: Path) -> None:
    d = root / "modelab-beam"
    out = d / "modelab_beam.uff"
    if out.exists():
        out.unlink()
    uff = pyuff.UFF(str(out))
    freq = None
    for i in range(1, 10):
        src = d / "original" / f"Hxysv{i:05d}.txt"
        head = src.read_text(encoding="latin-1").splitlines()[:9]
        assert head[5].split() == ["Frequency", "Real", "Imaginary"], head
        a = np.loadtxt(src, skiprows=9, encoding="latin-1")
        assert a.shape == (51201, 3)
        if freq is None:
            freq = a[:, 0]
            assert np.allclose(freq, np.arange(51201) * (1000.0 / 51200), rtol=0, atol=1e-9)
            freq = np.arange(51201) * (1000.0 / 51200)  # the exported axis, exact
        data = frf_record(a[:, 1] + 1j * a[:, 2], freq, (f"ModeLAB Hxysv{i:05d} accelerance",
                          "alxhslm/ModeLAB Example/SignalCalc"), (4, -1, i, 1), "accelerance", "beam",
                          binary=True)  # fmt: skip
        uff.write_sets(data, mode="add")


def convert_tool_holder(root: Path) -> None:
    d = root / "tool-holder"
    out = d / "tool_holder.uff"
    if out.exists():
        out.unlink()
    uff = pyuff.UFF(str(out))
    freq = None
    for i in range(1, 6):
        a = np.loadtxt(d / "original" / f"Point_{i}_Channel_1_CH1.txt")
        assert a.shape == (5001, 3), a.shape
        if freq is None:
            freq = a[:, 0]
            assert np.array_equal(freq, np.arange(5001, dtype=float))
        data = frf_record(a[:, 1] + 1j * a[:, 2], freq, (f"tool holder H1{i} receptance",
                          "leekunhwee/Vibration-Signal-Processing ExperimentalModalAnalysis"),
                          (1, 1, i, 1), "receptance", "tool")  # fmt: skip
        uff.write_sets(data, mode="add")


def main() -> None:
    if len(sys.argv) != 2:
        raise SystemExit("usage: python bench/corpus_convert.py CORPUS_DIR")
    root = Path(sys.argv[1])
    sets = {"pyfrf-impact": convert_pyfrf, "pyuff-3frf": convert_pyuff, "lvm-2ch": convert_lvm,
            "modelab-beam": convert_modelab, "tool-holder": convert_tool_holder}  # fmt: skip
    for name, convert in sets.items():
        if not (root / name / "original").is_dir():
            print(f"{name}: no {root / name / 'original'}; skipped", file=sys.stderr)
            continue
        convert(root)
        print(f"{name}: converted", file=sys.stderr)


if __name__ == "__main__":
    main()
