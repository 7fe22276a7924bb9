"""Units of imported columns and their conversion to SI (N for force, m/s^2 for response).

A unit is either a physical unit or a voltage with the sensor's sensitivity:

- force: ``N`` (also ``Newtons``, as LabVIEW labels it), ``kN``, ``mN``, ``lbf``, ``kgf``
- response: ``m/s^2`` (also ``m/s2``, ``m/s/s``), ``mm/s^2`` (also ``mm/s2``, ``mm/s/s``),
  ``cm/s^2``, ``in/s^2``, ``ft/s^2``, ``g`` (9.80665 m/s^2; also ``G``, ``g's``, ``G's``, as
  accelerometer software prints it), ``mg``
- (PHYSICAL_UNITS, which the FRF units of text tables and UFF files share, adds velocity
  and displacement)
- voltage: ``mV@10.2mV/g`` means "the column is in mV; the sensor gives 10.2 mV per g";
  ``V@2.25mV/N`` means "the column is in V; the sensor gives 2.25 mV per N".
  The column may be in ``V`` or ``mV``, the sensitivity in ``V/<unit>`` or ``mV/<unit>``
  with any physical unit of the same quantity.
"""

from __future__ import annotations

import math
import re

import numpy as np

from daq.formats.errors import FormatError

STANDARD_GRAVITY_M_S2 = 9.80665  # exact by definition (CGPM 1901)
POUND_FORCE_N = 0.45359237 * STANDARD_GRAVITY_M_S2  # exact: international pound x standard gravity
INCH_M = 0.0254  # exact: international inch

QUANTITIES = ("force", "response")

_FOOT_M = 0.3048  # exact: international foot

#: Physical units by quantity and their SI factor (value_in_SI = value_in_unit * factor),
#: as files, loggers and modal software label them. The one table every reader uses: CSV
#: and LabVIEW columns (force and acceleration), FRF units of text tables and UFF files.
PHYSICAL_UNITS: dict[str, dict[str, float]] = {
    "force": {"N": 1.0, "Newton": 1.0, "Newtons": 1.0, "kN": 1e3, "mN": 1e-3, "lbf": POUND_FORCE_N,
              "kgf": STANDARD_GRAVITY_M_S2, "kp": STANDARD_GRAVITY_M_S2},
    "acceleration": {"m/s^2": 1.0, "m/s2": 1.0, "m/s/s": 1.0, "mm/s^2": 1e-3, "mm/s2": 1e-3,
                     "mm/s/s": 1e-3, "cm/s^2": 1e-2, "g": STANDARD_GRAVITY_M_S2,
                     "G": STANDARD_GRAVITY_M_S2, "g's": STANDARD_GRAVITY_M_S2,
                     "G's": STANDARD_GRAVITY_M_S2, "mg": 1e-3 * STANDARD_GRAVITY_M_S2,
                     "ft/s^2": _FOOT_M, "ft/s2": _FOOT_M, "in/s^2": INCH_M, "in/s2": INCH_M},
    "velocity": {"m/s": 1.0, "mm/s": 1e-3, "cm/s": 1e-2, "um/s": 1e-6, "in/s": INCH_M,
                 "ft/s": _FOOT_M},
    "displacement": {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "um": 1e-6, "µm": 1e-6, "nm": 1e-9,
                     "in": INCH_M, "mil": 1e-3 * INCH_M, "mils": 1e-3 * INCH_M, "ft": _FOOT_M},
}  # fmt: skip
#: The labels messages list for each quantity (PHYSICAL_UNITS also takes other spellings).
SHOWN_UNITS = {"force": "N, kN, lbf, kgf", "acceleration": "m/s^2, mm/s^2, g, mg, ft/s^2, in/s^2",
               "velocity": "m/s, mm/s, in/s, ft/s", "displacement": "m, mm, um, in, mil, ft"}  # fmt: skip
# A time record's columns: a force and a response (an acceleration).
_PHYSICAL = {"force": PHYSICAL_UNITS["force"], "response": PHYSICAL_UNITS["acceleration"]}
_SHOWN = {"force": SHOWN_UNITS["force"], "response": SHOWN_UNITS["acceleration"]}
# Other spellings of response units, matched whole and case-sensitively: "G" is g only as
# an acceleration unit (no force or prefix reading: "GN" stays unknown, "G" for a force
# is refused), and only "G" itself, never a lower-cased text ("mG", "Gm/s^2" stay unknown).
_RESPONSE_SPELLINGS = {"G": "g", "g's": "g", "G's": "g", "m/s/s": "m/s^2", "mm/s/s": "mm/s^2"}
_VOLTS = {"V": 1.0, "mV": 1e-3}
# Units spelled out, as LabVIEW's DAQmx channels label them ("Newtons", "Volts").
_SPELLED_OUT = {"Newtons": "N", "Volts": "V"}
_NUMBER = re.compile(r"[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?|[-+]?(?:nan|inf|infinity)", re.I)


def accepted_forms(quantity: str) -> str:
    """The unit spellings accepted for ``quantity``, for error messages."""
    physical = _SHOWN[quantity]
    example = "mV@2.25mV/N" if quantity == "force" else "mV@10.2mV/g"
    return f"{physical}, or a voltage with sensitivity such as {example}"


def parse_unit(unit: str, quantity: str) -> float:
    """The factor that turns values in ``unit`` into SI (N or m/s^2) for ``quantity``.

    quantity: "force" or "response". Raises FormatError (one line) for an unknown unit or a
    sensitivity that is not a positive finite number.
    """
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {QUANTITIES}, got {quantity!r}")
    if not isinstance(unit, str):
        raise FormatError(f"{quantity} unit must be text, got {type(unit).__name__}")
    text = unit.strip()
    text = _SPELLED_OUT.get(text, text)
    table = _PHYSICAL[quantity]
    if quantity == "response":
        text = _RESPONSE_SPELLINGS.get(text, text)
    if text in table:
        return table[text]
    if "@" in text:
        return _voltage_factor(text, quantity)
    if text in _VOLTS:
        example = accepted_forms(quantity).split("such as ")[-1]
        raise FormatError(
            f"{quantity} unit {_show(unit)} is a voltage: give the sensor's sensitivity after '@', "
            f"e.g. {text}{example[example.index('@') :]}"
        )
    if quantity == "response" and (why := not_acceleration(text)):
        raise FormatError(f"response unit {why}")
    raise FormatError(f"unknown {quantity} unit {_show(unit)}: use {accepted_forms(quantity)}")


def spelled_as(unit: str, quantity: str) -> str:
    """The usual spelling of another spelling of a ``quantity`` unit ("g" for "G" or "g's",
    "m/s^2" for "m/s/s"), or "" when ``unit`` is spelled as parse_unit lists it."""
    text = unit.strip()
    return _RESPONSE_SPELLINGS.get(text, "") if quantity == "response" else ""


def to_si(values: np.ndarray, unit: str, quantity: str) -> np.ndarray:
    """``values`` (any shape, float or complex) in ``unit`` converted to SI, a new array.

    A factor of exactly 1 leaves every value bit for bit as it was.
    """
    factor = parse_unit(unit, quantity)
    array = np.asarray(values)
    if array.dtype.kind not in "fc":
        array = array.astype(np.float64)
    return array * factor if factor != 1.0 else array.copy()


def _voltage_factor(text: str, quantity: str) -> float:
    column, _, sensitivity = text.partition("@")
    column = column.strip()
    if column not in _VOLTS:
        raise FormatError(
            f"{quantity} unit {_show(text)}: the column unit before '@' must be V or mV, "
            f"e.g. {accepted_forms(quantity).split('such as ')[-1]}"
        )
    number = _NUMBER.match(sensitivity.strip())
    if number is None:
        raise FormatError(
            f"{quantity} unit {_show(text)}: sensitivity must be a number with mV/<unit> or V/<unit> "
            f"after '@'; use {accepted_forms(quantity)}"
        )
    rest = sensitivity.strip()[number.end() :].strip()
    volts, slash, physical = rest.partition("/")
    volts, physical = volts.strip(), physical.strip()
    if quantity == "response":
        physical = _RESPONSE_SPELLINGS.get(physical, physical)
    if not slash or volts not in _VOLTS:
        raise FormatError(f"unknown {quantity} unit {_show(text)}: use {accepted_forms(quantity)}")
    if physical not in _PHYSICAL[quantity]:
        # A sensitivity per the other quantity's unit (a force in mV/g) is a likely slip.
        other = next((q for q in QUANTITIES if q != quantity and physical in _PHYSICAL[q]), None)
        kind = {"force": "a force", "response": "an acceleration"}
        said = f"{physical!r} is {kind[other]} unit" if other else f"{physical!r} is not one of them"
        raise FormatError(
            f"{quantity} unit {_show(text)}: the sensitivity must be per a {quantity} unit "
            f"({_SHOWN[quantity]}); {said}"
        )
    value = float(number.group(0))
    if not math.isfinite(value) or value <= 0:
        raise FormatError(f"{quantity} unit {_show(text)}: sensitivity must be positive and finite")
    # column volts -> sensor volts; divided by (volts per physical unit) -> physical unit -> SI.
    return _VOLTS[column] / (value * _VOLTS[volts]) * _PHYSICAL[quantity][physical]


def _show(text: str) -> str:
    # repr() escapes newlines; long input is cut so the message stays one readable line.
    return repr(text if len(text) <= 40 else text[:40] + "...")


# --- units read from files: time columns, header labels, FRF units ---------------------------

TIME_UNITS = {"s": 1.0, "sec": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "μs": 1e-6}
FREQUENCY_UNITS = {"Hz": 1.0, "hz": 1.0, "kHz": 1e3, "khz": 1e3}
# Numerator of an FRF unit: (form, SI factor).
#: The FRF form whose numerator is each quantity.
FORM_OF_QUANTITY = {"displacement": "receptance", "velocity": "mobility", "acceleration": "accelerance"}
_FRF_NUMERATORS: dict[str, tuple[str, float]] = {
    unit: (form, factor)
    for quantity, form in FORM_OF_QUANTITY.items()
    for unit, factor in PHYSICAL_UNITS[quantity].items()
}


def not_acceleration(unit: str) -> str:
    """Why a velocity or displacement unit ("m/s", "mm") cannot be a time record's response,
    and what to do instead, as a clause for a one-line message; "" for any other unit.

    Time records are read as acceleration over force (the analysis and its checks need
    acceleration); an FRF table may hold mobility or receptance, which --frf-form says.
    """
    found = _FRF_NUMERATORS.get(clean_label(unit))
    if found is None or found[0] == "accelerance":
        return ""
    what, times = ("a velocity", "once") if found[0] == "mobility" else ("a displacement", "twice")
    return (
        f"{_show(unit)} is {what}, and a time record's response must be an acceleration (daq analyses "
        f"acceleration over force): differentiate it {times} to m/s^2 and import that, or, if you have "
        f"the FRF as a table, import that with --format frf-text --frf-form {found[0]}"
    )


def clean_label(unit: str) -> str:
    """A unit as files print it, in the spelling parse_unit knows: "m/s²" -> "m/s^2",
    "m/s**2" -> "m/s^2", surrounding spaces, brackets and quotes removed."""
    text = unit.strip().strip("[]()\"'").strip()
    text = text.replace("²", "^2").replace("**", "^").replace(" ", "")
    return text


# "(m/s²)(N)": numerator and denominator each in parentheses, no slash between them
# (DataPhysics SignalCalc); also after clean_label has taken the outer parentheses off.
_PAREN_PAIR = re.compile(r"\(?\s*([^()]+?)\s*\)\s*\(\s*([^()]+?)\s*\)?")


def _frf_parts(unit: str) -> tuple[str, str] | None:
    """(numerator, force) of an FRF unit in parse_unit's spelling, or None."""
    text = unit.strip()
    pair = _PAREN_PAIR.fullmatch(text)
    if pair is not None:
        text = f"({pair.group(1)})/{pair.group(2)}"
    text = clean_label(text)
    top, slash, bottom = text.rpartition("/")
    numerator = top.strip().removeprefix("(").removesuffix(")").strip()
    if not slash or bottom not in _PHYSICAL["force"] or numerator not in _FRF_NUMERATORS:
        return None
    return numerator, bottom


def frf_unit(unit: str) -> tuple[str, float]:
    """(form, SI factor) of an FRF unit such as "(m/s^2)/N", "g/N", "m/N", "mm/s/N", "m/s/N",
    or SignalCalc's "(m/s²)(N)".

    form: "receptance", "mobility" or "accelerance". FormatError (one line) otherwise.
    """
    parts = _frf_parts(unit)
    if parts is None:
        raise FormatError(
            f"unknown FRF unit {_show(unit)}: use a displacement, velocity or acceleration over a force, "
            "e.g. m/N, (m/s)/N, (m/s^2)/N, g/N, mm/N"
        )
    form, factor = _FRF_NUMERATORS[parts[0]]
    return form, factor / _PHYSICAL["force"][parts[1]]


def looks_like_frf_unit(unit: str) -> bool:
    """A unit written as something over a force, known or not: SignalCalc's pair
    "(furlong/s²)(N)", or "x/lbf". Such a unit in a units row is meant as the FRFs' unit
    and must be read or refused, never passed over as a label such as "Ratio"."""
    text = unit.strip()
    if _PAREN_PAIR.fullmatch(text):
        return True
    bottom = clean_label(text).rpartition("/")[2].strip("() ")
    return "/" in text and bottom in _PHYSICAL["force"]


def frf_unit_text(unit: str) -> str:
    """An FRF unit as the messages print it: "(m/s^2)/N" for "(m/s²)(N)" or "m/s^2)/N" (what
    clean_label leaves of "[(m/s^2)/N]"), "m/N" for "m/N"; the text itself if unknown."""
    parts = _frf_parts(unit)
    if parts is None:
        return unit.strip()
    numerator, force = parts
    return f"({numerator})/{force}" if "/" in numerator else f"{numerator}/{force}"


def response_form(unit: str) -> tuple[str, float] | None:
    """(form, SI factor) of a response unit alone (m, mm/s, g...): the numerator of an FRF."""
    return _FRF_NUMERATORS.get(clean_label(unit))
