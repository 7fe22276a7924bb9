"""The report's figures, drawn with matplotlib's Agg backend (no screen needed):
``draw_*`` returns the matplotlib Figure (the PDF takes it as a vector page), ``*_figure``
its PNG bytes. Inputs are a Run, the stored analysis payload (daq/workflows/analysis.py)
and the stored fits: nothing is computed here but what a plot needs."""

from __future__ import annotations

import io
from typing import Any

import numpy as np

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


def _png(fig: Any, close: bool = True) -> bytes:
    """The figure as PNG bytes; ``close=False`` keeps it open (e.g. for the PDF)."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110, bbox_inches="tight")
    if close:
        _pyplot().close(fig)
    return buffer.getvalue()


def failed_checks(checks: dict[str, Any]) -> list[str]:
    """The names of a hit's checks that failed (its stored check results)."""
    return [name for name, c in checks.items() if isinstance(c, dict) and c.get("passed") is False]


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
    fig.suptitle(f"Run {summary['run_id']}: FRF ({summary['source']}, accelerance)")
    return fig


def stability_figure(result: dict[str, Any]) -> bytes:
    """PNG of :func:`draw_stability`."""
    return _png(draw_stability(result))


def draw_stability(result: dict[str, Any]) -> Any:
    """Poles per model order by status, the selected modes, and |H| behind them."""
    plt = _pyplot()
    summary = result["summary"]
    fig, ax = plt.subplots(figsize=(10, 5))
    if "stability_order" in result:
        order = result["stability_order"]
        freq = np.abs(result["stability_pole"]) / (2 * np.pi)
        status = result["stability_status"]
        for code, (label, marker, colour) in STATUS_STYLE.items():
            pick = status == code
            if pick.any():
                ax.scatter(freq[pick], order[pick], marker=marker, s=18, color=colour, label=label)
    for mode in summary["modes"]:
        ax.axvline(mode["frequency_hz"], color="#1b7a2f", lw=0.8, alpha=0.6)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("model order")
    twin = ax.twinx()
    f = result["frequency_hz"]
    for h in np.atleast_2d(result["frf"]):
        twin.semilogy(f, np.abs(h), color="#555555", lw=0.7, alpha=0.6)
    twin.set_ylabel("|H| ((m/s²)/N)")
    ax.set_xlim(f[0], f[-1])
    # Below the plot: inside it, the legend hid the first mode's column.
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=4, fontsize=7, frameon=False)
    ax.set_title(f"Run {summary['run_id']}: stability diagram, {len(summary['modes'])} modes selected")
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
    shown = f", error {100 * error:.2g} %" if error is not None else ""
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
        f"Run {run.run_id}, hit {d['hit']}: measured and model response ({s['method']}, Psi {s['psi']:.3g} "
        f"{psi_unit(s)}); residual RMS {rms:.3g} m/s² ({100 * rms / rms_measured:.2g} % of the measured)"
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
            f"{name}: {method}, {s.get('domain', 'time')} domain, final Psi {s['psi']:.4g} {psi_unit(s)}",
            fontsize=9, loc="left",
        )  # fmt: skip
    fig.suptitle("Convergence of the fits: Psi of eq 17 along each search")
    fig.tight_layout()
    return fig
