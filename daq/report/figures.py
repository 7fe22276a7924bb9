"""The report's figures, drawn with matplotlib's Agg backend (no screen needed):
``draw_*`` returns the matplotlib Figure (the PDF takes it as a vector page), ``*_figure``
its PNG bytes. Inputs are a Run, the stored analysis payload (daq/workflows/analysis.py)
and the stored fits: nothing is computed here but what a plot needs."""

from __future__ import annotations

import io
from typing import Any

import numpy as np

from analysis.modal_id import DENOMINATOR, NORMALISATIONS
from daq.report.numbers import plain

#: Hits drawn at most (the rest are listed in the page's table).
MAX_HITS_DRAWN = 12
STATUS_STYLE = {  # stability code -> (label, marker, colour)
    0: ("new pole", "o", "#bbbbbb"),
    1: ("frequency stable", "^", "#7fa6d8"),
    2: ("frequency and damping stable", "s", "#e0a040"),
    3: ("stable (frequency, damping, residue)", "+", "#1b7a2f"),
}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # no display on a lab PC's service or in CI
    import matplotlib.pyplot as plt

    return plt


#: The PNGs' resolution, dots per inch, and the margin left round what is drawn, inches
#: (savefig's own for bbox_inches="tight").
PNG_DPI = 110
PNG_PAD_IN = 0.1


def _png(fig: Any, close: bool = True) -> bytes:
    """The figure as PNG bytes at PNG_DPI, cut to what is drawn and PNG_PAD_IN round it
    (as savefig's bbox_inches="tight"); ``close=False`` keeps it open (e.g. for the PDF).

    The extent is measured first and handed to savefig: with "tight", savefig lays the
    whole figure out once more (every tick and text) before measuring it. Same box, same
    pixels, a layout pass fewer."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    dpi = fig.dpi
    try:
        fig.dpi = PNG_DPI  # the texts measured as drawn
        box = fig.get_tightbbox(canvas.get_renderer()).padded(PNG_PAD_IN)
    finally:
        fig.dpi = dpi
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=PNG_DPI, bbox_inches=box)
    if close:
        _pyplot().close(fig)
    return buffer.getvalue()


def failed_checks(checks: dict[str, Any]) -> list[str]:
    """The names of a hit's checks that failed (its stored check results)."""
    from daq.workflows.run_views import failed_check_names

    return failed_check_names(checks)


def hits_figure(run: Any) -> bytes:
    """PNG of :func:`draw_hits`."""
    return _png(draw_hits(run))


def draw_hits(run: Any) -> Any:
    """Force and response of each hit (up to MAX_HITS_DRAWN); rejected hits in red with why."""
    plt = _pyplot()
    hits = run.hits
    n = min(hits.n_hits, MAX_HITS_DRAWN)
    fig, axes = plt.subplots(n, 2, figsize=(11, 1.6 * n + 0.8), sharex=True, squeeze=False)
    t_ms = hits.time_s() * 1e3
    for i in range(n):
        ok = bool(hits.accepted[i])
        failed = failed_checks(hits.checks[i])
        colour = ("#b35900" if failed else "#1f4e9c") if ok else "#c0392b"
        for col, (data, unit) in enumerate(((hits.force_n[i], "N"), (hits.response_m_s2[i], "m/s²"))):
            ax = axes[i, col]
            if np.iscomplexobj(data):  # zoom: the complex envelope's real part and magnitude
                ax.plot(t_ms, data.real, color=colour, lw=0.7)
                ax.plot(t_ms, np.abs(data), color=colour, lw=0.7, alpha=0.4)
            else:
                ax.plot(t_ms, data, color=colour, lw=0.7)
            ax.set_ylabel(unit, fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
        if ok and failed:
            verdict = f"ACCEPTED against failed check: {', '.join(failed)}"
        else:
            verdict = "accepted" if ok else f"REJECTED: {hits.reject_reason[i]}"
        axes[i, 0].set_title(f"hit {i + 1} force — {verdict}", fontsize=8, loc="left", color=colour)
        axes[i, 1].set_title(f"hit {i + 1} response", fontsize=8, loc="left", color=colour)
    for ax in axes[-1]:
        ax.set_xlabel("time after trigger (ms)", fontsize=8)
    fig.suptitle(f"Run {run.run_id}: time records ({hits.n_hits} hits, {int(hits.accepted.sum())} accepted)")
    return fig


#: Hits given a quality figure of their own: the first QUALITY_HITS, and every hit
#: accepted although a check failed (the report's note names the others).
# Three: what the first hits show of tip, range and windows holds for the rest (the
# Hits table lists every hit's checks), and each figure costs a second of drawing.
QUALITY_HITS = 3


def quality_indices(run: Any) -> list[int]:
    """The 0-based hits the report draws a quality figure for, in order."""
    from daq.workflows.run_views import accepted_against_checks

    hits = run.hits
    if hits is None:
        return []
    return sorted(set(range(min(hits.n_hits, QUALITY_HITS))) | set(accepted_against_checks(run)))


def hit_quality_views(
    run: Any, indices: list[int]
) -> tuple[dict[int, dict[str, Any]], dict[str, Any] | None]:
    """({hit index: daq.workflows.hit_quality.hit_quality of it}, the average of every
    accepted hit or None): the numbers of the quality figures, computed by the view the
    service's page shows (nothing is computed twice). A hit whose view cannot be made
    (a record too short for the span's ends) is left out; the page lists it as not drawn."""
    from daq.workflows.hit_quality import hit_quality

    hits = run.hits
    settings = run.instrument.settings if run.instrument is not None else {}
    imported = (run.provenance or {}).get("imported_from", {})
    if not settings and isinstance(imported, dict) and isinstance(imported.get("windows"), dict):
        settings = imported["windows"]  # the windows an importer read (as the analysis takes them)
    records = [(hits.force_n[i], hits.response_m_s2[i]) for i in range(hits.n_hits)]
    accepted = [bool(a) for a in hits.accepted]

    def view(i: int) -> dict[str, Any]:
        return hit_quality(settings, records, accepted, i, float(hits.sample_rate_hz), float(hits.center_hz))

    views: dict[int, dict[str, Any]] = {}
    for i in indices:
        try:
            views[i] = view(i)
        except ValueError:  # a record too short to resolve the span's ends: not drawn
            continue
    last = hits.n_hits - 1
    try:
        average = (views[last] if last in views else view(last))["average"]
    except ValueError:
        average = None
    return views, average


#: The pulse zoom: the samples where |force| exceeds this share of the peak (a second
#: pulse the double-impact check would count included), widened by PULSE_MARGIN widths.
PULSE_SHARE = 0.2
PULSE_MARGIN = 3.0


def pulse_zoom_s(t_s: np.ndarray, force: np.ndarray) -> tuple[float, float]:
    """(start, end) s of the force pulse's zoom: every sample above PULSE_SHARE of the
    peak |force|, widened by PULSE_MARGIN times that stretch (and 4 samples) each side."""
    magnitude = np.abs(np.asarray(force))
    above = np.flatnonzero(magnitude >= PULSE_SHARE * magnitude.max()) if magnitude.max() > 0 else []
    if len(above) == 0:
        return float(t_s[0]), float(t_s[-1])
    first, last = int(above[0]), int(above[-1])
    pad = max(4, int(PULSE_MARGIN * (last - first + 1)))
    return float(t_s[max(0, first - pad)]), float(t_s[min(t_s.size - 1, last + pad)])


def draw_hit_quality(
    run: Any, index: int, quality: dict[str, Any], average: dict[str, Any] | None, verdict: str
) -> Any:
    """One hit's quality (hit ``index``, 0-based; titled from 1), six panels: the force
    pulse zoomed with the force window over it; the whole response with its (exponential)
    window over it; the force autospectrum in dB against the tip check's roll-off limit;
    this hit's FRF magnitude and phase over the average of the run's accepted hits; the
    average's coherence. ``quality``: daq.workflows.hit_quality.hit_quality of the hit;
    ``average``: its "average" for the last hit (every accepted hit), or None."""
    plt = _pyplot()
    hits = run.hits
    t_s = hits.time_s()
    t_ms = t_s * 1e3
    force, response = hits.force_n[index], hits.response_m_s2[index]
    failed = failed_checks(hits.checks[index])
    colour = ("#b35900" if failed else "#1f4e9c") if hits.accepted[index] else "#c0392b"
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.4))
    (ax_f, ax_r, ax_s), (ax_m, ax_p, ax_c) = axes

    def trace(ax: Any, data: np.ndarray, window: np.ndarray, unit: str, name: str) -> None:
        if np.iscomplexobj(data):  # zoom: the envelope's real part and magnitude
            ax.plot(t_ms, data.real, color=colour, lw=0.8)
            ax.plot(t_ms, np.abs(data), color=colour, lw=0.8, alpha=0.4)
        else:
            ax.plot(t_ms, data, color=colour, lw=0.8)
        scale = float(np.max(np.abs(data))) or 1.0
        ax.plot(t_ms, scale * np.asarray(window), color="#2a7f62", lw=1.0, ls="--", label=f"{name} (x peak)")
        ax.set_ylabel(unit)
        ax.set_xlabel("time after trigger (ms)")
        ax.legend(fontsize=7, loc="upper right")

    trace(ax_f, force, quality["force_window"], "force (N)", "force window")
    lo, hi = pulse_zoom_s(t_s, force)
    ax_f.set_xlim(1e3 * lo, 1e3 * hi)
    ax_f.set_title("force pulse (zoom)", fontsize=9, loc="left")
    trace(ax_r, response, quality["response_window"], "response (m/s²)", "response window")
    ax_r.set_title("response, whole record", fontsize=9, loc="left")

    spectrum = quality["force_spectrum"]
    f_spec = np.asarray(spectrum["frequency_hz"]) + float(hits.center_hz)
    ax_s.plot(f_spec, spectrum["level_db"], color=colour, lw=0.8)
    limit, from_hz = spectrum["rolloff_limit_db"], spectrum["rolloff_hz"] + float(hits.center_hz)
    ax_s.hlines(limit, from_hz, f_spec[-1], color="#c0392b", lw=1.2, ls="--",
                label=f"roll-off limit {limit:g} dB (top band mean)")  # fmt: skip
    ax_s.axhline(0.0, color="#999999", lw=0.6)
    ax_s.axvspan(from_hz, f_spec[-1], color="#e0a040", alpha=0.15, lw=0)
    drop = spectrum.get("drop_db")
    ax_s.set_title(
        "force autospectrum" + (f": falls {drop:.1f} dB" if drop is not None else ""), fontsize=9, loc="left"
    )
    finite = np.asarray(spectrum["level_db"])[np.isfinite(spectrum["level_db"])]
    if finite.size:
        ax_s.set_ylim(max(float(finite.min()), limit - 30.0) - 3, float(finite.max()) + 3)
    ax_s.set_ylabel("dB re low band")
    ax_s.set_xlabel("frequency (Hz)")
    ax_s.legend(fontsize=7, loc="lower left")

    frf = quality["frf"]
    ax_m.semilogy(frf["frequency_hz"], frf["magnitude"], color=colour, lw=0.8, label=f"hit {index + 1}")
    ax_p.plot(frf["frequency_hz"], frf["phase_deg"], color=colour, lw=0.8)
    if average is not None:
        label = f"average of {average['n_averaged']} accepted"
        ax_m.semilogy(
            average["frequency_hz"], average["magnitude"], color="#444444", lw=0.9, ls="--", label=label
        )
        ax_p.plot(average["frequency_hz"], average["phase_deg"], color="#444444", lw=0.9, ls="--")
        ax_c.plot(average["frequency_hz"], average["coherence"], color="#2a7f62", lw=0.9)
        ax_c.set_title(f"coherence of the average ({average['n_averaged']} hits)", fontsize=9, loc="left")
    else:
        ax_c.text(0.5, 0.5, "no accepted hit: no average", ha="center", va="center", transform=ax_c.transAxes)
        ax_c.set_title("coherence", fontsize=9, loc="left")
    ax_m.set_ylabel("|H| ((m/s²)/N)")
    ax_m.set_title("FRF magnitude: this hit over the average", fontsize=9, loc="left")
    ax_m.legend(fontsize=7, loc="upper right")
    ax_p.set_ylabel("phase (°)")
    ax_p.set_yticks([-180, -90, 0, 90, 180])
    ax_p.set_title("FRF phase", fontsize=9, loc="left")
    ax_c.set_ylim(0, 1.05)
    ax_c.set_ylabel("coherence")
    for ax in (ax_m, ax_p, ax_c):
        ax.set_xlabel("frequency (Hz)")
    for ax in axes.flat:
        ax.grid(alpha=0.3, which="both")
        ax.tick_params(labelsize=7)
    fig.suptitle(f"Run {run.run_id}, hit {index + 1} of {hits.n_hits}: {verdict}", color=colour, fontsize=10)
    fig.tight_layout()
    return fig


def frf_figure(result: dict[str, Any]) -> bytes:
    """PNG of :func:`draw_frf`."""
    return _png(draw_frf(result))


def draw_frf(result: dict[str, Any]) -> Any:
    """Magnitude, phase and coherence of the analysed FRF."""
    plt = _pyplot()
    f = result["frequency_hz"]
    frf = np.atleast_2d(result["frf"])
    coherence = result.get("coherence")
    rows = 3 if coherence is not None else 2
    fig, axes = plt.subplots(rows, 1, figsize=(10, 2.4 * rows + 0.5), sharex=True)
    for k, h in enumerate(frf):
        axes[0].semilogy(f, np.abs(h), lw=0.9, label=f"FRF {k + 1}" if frf.shape[0] > 1 else None)
        axes[1].plot(f, np.degrees(np.angle(h)), lw=0.9)
    axes[0].set_ylabel("|H| ((m/s²)/N)")
    axes[1].set_ylabel("phase (°)")
    axes[1].set_yticks([-180, -90, 0, 90, 180])
    if coherence is not None:
        for c in np.atleast_2d(coherence):
            axes[2].plot(f, c, lw=0.9, color="#2a7f62")
        axes[2].set_ylim(0, 1.05)
        axes[2].set_ylabel("coherence")
    axes[-1].set_xlabel("frequency (Hz)")
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
    summary = result["summary"]
    fig.suptitle(f"Run {summary['run_id']}: FRF ({summary['source']}, {_form_shown(summary)})")
    return fig


def _form_shown(summary: dict[str, Any]) -> str:
    """The FRF's form as drawn: accelerance, said converted when the run stored another."""
    stored = (summary.get("form") or {}).get("stored", "accelerance")
    if stored in ("accelerance", "time records"):
        return "accelerance"
    return f"accelerance, converted from the {stored} stored"


def _modes(n: int) -> str:
    return f"{n} mode{'s' * (n != 1)}"


def stability_figure(result: dict[str, Any]) -> bytes:
    """PNG of :func:`draw_stability`."""
    return _png(draw_stability(result))


def draw_stability(result: dict[str, Any]) -> Any:
    """Poles per model order by status, the selected modes, and |H| behind them: one panel
    per LSCF normalisation (every zone is fitted with each, analysis.modal_id), each mode's
    line solid in the panel it was read from; one panel for results stored without it."""
    plt = _pyplot()
    summary = result["summary"]
    norm = result.get("stability_normalisation")
    panels = (
        [None] if norm is None or "stability_order" not in result else sorted(set(np.asarray(norm).tolist()))
    )
    fig, axes = plt.subplots(
        1, len(panels), figsize=(10 if len(panels) == 1 else 14, 5), sharey=True, squeeze=False
    )
    f = result["frequency_hz"]
    # The lines analysed (the band): the poles lie there, and a record's lines may reach far beyond.
    analysed = np.asarray(result.get("synthesized_frequency_hz", f))
    in_band = (f >= analysed[0]) & (f <= analysed[-1])
    for ax, panel in zip(axes[0], panels, strict=True):
        if "stability_order" in result:
            pick_panel = (
                np.ones(len(result["stability_order"]), bool) if panel is None else np.asarray(norm) == panel
            )
            order = result["stability_order"][pick_panel]
            freq = np.abs(result["stability_pole"][pick_panel]) / (2 * np.pi)
            status = result["stability_status"][pick_panel]
            for code, (label, marker, colour) in STATUS_STYLE.items():
                pick = status == code
                if pick.any():
                    ax.scatter(freq[pick], order[pick], marker=marker, s=18, color=colour, label=label)
        for mode in summary["modes"]:
            mine = (
                panel is None
                or mode.get("quality", {}).get("normalisation", NORMALISATIONS[0]) == NORMALISATIONS[panel]
            )
            ax.axvline(mode["frequency_hz"], color="#1b7a2f", lw=0.8, alpha=0.6 if mine else 0.3,
                       ls="-" if mine else ":")  # fmt: skip
        for k, chain in enumerate(summary.get("set_aside") or []):
            # Named in a caution: the reader finds them here (analysis.modal_id.identify.SetAside).
            ax.axvline(chain["frequency_hz"], color="#d35400", lw=0.9, ls="--",
                       label="possible mode left out (see the cautions)" if k == 0 else None)  # fmt: skip
        ax.set_xlabel("frequency (Hz)")
        twin = ax.twinx()
        for h in np.atleast_2d(result["frf"]):
            twin.semilogy(f[in_band], np.abs(h[in_band]), color="#555555", lw=0.7, alpha=0.6)
        if ax is axes[0][-1]:
            twin.set_ylabel("|H| ((m/s²)/N)")
        ax.set_xlim(analysed[0], analysed[-1])
        if panel is not None:
            n_read = sum(m.get("quality", {}).get("normalisation", NORMALISATIONS[0]) == NORMALISATIONS[panel]
                         for m in summary["modes"])  # fmt: skip
            ax.set_title(
                f"LSCF with {DENOMINATOR[NORMALISATIONS[panel]]}: "
                f"{_modes(n_read)} read from it (solid lines)",
                fontsize=9,
            )
    axes[0][0].set_ylabel("model order")
    # Below the plot: inside it, the legend hid the first mode's column.
    axes[0][0].legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=4, fontsize=7, frameon=False)
    fig.suptitle(f"Run {summary['run_id']}: stability diagram, {_modes(len(summary['modes']))} selected")
    return fig


def synthesis_figure(result: dict[str, Any]) -> bytes:
    """PNG of :func:`draw_synthesis`."""
    return _png(draw_synthesis(result))


def draw_synthesis(result: dict[str, Any]) -> Any:
    """The measured FRF and the one synthesised from the identified modes."""
    plt = _pyplot()
    f_meas, f_syn = result["frequency_hz"], result["synthesized_frequency_hz"]
    fig, axes = plt.subplots(2, 1, figsize=(10, 5.5), sharex=True)
    for k, (h, s) in enumerate(
        zip(np.atleast_2d(result["frf"]), np.atleast_2d(result["synthesized"]), strict=True)
    ):
        axes[0].semilogy(f_meas, np.abs(h), color="#1f4e9c", lw=0.9, label="measured" if k == 0 else None)
        axes[0].semilogy(
            f_syn, np.abs(s), color="#c0392b", lw=0.9, ls="--", label="synthesised" if k == 0 else None
        )
        axes[1].plot(f_meas, np.degrees(np.angle(h)), color="#1f4e9c", lw=0.9)
        axes[1].plot(f_syn, np.degrees(np.angle(s)), color="#c0392b", lw=0.9, ls="--")
    axes[0].set_ylabel("|H| ((m/s²)/N)")
    axes[1].set_ylabel("phase (°)")
    axes[1].set_xlabel("frequency (Hz)")
    axes[0].legend(fontsize=8)
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
    error = result["summary"].get("synthesis_error")
    shown = f", error {plain(100 * error, '.2g')} %" if error is not None else ""
    fig.suptitle(f"Run {result['summary']['run_id']}: synthesis from the identified modes{shown}")
    return fig


#: The response fit's zoom: at most this share of the record...
ZOOM_RECORD_SHARE = 0.2
#: ... and at most this many periods of the first mode after the trigger.
ZOOM_PERIODS = 3


def response_fit_data(run: Any, fit: dict[str, Any]) -> dict[str, Any]:
    """What the response-fit figure draws: the hit (``hit``, counted from 1), time
    ``t_s``, ``measured``, ``model`` and ``residual`` (measured minus model, m/s^2), and
    the zoom on the first decay, ``zoom_s`` = (start, end): from the record's start to
    ZOOM_PERIODS periods of the fit's first mode after the trigger, at most
    ZOOM_RECORD_SHARE of the record (that share when the fit has no mode frequency)."""
    hits = run.hits
    k = int(fit["hit_index"][0])
    t = hits.time_s()
    measured = np.real(hits.response_m_s2[k])
    model = np.real(np.asarray(fit["model_response"]))
    f1 = next((m["frequency_hz"] for m in fit["summary"].get("modes", []) if m.get("frequency_hz")), None)
    duration = hits.n_samples / hits.sample_rate_hz
    end = t[0] + ZOOM_RECORD_SHARE * duration
    if f1 is not None and f1 > 0:
        end = min(end, max(0.0, t[0]) + ZOOM_PERIODS / f1)
    end = max(end, t[min(20, t.size - 1)])  # a few samples at least
    return {
        "hit": k + 1, "t_s": t, "measured": measured, "model": model, "residual": measured - model,
        "zoom_s": (float(t[0]), float(end)), "mode_1_hz": f1,
    }  # fmt: skip


def response_fit_figure(run: Any, fit: dict[str, Any]) -> bytes:
    """PNG of :func:`draw_response_fit`."""
    return _png(draw_response_fit(run, fit))


def draw_response_fit(run: Any, fit: dict[str, Any]) -> Any:
    """Like the seed's Fig. 5: the measured tip acceleration of one hit and the fitted
    model's response to that hit's measured force, over the whole record (left) and
    zoomed on the first decay (right), each with the residual (measured minus model,
    same unit) under it."""
    plt = _pyplot()
    d = response_fit_data(run, fit)
    t_ms = d["t_s"] * 1e3
    lo, hi = (1e3 * x for x in d["zoom_s"])
    fig, axes = plt.subplots(
        2,
        2,
        figsize=(11, 5.6),
        sharex="col",
        gridspec_kw={"height_ratios": [2.2, 1], "width_ratios": [1.4, 1]},
    )
    rms = float(np.sqrt(np.mean(d["residual"] ** 2)))
    rms_measured = float(np.sqrt(np.mean(d["measured"] ** 2)))
    for col, title in enumerate(("whole record", "first decay (zoom)")):
        top, bottom = axes[0, col], axes[1, col]
        top.plot(t_ms, d["measured"], color="#1f4e9c", lw=0.8, label="measured")
        top.plot(t_ms, d["model"], color="#c0392b", lw=0.8, ls="--", label="model with the fitted R")
        bottom.plot(t_ms, d["residual"], color="#444444", lw=0.7)
        bottom.axhline(0.0, color="#999999", lw=0.6)
        top.set_ylabel("tip acceleration (m/s²)")
        bottom.set_ylabel("residual (m/s²)")
        bottom.set_xlabel("time after trigger (ms)")
        top.set_title(title, fontsize=9, loc="left")
        for ax in (top, bottom):
            ax.grid(alpha=0.3)
    axes[0, 0].axvspan(lo, hi, color="#e0a040", alpha=0.15, lw=0, label="zoom")
    axes[1, 0].axvspan(lo, hi, color="#e0a040", alpha=0.15, lw=0)
    axes[0, 1].set_xlim(lo, hi)
    inside = (t_ms >= lo) & (t_ms <= hi)
    for row, key in ((0, "measured"), (1, "residual")):
        values = d[key][inside] if row else np.concatenate([d["measured"][inside], d["model"][inside]])
        span = float(np.max(np.abs(values))) if values.size else 0.0
        if span > 0:
            axes[row, 1].set_ylim(-1.08 * span, 1.08 * span)
    axes[0, 0].legend(fontsize=8, loc="upper right")
    s = fit["summary"]
    fig.suptitle(
        f"Run {run.run_id}, hit {d['hit']}: measured and model response ({s['method']}, Psi "
        f"{plain(s['psi'], '.3g')} {psi_unit(s)}); residual RMS {plain(rms, '.3g')} m/s² "
        f"({plain(100 * rms / rms_measured, '.2g')} % of the measured)"
        if rms_measured > 0
        else f"Run {run.run_id}, hit {d['hit']}: measured and model response ({s['method']})",
        fontsize=10,
    )
    fig.tight_layout()
    return fig


def psi_unit(summary: dict[str, Any]) -> str:
    """Psi's unit (eq 17: (1/n) sqrt(sum of squared residuals)): that of the response,
    m/s², for a time-domain fit; of the accelerance, (m/s²)/N, for a frequency-domain one."""
    return "(m/s²)/N" if summary.get("domain") == "frequency" else "m/s²"


def convergence_figure(fits: dict[str, dict[str, Any]]) -> bytes:
    """PNG of :func:`draw_convergence`."""
    return _png(draw_convergence(fits))


def draw_convergence(fits: dict[str, dict[str, Any]]) -> Any:
    """Psi along the search of every fit that has a history, a panel each (a GA's 30
    generations and a least-squares search's hundreds of evaluations do not share an
    axis): the best Psi of each generation (GA; no elitism, so it may rise), iteration
    (DE) or the best so far per evaluation (least squares). Whole-number ticks, Psi in
    its unit, a log scale when a panel's Psi spans a decade or more."""
    from matplotlib.ticker import MaxNLocator

    plt = _pyplot()
    curves = [(name, fit) for name, fit in fits.items() if "history" in fit]
    n = max(1, len(curves))
    fig, axes = plt.subplots(n, 1, figsize=(8, 2.7 * n + 0.6), squeeze=False)
    steps = {"ga": "generation, from 1", "de": "iteration, from 1"}
    for ax, (name, fit) in zip(axes[:, 0], curves, strict=False):
        s = fit["summary"]
        history = np.asarray(fit["history"], dtype=float)
        finite = history[np.isfinite(history) & (history > 0)]
        log = finite.size > 0 and finite.max() >= 10 * finite.min()
        x = np.arange(1, history.size + 1)
        (ax.semilogy if log else ax.plot)(x, history, marker="." if history.size <= 60 else None, lw=0.9)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        method = str(s.get("method", ""))
        ax.set_xlabel(steps.get(method, "evaluation, from 1 (the best Psi so far)"))
        ax.set_ylabel(f"Psi ({psi_unit(s)})")
        ax.grid(alpha=0.3, which="both")
        ax.set_title(
            f"{name}: {method}, {s.get('domain', 'time')} domain, final Psi "
            f"{plain(s['psi'], '.4g')} {psi_unit(s)}",
            fontsize=9, loc="left",
        )  # fmt: skip
    fig.suptitle("Convergence of the fits: Psi of eq 17 along each search")
    fig.tight_layout()
    return fig
