"""What `daq export --format sdf` says in its COMMENT record beyond SDF's own fields.

SDF has no place for a hit's verdict, an FRF's or a spectrum's full label, a unit
longer than SDF's 10 characters or the exact float64 sample rate (the DATA_HDR keeps
1 / rate), so the export adds one file-scope COMMENT (revision 3) of plain ASCII lines,
and the import reads them back when the comment starts with the marker line:

    cantilever-daq run <run id>
    sample_rate_hz=25600.0 start_s=-0.01 center_hz=0.0
    exp_decay_s=0.5 pulse_s=0.01
    label 0: "H21 point 0"
    spectrum 0: "Pwr Spec"
    spectrum 0 unit: "V^2"
    hit 2 rejected: "double hit \\u2014 second peak 40 % of first"

Texts are JSON strings (so any character survives in ASCII). Comments of other
programs are kept in the run's provenance as they are, never interpreted.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field

from daq.formats.sdf.model import Comment

MARKER = "cantilever-daq run "
_KEY_VALUE = re.compile(r"^([a-z_]+)=(\S+)$")
_INDEXED = re.compile(r"^(label|hit|spectrum) (\d+)( rejected| unit)?: (\".*\")$")


@dataclass
class Notes:
    """Our comment's content. keys: "sample_rate_hz" etc. as text; labels: FRF index
    -> label; rejected: hit index -> reason; spectrum_labels, spectrum_units: spectrum
    index (the run's order) -> its label, its unit."""

    run_id: str = ""
    keys: dict[str, str] = field(default_factory=dict)
    labels: dict[int, str] = field(default_factory=dict)
    rejected: dict[int, str] = field(default_factory=dict)
    spectrum_labels: dict[int, str] = field(default_factory=dict)
    spectrum_units: dict[int, str] = field(default_factory=dict)


def encode_notes(notes: Notes) -> str:
    """The comment text of ``notes`` (lines end in CR LF, as SDF comments do)."""
    lines = [MARKER + notes.run_id]
    if notes.keys:
        lines.append(" ".join(f"{key}={value}" for key, value in notes.keys.items()))
    lines += [f"label {k}: {json.dumps(text)}" for k, text in sorted(notes.labels.items())]
    lines += [f"hit {k} rejected: {json.dumps(text)}" for k, text in sorted(notes.rejected.items())]
    lines += [f"spectrum {k}: {json.dumps(text)}" for k, text in sorted(notes.spectrum_labels.items())]
    lines += [f"spectrum {k} unit: {json.dumps(text)}" for k, text in sorted(notes.spectrum_units.items())]
    return "\r\n".join(lines) + "\r\n"


def decode_notes(comments: list[Comment]) -> Notes | None:
    """Our notes from the first comment that carries the marker, else None. Lines that do
    not parse are ignored (the comment is text a person may have edited)."""
    for comment in comments:
        lines = comment.text.splitlines()
        if not lines or not lines[0].startswith(MARKER):
            continue
        notes = Notes(run_id=lines[0][len(MARKER) :].strip())
        for line in lines[1:]:
            indexed = _INDEXED.match(line.strip())
            if indexed:
                kind, number, suffix, text = indexed.groups()
                try:
                    value = json.loads(text)
                except ValueError:
                    continue
                target = {
                    ("label", None): notes.labels,
                    ("hit", " rejected"): notes.rejected,
                    ("hit", None): notes.rejected,
                    ("spectrum", None): notes.spectrum_labels,
                    ("spectrum", " unit"): notes.spectrum_units,
                }.get((kind, suffix))
                if isinstance(value, str) and target is not None:
                    target[int(number)] = value
                continue
            for word in line.split():
                match = _KEY_VALUE.match(word)
                if match:
                    notes.keys[match.group(1)] = match.group(2)
        return notes
    return None
