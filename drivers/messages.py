"""What every part of the driver shares about messages: the bytes of a command, a reply
line as text, and the analyzer's status. Imports nothing of the driver but its errors,
so that the base driver, the dumps, the dialects and the detection can all use it."""

from __future__ import annotations

import enum

from drivers.errors import ProtocolError


class Status(enum.IntFlag):
    """The state of a measurement as every dialect reports it: the bits of the HP
    dialects' STA? (proj), to which the SCPI dialect maps its status registers. A
    status reads by name (``status.done``) and prints its set bits (``idle``: none)."""

    DONE = 1
    WAITING_FOR_TRIGGER = 2
    OVERLOAD_CH1 = 4
    OVERLOAD_CH2 = 8
    ERROR = 16
    HIT_PENDING = 32
    MEASURING = 64
    PAUSED = 128

    @property
    def bits(self) -> int:
        return int(self)

    def __getattr__(self, name: str) -> bool:
        # status.done, status.hit_pending ...: whether that bit is set.
        member = type(self).__members__.get(name.upper())
        if member is None or name != name.lower():
            raise AttributeError(name)
        return bool(self & member)

    def __str__(self) -> str:
        return ", ".join(m.name.lower() for m in type(self) if m in self) or "idle"  # type: ignore[union-attr]


#: The status bits by name (``Status`` spells them too): what a dialect maps its registers to.
STATUS_BITS = {m.name.lower(): m.value for m in Status}  # type: ignore[union-attr]


def ascii_message(text: str) -> bytes:
    """``text`` as the bytes of one message: ASCII, one line, not empty."""
    try:
        data = text.strip().encode("ascii")
    except UnicodeEncodeError:
        raise ValueError(f"commands are ASCII: {text!r}") from None
    if not data or b"\n" in data or b"\r" in data:
        raise ValueError("one command line, not empty")
    return data


def decode_line(raw: bytes, command_text: str) -> str:
    """A reply line as text; ProtocolError if it is not printable ASCII."""
    try:
        text = raw.decode("ascii")
    except UnicodeDecodeError:
        raise ProtocolError(command_text, "reply is not ASCII", raw) from None
    if any(ch < " " for ch in text):
        raise ProtocolError(command_text, "control characters in the reply", raw)
    return text
