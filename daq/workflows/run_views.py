"""What a run is, as plain data: the JSON of a run's summary and of the whole run, which
`daq runs list/show --json` print and the service's API serves. One view for both, so
that the page and the terminal can never disagree about a run."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any


def summary_dict(s) -> dict[str, Any]:
    """The JSON of a store listing's RunSummary ``s``."""
    return {
        "run_id": s.run_id,
        "file": s.file_name,
        "start_time": s.start_time,
        "kind": s.kind,
        "complete": s.complete,
        "n_hits": s.n_hits,
        "n_accepted": s.n_accepted,
        "operator": s.operator,
        "note": s.note,
        "size_bytes": s.size_bytes,
        "error": s.error,
    }


#: Where the JSON's hit ``index`` starts: 0, as in the run file and the API. People read
#: ``number`` (= index + 1): `daq runs show`, the report, the page and the capture prompt
#: count hits from 1.
HIT_INDEX_BASE = 0


def failed_check_names(checks: dict[str, Any]) -> list[str]:
    """The names of the checks that failed in one hit's stored check results (each a dict
    with a ``passed`` flag, analysis/hit_checks.py HitCheck.as_dict); other entries
    (flags, numbers) are not checks and are skipped."""
    return [name for name, c in checks.items() if isinstance(c, dict) and c.get("passed") is False]


def accepted_against_checks(run) -> list[int]:
    """The 0-based indices of the hits of ``run`` that were accepted although one of their
    checks failed (the operator overrode it), in order; [] for a run without hits."""
    hits = run.hits
    if hits is None:
        return []
    return [i for i in range(int(hits.n_hits)) if hits.accepted[i] and failed_check_names(hits.checks[i])]


_PLAIN_COLUMN = re.compile(r"[A-Za-z0-9_.+-]+")


def options_text(options: dict[str, Any] | None) -> str:
    """The analysis options a stored result was made with, as the `daq analyze` options that
    make it again ("default options" for none): a reader of a report must be able to tell
    a tuned analysis from a default one, and repeat it."""
    options = options or {}
    parts = []
    band = options.get("band_hz")
    if band:
        parts.append(f"--band {band[0]:g}:{band[1]:g}")
    if options.get("max_order") is not None:
        parts.append(f"--max-order {options['max_order']}")
    if options.get("frequencies_hz"):
        parts.append("--frequencies " + ",".join(f"{f:g}" for f in options["frequencies_hz"]))
    if options.get("estimator") not in (None, "h1"):
        parts.append(f"--estimator {options['estimator']}")
    return " ".join(parts) if parts else "default options"


def zones_text(zones: list[dict[str, Any]] | None) -> str:
    """'N frequency zones, LSCF orders a-b' (or 'one zone, LSCF order n') of a stored result:
    the zones fitted, a zone listed once per piece of its core counted once."""
    fitted = {(z["low_hz"], z["high_hz"], z["max_order"], z.get("basis")): z for z in zones or []}
    zones = list(fitted.values())
    if not zones:
        return ""
    low, high = min(z["max_order"] for z in zones), max(z["max_order"] for z in zones)
    if len(zones) == 1:
        return f"one frequency zone, LSCF order {low}"
    orders = f"LSCF order {low} in each" if low == high else f"LSCF orders {low}-{high}"
    return f"{len(zones)} frequency zones, {orders}"


def swapped_columns(run) -> tuple[list[int], str] | None:
    """(the 0-based indices of the hits whose response looks like the hammer pulse and
    force like a decaying response, analysis/hit_checks.py channels_swapped; one line
    saying so, with the --columns that reads the file the other way round for a CSV file)
    or None when no hit looks swapped. The same for all hits as a rule: one line for the
    file, not one per hit."""
    from analysis.hit_checks import SWAPPED

    hits = run.hits
    if hits is None:
        return None
    bad = [i for i, checks in enumerate(hits.checks) if (checks.get(SWAPPED) or {}).get("passed") is False]
    if not bad:
        return None
    n = int(hits.n_hits)
    which = (
        "every hit" if len(bad) == n else f"hit{'s' * (len(bad) > 1)} {', '.join(str(i + 1) for i in bad)}"
    )
    first = hits.checks[bad[0]][SWAPPED].get("detail", "")
    text = f"the force and response columns look swapped in {which} (hit {bad[0] + 1}: {first})"
    imported = (run.provenance or {}).get("imported_from")
    columns = imported.get("columns") if isinstance(imported, dict) else None
    from_csv = isinstance(imported, dict) and imported.get("format") == "csv" and not imported.get("zoom")
    if from_csv and isinstance(columns, list) and len(columns) == 3:
        # A file with no time column (its times made from --sample-rate) names two.
        named = (columns[2], columns[1]) if columns[0] is None else (columns[0], columns[2], columns[1])
        if all(isinstance(c, str) for c in named):
            given = ",".join(named)
            shown = given if all(_PLAIN_COLUMN.fullmatch(c) for c in named) else f"'{given}'"
            rate = f" --sample-rate {float(hits.sample_rate_hz):g}" if columns[0] is None else ""
            return (
                bad,
                f"{text}; if so, import the file again with --columns {shown}{rate}{_units_kept(imported)}",
            )
    if isinstance(imported, dict) and imported.get("format") == "lvm" and isinstance(columns, list):
        from daq.formats.csv_text import header_name_unit

        names = [header_name_unit(str(c))[0] for c in columns[1:3]]
        given = ",".join(reversed(names))
        shown = given if all(_PLAIN_COLUMN.fullmatch(c) for c in names) else f"'{given}'"
        return bad, f"{text}; if so, import the file again with --columns {shown} (force, response channels)"
    return bad, f"{text}; if so, swap the force and response records of the file and import it again"


def _hz(value: float) -> str:
    """A frequency in Hz for a sentence: 4266, 19.9."""
    return f"{value:.0f}" if value >= 100 else f"{value:.3g}"


def skewed_channels(run) -> tuple[list[int], str] | None:
    """(the 0-based indices of the hits whose response moves before the hammer strikes or
    long after it, analysis/hit_checks.py response_timing; one line saying what that does
    to the FRF and what to do) when every accepted hit does, else None. One line for the
    file: a skew between the channels is the recorder's, not a hit's."""
    from analysis.hit_checks import RESPONSE_TIMING, response_timing

    hits = run.hits
    if hits is None:
        return None
    timing = [checks.get(RESPONSE_TIMING) for checks in hits.checks]
    if run.kind == "imported":
        # Runs imported before the check existed carry no verdict: judged here from their
        # records (an analyzer's channels are sampled together; its captures need none).
        timing = [
            t
            if t is not None
            else response_timing(hits.force_n[i], hits.response_m_s2[i], hits.sample_rate_hz).as_dict()
            for i, t in enumerate(timing)
        ]
    # The recorder's skew is every hit's: only where every hit in the average fails is it
    # said once for the file; a hit of its own (cut from another trigger) is a failed check
    # like any other, with the line that leaves it out.
    kept = [i for i in range(int(hits.n_hits)) if hits.accepted[i]]
    bad = [i for i in kept if (timing[i] or {}).get("passed") is False]
    if not bad or len(bad) < len(kept):
        return None
    n = int(hits.n_hits)
    which = "every hit" if len(bad) == n else "every hit in the average"
    first = timing[bad[0]]
    skew_s = first.get("value")
    turn = (
        f", and the FRF's phase turns an extra full turn every {_hz(1 / abs(skew_s))} Hz"
        if isinstance(skew_s, (int, float)) and skew_s
        else ""
    )
    return bad, (
        f"the response is not timed with the force in {which} (hit {bad[0] + 1}: {first.get('detail', '')}): "
        f"the channels are skewed, by a delay between them or records cut from different triggers{turn}; "
        "align the response with the force and import the file again"
    )


def _units_kept(imported: dict) -> str:
    """The --force-unit and --response-unit that keep a swapped file's units with their
    quantities (" --force-unit N --response-unit g"), or "" when both were the defaults.
    A header's units belong to its labels, which the swap leaves where they were: read the
    other way round, 'Accel (g)' is refused as a force (a new user went round in a circle)."""
    from_ = imported.get("units_from") or {}
    if not any(from_.get(q) in ("header", "option") for q in ("force", "response")):
        return ""
    force, response = imported.get("force_unit"), imported.get("response_unit")
    if not (isinstance(force, str) and isinstance(response, str)):
        return ""
    return f" --force-unit {_shell_word(force)} --response-unit {_shell_word(response)}"


def _shell_word(unit: str) -> str:
    """A unit as one shell word: quoted where it holds a space, brackets or the like."""
    return unit if _PLAIN_COLUMN.fullmatch(unit.replace("/", "").replace("^", "")) else f"'{unit}'"


def _number(value: Any, unit: str) -> str:
    if value is None:
        return "auto"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return "?"
    return f"{value:.4g} {unit}"


def auto_range_text(record: Any, trigger_source: Any = "CH1") -> str | None:
    """One line of what practice hits chose for a run (its ``provenance["auto_range"]``,
    daq/workflows/auto_range.py AutoRange.record), for `daq runs show` and the report:
    "2 practice hits: hammer range 0.01995 V, accelerometer range 0.7943 V, trigger 0.473 N;
    the setup's own values were hammer range 0.02 V, ...". None when the run records none
    (not a dict: a foreign file's)."""
    if not isinstance(record, dict):
        return None
    unit = "m/s^2" if trigger_source == "CH2" else "N"

    def values(d: dict[str, Any]) -> str:
        return (
            f"hammer range {_number(d.get('hammer_range_v'), 'V')}, accelerometer range "
            f"{_number(d.get('accelerometer_range_v'), 'V')}, "
            f"trigger {_number(d.get('trigger_level_eu'), unit)}"
        )

    hits = record.get("practice_hits")
    text = f"{hits} practice hit{'' if hits == 1 else 's'}: {values(record)}"
    own = record.get("setup")
    if isinstance(own, dict):
        text += f"; the setup's own values were {values(own)}"
    return text


def run_dict(run, path: Path) -> dict[str, Any]:
    """The JSON of a whole ``run`` (daq.store.Run) read from ``path``: its metadata, every
    hit's verdict, and the shape of its FRFs and spectra (not the arrays). Each hit has
    its 0-based ``index`` (``hit_index_base`` says so) and its ``number`` from 1, as people
    read it; ``accepted_against_checks`` with ``failed_checks`` marks a hit accepted
    although a check failed."""
    hits = run.hits
    hits_data = None
    against = set(accepted_against_checks(run))
    n_hits = n_accepted = 0
    if hits is not None:
        n_hits, n_accepted = int(hits.n_hits), int(hits.accepted.sum())
        hits_data = {
            "n_hits": n_hits,
            "n_accepted": n_accepted,
            "n_rejected": n_hits - n_accepted,
            "n_samples": int(hits.n_samples),
            "sample_rate_hz": float(hits.sample_rate_hz),
            "start_s": float(hits.start_s),
            "center_hz": float(hits.center_hz),
            "zoom": bool(hits.is_zoom),
            "n_accepted_against_checks": len(against),
            "hits": [
                {
                    "index": i,
                    "number": i + 1,
                    "accepted": bool(hits.accepted[i]),
                    "accepted_against_checks": i in against,
                    "failed_checks": failed_check_names(hits.checks[i]),
                    "reject_reason": str(hits.reject_reason[i]),
                    "peak_force_n": float(hits.peak_force_n[i]),
                    "overload_force": bool(hits.overload[i, 0]),
                    "overload_response": bool(hits.overload[i, 1]),
                    "timestamp_utc": str(hits.timestamp_utc[i]),
                    "time_recorded": run.kind != "imported",
                }
                for i in range(n_hits)
            ],
        }
    return {
        "run_id": run.run_id,
        "file": str(path),
        "size_bytes": path.stat().st_size,
        "kind": run.kind,
        "complete": bool(run.complete),
        "start_time": run.start_time,
        "end_time": run.end_time,
        "operator": run.operator,
        "note": run.note,
        "software": run.software,
        "provenance": run.provenance,
        "instrument": None if run.instrument is None else dict(vars(run.instrument)),
        "sample": None if run.sample is None else dict(vars(run.sample)),
        "points": {**run.resolved_points().to_dicts(), "recorded": run.points is not None},
        "n_hits": n_hits,
        "n_accepted": n_accepted,
        "hit_index_base": HIT_INDEX_BASE,
        "hits": hits_data,
        "analyzer": frf_dict(run.analyzer),
        "measured_frf": frf_dict(run.measured_frfs),
        "spectra": spectra_dict(run.spectra),
    }


def frf_dict(frf) -> dict[str, Any] | None:
    if frf is None:
        return None
    return {
        "n_frf": int(frf.n_frf),
        "n_lines": int(frf.n_lines),
        "f_min_hz": float(frf.frequency_hz[0]),
        "f_max_hz": float(frf.frequency_hz[-1]),
        "coherence": frf.coherence is not None,
        "labels": list(frf.labels),
        "form": frf.form,
    }


def spectra_dict(spectra) -> dict[str, Any] | None:
    if spectra is None:
        return None
    lines = spectra.frequency_hz
    return {
        "n_traces": spectra.n_traces, "n_lines": spectra.n_lines,
        "f_min_hz": float(lines[0]), "f_max_hz": float(lines[-1]),
        "complex": bool(spectra.values.dtype.kind == "c"),
        "kinds": list(spectra.kinds), "units": list(spectra.units), "labels": list(spectra.labels),
    }  # fmt: skip


def pretrigger_text(summary: dict[str, Any]) -> str:
    """The line saying an analysis cut the hits at their impacts (analysis.pretrigger),
    from an analysis summary; "" when it did not."""
    cut = summary.get("pretrigger_cut_s") or 0.0
    if cut <= 0:
        return ""
    low, high = summary.get("pretrigger_range_s") or (cut, cut)
    spread = f" ({low:.4g}-{high:.4g} s over the hits)" if high > low else ""
    kept = summary.get("record_after_cut_s") or 0.0
    records = f", records of {kept:.4g} s from each impact" if kept > 0 else ""
    return (
        f"hits cut at their impacts: {cut:.4g} s of pre-trigger left out{spread}{records}, because "
        "the response had not died away by the record's end and the modes read from the whole "
        "records moved by more than 3 times their ± (docs/analysis.md)"
    )
