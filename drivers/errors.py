"""What can go wrong between us and the instrument, as exceptions the application can act on."""

from __future__ import annotations


class DriverError(Exception):
    """Base of every driver error; the message is one line for a technician."""


class ConnectionFailed(DriverError):
    """The resource cannot be opened (absent, unreachable, wrong name)."""


class ConnectionLost(DriverError):
    """An open link broke (the peer closed it, the adapter vanished)."""


class InstrumentTimeout(DriverError):
    """The instrument did not answer in time.

    ``instrument_answers``: True if it answered the driver's probe (ID?) after the
    timeout, so it lives and may have refused the exchange (the reason is then in
    its error queue, for ``errors()``); False if it answers nothing; None if not probed.
    """

    instrument_answers: bool | None = None


class Interrupted(DriverError):
    """A wait was given up on request (``HP35660A.interrupt`` was set), e.g. the
    service's Stop button while the analyzer waits for a hit."""


class ResourceBusy(DriverError):
    """Another process is talking to this instrument (its lock file is held)."""


class InstrumentError(DriverError):
    """The instrument reported an error (through its error query)."""

    def __init__(self, code: int, message: str) -> None:
        super().__init__(f"instrument error {code}: {message}")
        self.code = code
        self.instrument_message = message


def summarize(data: bytes, limit: int = 48) -> str:
    """Bytes for a log line or an error message: short, printable, length-stamped."""
    shown = data[:limit]
    text = repr(shown)
    return text if len(data) <= limit else f"{text}... ({len(data)} bytes)"


class ProtocolError(DriverError):
    """The instrument said something that is not what the protocol allows.

    Names the command that was sent and summarises the bytes received.
    """

    def __init__(self, command: str, reason: str, received: bytes = b"") -> None:
        detail = f"; received {summarize(received)}" if received else ""
        super().__init__(f"{command}: {reason}{detail}")
        self.command = command
        self.reason = reason
        self.received = received


class UnknownInstrument(DriverError):
    """What answers is not an analyzer of the family the driver knows; the message
    names what it replied."""
