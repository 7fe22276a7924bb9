"""The stability diagram shows each LSCF normalisation in its own panel.

identify_modes fits every zone twice (analysis.modal_id.NORMALISATIONS): alpha_p = 1 is
read first and alpha_0 = 1 adds the modes it misses. Overlaid in one panel the two fits
gave two poles per mode and order with nothing to tell them apart; the stored analysis
now says which fit each pole is from, and the report draws one panel per fit.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from analysis.modal_id import DENOMINATOR, NORMALISATIONS, identify_modes
from daq.report.figures import draw_frf, draw_stability
from daq.workflows.analysis import result_arrays
from tests.analysis.modal_id.test_heavily_damped_modes import tool_holder_like


@pytest.fixture(scope="module")
def analysed():
    """A tool-holder-like test (heavily damped modes in noise) whose modes come from both fits."""
    f, h = tool_holder_like(0)
    modal = identify_modes(f[1:], h[:, 1:])
    read_with = [m.normalisation for m in modal.modes]
    assert set(read_with) == set(NORMALISATIONS), read_with  # the case this file is about
    # What result_arrays reads of a run's analysis (analysis.run_analysis.RunAnalysis).
    arrays = result_arrays(SimpleNamespace(modal=modal, frequency_hz=f[1:], frf=h[:, 1:], coherence=None))
    summary = {
        "run_id": "panels",
        "modes": [{"frequency_hz": m.frequency_hz, "quality": {"normalisation": n}}
                  for m, n in zip(modal.modes, read_with, strict=True)],
    }  # fmt: skip
    return modal, read_with, {"summary": summary, **arrays}


def test_each_pole_says_which_fit_it_is_from_and_a_modes_poles_are_from_its_own_fit(analysed):
    _, read_with, payload = analysed
    norm, mode = payload["stability_normalisation"], payload["stability_mode"]
    assert norm.shape == payload["stability_pole"].shape == mode.shape
    assert set(norm.tolist()) == {0, 1}
    for r, name in enumerate(read_with):
        assert np.any(mode == r), r
        assert set(norm[mode == r].tolist()) == {NORMALISATIONS.index(name)}, (r, name)
    # Both fits span every order of the diagram: the second is not an afterthought of a few orders.
    for k in (0, 1):
        assert np.unique(payload["stability_order"][norm == k]).size >= 20


def test_the_report_draws_one_panel_per_fit_and_one_for_a_result_stored_before(analysed):
    _, read_with, payload = analysed
    fig = draw_stability(payload)
    titled = [ax.get_title() for ax in fig.axes if ax.get_title()]
    assert len(titled) == 2, titled
    for name, title in zip(NORMALISATIONS, titled, strict=True):
        n = read_with.count(name)
        assert f"LSCF with {DENOMINATOR[name]}: {n} mode{'s' * (n != 1)} read from it (solid lines)" == title
    old = {k: v for k, v in payload.items() if k != "stability_normalisation"}
    fig = draw_stability(old)
    assert [ax.get_title() for ax in fig.axes if ax.get_title()] == []
    assert len(fig.axes) == 2  # the diagram and its |H| axis, as before


def test_a_modal_tests_diagram_has_a_panel_per_fit_and_refuses_an_unknown_one(monkeypatch):
    from daq.report import modal_test_report as mtr
    from tests.report.test_modal_test_report import _report

    rows = _report().stability
    arrays = {
        "order": np.array([o for o, _, _ in rows]),
        "frequency_hz": np.array([f for _, f, _ in rows]),
        "status": np.array([s for _, _, s in rows]),
        "normalisation": np.array([NORMALISATIONS[k % 2] for k in range(len(rows))]),
    }
    drawn = []
    monkeypatch.setattr(mtr, "_png", lambda fig: drawn.append(fig) or b"")
    mtr.stability_figure(_report(stability=arrays))
    titles = [ax.get_title() for ax in drawn[0].axes if ax.get_title()]
    assert titles == [f"LSCF with {DENOMINATOR[n]}" for n in NORMALISATIONS]
    arrays["normalisation"] = np.array(["both"] * len(rows))
    with pytest.raises(ValueError, match="stability normalisation must name one of highest, lowest per pole"):
        mtr.render_modal_test_report(_report(stability=arrays))


def test_the_diagram_spans_the_band_analysed_not_the_whole_record(analysed):
    """A hit's record reaches 20 kHz while the band analysed ends at 1.4 kHz: the poles lie
    in the band, and the diagram is drawn over it (a new user's trial)."""
    _, _, payload = analysed
    wide = dict(payload)
    f = payload["frequency_hz"]
    step = f[1] - f[0]
    wide["frequency_hz"] = np.concatenate([f, f[-1] + step * np.arange(1, 4 * f.size)])
    wide["frf"] = np.concatenate([payload["frf"], np.ones((payload["frf"].shape[0], 4 * f.size - 1))], axis=1)
    fig = draw_stability(wide)
    band = payload["synthesized_frequency_hz"]
    for ax in fig.axes:
        assert ax.get_xlim() == (band[0], band[-1])


@pytest.mark.parametrize(
    ("stored", "said"),
    [
        ("receptance", "accelerance, converted from the receptance stored"),
        ("accelerance", "accelerance"),
        ("time records", "accelerance"),
    ],
)
def test_the_frf_figure_says_a_stored_form_was_converted(analysed, stored, said):
    _, _, payload = analysed
    summary = {
        **payload["summary"],
        "source": "measured_frf",
        "form": {"stored": stored, "analysed": "accelerance"},
    }
    fig = draw_frf({**payload, "summary": summary})
    assert fig._suptitle.get_text() == f"Run panels: FRF (measured_frf, {said})"


def test_chains_set_aside_are_drawn_where_the_caution_names_them(analysed):
    _, _, payload = analysed
    summary = {**payload["summary"], "set_aside": [{"frequency_hz": 640.0, "damping_ratio": 0.02}]}
    fig = draw_stability({**payload, "summary": summary})
    panels = [ax for ax in fig.axes if ax.get_title()]
    for ax in panels:
        dashed = [line for line in ax.get_lines() if line.get_linestyle() == "--"]
        assert [line.get_xdata()[0] for line in dashed] == [640.0]
    labels = panels[0].get_legend_handles_labels()[1]
    assert "possible mode left out (see the cautions)" in labels


def test_a_modal_tests_diagram_draws_the_possible_modes_left_out(monkeypatch):
    from daq.report import modal_test_report as mtr
    from tests.report.test_modal_test_report import _report

    drawn = []
    monkeypatch.setattr(mtr, "_png", lambda fig: drawn.append(fig) or b"")
    report = _report()
    inside = float(np.mean(report.frequency_hz[[0, -1]]))
    mtr.stability_figure(_report(set_aside_hz=np.array([inside])))
    (ax,) = [ax for ax in drawn[0].axes if ax.get_ylabel() == "model order"]
    dashed = [line for line in ax.get_lines() if line.get_linestyle() == "--"]
    assert [line.get_xdata()[0] for line in dashed] == [inside]
    assert "possible mode left out (see the cautions)" in ax.get_legend_handles_labels()[1]
