"""The report page: one HTML file with its style inline and every figure embedded as a
base64 PNG, so that it opens from disk, is mailed as one attachment, and needs no
network. Every text from a run (operator, note, reasons) is HTML-escaped."""

from __future__ import annotations

import base64
import html
from typing import Any

STYLE = """
body { font: 14px/1.45 system-ui, sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.15em; margin-top: 2em; border-bottom: 1px solid #ddd; }
table { border-collapse: collapse; margin: 0.5em 0; } td, th { padding: 3px 10px; border: 1px solid #ddd; }
th { background: #f4f4f4; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.rejected td { color: #c0392b; } img { max-width: 100%; border: 1px solid #eee; }
.note { color: #666; font-size: 0.9em; }
.caution { color: #8a4b00; background: #fff4e0; border-left: 4px solid #e69500; padding: 4px 8px; }
"""


TABLE2_HEADER = ["mode", "Ritz (Hz)", "exact beam (Hz)", "this run (Hz)", "run vs exact (%)", "damping (%)"]


def _pct(value: float | None) -> float | None:
    return None if value is None else 100 * value


def _e(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _num(value: float | None, fmt: str) -> str:
    return "–" if value is None else format(value, fmt)


def _table(header: list[str], rows: list[list[str]], classes: list[str] | None = None) -> str:
    head = "".join(f"<th>{_e(h)}</th>" for h in header)
    body = []
    for i, row in enumerate(rows):
        cls = f' class="{classes[i]}"' if classes and classes[i] else ""
        body.append(f"<tr{cls}>" + "".join(row) + "</tr>")
    return f"<table><tr>{head}</tr>{''.join(body)}</table>"


def _img(png: bytes, alt: str) -> str:
    return f'<img alt="{_e(alt)}" src="data:image/png;base64,{base64.b64encode(png).decode("ascii")}">'


def render(
    run: Any,
    result: dict[str, Any],
    figures: dict[str, bytes],
    fits: dict[str, dict] | None = None,
    fit_hint: bool = False,
) -> str:
    """The page for ``run`` with its analysis ``result``, its damping fits (result name
    -> stored fit) and ``figures`` (name -> PNG); ``fit_hint``: say that no fit is stored
    and how to make one."""
    s = result["summary"]
    info = [
        ("run", run.run_id), ("kind", run.kind + ("" if run.complete else ", INCOMPLETE")),
        ("started", run.start_time), ("operator", run.operator or "–"), ("note", run.note or "–"),
        ("software", run.software),
    ]  # fmt: skip
    if run.instrument is not None:
        info.append(("instrument", f"{run.instrument.model} ({run.instrument.identification})"))
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        f"<title>Run {_e(run.run_id)}</title><style>{STYLE}</style></head><body>",
        f"<h1>Impact test {_e(run.run_id)}</h1>",
        _table(["", ""], [[f"<th>{_e(k)}</th>", f"<td>{_e(v)}</td>"] for k, v in info]),
    ]
    if run.hits is not None:
        rows, classes = [], []
        for i in range(run.hits.n_hits):
            ok = bool(run.hits.accepted[i])
            rows.append([
                f"<td class='num'>{i + 1}</td>", f"<td>{_e(run.hits.timestamp_utc[i])}</td>",
                f"<td class='num'>{run.hits.peak_force_n[i]:.3g}</td>",
                f"<td>{'accepted' if ok else 'rejected: ' + _e(run.hits.reject_reason[i])}</td>",
            ])  # fmt: skip
            classes.append("" if ok else "rejected")
        parts += ["<h2>Hits</h2>", _table(["hit", "time (UTC)", "peak force (N)", "verdict"], rows, classes)]
        if "hits" in figures:
            parts.append(_img(figures["hits"], "force and response of each hit"))
    parts.append("<h2>Modes</h2>")
    source = {"hits": f"{s['n_averages']} accepted hits, {s.get('estimator')}"}.get(s["source"], s["source"])
    windows = s.get("windows", {}).get("from", "")
    band = s.get("band")
    band_text = f" Band {band['low_hz']:.6g}-{band['high_hz']:.6g} Hz: {band['reason']}." if band else ""
    u_from = sorted({m.get("uncertainty_from") for m in s["modes"]} - {None})
    parts.append(
        f"<p class='note'>From {_e(source)}.{_e(band_text)} Windows: {_e(windows)}; the exponential "
        f"window's decay ({s['added_decay_1_s']:.4g} 1/s) is removed from every damping ratio. "
        + (f"± is the standard uncertainty of the value, from {_e(', '.join(u_from))}. " if u_from else "")
        + (
            f"Synthesis error {100 * s['synthesis_error']:.3g} %."
            if s.get("synthesis_error") is not None
            else ""
        )
        + "</p>"
    )
    windows_from = s.get("windows", {}).get("from", "")
    unknown_windows = [f"windows {windows_from}"] if str(windows_from).startswith("unknown") else []
    parts += _cautions([*unknown_windows, *s.get("cautions", [])])
    mode_rows = []
    for k, m in enumerate(s["modes"], 1):
        q = m["quality"]
        zeta = m["damping_ratio"]
        mode_rows.append([
            f"<td class='num'>{k}</td>",
            f"<td class='num'>{m['frequency_hz']:.4f} ± {_num(m.get('frequency_u_hz'), '.2g')}</td>",
            f"<td class='num'>{_num(None if zeta is None else 100 * zeta, '.3g')} ± "
            f"{_num(None if m.get('damping_u') is None else 100 * m['damping_u'], '.2g')}</td>",
            f"<td class='num'>{q['n_stable_orders']}</td>",
            f"<td class='num'>{100 * q['synthesis_share']:.2g} %</td>",
        ])  # fmt: skip
    parts.append(
        _table(["mode", "frequency (Hz)", "damping (%)", "stable orders", "share of synthesis"], mode_rows)
    )
    t = s["table2"]
    rows = [
        [
            f"<td class='num'>{r['mode']}</td>", f"<td class='num'>{_num(r['ritz_hz'], '.3f')}</td>",
            f"<td class='num'>{_num(r['exact_hz'], '.3f')}</td>",
            f"<td class='num'>{_num(r['identified_hz'], '.3f')}</td>",
            f"<td class='num'>{_num(r['difference_exact_pct'], '+.2f')}</td>",
            f"<td class='num'>{_num(_pct(r['damping_ratio']), '.3g')}</td>",
        ]
        for r in t["rows"]
    ]  # fmt: skip
    if t.get("n_functions") is None:
        parts.append(f"<h2>Table 2</h2><p class='note'>{_e(t['beam'])}.</p>")
    else:
        parts += [
            f"<h2>Table 2</h2><p class='note'>Beam: {_e(t['beam'])}; Ritz with N = {t['n_functions']}.</p>",
            _table(
                ["mode", "Ritz (Hz)", "exact beam (Hz)", "this run (Hz)", "run vs exact (%)", "damping (%)"],
                rows,
            ),
        ]
    for name, title in (("frf", "FRF and coherence"), ("stability", "Stability diagram"),
                        ("synthesis", "Synthesis")):  # fmt: skip
        if name in figures:
            parts += [f"<h2>{_e(title)}</h2>", _img(figures[name], title)]
    if fits:
        parts += _fit_section(fits, figures)
    elif fit_hint:
        parts.append(
            "<h2>Damping matrix</h2><p class='note'>No damping fit is stored for this run: "
            f"<code>daq fit {_e(run.run_id)}</code> makes one, then this report shows it.</p>"
        )
    parts.append("</body></html>")
    return "\n".join(parts)


def _cautions(cautions: list[str]) -> list[str]:
    """Each caution as a paragraph the eye cannot miss (escaped: texts may come from runs)."""
    return [f"<p class='caution'>caution: {_e(text)}</p>" for text in cautions]


def _fit_section(fits: dict[str, dict], figures: dict[str, bytes]) -> list[str]:
    """The damping matrix of each fit with its uncertainty, the modes it implies, and
    the figures of the fit."""
    parts = ["<h2>Damping matrix</h2>"]
    for name, fit in fits.items():
        s = fit["summary"]
        floor = s.get("psi_noise_floor")
        floor_text = f"; noise floor {floor:.3g}" if floor is not None else ""
        scale = s["stiffness"].get("scale")
        stiffness = s["stiffness"].get("update", "") + ("" if scale is None else f" x {scale:.5f}")
        parts.append(
            f"<p><b>{_e(name)}</b>: Psi = {s['psi']:.4g}{_e(floor_text)}, {s['n_evaluations']} model "
            f"evaluations, stiffness: {_e(stiffness)}.</p>"
        )
        unc = s["uncertainty"]
        by_name = dict(zip(unc["names"], zip(unc["std"], unc["determined"], strict=True), strict=True))
        r = s["damping_matrix"]
        rows = []
        for i in range(len(r)):
            cells = [f"<th>{i + 1}</th>"]
            for j in range(len(r)):
                std, determined = by_name.get(f"R{min(i, j) + 1}{max(i, j) + 1}", (None, True))
                spread = f" ± {std:.2g}" if std is not None else ""
                mark = "" if determined else " <b>?</b>"
                cells.append(f"<td class='num'>{r[i][j]:.4f}{spread}{mark}</td>")
            rows.append(cells)
        parts.append(_table(["R (N s/m)", *[str(j + 1) for j in range(len(r))]], rows))
        for direction in unc["null_directions"]:
            combo = " ".join(f"{w:+.2f} {k}" for k, w in direction["combination"].items() if abs(w) >= 0.05)
            parts.append(f"<p class='note'>Not determined by the data (? above): {_e(combo)}.</p>")
        mode_rows = [
            [f"<td class='num'>{k}</td>", f"<td class='num'>{_num(m['frequency_hz'], '.4f')}</td>",
             f"<td class='num'>{_num(_pct(m['damping_ratio']), '.3g')}</td>"]
            for k, m in enumerate(s["modes"], 1)
        ]  # fmt: skip
        parts.append(_table(["mode", "frequency (Hz)", "damping (%)"], mode_rows))
        windows_from = s.get("windows", {}).get("from", "")
    unknown_windows = [f"windows {windows_from}"] if str(windows_from).startswith("unknown") else []
    parts += _cautions([*unknown_windows, *s.get("cautions", [])])
    for key, title in (("response_fit", "Measured and model response"), ("convergence", "Convergence")):
        if key in figures:
            parts += [f"<h2>{_e(title)}</h2>", _img(figures[key], title)]
    return parts
