"""The HP mnemonic dialects: the 35660A (drivers/commands.py, tagged) and the 3562A.

Both speak the mnemonics public code shows driving an HP 3562A (``ID?``, ``FRS``,
``STRT``, ``DDAN`` ...) and the project's choices where no source was found (tag
``proj``). They differ in what the driver checks, not in what it sends: the
identification (``HP35660A``, ``HP3562A``) and the record geometry (400 lines and
1024-sample records, 800 lines and 2048-sample records: drivers/dialects.py).
"""

from __future__ import annotations

import math

from drivers.analyzer import SignalAnalyzer, Status
from drivers.commands import COMMANDS, command, parse_reply, replies
from drivers.dialects import HP35660A, Dialect, Geometry
from drivers.dumps import DumpsMixin
from drivers.errors import ProtocolError
from drivers.settings import ChannelSetup, ImpactSettings, Window
from drivers.transport import Transport


class HPMnemonicAnalyzer(DumpsMixin, SignalAnalyzer):
    """An HP 35660A or 3562A/3563A, in its mnemonic dialect (``dialect``: the 35660A's
    unless told)."""

    def __init__(self, transport: Transport, dialect: Dialect = HP35660A, **kwargs: object) -> None:
        if dialect.family != "hp":
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

    def errors(self) -> list[tuple[int, str]]:
        """Drain the instrument's error queue, oldest first."""
        found = []
        for _ in range(64):
            reply = self.query("ERR?")
            code_text, _, message = reply.partition(",")
            if not code_text.strip().lstrip("+-").isdigit():
                raise ProtocolError("ERR?", 'expected code,"message"', reply.encode())
            code = int(code_text)
            if code == 0:
                return found
            found.append((code, message.strip().strip('"')))
        raise ProtocolError("ERR?", "the error queue does not empty")

    # ------------------------------------------------------------ settings
    def configure(self, settings: ImpactSettings) -> ImpactSettings:
        """Apply ``settings`` and return them as the analyzer holds them (span and
        ranges rounded up to what it offers). The model fixes the lines: settings
        naming others are refused (ValueError)."""
        geometry = self.dialect.geometry(settings.lines)
        settings = settings.with_lines(geometry.lines)
        self.send("CLER")  # errors left by earlier commands must not be blamed on these settings
        messages = settings.commands()
        for message in messages[:3]:  # up to the span
            self.send(message.decode())
        self.check_errors()
        # The analyzer rounds the span up; the baseband center follows the span it chose,
        # and the pre-trigger must fit the record of that span.
        actual_span = float(self.read("FRS"))
        settings = self.fit_to_span(settings, geometry, actual_span)
        for message in settings.commands(actual_span_hz=actual_span)[3:]:
            self.send(message.decode())
        self.check_errors()
        actual = self.read_settings()
        self._record_length_s = actual.record_length_s
        return actual

    def read_settings(self) -> ImpactSettings:
        """The impact-test settings the analyzer holds now."""

        # The order of the queries is the golden transcripts' (tests/drivers/test_protocol.py).
        span = float(self.read("FRS"))
        center = float(self.read("CF"))
        channels = []
        for ch in (1, 2):
            channels.append(
                ChannelSetup(
                    window=Window(self.read(f"WIN{ch}")),
                    sensitivity_v_per_eu=float(self.read(f"SNS{ch}")),
                    range_v=None if self.read(f"AU{ch}?") else float(self.read(f"RNG{ch}")),
                    force_width_s=float(self.read(f"FWD{ch}")),
                    exp_decay_s=float(self.read(f"EXD{ch}")),
                    ac_coupled=bool(self.read(f"C{ch}AC")),
                )
            )
        source = str(self.read("TSRC"))
        level_v = float(self.read("TLVL"))
        trigger_channel = channels[1] if source == "CH2" else channels[0]
        averaging = self.read("AVMD?")
        settings = ImpactSettings(
            span_hz=span,
            center_hz=None if math.isclose(center, span / 2, rel_tol=1e-9) else center,
            hammer=channels[0],
            accelerometer=channels[1],
            trigger_source=source,
            trigger_level_eu=level_v / trigger_channel.sensitivity_v_per_eu,
            trigger_slope=str(self.read("TSLP")),
            pre_trigger_s=max(0.0, -float(self.read("TDLY"))),
            averages=1 if averaging == "AVOF" else int(self.read("NAVG")),
            preview=bool(self.read("PRVW")),
            lines=self.geometry.lines,
        )
        self._record_length_s = settings.record_length_s
        return settings

    # ------------------------------------------------------------ measuring
    def _record_length(self) -> float:
        if self._record_length_s is None:
            self._record_length_s = self.geometry.record_length_s(float(self.read("FRS")))
        return self._record_length_s

    def start(self) -> None:
        """Clear the average and arm the trigger (STRT); InstrumentError if it refuses."""
        self._record_length()
        self.send("STRT")
        if self.status().error:
            self.check_errors()

    def accept(self) -> None:
        """Preview: put the pending hit into the average."""
        self._exchange("ACPT", lambda: self.transport.write(b"ACPT"), repeatable=False)
        self._raise_if_error()

    def reject(self) -> None:
        """Preview: throw the pending hit away and re-arm."""
        self._exchange("RJCT", lambda: self.transport.write(b"RJCT"), repeatable=False)
        self._raise_if_error()

    def _raise_if_error(self) -> None:
        if self.status().error:
            self.check_errors()

    def averages_done(self) -> int:
        return int(self.read("AVG?"))


def _repeatable(text: str) -> bool:
    """False if any command in the message would change the outcome when sent twice."""
    for part in text.replace(";", " ; ").split(";"):
        head = part.strip().split(" ")[0].upper()
        if head in COMMANDS and not COMMANDS[head].idempotent:
            return False
    return True
