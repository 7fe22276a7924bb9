"""A transport that checks the exact bytes the driver sends and plays scripted replies,
in the spirit of PyMeasure's ``expected_protocol``: used as a context manager, it
also checks on exit that every scripted exchange happened and every reply was read,
so a test whose driver skips an exchange fails. ``expected`` puts the driver of any
dialect (HP 35660A, HP 3562A, SCPI) on it; ``link_lost`` on a link that is gone."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from drivers.base import SignalAnalyzer
from drivers.dialects import HP3562A, HP35660A, SCPI, Dialect
from drivers.errors import ConnectionLost, InstrumentTimeout
from drivers.hp_mnemonic import HPMnemonicAnalyzer
from drivers.scpi_analyzer import ScpiAnalyzer
from drivers.transport import Transport

#: The driver class of each dialect the protocol tests script.
DRIVERS: dict[Dialect, type[SignalAnalyzer]] = {
    HP35660A: HPMnemonicAnalyzer,
    HP3562A: HPMnemonicAnalyzer,
    SCPI: ScpiAnalyzer,
}


class ExpectedProtocol(Transport):
    """``steps``: (bytes the driver must write, bytes the instrument replies or None)."""

    def __init__(self, steps: list[tuple[bytes, bytes | None]]) -> None:
        super().__init__("EXPECTED", timeout_s=1.0, lock_file=False)
        self.steps = list(steps)
        self.position = 0
        self.pending = bytearray()
        self.open()

    def _open(self) -> None:
        pass

    def _close(self) -> None:
        pass

    def _write(self, message: bytes) -> None:
        assert self.position < len(self.steps), f"unexpected extra write {message!r}"
        expected, reply = self.steps[self.position]
        assert message == expected, f"step {self.position}: sent {message!r}, expected {expected!r}"
        assert not self.pending, f"unread reply {bytes(self.pending)!r} before {message!r}"
        self.position += 1
        if reply is not None:
            self.pending += reply

    def _read_line(self) -> bytes:
        if b"\n" not in self.pending:
            raise InstrumentTimeout("no scripted reply line")
        line, _, rest = bytes(self.pending).partition(b"\n")
        self.pending = bytearray(rest)
        return line.rstrip(b"\r")

    def _read_exact(self, count: int) -> bytes:
        if len(self.pending) < count:
            raise InstrumentTimeout("no scripted reply bytes")
        data = bytes(self.pending[:count])
        del self.pending[:count]
        return data

    def _clear(self) -> None:
        self.pending.clear()

    def __enter__(self) -> ExpectedProtocol:
        return self

    def __exit__(self, exc_type: object, *rest: object) -> None:
        self.close()
        if exc_type is None:  # an exception already says what went wrong
            self.done()

    def done(self) -> None:
        assert self.position == len(self.steps), f"only {self.position} of {len(self.steps)} steps happened"
        assert not self.pending, f"unread reply {bytes(self.pending)!r}"


@contextmanager
def expected(
    steps: list[tuple[bytes, bytes | None]], dialect: Dialect = HP35660A, **kwargs: object
) -> Iterator[SignalAnalyzer]:
    """The ``dialect``'s driver on a scripted transport; on leaving, every step must have
    happened."""
    with ExpectedProtocol(steps) as transport:
        yield DRIVERS[dialect](transport, dialect, **kwargs)  # type: ignore[arg-type]


class _LinkLost(ExpectedProtocol):
    def _write(self, message: bytes) -> None:
        raise ConnectionLost("link lost")


def link_lost(dialect: Dialect = HP35660A, **kwargs: object) -> SignalAnalyzer:
    """The ``dialect``'s driver on a link where every write is lost."""
    return DRIVERS[dialect](_LinkLost([]), dialect, **kwargs)  # type: ignore[arg-type]
