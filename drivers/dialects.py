"""The HP dynamic signal analyzer family: which dialect each model speaks, and the
record geometry each one measures with (docs/dialects.md).

A dialect is data (this module, the command tables) plus a little code (the
protocol classes in drivers/hp_mnemonic.py and drivers/scpi_analyzer.py). Three
are known:

* ``35660A``: the mnemonic dialect of drivers/commands.py, written for the 35660A
  from its sibling the 3562A (nothing of it confirmed on a 35660A: tag ``proj``);
  400 lines, 1024-sample records.
* ``3562A``: the same mnemonics, as public code driving an HP 3562A/3563A shows
  them (tag ``3562A``): ``ID?`` replies ``HP3562A``; 800 lines (a trace holds 801
  points), 2048-sample records.
* ``SCPI``: the HP 35665A and 35670A (docs/instrument-scpi.md): ``*IDN?``, IEEE
  488.2 blocks, lines chosen with ``SENS:FREQ:RES``.

Every model samples at 2.56 x span at baseband, so a record of ``lines`` lines
holds 2.56 x lines real samples and lasts lines / span seconds; a zoom record holds
half as many complex samples at 1.28 x span, of the same length.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: Sample rate over span at baseband, the whole family (3562A and 35670A manuals as
#: quoted publicly; the 35660A by analogy).
SAMPLE_RATE_PER_SPAN = 2.56


@dataclass(frozen=True)
class Geometry:
    """The records of a measurement of ``lines`` lines.

    lines : lines the span is resolved into; a spectrum trace holds lines + 1 points.
    """

    lines: int

    def __post_init__(self) -> None:
        if not (isinstance(self.lines, int) and self.lines > 0 and (self.lines * 256) % 100 == 0):
            raise ValueError(f"lines must be a positive integer with 2.56 x lines whole, got {self.lines!r}")

    @property
    def spectrum_points(self) -> int:
        return self.lines + 1

    @property
    def record_samples(self) -> int:
        """Real samples of a baseband record (2.56 x lines)."""
        return self.lines * 256 // 100

    def time_points(self, zoom: bool) -> int:
        """Points of a time record: real at baseband, complex (half as many) in zoom."""
        return self.record_samples // 2 if zoom else self.record_samples

    def record_length_s(self, span_hz: float) -> float:
        """Length of one record, s: lines / span (Hz)."""
        return self.lines / span_hz

    def sample_rate_hz(self, span_hz: float, zoom: bool) -> float:
        """Hz: 2.56 x span at baseband, 1.28 x span in zoom."""
        return SAMPLE_RATE_PER_SPAN * span_hz / (2 if zoom else 1)


@dataclass(frozen=True)
class Dialect:
    """What the driver needs to know of one dialect before it talks to the instrument.

    name : ``35660A``, ``3562A`` or ``SCPI`` (what ``--dialect`` takes and a run records).
    family : ``hp`` (mnemonics, #A dumps) or ``scpi``.
    identity_query : the query that identifies the instrument (``ID?``, ``*IDN?``).
    line_choices : the resolutions it offers, lines.
    default_lines : the resolution asked for when the settings name none.
    max_span_hz : the widest span; the instrument offers max / 2^n and rounds up.
    source : where the facts come from (``3562A``, ``proj``, docs/instrument-scpi.md).
    """

    name: str
    family: str
    identity_query: str
    line_choices: tuple[int, ...]
    default_lines: int
    max_span_hz: float
    source: str

    def geometry(self, lines: int | None = None) -> Geometry:
        """The geometry at ``lines`` (None: the default); ValueError if not offered."""
        chosen = self.default_lines if lines is None else lines
        if chosen not in self.line_choices:
            offered = ", ".join(str(n) for n in self.line_choices)
            raise ValueError(f"the {self.name} dialect offers {offered} lines, not {lines!r}")
        return Geometry(chosen)

    def spans_hz(self, count: int = 24) -> tuple[float, ...]:
        return tuple(self.max_span_hz / 2**n for n in range(count))

    def round_span(self, span_hz: float) -> float:
        """The span the instrument makes of ``span_hz``: the next max / 2^n up."""
        if not span_hz > 0:
            raise ValueError("span must be > 0 Hz")
        n = max(0, math.floor(math.log2(self.max_span_hz / span_hz) + 1e-9))
        return self.max_span_hz / 2**n


HP35660A = Dialect("35660A", "hp", "ID?", (400,), 400, 102_400.0, "proj (mnemonics of the 3562A)")
HP3562A = Dialect("3562A", "hp", "ID?", (800,), 800, 100_000.0, "3562A (public code); spans proj")
SCPI = Dialect("SCPI", "scpi", "*IDN?", (100, 200, 400, 800, 1600), 400, 51_200.0, "docs/instrument-scpi.md")

DIALECTS: dict[str, Dialect] = {d.name: d for d in (HP35660A, HP3562A, SCPI)}

#: ``ID?`` replies of the HP-mnemonic models, and the dialect each speaks.
HP_IDENTITIES = {"HP35660A": HP35660A, "HP3562A": HP3562A, "HP3563A": HP3562A}
#: Models in a SCPI ``*IDN?`` reply (its second field) that speak the SCPI dialect, and
#: the resolutions each offers (docs/instrument-scpi.md, proj).
SCPI_MODEL_LINES = {"35665A": (100, 200, 400, 800), "35670A": (100, 200, 400, 800, 1600)}
SCPI_MODELS = tuple(SCPI_MODEL_LINES)


def dialect_named(name: str) -> Dialect:
    """The dialect ``name`` (case-insensitive; a model name such as 35670A or 3563A
    gives its dialect); ValueError naming the choices otherwise."""
    key = name.strip().upper()
    if key in (m.upper() for m in SCPI_MODELS):
        return SCPI
    if "HP" + key in HP_IDENTITIES:
        return HP_IDENTITIES["HP" + key]
    for dialect in DIALECTS.values():
        if dialect.name.upper() == key:
            return dialect
    raise ValueError(
        f"unknown dialect {name!r}: one of {', '.join(DIALECTS)} (or a model: 3563A, 35665A, 35670A)"
    )


def identity_mismatch(dialect: Dialect, reply: str) -> str | None:
    """None if ``reply`` (to the dialect's identity query) names an instrument that
    speaks ``dialect``, else why not, one phrase."""
    if dialect.family == "scpi":
        fields = [f.strip() for f in reply.split(",")]
        if len(fields) >= 2 and fields[1].upper() in SCPI_MODELS:
            return None
        return f"*IDN? replied {reply!r}, not a {' or '.join(SCPI_MODELS)}"
    found = HP_IDENTITIES.get(reply.strip().upper())
    if found is dialect:
        return None
    if found is not None:
        return f"ID? replied {reply!r}, an analyzer of the {found.name} dialect, not the {dialect.name}"
    return f"ID? replied {reply!r}, not an analyzer of the family ({', '.join(HP_IDENTITIES)})"


def model_of(dialect: Dialect, identification: str) -> str:
    """The model name a run records, from the dialect and the instrument's reply."""
    if dialect.family == "scpi":
        fields = [f.strip() for f in identification.split(",")]
        return f"HP {fields[1]}" if len(fields) > 1 and fields[1] else "HP 35670A"
    return (
        f"HP {identification.strip()[2:]}"
        if identification.strip().startswith("HP")
        else "HP " + dialect.name
    )
