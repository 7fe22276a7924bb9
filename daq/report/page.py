"""The report page: one HTML file with its style inline and every figure embedded as a
base64 PNG, so that it opens from disk, is mailed as one attachment, and needs no
network. Every text from a run (operator, note, reasons) is HTML-escaped.

The report is first a list of sections (:func:`sections`: headings, paragraphs,
cautions, tables and figure names, all plain text); :func:`render` writes them as the
HTML page and :func:`render_pdf` as a PDF of the same sections (matplotlib's PDF
backend: text pages for the tables, the figures as vector pages), so the two hold the
same report."""

from __future__ import annotations

import base64
import html
import io
import json
import textwrap
from dataclasses import dataclass, field
from typing import Any

from analysis.hit_checks import BAND_FRACTION, MAX_DROP_DB
from daq.report.figures import QUALITY_HITS, psi_unit
from daq.report.numbers import plain, span, with_uncertainty
from daq.workflows.run_views import accepted_against_checks as _against
from daq.workflows.run_views import failed_check_names, options_text, pretrigger_text, zones_text

STYLE = """
body { font: 14px/1.45 system-ui, sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.15em; margin-top: 2em; border-bottom: 1px solid #ddd; }
table { border-collapse: collapse; margin: 0.5em 0; } td, th { padding: 3px 10px; border: 1px solid #ddd; }
th { background: #f4f4f4; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.rejected td { color: #c0392b; } img { max-width: 100%; border: 1px solid #eee; }
.note { color: #666; font-size: 0.9em; }
tr.caution td { color: #8a4b00; }
.caution { color: #8a4b00; background: #fff4e0; border-left: 4px solid #e69500; padding: 4px 8px; }
"""


TABLE2_HEADER = ["mode", "Ritz (Hz)", "exact beam (Hz)", "this run (Hz)", "run vs exact (%)", "damping (%)"]


def _pct(value: float | None) -> float | None:
    return None if value is None else 100 * value


def _e(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _num(value: float | None, fmt: str) -> str:
    return "–" if value is None else plain(value, fmt)


def _table(header: list[str], rows: list[list[str]], classes: list[str] | None = None) -> str:
    head = "".join(f"<th>{_e(h)}</th>" for h in header)
    body = []
    for i, row in enumerate(rows):
        cls = f' class="{classes[i]}"' if classes and classes[i] else ""
        body.append(f"<tr{cls}>" + "".join(row) + "</tr>")
    return f"<table><tr>{head}</tr>{''.join(body)}</table>"


def _img(png: bytes, alt: str) -> str:
    return f'<img alt="{_e(alt)}" src="data:image/png;base64,{base64.b64encode(png).decode("ascii")}">'


def _cautions(cautions: list[str]) -> list[str]:
    """Each caution as a paragraph the eye cannot miss (escaped: texts may come from runs)."""
    return [f"<p class='caution'>caution: {_e(text)}</p>" for text in cautions]


# ------------------------------------------------------------------ the report's sections


@dataclass
class Para:
    """A paragraph: ``kind`` "p" (text), "note" (grey) or "caution" (shown with "caution: ")."""

    text: str
    kind: str = "p"


@dataclass
class Table:
    """Plain-text cells; ``numeric``: columns aligned right; ``row_header``: each row's
    first cell heads it; ``classes``: a CSS class per row ("rejected", "caution" or "")."""

    header: list[str] | None
    rows: list[list[str]]
    numeric: frozenset[int] = frozenset()
    row_header: bool = False
    classes: list[str] | None = None


@dataclass
class Fig:
    """A figure of the report, by its name in the figures dict."""

    name: str
    title: str


@dataclass
class Section:
    """A heading ("" for none) and its blocks (Para, Table, Fig) in order."""

    title: str
    blocks: list[Any] = field(default_factory=list)


#: Window mnemonics as the analyzer stores them -> what a reader calls them.
WINDOW_NAMES = {"UNIF": "uniform", "HANN": "Hann", "FLAT": "flat top", "FORC": "force", "EXPO": "exponential"}
#: The analyzer's channels as the run's settings name them: (input, role, engineering unit).
CHANNELS = {
    "hammer": ("CH1", "hammer (force)", "N"),
    "accelerometer": ("CH2", "accelerometer (response)", "m/s²"),
}
TRIGGER_UNITS = {"CH1": "N", "CH2": "m/s²"}
STANDARD_GRAVITY = 9.80665
#: Settings the acquisition tables show; any other stored key is listed as stored.
SHOWN_SETTINGS = frozenset({
    "span_hz", "lines", "center_hz", "averages", "trigger_source", "trigger_level_eu", "trigger_slope",
    "pre_trigger_s", "preview", "hammer", "accelerometer",
})  # fmt: skip
NOT_RECORDED = "not recorded"


def _g(value: float, unit: str, fmt: str = ".4g") -> str:
    return f"{plain(value, fmt)} {unit}"


def _time(seconds: float) -> str:
    """A duration in the unit a reader takes in: ms below one second, else s."""
    return _g(1e3 * seconds, "ms") if abs(seconds) < 1 else _g(seconds, "s")


def _compact(value: Any, limit: int = 240) -> str:
    text = value if isinstance(value, str) else json.dumps(value, ensure_ascii=False, sort_keys=True)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def hit_time(run: Any, i: int) -> str:
    """Hit ``i``'s time as the report shows it: a run read from a file records none."""
    return "not recorded" if run.kind == "imported" else str(run.hits.timestamp_utc[i])


def accepted_against_checks(run: Any) -> list[str]:
    """One line per hit accepted although a check failed (hits counted from 1), from
    daq.workflows.run_views.accepted_against_checks, as `daq runs show` marks them."""
    hits = run.hits
    lines = []
    for i in _against(run):
        failed = failed_check_names(hits.checks[i])
        details = "; ".join(f"{name}: {hits.checks[i][name].get('detail', 'failed')}" for name in failed)
        lines.append(f"hit {i + 1} was accepted although its check failed ({details})")
    return lines


def _channel_rows(settings: dict[str, Any]) -> tuple[list[list[str]], list[list[str]]]:
    """(channel rows, transducer rows) of the stored settings."""
    channels, transducers = [], []
    for key, (inp, role, eu) in CHANNELS.items():
        setup = settings.get(key)
        if not isinstance(setup, dict):
            continue
        sens = setup.get("sensitivity_v_per_eu")
        if isinstance(sens, (int, float)) and sens > 0:
            sens_text = f"{plain(1e3 * sens, '.4g')} mV/{'N' if eu == 'N' else '(m/s²)'}"
            if eu != "N":
                sens_text += f" (= {plain(1e3 * sens * STANDARD_GRAVITY, '.4g')} mV/g)"
        else:
            sens, sens_text = None, NOT_RECORDED
        range_v = setup.get("range_v")
        if range_v is None:
            range_text = "auto" if "range_v" in setup else NOT_RECORDED
        else:
            full_scale = f" (= {plain(range_v / sens, '.4g')} {eu} full scale)" if sens else ""
            range_text = _g(range_v, "V") + full_scale
        coupling = {True: "AC", False: "DC"}.get(setup.get("ac_coupled"), NOT_RECORDED)
        mnemonic = setup.get("window")
        window = f"{WINDOW_NAMES.get(mnemonic, mnemonic)} ({mnemonic})" if mnemonic else NOT_RECORDED
        if mnemonic == "FORC" and setup.get("force_width_s") is not None:
            window += f", width {_time(setup['force_width_s'])} from the record's start"
        if mnemonic == "EXPO" and setup.get("exp_decay_s"):
            tau = float(setup["exp_decay_s"])
            window += f", time constant {_time(tau)} (decay {plain(1 / tau, '.4g')} 1/s)"
        channels.append([f"{inp} {role}", sens_text, range_text, coupling, window])
        transducer = setup.get("transducer") if isinstance(setup.get("transducer"), dict) else {}
        due = str(transducer.get("due_date") or transducer.get("due") or NOT_RECORDED)
        if transducer.get("overdue") is True:
            due += " OVERDUE"  # at the capture
        model = str(transducer.get("model") or NOT_RECORDED)
        if transducer.get("id"):
            model += f" ({transducer['id']})"  # the id in the station's transducer table
        transducers.append([
            f"{inp} {role}", model, str(transducer.get("serial") or NOT_RECORDED),
            _transducer_sensitivity(transducer, sens_text),
            str(transducer.get("calibration_date") or transducer.get("calibrated") or NOT_RECORDED), due,
        ])  # fmt: skip
    return channels, transducers


def _transducer_sensitivity(transducer: dict[str, Any], sens_text: str) -> str:
    """The transducer's sensitivity in the unit of its calibration sheet, with the
    channel's (V per SI unit, as the analyzer used it) when that unit differs."""
    value, unit = transducer.get("sensitivity"), transducer.get("sensitivity_unit")
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not unit:
        return sens_text
    own = f"{plain(value, '.4g')} {unit}"
    if sens_text == NOT_RECORDED:
        return own
    return sens_text if own in sens_text else f"{own} (channel: {sens_text})"


def run_setup(run: Any) -> tuple[str, Any] | None:
    """(name, version) of the named setup the run was captured with, None when the run
    records none (settings from options or a setup file)."""
    setup = (run.provenance or {}).get("setup")
    if isinstance(setup, dict) and setup.get("name"):
        return str(setup["name"]), setup.get("version")
    return None


def stored_cautions(run: Any) -> list[str]:
    """The cautions the capture stored with the run (e.g. a transducer's calibration past
    due), without their leading "caution: " (the report adds its own)."""
    cautions = (run.provenance or {}).get("cautions")
    if not isinstance(cautions, list):
        return []
    return [str(text).removeprefix("caution: ") for text in cautions if str(text).strip()]


def _point_text(point: Any) -> str:
    where = (
        f"{plain(point.position_m, '.4g')} m from the clamp"
        if point.position_m is not None
        else f"node {point.node}"
    )
    return f"{point.name}: {where}, {point.direction}"


def acquisition_section(run: Any) -> Section:
    """The analyzer, its settings as the run stored them, the transducers as far as the
    run records them, the record, the points, and what the simulator or importer says."""
    section = Section("Acquisition")
    blocks = section.blocks
    inst = run.instrument
    settings = inst.settings if inst is not None else {}
    if inst is not None:
        blocks.append(
            Table(
                None,
                [
                    ["analyzer", inst.model],
                    ["identification", inst.identification or NOT_RECORDED],
                    ["resource", inst.resource or NOT_RECORDED],
                    ["transport, dialect", f"{inst.transport}, {inst.dialect}"],
                ],
                row_header=True,
            )
        )
    else:
        blocks.append(Para("No analyzer: the run holds no analyzer settings (see its origin below).", "note"))
    rows = []
    named = run_setup(run)
    if named is not None:
        name, version = named
        rows.append(["setup", name + (f", version {version}" if version is not None else "")])
    elif inst is not None:
        rows.append(["setup", "no named setup recorded (options or a setup file)"])
    ranged = (run.provenance or {}).get("auto_range")
    if ranged is not None:
        from daq.workflows.run_views import auto_range_text

        text = auto_range_text(ranged, settings.get("trigger_source"))
        rows.append(["auto-range", text.replace("^2", "²") if text else _compact(ranged)])
    span, lines = settings.get("span_hz"), settings.get("lines")
    if span is not None:
        rows.append(["span", _g(span, "Hz")])
    if lines is not None:
        rows.append(["lines", str(lines)])
        if span:
            rows.append(["resolution (span / lines)", _g(span / lines, "Hz")])
            rows.append(["record length (lines / span)", _time(lines / span)])
    if "center_hz" in settings:
        centre = settings["center_hz"]
        rows.append(["centre", "baseband (0 to span)" if not centre else _g(centre, "Hz") + " (zoom)"])
    if "averages" in settings:
        rows.append(["averages", f"{settings['averages']} hits (stable averaging)"])
    source = settings.get("trigger_source")
    if source is not None:
        role = {"CH1": " (hammer)", "CH2": " (accelerometer)"}.get(source, "")
        rows.append(["trigger source", f"{source}{role}"])
    if settings.get("trigger_level_eu") is not None:
        rows.append(["trigger level", _g(settings["trigger_level_eu"], TRIGGER_UNITS.get(source, "EU"))])
    if settings.get("trigger_slope") is not None:
        slope = settings["trigger_slope"]
        rows.append(["trigger slope", {"POS": "rising (POS)", "NEG": "falling (NEG)"}.get(slope, slope)])
    if settings.get("pre_trigger_s") is not None:
        rows.append(["pre-trigger", _time(settings["pre_trigger_s"])])
    if "preview" in settings:
        rows.append(["preview", "each hit accepted or rejected before it is averaged" if settings["preview"]
                     else "off: every triggered hit averaged"])  # fmt: skip
    if rows:
        blocks += [
            Para("Analyzer settings, as the run stored them:", "note"),
            Table(["setting", "value"], rows),
        ]
    channels, transducers = _channel_rows(settings)
    if channels:
        blocks.append(Table(["channel", "sensitivity", "range", "coupling", "window"], channels))
        blocks += [
            Para("Transducers, as far as the run records them:", "note"),
            Table(
                ["channel", "model (id)", "serial", "sensitivity", "calibrated", "calibration due"],
                transducers,
                classes=["caution" if "OVERDUE" in row[5] else "" for row in transducers],
            ),
        ]
    other = {k: v for k, v in settings.items() if k not in SHOWN_SETTINGS}
    if other:
        blocks += [
            Para("Other settings, as stored:", "note"),
            Table(["setting", "value"], [[k, _compact(v)] for k, v in sorted(other.items())]),
        ]
    if run.hits is not None:
        h = run.hits
        record = [
            ["hits", f"{h.n_hits} ({int(h.accepted.sum())} accepted), counted from 1"],
            ["samples per record", str(h.n_samples)],
            ["sample rate", _g(h.sample_rate_hz, "Hz")],
            ["record length", _time(h.n_samples / h.sample_rate_hz)],
            [
                "first sample",
                _time(h.start_s) + " after the trigger" + (" (pre-trigger)" if h.start_s < 0 else ""),
            ],
            [
                "centre",
                "baseband" if h.center_hz == 0 else _g(h.center_hz, "Hz") + " (zoom, complex records)",
            ],
        ]
        blocks += [Para("Time records:", "note"), Table(None, record, row_header=True)]
    points = run.resolved_points()
    article = points.article
    article_text = str(article.get("kind", "")) + (f" ({article['name']})" if article.get("name") else "")
    point_rows = [
        ["modal test", points.test or "none"],
        [
            "article",
            article_text + ("" if run.points is not None else ", assumed: the run records no points"),
        ],
        ["force point", _point_text(points.force_point)],
    ] + [[f"response point {i}", _point_text(p)] for i, p in enumerate(points.response_points, 1)]
    if run.points is None and run.kind == "imported":
        # An imported file says nothing of the structure: the seed's beam is no fact of it.
        point_rows = [["article and points", "not recorded: the imported file says nothing of the structure"]]
    blocks += [Para("Points:", "note"), Table(None, point_rows, row_header=True)]
    blocks += _origin(run)
    return section


#: Provenance keys the report shows in their own rows, not again as raw provenance.
_SHOWN_ELSEWHERE = {
    "hits_wanted", "simulator", "replayed_from", "imported_from", "setup", "cautions", "auto_range",
}  # fmt: skip


def _origin(run: Any) -> list[Any]:
    """What the simulator, a replay or an importer recorded about where the data came from."""
    prov = run.provenance or {}
    rows = []
    if "hits_wanted" in prov:
        rows.append(["hits wanted", str(prov["hits_wanted"])])
    sim = prov.get("simulator")
    if isinstance(sim, dict):
        for key, value in sorted(sim.items()):
            unit = " m" if key.endswith("_m") else ""
            rows.append(
                [f"simulator {key.replace('_', ' ')}", f"{_compact(value)}{unit}" if value != "" else "–"]
            )
    if prov.get("replayed_from"):
        rows.append(["replayed from", _compact(prov["replayed_from"])])
    imported = prov.get("imported_from")
    if isinstance(imported, dict):
        for key, value in imported.items():
            rows.append([f"imported {key.replace('_', ' ')}", _compact(value)])
    for key, value in sorted(prov.items()):
        if key not in _SHOWN_ELSEWHERE:
            rows.append([key.replace("_", " "), _compact(value)])
    if not rows:
        return []
    return [Para("Origin, as the run records it:", "note"), Table(None, rows, row_header=True)]


def _window_cautions(summary: dict[str, Any]) -> list[str]:
    windows_from = summary.get("windows", {}).get("from", "")
    said = f"windows {windows_from}"
    # Analyses stored before it was one of their cautions do not hold it.
    return (
        [said] if str(windows_from).startswith("unknown") and said not in summary.get("cautions", []) else []
    )


def hit_verdict(run: Any, i: int) -> tuple[str, str]:
    """(verdict text, row class) of hit ``i`` (0-based): "accepted", "rejected: why" or,
    marked "caution", "accepted against failed check: names"."""
    hits = run.hits
    failed = failed_check_names(hits.checks[i])
    if hits.accepted[i] and failed:
        return f"accepted against failed check: {', '.join(failed)}", "caution"
    return ("accepted", "") if hits.accepted[i] else (f"rejected: {hits.reject_reason[i]}", "rejected")


def hit_quality_section(run: Any, figures: Any) -> Section | None:
    """Each drawn hit's quality figure (names ``hit_quality_<number>``), with a note on
    what the panels show and which hits are not drawn."""
    numbers = sorted(int(name.rsplit("_", 1)[1]) for name in figures if name.startswith("hit_quality_"))
    if not numbers:
        return None
    n = run.hits.n_hits
    rest = [k for k in range(1, n + 1) if k not in numbers]
    section = Section("Hit quality")
    section.blocks.append(Para(
        "For each hit: the force pulse (zoomed) with the force window over it; the response with its "
        f"window over it; the force autospectrum in dB against the tip check's roll-off limit "
        f"({-MAX_DROP_DB:g} dB over the top {BAND_FRACTION:.0%} of the span, against the lowest "
        f"{BAND_FRACTION:.0%}); the hit's own FRF (H1 with the windows) over the average of the run's "
        "accepted hits, magnitude and phase; and the coherence of that average.",
        "note",
    ))  # fmt: skip
    if rest:
        section.blocks.append(Para(
            f"Drawn: {_hits_text(numbers)} (the first {QUALITY_HITS} and every hit accepted against "
            f"a failed check, as far as their records resolve the span); not drawn: "
            f"{_hits_text(rest)}, listed in the Hits table.",
            "note",
        ))  # fmt: skip
    for k in numbers:
        verdict, _ = hit_verdict(run, k - 1)
        section.blocks.append(Fig(f"hit_quality_{k}", f"hit {k}: {verdict}"))
    return section


def _hits_text(numbers: list[int]) -> str:
    """ "hit 4", "hits 1-3, 5": the word in the number the list holds."""
    return f"hit{'s' * (len(numbers) != 1)} {_numbers_text(numbers)}"


def _numbers_text(numbers: list[int]) -> str:
    """ "1-6, 9, 11": runs of consecutive numbers joined."""
    parts, start = [], None
    for j, k in enumerate(numbers):
        if start is None:
            start = k
        if j + 1 == len(numbers) or numbers[j + 1] != k + 1:
            parts.append(str(start) if start == k else f"{start}-{k}")
            start = None
    return ", ".join(parts)


def cautions_section(run: Any, result: dict[str, Any], fits: dict[str, dict] | None) -> Section:
    """Every caution of the report in one place: the analysis's, each fit's, and the hits
    accepted although a check failed."""
    section = Section("Cautions")
    groups = [
        ("the analysis", [*_window_cautions(result["summary"]), *result["summary"].get("cautions", [])])
    ]
    groups += [
        (name, [*_window_cautions(fit["summary"]), *fit["summary"].get("cautions", [])])
        for name, fit in (fits or {}).items()
    ]
    groups.append(("the hits", accepted_against_checks(run)))
    groups.insert(0, ("the capture (its setup and transducers)", stored_cautions(run)))
    for where, cautions in groups:
        if cautions:
            section.blocks.append(Para(f"From {where}:", "note"))
            section.blocks += [Para(text, "caution") for text in cautions]
    if not section.blocks:
        section.blocks.append(
            Para("None: the capture, the analysis, the fits and the hits raised no caution.", "note")
        )
    return section


def sections(
    run: Any,
    result: dict[str, Any],
    figures: Any,
    fits: dict[str, dict] | None = None,
    fit_hint: bool = False,
) -> list[Section]:
    """The report's sections, in order; ``figures``: the names of the figures drawn."""
    s = result["summary"]
    info = [
        ["run", run.run_id], ["kind", run.kind + ("" if run.complete else ", INCOMPLETE")],
        ["started", run.start_time], ["operator", run.operator or "–"], ["note", run.note or "–"],
        ["software", run.software],
    ]  # fmt: skip
    if run.instrument is not None:
        info.append(["instrument", f"{run.instrument.model} ({run.instrument.identification})"])
    out = [
        Section("", [Table(["", ""], info, row_header=True)]),
        cautions_section(run, result, fits),
        acquisition_section(run),
    ]
    if run.hits is not None:
        rows, classes = [], []
        for i in range(run.hits.n_hits):
            verdict, cls = hit_verdict(run, i)
            rows.append([str(i + 1), hit_time(run, i), plain(run.hits.peak_force_n[i], ".3g"), verdict])
            classes.append(cls)
        hits = Section(
            "Hits",
            [
                Table(
                    ["hit", "time (UTC)", "peak force (N)", "verdict"],
                    rows,
                    frozenset({0, 2}),
                    classes=classes,
                )
            ],
        )
        if "hits" in figures:
            hits.blocks.append(Fig("hits", "force and response of each hit"))
        out.append(hits)
        quality = hit_quality_section(run, figures)
        if quality is not None:
            out.append(quality)
    n_hits = s["n_averages"]
    hits_text = f"{n_hits} accepted hit{'s' * (n_hits != 1)}"  # "1 accepted hit", never "1 ... hits"
    source = {"hits": f"{hits_text}, {s.get('estimator')}"}.get(s["source"], s["source"])
    windows = s.get("windows", {}).get("from", "")
    band = s.get("band")
    # Four digits, as `daq analyze` prints them: the edges are lines (0.999997 Hz).
    band_text = f" Band {span(band['low_hz'], band['high_hz'], '.4g')}: {band['reason']}." if band else ""
    u_from = sorted({m.get("uncertainty_from") for m in s["modes"]} - {None})
    decay = s.get("added_decay_1_s") or 0.0
    removed = (
        f"; the exponential window's decay ({plain(decay, '.4g')} 1/s) is removed from every damping ratio. "
        if decay > 0
        else ". "
    )
    cut_text = pretrigger_text(s)
    cut_text = f"{cut_text[0].upper()}{cut_text[1:]}. " if cut_text else ""
    # The options and zones the stored result was made with: a tuned analysis is told
    # from a default one, and can be made again.
    made = f"Analysed with {options_text(s.get('options'))}"
    zones = zones_text(s.get("zones"))
    made += f" ({zones}). " if zones else ". "
    note = (
        f"From {source}.{band_text} {made}Windows: {windows}{removed}{cut_text}"
        + (f"± is the standard uncertainty of the value, from {', '.join(u_from)}. " if u_from else "")
        + (
            f"Synthesis error {plain(100 * s['synthesis_error'], '.3g')} %."
            if s.get("synthesis_error") is not None
            else ""
        )
    )
    mode_rows = []
    for k, m in enumerate(s["modes"], 1):
        q = m["quality"]
        zeta = m["damping_ratio"]
        mode_rows.append([
            str(k), " ± ".join(with_uncertainty(m["frequency_hz"], m.get("frequency_u_hz"), ".4f")),
            "– ± –" if zeta is None else " ± ".join(with_uncertainty(
                100 * zeta, None if m.get("damping_u") is None else 100 * m["damping_u"], ".3g")),
            # A mode added among close ones (analysis/modal_id/refine.py, missing) has no chain.
            "none: added (LSCF missed it)" if q.get("added") else
            str(q["n_stable_orders"]) + (" (alpha_0 = 1)" if q.get("normalisation") == "lowest" else "")
            + (" (kept for a clear peak)" if q.get("for_peak") else ""),
            f"{plain(100 * q['synthesis_share'], '.2g')} %",
        ])  # fmt: skip
    modes = Section("Modes", [Para(note, "note")])
    modes.blocks += [Para(c, "caution") for c in [*_window_cautions(s), *s.get("cautions", [])]]
    modes.blocks.append(
        Table(
            ["mode", "frequency (Hz)", "damping (%)", "stable orders", "share of synthesis"],
            mode_rows,
            frozenset(range(5)),
        )
    )
    out.append(modes)
    t = s["table2"]
    if t.get("n_functions") is None:
        out.append(Section("Table 2", [Para(f"{t['beam']}.", "note")]))
    else:
        rows = [
            [
                str(r["mode"]),
                _num(r["ritz_hz"], ".3f"),
                _num(r["exact_hz"], ".3f"),
                _num(r["identified_hz"], ".3f"),
                _num(r["difference_exact_pct"], "+.2f"),
                _num(_pct(r["damping_ratio"]), ".3g"),
            ]
            for r in t["rows"]
        ]
        out.append(Section("Table 2", [
            Para(f"Beam: {t['beam']}; Ritz with N = {t['n_functions']}.", "note"),
            Table(TABLE2_HEADER, rows, frozenset(range(6))),
        ]))  # fmt: skip
    for name, title in (("frf", "FRF and coherence"), ("stability", "Stability diagram"),
                        ("synthesis", "Synthesis")):  # fmt: skip
        if name in figures:
            out.append(Section(title, [Fig(name, title)]))
    if fits:
        out += _fit_sections(fits, figures)
    elif fit_hint:
        out.append(
            Section(
                "Damping matrix",
                [
                    Para(
                        f"No damping fit is stored for this run: `daq fit {run.run_id}` makes one, "
                        "then this report shows it.",
                        "note",
                    )
                ],
            )
        )
    return out


def _stiffness_text(summary: dict) -> str:
    """The model's stiffness as `daq fit` prints it: 'stiffness scaled by 0.98443 to the
    run's frequencies, then each mode at its identified frequency'."""
    info = summary.get("stiffness") or {}
    scale = info.get("scale")
    if info.get("update", "none") == "none" or scale is None:
        return "stiffness as built (--stiffness none)"
    modes = info.get("mode_frequencies") or {}
    then = ", then each mode at its identified frequency" if modes.get("applied") else ""
    kept = "" if modes.get("applied") or not modes.get("reason") else f" (modes kept: {modes['reason']})"
    return f"stiffness scaled by {scale:.5f} to the run's frequencies{then}{kept}"


def _fit_sections(fits: dict[str, dict], figures: Any) -> list[Section]:
    """The damping matrix of each fit with its uncertainty, the modes it implies, its
    cautions, and the figures of the fit."""
    section = Section("Damping matrix")
    for name, fit in fits.items():
        s = fit["summary"]
        unit = psi_unit(s)
        floor = s.get("psi_noise_floor")
        floor_text = f"; noise floor {plain(floor, '.3g')} {unit}" if floor is not None else ""
        section.blocks.append(Para(
            f"Fit {name}: Psi (eq 17) = {plain(s['psi'], '.4g')} {unit}{floor_text}, "
            f"{s['n_evaluations']} model evaluations, {_stiffness_text(s)}."
        ))  # fmt: skip
        unc = s["uncertainty"]
        by_name = dict(zip(unc["names"], zip(unc["std"], unc["determined"], strict=True), strict=True))
        r = s["damping_matrix"]
        rows = []
        for i in range(len(r)):
            cells = [str(i + 1)]
            for j in range(len(r)):
                std, determined = by_name.get(f"R{min(i, j) + 1}{max(i, j) + 1}", (None, True))
                spread = f" ± {plain(std, '.2g')}" if std is not None else ""
                cells.append(f"{r[i][j]:.4f}{spread}{'' if determined else ' ?'}")
            rows.append(cells)
        section.blocks.append(Table(["R (N s/m)", *[str(j + 1) for j in range(len(r))]], rows,
                                    frozenset(range(1, len(r) + 1)), row_header=True))  # fmt: skip
        for direction in unc["null_directions"]:
            combo = " ".join(f"{w:+.2f} {k}" for k, w in direction["combination"].items() if abs(w) >= 0.05)
            section.blocks.append(Para(f"Not determined by the data (? above): {combo}.", "note"))
        # Numbered as the run's analysis numbers its modes, beside that reading (a fit
        # stored before the partner was kept has none: its position, and "–").
        mode_rows = [
            [
                str(m["identified"]["mode"]) if m.get("identified") else "–" if "identified" in m else str(k),
                _num(m["frequency_hz"], ".4f"),
                _num(_pct(m["damping_ratio"]), ".3g"),
                _analysis_damping(m.get("identified")),
            ]
            for k, m in enumerate(s["modes"], 1)
        ]
        section.blocks.append(
            Table(
                ["mode", "frequency (Hz)", "damping with R (%)", "analysis (%)"],
                mode_rows,
                frozenset({0, 1, 2, 3}),
            )
        )
        section.blocks += [Para(c, "caution") for c in [*_window_cautions(s), *s.get("cautions", [])]]
    out = [section]
    for key, title in (("response_fit", "Measured and model response"), ("convergence", "Convergence")):
        if key in figures:
            out.append(Section(title, [Fig(key, title)]))
    return out


# ---------------------------------------------------------------------------- HTML


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
    return render_sections(run, sections(run, result, figures, fits, fit_hint), figures)


def title(run: Any) -> str:
    return f"Impact test {run.run_id}"


def render_sections(run: Any, report: list[Section], figures: dict[str, bytes]) -> str:
    """The HTML page of ``report``'s sections (every text escaped, figures embedded)."""
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        f"<title>Run {_e(run.run_id)}</title><style>{STYLE}</style></head><body>",
        f"<h1>{_e(title(run))}</h1>",
    ]
    for section in report:
        if section.title:
            parts.append(f"<h2>{_e(section.title)}</h2>")
        for block in section.blocks:
            if isinstance(block, Para):
                if block.kind == "caution":
                    parts += _cautions([block.text])
                else:
                    cls = " class='note'" if block.kind == "note" else ""
                    parts.append(f"<p{cls}>{_e(block.text)}</p>")
            elif isinstance(block, Table):
                parts.append(_html_table(block))
            elif isinstance(block, Fig) and block.name in figures:
                parts.append(_img(figures[block.name], block.title))
    parts.append("</body></html>")
    return "\n".join(parts)


def _html_table(table: Table) -> str:
    rows = []
    for row in table.rows:
        cells = []
        for j, cell in enumerate(row):
            if j == 0 and table.row_header:
                cells.append(f"<th>{_e(cell)}</th>")
            else:
                cells.append(
                    f"<td class='num'>{_e(cell)}</td>" if j in table.numeric else f"<td>{_e(cell)}</td>"
                )
        rows.append(cells)
    if table.header is None:
        body = "".join(f"<tr{_cls(table.classes, i)}>" + "".join(row) + "</tr>" for i, row in enumerate(rows))
        return f"<table>{body}</table>"
    return _table(table.header, rows, table.classes)


def _cls(classes: list[str] | None, i: int) -> str:
    return f' class="{classes[i]}"' if classes and classes[i] else ""


# ----------------------------------------------------------------------------- PDF

#: A4 portrait, inches; text lines per page and characters per line of the text pages.
PAGE_IN = (8.27, 11.69)
LINES_PER_PAGE = 64
CHARS_PER_LINE = 96


def render_pdf(run: Any, report: list[Section], figures: dict[str, Any]) -> bytes:
    """The PDF of ``report``'s sections: text pages (headings, paragraphs, cautions, the
    tables in monospace columns) and each figure (``figures``: name -> matplotlib
    Figure) as a vector page of its own, right after the text page that names it.
    Drawn with matplotlib's PDF backend: no system library needed."""
    from matplotlib.backends.backend_pdf import PdfPages
    from matplotlib.figure import Figure

    buffer = io.BytesIO()
    lines: list[tuple[str, str]] = [(title(run), "h1"), ("", "p")]
    pending: list[tuple[int, Any]] = []  # (line it follows, figure)

    with PdfPages(buffer, metadata={"Title": title(run), "Creator": run.software}) as pdf:

        def page(text: list[tuple[str, str]]) -> None:
            fig = Figure(figsize=PAGE_IN)
            for k, (line, style) in enumerate(text):
                fig.text(
                    0.06,
                    1 - (0.05 + k * 0.9 / LINES_PER_PAGE),
                    _pdf_text(line),
                    va="top",
                    **_PDF_STYLES[style],
                )
            pdf.savefig(fig)

        def emit(last: bool = False) -> None:
            """Each full text page (every page when ``last``), then the figures it names."""
            while len(lines) >= LINES_PER_PAGE or (last and (lines or pending)):
                shown = min(len(lines), LINES_PER_PAGE)
                if shown:
                    page(lines[:shown])
                for at, fig in pending:
                    if at <= shown:
                        pdf.savefig(fig)
                pending[:] = [(at - shown, fig) for at, fig in pending if at > shown]
                del lines[:shown]

        def keep_together(n: int) -> None:
            room = LINES_PER_PAGE - len(lines)
            if n > room and n <= LINES_PER_PAGE:
                lines.extend([("", "p")] * room)
                emit()

        for section in report:
            if section.title:
                keep_together(6)  # no heading alone at a page's foot
                lines.extend([("", "p"), (section.title, "h2")])
            for block in section.blocks:
                if isinstance(block, Fig):
                    if block.name in figures:
                        pending.append((len(lines), figures[block.name]))
                    continue
                if isinstance(block, Para):
                    prefix = "caution: " if block.kind == "caution" else ""
                    text = [
                        (w, block.kind) for w in textwrap.wrap(prefix + block.text, CHARS_PER_LINE) or [""]
                    ]
                else:
                    text = [(row, "mono") for row in _text_table(block)] + [("", "p")]
                keep_together(len(text))
                lines.extend(text)
                emit()
        emit(last=True)
    return buffer.getvalue()


_PDF_STYLES = {
    "h1": {"fontsize": 15, "fontweight": "bold"},
    "h2": {"fontsize": 11.5, "fontweight": "bold"},
    "p": {"fontsize": 8.5},
    "note": {"fontsize": 8.5, "color": "#555555"},
    "caution": {"fontsize": 8.5, "color": "#8a4b00", "fontweight": "bold"},
    "mono": {"fontsize": 7.2, "family": "monospace"},
}


def _pdf_text(text: str) -> str:
    """Text as matplotlib draws it literally ($ would start mathtext)."""
    return text.replace("$", r"\$")


def _text_table(table: Table, width: int = 112) -> list[str]:
    """The table as monospace lines: columns padded, long cells wrapped within their column
    (the widest column narrowed first, down to the next widest, until the row fits)."""
    has_header = table.header is not None and any(table.header)
    rows = ([table.header] if has_header else []) + table.rows
    n = max(len(r) for r in rows) if rows else 0
    widths = [max(len(r[j]) if j < len(r) else 0 for r in rows) for j in range(n)]
    budget = width - 3 * (n - 1)
    while sum(widths) > budget and max(widths) > 12:
        widest = widths.index(max(widths))
        others = sorted(widths, reverse=True)
        target = max(12, others[1] if len(others) > 1 else 12, widths[widest] - (sum(widths) - budget))
        widths[widest] = target if target < widths[widest] else widths[widest] - 1
    out = []
    for i, row in enumerate(rows):
        cells = [(textwrap.wrap(row[j], widths[j]) or [""]) if j < len(row) else [""] for j in range(n)]
        for k in range(max(len(c) for c in cells)):
            parts = []
            for j, c in enumerate(cells):
                text = c[k] if k < len(c) else ""
                parts.append(text.rjust(widths[j]) if j in table.numeric else text.ljust(widths[j]))
            out.append("   ".join(parts).rstrip())
        if i == 0 and has_header:
            out.append("-" * min(width, sum(widths) + 3 * (n - 1)))
    return out


def _analysis_damping(partner: dict | None) -> str:
    """The run's analysis reading of a fitted mode's damping, "0.39978 ± 0.00014", or "–"."""
    if not partner or partner.get("damping_ratio") is None:
        return "–"
    u = partner.get("damping_u")
    value, u_text = with_uncertainty(100 * partner["damping_ratio"], 100 * u if u else None, ".3g")
    return value if u_text == "–" else f"{value} ± {u_text}"
