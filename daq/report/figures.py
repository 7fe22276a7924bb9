"""The report's figures, drawn with matplotlib's Agg backend (no screen needed), each
returned as PNG bytes. Inputs are a Run and the stored analysis payload
(daq/workflows/analysis.py): nothing is computed here but what a plot needs."""

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


def _png(fig: Any) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110, bbox_inches="tight")
    _pyplot().close(fig)
    return buffer.getvalue()


def hits_figure(run: Any) -> bytes:
    """Force and response of each hit (up to MAX_HITS_DRAWN); rejected hits in red with why."""
    plt = _pyplot()
    hits = run.hits
    n = min(hits.n_hits, MAX_HITS_DRAWN)
    fig, axes = plt.subplots(n, 2, figsize=(11, 1.6 * n + 0.8), sharex=True, squeeze=False)
    t_ms = hits.time_s() * 1e3
    for i in range(n):
        ok = bool(hits.accepted[i])
        colour = "#1f4e9c" if ok else "#c0392b"
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
        verdict = "accepted" if ok else f"REJECTED: {hits.reject_reason[i]}"
        axes[i, 0].set_title(f"hit {i + 1} force — {verdict}", fontsize=8, loc="left", color=colour)
        axes[i, 1].set_title(f"hit {i + 1} response", fontsize=8, loc="left", color=colour)
    for ax in axes[-1]:
        ax.set_xlabel("time after trigger (ms)", fontsize=8)
    fig.suptitle(f"Run {run.run_id}: time records ({hits.n_hits} hits, {int(hits.accepted.sum())} accepted)")
    return _png(fig)


def frf_figure(result: dict[str, Any]) -> bytes:
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
    return _png(fig)


def stability_figure(result: dict[str, Any]) -> bytes:
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
    return _png(fig)


def synthesis_figure(result: dict[str, Any]) -> bytes:
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
    return _png(fig)


def response_fit_figure(run: Any, fit: dict[str, Any]) -> bytes:
    """Like the seed's Fig. 5: the measured tip acceleration of one hit and the fitted
    model's response to that hit's measured force."""
    plt = _pyplot()
    hits = run.hits
    k = int(fit["hit_index"][0])
    t_ms = hits.time_s() * 1e3
    fig, ax = plt.subplots(figsize=(10, 4))
    ax.plot(t_ms, hits.response_m_s2[k], color="#1f4e9c", lw=0.8, label="measured")
    ax.plot(t_ms, fit["model_response"], color="#c0392b", lw=0.8, ls="--", label="model with the fitted R")
    ax.set_xlabel("time after trigger (ms)")
    ax.set_ylabel("tip acceleration (m/s²)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    s = fit["summary"]
    ax.set_title(
        f"Run {run.run_id}, hit {k + 1}: measured and model response ({s['method']}, Psi {s['psi']:.3g})"
    )
    return _png(fig)


def convergence_figure(fits: dict[str, dict[str, Any]]) -> bytes:
    """Best Psi per generation (GA) or iteration (DE) of every fit that has a history."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 4))
    for name, fit in fits.items():
        if "history" in fit:
            history = np.asarray(fit["history"], dtype=float)
            ax.semilogy(np.arange(1, history.size + 1), history, marker=".", lw=0.9, label=name)
    ax.set_xlabel("generation / iteration")
    ax.set_ylabel("best Psi (eq 17)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    ax.set_title("Convergence of the fits: best Psi per generation (GA) or iteration")
    return _png(fig)
