"""Hits whose time axes differ are refused (a run's hits share one axis); the one-line
refusal says how they differ and what to do: put every hit on one axis, or import them
separately."""

from __future__ import annotations

import numpy as np

from tests.cli_helpers import assert_one_line_error, invoke_daq
from tests.formats.test_uff58 import time_set, write_sets

REMEDY = (
    "the hits of one run must share one time axis (the same start and step): put every hit on one "
    "(e.g. each from the same pre-trigger) or import them separately"
)


def test_csv_hits_each_from_their_own_pretrigger_are_refused_with_the_remedy(tmp_path):
    fs = 1024.0
    rows = ["hit,Time (s),Force [N],acc [m/s^2]"]
    for k, pre in enumerate((0.02, 0.05)):
        t = np.arange(256) / fs - pre
        force = np.where(np.abs(t) < 2e-3, 100.0, 0.0)
        response = np.exp(-5 * np.clip(t, 0, None)) * np.sin(2 * np.pi * 40 * t) * (t > 0)
        rows += [f"{k},{a:.9g},{f:.9g},{r:.9g}" for a, f, r in zip(t, force, response, strict=True)]
    path = tmp_path / "prevar.csv"
    path.write_text("\n".join(rows) + "\n")
    result = invoke_daq("import", str(path), "--store", str(tmp_path / "runs"))
    assert_one_line_error(
        result,
        "hit 1 (line 258) has a different time axis from hit 0 (it starts at -0.05 s, hit 0 at -0.02 s); "
        + REMEDY,
    )
    assert not (tmp_path / "runs").exists() or not list((tmp_path / "runs").glob("*.h5"))


def test_csv_hits_with_different_steps_say_so(tmp_path):
    path = tmp_path / "steps.csv"
    rows = ["hit,time,force,response"]
    rows += [f"0,{i * 0.001:g},{1.0 if i == 1 else 0.0},{(-1) ** i}" for i in range(64)]
    rows += [f"1,{i * 0.002:g},{1.0 if i == 1 else 0.0},{(-1) ** i}" for i in range(64)]
    path.write_text("\n".join(rows) + "\n")
    result = invoke_daq("import", str(path), "--store", str(tmp_path / "runs"))
    assert_one_line_error(result, "(its step is 0.002 s, hit 0's 0.001 s); " + REMEDY)


def test_uff_time_records_on_different_axes_are_refused_with_the_remedy(tmp_path):
    x = np.arange(8) * 0.001
    sets = [
        time_set(np.r_[0.0, 5, np.zeros(6)], 13, "N", x),
        time_set(np.sin(np.arange(8.0)), 12, "m/s^2", x - 0.003),
    ]
    path = write_sets(tmp_path / "f.uff", sets)
    result = invoke_daq("import", str(path), "--store", str(tmp_path / "runs"))
    assert_one_line_error(result, "has a different time axis from #", "(it starts at -0.003 s, #", REMEDY)
