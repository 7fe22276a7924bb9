"""UFF dataset 58 export through pyuff (the reader is daq/formats/uff58.py, whose
docstring gives the records written and why binary 58 is used).

The file is written to a temporary in the target's folder, read back with pyuff and
compared record by record before it replaces the target: a file pyuff cannot read
back unchanged is never left at ``path``.
"""

from __future__ import annotations

import gc
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pyuff

from daq.formats.errors import FormatError
from daq.formats.imported import atomic_temp, commit_temp, discard_temp, one_line, show_path
from daq.formats.uff58 import FUNC_COHERENCE, FUNC_FRF, FUNC_TIME, read_uff_sets
from daq.store.model import Run


def write_uff(run: Run, path: Path) -> None:
    """Write ``run``'s hits, analyzer FRF and measured FRFs as binary UFF 58, atomically.

    The written file is read back with pyuff before it replaces ``path``: every value
    must come back bit for bit, else FormatError and ``path`` is left untouched.
    """
    path = Path(path)
    name = show_path(path)
    sets = _time_sets(run) + _frf_sets(run)
    for dset in sets:
        if dset["data"].size < 2:
            raise FormatError(f"cannot write {name}: UFF 58 records need at least 2 points")
        if not np.all(np.isfinite(dset["data"])):
            # pyuff would silently write NaN and inf as numbers (nan_to_num).
            raise FormatError(f"cannot write {name}: run {run.run_id} holds non-finite values")
    expected = [(d["data"].copy(), d["x"].copy(), d["abscissa_spacing"]) for d in sets]
    temp = atomic_temp(path)
    try:
        failure = ""
        with warnings.catch_warnings():
            # pyuff's binary writer leaves a file object for the garbage collector.
            warnings.simplefilter("ignore", ResourceWarning)
            try:
                pyuff.UFF(str(temp)).write_sets(sets, mode="add")  # "overwrite" + binary truncates
            except Exception as exc:  # pyuff raises bare Exception on any write problem
                failure = one_line(str(exc))[:100] or type(exc).__name__
                del exc
            gc.collect()  # close what pyuff left open while its warning is silenced
        if failure:
            raise FormatError(f"cannot write {name}: {failure}")
        back = read_uff_sets(temp, name)
        if len(back) != len(expected) or not all(
            _equal(b.get("data"), data) and (not _exact_x(spacing, b) or _equal(b.get("x"), x))
            for b, (data, x, spacing) in zip(back, expected, strict=False)
        ):
            raise FormatError(f"cannot write {name} exactly: pyuff read back different values")
        commit_temp(temp, path)
    except BaseException:
        discard_temp(temp)
        raise


def _exact_x(spacing: int, back: dict) -> bool:
    # Even time axes come back from the %13.5e header (the exact values are in the ID
    # lines); every other abscissa was chosen so that pyuff rebuilds it exactly.
    return not (spacing == 1 and back.get("func_type") == FUNC_TIME)


def _equal(a: Any, b: np.ndarray) -> bool:
    """Same shape, dtype and values. Value equality, not bytes: pyuff builds complex
    values as re + 1j * im, which turns a -0.0 part into +0.0 (equal, but other bits)."""
    a = np.asarray(a)
    return a.shape == b.shape and a.dtype == b.dtype and bool(np.array_equal(a, b))


def _time_sets(run: Run) -> list[dict]:
    hits = run.hits
    if hits is None:
        return []
    ids = (run.start_time, f"center_hz={float(hits.center_hz)!r}")
    ids += (f"sample_rate_hz={float(hits.sample_rate_hz)!r} start_s={float(hits.start_s)!r}",)
    sets = []
    for k in range(hits.n_hits):
        for what, data, node, kind, unit in (
            ("force", hits.force_n[k], 1, 13, "N"),
            ("response", hits.response_m_s2[k], 2, 12, "m/s^2"),
        ):
            title = f"{run.run_id} hit {k} {what}"
            if not hits.accepted[k]:
                # The verdict travels in ID line 1 (80 characters), read back by read_uff.
                title = f"{title} rejected: {one_line(str(hits.reject_reason[k]))}"[:80]
            head = (title, run.run_id, *ids)
            kinds = ((kind, unit), (0, "NONE"))
            sets.append(_dset(FUNC_TIME, k, head, node, True, (17, "s"), *kinds, data, hits.time_s()))
    return sets


def _frf_sets(run: Run) -> list[dict]:
    frf_sets, coh_sets = [], []
    for tag, frfs in (("analyzer", run.analyzer), ("measured", run.measured_frfs)):
        if frfs is None:
            continue
        even = _even_axis(frfs.frequency_hz)
        numerator = {"receptance": (8, "m"), "mobility": (11, "m/s"), "accelerance": (12, "m/s^2")}[frfs.form]
        axis, frf_kinds, coh_kinds = frfs.frequency_hz, (numerator, (13, "N")), ((0, "NONE"), (0, "NONE"))
        windows = _frf_windows(run, tag)
        for i in range(frfs.n_frf):
            head = (_id_text(frfs.labels[i]), f"{run.run_id} {tag}", run.start_time, windows, "NONE")
            frf_sets.append(_dset(FUNC_FRF, i, head, 2, even, (18, "Hz"), *frf_kinds, frfs.frf[i], axis))
            if frfs.coherence is not None:
                coh = frfs.coherence[i]
                coh_sets.append(_dset(FUNC_COHERENCE, i, head, 2, even, (18, "Hz"), *coh_kinds, coh, axis))
    return frf_sets + coh_sets


def _frf_windows(run: Run, tag: str) -> str:
    """ID line 4 of an FRF record: the exponential window the FRF went through
    (``exp_decay_s=... pulse_s=...``), read back by read_uff so that the analysis can
    take the window's damping out; "NONE" when it is not known."""
    decay = pulse = None
    if tag == "analyzer" and run.instrument is not None:
        setup = run.instrument.settings.get("accelerometer", {})
        if isinstance(setup, dict) and setup.get("window") == "EXPO" and setup.get("exp_decay_s"):
            decay = float(setup["exp_decay_s"])
            pulse = max(0.0, -run.hits.start_s) if run.hits is not None else 0.0
    elif tag == "measured":
        source = run.provenance.get("imported_from", {})
        if isinstance(source, dict) and source.get("exp_decay_s"):
            decay, pulse = float(source["exp_decay_s"]), float(source.get("pulse_s") or 0.0)
    return "NONE" if decay is None else f"exp_decay_s={decay!r} pulse_s={pulse!r}"


def _dset(func, number, ids, rsp_node, even, abscissa, ordinate, denominator, data, x) -> dict:
    """One binary dataset 58 dict; abscissa, ordinate, denominator: (specific data type, units label)."""
    dset = pyuff.prepare_58(
        binary=1,
        **{f"id{i + 1}": text for i, text in enumerate(ids)},
        func_type=func,
        ver_num=number,
        load_case_id=0,
        rsp_node=rsp_node,
        rsp_dir=3,
        ref_node=1,  # the hammer: node 1, +Z
        ref_dir=3,
        abscissa_spacing=1 if even else 0,
        abscissa_spec_data_type=abscissa[0],
        ordinate_spec_data_type=ordinate[0],
        orddenom_spec_data_type=denominator[0],
        z_axis_spec_data_type=0,
        data=np.array(data),
        x=np.array(x, dtype=np.float64),
    )
    dset.update(
        abscissa_axis_units_lab=abscissa[1],
        ordinate_axis_units_lab=ordinate[1],
        orddenom_axis_units_lab=denominator[1],
    )
    return dset


def _even_axis(freq: np.ndarray) -> bool:
    """Whether pyuff's even-spacing header (%13.5e min and step) rebuilds ``freq`` exactly."""
    if freq.size < 2:
        return False
    # The same text round trip pyuff does: write min and x[1]-x[0] as %13.5e, read them,
    # rebuild min + arange(n) * step.
    lo, step = float(f"{freq[0]:13.5e}"), float(f"{freq[1] - freq[0]:13.5e}")
    return _same(lo + np.arange(freq.size) * step, freq)


def _id_text(text: str) -> str:
    # An ID line is one 80-character record: no line breaks, and no run of 4 spaces that
    # could form pyuff's "    -1" block marker; "NONE" when blank, as the format asks.
    clean = " ".join("".join(ch if ch.isprintable() else " " for ch in text).split())[:80]
    return clean or "NONE"


def _same(a: Any, b: np.ndarray) -> bool:
    """Bit-for-bit equality (so -0.0 and 0.0 differ) of two arrays of the same dtype."""
    a = np.asarray(a)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()
