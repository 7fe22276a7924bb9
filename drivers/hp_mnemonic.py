"""The HP mnemonic dialects: the 35660A (drivers/commands.py, tagged) and the 3562A.

Both speak the mnemonics public code shows driving an HP 3562A (``ID?``, ``FRS``,
``STRT``, ``DDAN`` ...) and the project's choices where no source was found (tag
``proj``). They differ in what the driver checks, not in what it sends: the
identification (``HP35660A``, ``HP3562A``) and the record geometry (400 lines and
1024-sample records, 800 lines and 2048-sample records: drivers/dialects.py).
"""

from __future__ import annotations

import math

from drivers.base import SignalAnalyzer
from drivers.commands import COMMANDS, SETTINGS, command, parse_reply, replies
from drivers.dialects import HP35660A, Dialect, Geometry
from drivers.dumps import DumpsMixin
from drivers.errors import ProtocolError
from drivers.messages import Status
from drivers.transport import Transport


class HPMnemonicAnalyzer(DumpsMixin, SignalAnalyzer):
    """An HP 35660A or 3562A/3563A, in its mnemonic dialect (``dialect``: the 35660A's
    unless told)."""

    family = "hp"
    settings_table = SETTINGS
    clear_errors_command = "CLER"
    error_query = "ERR?"

    def __init__(self, transport: Transport, dialect: Dialect = HP35660A, **kwargs: object) -> None:
        if dialect.family != self.family:
            raise ValueError(f"the {dialect.name} dialect is not an HP mnemonic dialect")
        super().__init__(transport, dialect, **kwargs)  # type: ignore[arg-type]

    @property
    def geometry(self) -> Geometry:
        """Lines and record length; fixed by the model in the mnemonic dialects."""
        return self.dialect.geometry()

    def replies(self, text: str) -> list[str]:
        return replies(text)

    def repeatable(self, text: str) -> bool:
        return _repeatable(text)

    def read(self, mnemonic: str) -> float | int | bool | str:
        """A setting read back (``read("FRS")`` asks FRS?) or a one-line query
        (``read("AVMD?")``), typed by the command table: float (SI), int, bool or str."""
        entry = COMMANDS.get(mnemonic)
        if entry is None:
            raise KeyError(f"{mnemonic} is not in the driver's command table")
        query = entry.readback or mnemonic
        reply = self.query(query)
        try:
            return parse_reply(query, reply)
        except ValueError as exc:
            raise ProtocolError(query, str(exc), reply.encode()) from None

    def set(self, mnemonic: str, value: object = None) -> None:
        """Send one table entry with its argument, spelled by the table:
        ``set("FRS", 200.0)`` sends ``FRS 200 HZ``."""
        self.send(command(mnemonic, value).decode("ascii"))

    # ------------------------------------------------------------ instrument
    def reset(self) -> None:
        self.send("RST")
        self._record_length_s = None

    def status(self) -> Status:
        bits = self.read("STA?")
        if not 0 <= bits <= 255:  # type: ignore[operator]
            raise ProtocolError("STA?", "expected a status byte", str(bits).encode())
        return Status(int(bits))

    # ------------------------------------------------------------ settings
    def _put(self, command: str, value: object, ch: int | None) -> None:
        self.set(command.format(ch=ch), value)

    def _ask(self, query: str, ch: int | None) -> object:
        return self.read(query.format(ch=ch))

    def _keep_read(self, fields: dict, channels: dict[int, dict]) -> int:
        return self.geometry.lines

    @staticmethod
    def baseband(span: float, center: float) -> bool:
        """A center at span/2 is a baseband measurement."""
        return math.isclose(center, span / 2, rel_tol=1e-9)

    # ------------------------------------------------------------ measuring
    def _record_length(self) -> float:
        if self._record_length_s is None:
            self._record_length_s = self.geometry.record_length_s(float(self.read("FRS")))
        return self._record_length_s

    def start(self) -> None:
        """Clear the average and arm the trigger (STRT); InstrumentError if it refuses."""
        self._record_length()
        self.send("STRT")
        self.raise_if_error()

    def accept(self) -> None:
        """Preview: put the pending hit into the average."""
        self._exchange("ACPT", lambda: self.transport.write(b"ACPT"), repeatable=False)
        self.raise_if_error()

    def reject(self) -> None:
        """Preview: throw the pending hit away and re-arm."""
        self._exchange("RJCT", lambda: self.transport.write(b"RJCT"), repeatable=False)
        self.raise_if_error()

    def averages_done(self) -> int:
        return int(self.read("AVG?"))


def _repeatable(text: str) -> bool:
    """False if any command in the message would change the outcome when sent twice."""
    for part in text.replace(";", " ; ").split(";"):
        head = part.strip().split(" ")[0].upper()
        if head in COMMANDS and not COMMANDS[head].idempotent:
            return False
    return True
