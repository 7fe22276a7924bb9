"""A pseudo-terminal that behaves like a Prologix GPIB-USB controller with the analyzer
at its GPIB address, for the serial path (pyserial, pyvisa-py ASRL or PRLGX).

What the Prologix manual (v6.1, docs/instrument.md) specifies is honoured:
``++`` commands end with CR or LF; other lines go to the instrument at ``++addr``,
with ESC-escaped CR, LF, ESC and ``+`` restored and the ``++eos`` characters
appended, EOI on the last byte when ``++eoi 1``. With ``++auto 1`` the
instrument is read after every line; with ``++auto 0`` only on ``++read``.
Reads stop at EOI (``++read eoi``), at a character (``++read N``) or at the
``++read_tmo_ms`` timeout; ``++eot_enable`` appends ``++eot_char`` at EOI.

The analyzer asserts EOI on the last byte of each reply, so a reply is the unit
of a read. ``drop`` over a serial line cannot close anything: it behaves as a
truncated transfer.
"""

from __future__ import annotations

import collections
import contextlib
import logging
import os
import select
import threading
import time
import tty
from collections.abc import Sequence

from sims.faults import parse_fault
from sims.instrument import Analyzer
from sims.session import Chunk, Session

log = logging.getLogger(__name__)

VERSION = "Prologix GPIB-USB Controller version 6.101"
ESC = 0x1B
POLL_S = 0.05
#: The longest close() waits for the adapter's thread, s.
CLOSE_WAIT_S = 2.0
#: A host that stops reading for this long has gone; its output is dropped.
WRITE_GIVE_UP_S = 10.0


class PrologixPty:
    """Serve ``analyzer`` behind an emulated Prologix controller on a new pty."""

    def __init__(self, analyzer: Analyzer, gpib_address: int = 11, faults: Sequence[str] = ()) -> None:
        if not 0 <= gpib_address <= 30:
            raise ValueError("GPIB addresses are 0..30")
        for spec in faults:
            parse_fault(spec)
        self.analyzer = analyzer
        self.gpib_address = gpib_address
        self.faults = tuple(faults)
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        # Never block on the master: a host that stops reading must not be able to
        # wedge this thread (and with it close() and Ctrl-C).
        os.set_blocking(self._master, False)
        self.port = os.ttyname(self._slave)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name=f"sim-prologix-{self.port}", daemon=True)
        self._reset_controller()
        self.session = Session(analyzer, self.faults)

    @property
    def resource(self) -> str:
        """pyvisa-py's name for the serial port itself."""
        return f"ASRL{self.port}::INSTR"

    def start(self) -> PrologixPty:
        self._thread.start()
        return self

    def __enter__(self) -> PrologixPty:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Stop the adapter's thread, waiting at most CLOSE_WAIT_S, and close the pty.

        A thread computing a reply under the instrument's lock (e.g. 9999 averages at
        time scale 0) looks up only when done: it is a daemon and is not waited for,
        and the pty stays open for it (closing its descriptors under it could hand
        their numbers to another file it would then write to).
        """
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(CLOSE_WAIT_S)
        if self._thread.is_alive():
            log.warning("closed with %s still busy after %g s; not waiting", self._thread.name, CLOSE_WAIT_S)
            return
        for fd in (self._master, self._slave):
            with contextlib.suppress(OSError):
                os.close(fd)

    # ----------------------------------------------------------- controller
    def _reset_controller(self) -> None:
        self.address = self.gpib_address
        self.auto = 0
        self.eoi = 1
        self.eos = 0
        self.eot_enable = 0
        self.eot_char = 10
        self.mode = 1
        self.read_tmo_ms = 500
        # Replies the instrument holds until the controller addresses it to talk:
        # (bytes, time from which they can be read).
        self._outbox: collections.deque[tuple] = collections.deque()  # (bytes, ready at, until)

    def _run(self) -> None:
        buffer = b""
        while not self._stop.is_set():
            ready, _, _ = select.select([self._master], [], [], POLL_S)
            if not ready:
                continue
            try:
                data = os.read(self._master, 65536)
            except BlockingIOError:
                continue
            except OSError:  # no host has the port open right now
                time.sleep(POLL_S)
                continue
            buffer += data
            while True:
                line, terminator = _take_line(buffer)
                if line is None:
                    break
                buffer = buffer[len(line) + terminator :]
                try:
                    self._handle(line)
                except OSError as exc:
                    log.debug("pty write failed: %s", exc)
                except Exception:  # one bad line must not silence the adapter for good
                    log.exception("Prologix emulation: line %r", line[:80])

    def _handle(self, line: bytes) -> None:
        if line.startswith(b"++"):
            self._command(line[2:].decode("ascii", errors="replace").strip())
            return
        if not line.strip():
            return
        data = _unescape(line) + {0: b"\r\n", 1: b"\r", 2: b"\n", 3: b""}[self.eos]
        if self.address != self.gpib_address:
            return  # nobody listens at that address
        chunks = self.session.feed(data)
        if self.eoi or self.eos == 3:
            chunks += self.session.end_of_message()
        self._queue(chunks)
        if self.auto:
            self._read("eoi")

    def _queue(self, chunks: list[Chunk]) -> None:
        ready = max(time.monotonic(), self._outbox[-1][1] if self._outbox else 0.0)
        for chunk in chunks:
            ready += chunk.delay_s  # replies come one after the other: delays add up
            if chunk.data:
                self._outbox.append((chunk.data, ready, chunk.until))
            if chunk.close:
                # A serial line cannot be closed by the far end: the transfer just
                # stops short, and the instrument listens again, as on a new link.
                self.session = Session(self.analyzer, self.faults)

    def _command(self, text: str) -> None:
        name, _, arg = text.partition(" ")
        name, arg = name.lower(), arg.strip()
        settable = {
            "auto": (0, 1),
            "eoi": (0, 1),
            "eos": (0, 3),
            "eot_enable": (0, 1),
            "eot_char": (0, 255),
            "mode": (0, 1),
            "read_tmo_ms": (1, 3000),
        }
        if name in settable:
            if not arg:
                self._write(f"{getattr(self, name)}\r\n".encode())
                return
            low, high = settable[name]
            if arg.isdigit() and low <= int(arg) <= high:
                setattr(self, name, int(arg))
            return
        if name == "addr":
            if not arg:
                self._write(f"{self.address}\r\n".encode())
            elif arg.split()[0].isdigit() and 0 <= int(arg.split()[0]) <= 30:
                self.address = int(arg.split()[0])
        elif name == "ver":
            self._write(VERSION.encode() + b"\r\n")
        elif name == "read":
            until = arg.lower()
            if until in ("", "eoi") or (until.isdigit() and int(until) <= 255):
                self._read(until)
        elif name == "clr":
            if self.address == self.gpib_address:
                self._outbox.clear()
                self.session.clear()
        elif name == "spoll":
            target = int(arg.split()[0]) if arg[:1].isdigit() else self.address
            status = self.analyzer.serial_poll() if target == self.gpib_address else 0
            self._write(str(int(status) & 0xFF).encode() + b"\r\n")
        elif name == "srq":
            self._write(b"0\r\n")
        elif name == "loc":
            self.analyzer.go_to_local()
        elif name == "rst":
            self._reset_controller()
        elif name in ("ifc", "llo", "trg", "savecfg"):
            pass
        else:
            self._write(b"Unrecognized command\r\n")

    def _read(self, until: str) -> None:
        """Address the instrument to talk and pass what it says to the host."""
        if self.address != self.gpib_address:
            return
        deadline = time.monotonic() + self.read_tmo_ms / 1000
        out = bytearray()
        eoi = False
        while not self._stop.is_set():
            if self._outbox and self._outbox[0][1] <= time.monotonic() and _released(self._outbox[0]):
                data = self._outbox.popleft()[0]
                if until.isdigit():  # stop at a character, keep the rest for later
                    cut = data.find(bytes([int(until)]))
                    if cut >= 0:
                        if data[cut + 1 :]:
                            self._outbox.appendleft((data[cut + 1 :], 0.0, None))
                        out += data[: cut + 1]
                        break
                out += data
                eoi = True
                if until == "eoi":
                    break
                continue
            if time.monotonic() >= deadline:
                break
            time.sleep(0.002)
        if eoi and self.eot_enable:
            out.append(self.eot_char)
        if out:
            self._write(bytes(out))

    def _write(self, data: bytes) -> None:
        view = memoryview(data)
        deadline = time.monotonic() + WRITE_GIVE_UP_S
        while view and not self._stop.is_set() and time.monotonic() < deadline:
            _, ready, _ = select.select([], [self._master], [], POLL_S)
            if ready:
                try:
                    view = view[os.write(self._master, view[:4096]) :]
                except BlockingIOError:
                    continue


def _released(entry: tuple) -> bool:
    """A queued reply is not held back by a condition (SCPI's *OPC? waits for the measurement)."""
    return entry[2] is None or bool(entry[2]())


def _take_line(buffer: bytes) -> tuple[bytes | None, int]:
    """The first line of ``buffer`` ended by an unescaped CR or LF, and the
    length of its terminator (CR LF counts as one)."""
    i = 0
    while i < len(buffer):
        byte = buffer[i]
        if byte == ESC:
            i += 2
            continue
        if byte in (0x0A, 0x0D):
            size = 2 if byte == 0x0D and buffer[i + 1 : i + 2] == b"\n" else 1
            if byte == 0x0D and i + 1 == len(buffer):
                size = 1
            return buffer[:i], size
        i += 1
    return None, 0


def _unescape(data: bytes) -> bytes:
    out = bytearray()
    i = 0
    while i < len(data):
        if data[i] == ESC and i + 1 < len(data):
            out.append(data[i + 1])
            i += 2
        else:
            out.append(data[i])
            i += 1
    return bytes(out)
