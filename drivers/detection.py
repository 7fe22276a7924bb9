"""Which analyzer of the family answers (docs/dialects.md), and opening a driver on it.

Detection asks in the order that disturbs least: a device clear, then ``*IDN?``
with a short timeout (a SCPI 35665A/35670A answers it; an HP-mnemonic instrument
does not know it and stays silent), then a clear and ``ID?`` (``HP35660A``,
``HP3562A``, ``HP3563A``). The mnemonic instruments queue an error for the
``*IDN?`` they did not understand; it is cleared (``CLER``), so that it is not
blamed on the next command. ``dialect`` skips all of this and trusts the caller.

Which class drives a dialect is the caller's ``driver_for``: drivers/family.py's for
every dialect (``open_analyzer``), a dialect class's own for ``open`` on it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from drivers.dialects import HP_IDENTITIES, SCPI, SCPI_MODELS, Dialect, dialect_named
from drivers.errors import InstrumentTimeout, ProtocolError, UnknownInstrument
from drivers.messages import decode_line
from drivers.resources import open_transport
from drivers.transport import Transport

#: The class that drives a dialect, built as ``driver(transport, dialect, **kwargs)``.
DriverFor = Callable[[Dialect], Callable[..., Any]]

#: How long each identity query of the detection may take, s: the instrument answers a
#: query it knows within milliseconds; the one it does not know costs this much.
DETECT_TIMEOUT_S = 0.5


@dataclass(frozen=True)
class Detection:
    """What detection found: the dialect, the instrument's reply and why (one line)."""

    dialect: Dialect
    identification: str
    reason: str


def _ask(transport: Transport, query: str) -> str | None:
    """The one-line reply to ``query``, or None if none came in time."""
    transport.write(query.encode("ascii"))
    try:
        raw = transport.read_line()
    except InstrumentTimeout:
        return None
    return decode_line(raw, query).strip()


def detect(transport: Transport, timeout_s: float = DETECT_TIMEOUT_S) -> Detection:
    """Find out which dialect the instrument behind ``transport`` speaks.

    UnknownInstrument, naming what was received, for an instrument the family does
    not hold; InstrumentTimeout if neither query gets a reply.
    """
    saved = transport.timeout_s
    transport.timeout_s = min(timeout_s, saved)
    try:
        with transport.lock:
            transport.clear()
            idn = _ask(transport, "*IDN?")
            if idn is not None:
                fields = [f.strip() for f in idn.split(",")]
                if len(fields) >= 2 and fields[1].upper() in SCPI_MODELS:
                    return Detection(SCPI, idn, f"*IDN? replied {idn!r}: a {fields[1].upper()} speaks SCPI")
                raise UnknownInstrument(
                    f"{transport.resource}: *IDN? replied {idn!r}, not an analyzer this driver knows "
                    f"({', '.join(SCPI_MODELS)}; or HP35660A, HP3562A to ID?); give --dialect to force one"
                )
            transport.clear()
            reply = _ask(transport, "ID?")
            if reply is None:
                raise InstrumentTimeout(
                    f"{transport.resource}: no reply to *IDN? nor to ID? within {transport.timeout_s:g} s "
                    "each: is the analyzer on, at this address?"
                )
            dialect = HP_IDENTITIES.get(reply.upper())
            if dialect is None:
                raise UnknownInstrument(
                    f"{transport.resource}: ID? replied {reply!r} (and *IDN? nothing), not an analyzer "
                    f"this driver knows ({', '.join(HP_IDENTITIES)}); give --dialect to force one"
                )
            transport.write(b"CLER")  # the error our *IDN? left in its queue
            reason = f"no reply to *IDN? within {transport.timeout_s:g} s; ID? replied {reply!r}"
            return Detection(dialect, reply, reason)
    except ProtocolError as exc:
        raise UnknownInstrument(f"{transport.resource}: {exc}; give --dialect to force one") from None
    finally:
        transport.timeout_s = saved


def connect(
    transport: Transport, driver_for: DriverFor, dialect: Dialect | str | None = None, **kwargs: object
) -> Any:
    """The driver for the instrument behind the open ``transport``: of the dialect
    detection finds, or of ``dialect`` (a Dialect or its name) without asking."""
    forced = dialect is not None
    if dialect is None:
        found = detect(transport)
        chosen, reason = found.dialect, found.reason
    else:
        chosen = dialect if isinstance(dialect, Dialect) else dialect_named(dialect)
        reason = f"the {chosen.name} dialect was forced (--dialect or $DAQ_DIALECT); no detection"
    return driver_for(chosen)(transport, chosen, detection=reason, forced=forced, **kwargs)


def open_driver(
    resource: str,
    driver_for: DriverFor,
    timeout_s: float = 5.0,
    lock_file: bool = True,
    dialect: Dialect | str | None = None,
    **kwargs: object,
) -> Any:
    """Open ``resource`` (drivers/resources.py) and ``connect`` to what answers."""
    if isinstance(dialect, str):
        dialect = dialect_named(dialect)  # a bad name must fail before the link is opened
    transport = open_transport(resource, timeout_s, lock_file)
    try:
        return connect(transport, driver_for, dialect, **kwargs)
    except BaseException:
        transport.close()  # a bad argument or a failed detection must not leave the link held
        raise
