"""VISA resources through pyvisa with the pyvisa-py backend.

``GPIB0::11::INSTR`` (pyvisa-py over linux-gpib or gpib-ctypes),
``TCPIP::host::port::SOCKET`` (the simulator, LAN-GPIB gateways) and
``ASRL/dev/ttyUSB0::INSTR``. Replies end with LF (CR LF from the analyzer); binary
blocks are read by count, never through the termination character (pyvisa #348).
"""

from __future__ import annotations

import contextlib
import os
import socket

from drivers.errors import ConnectionFailed, ConnectionLost, InstrumentTimeout
from drivers.transport import Transport

#: The longest reply line we accept; a line without its LF beyond this is garbage.
MAX_LINE_BYTES = 65536


class VisaTransport(Transport):
    def __init__(
        self, resource: str, timeout_s: float = 5.0, backend: str = "@py", lock_file: bool = True
    ) -> None:
        super().__init__(resource, timeout_s, lock_file, lock_key=_lock_key(resource))
        self.backend = backend
        self._rm = None
        self._inst = None

    @property
    def is_socket(self) -> bool:
        return self.resource.upper().endswith("::SOCKET")

    def _open(self) -> None:
        import pyvisa

        try:
            self._rm = pyvisa.ResourceManager(self.backend)
            self._inst = self._rm.open_resource(self.resource, open_timeout=int(self.timeout_s * 1000))
        except (pyvisa.errors.VisaIOError, ValueError, OSError) as exc:
            self._release()
            raise ConnectionFailed(f"cannot open {self.resource}: {_reason(exc)}") from None
        except Exception as exc:  # pyvisa raises assorted types for unknown resource names
            self._release()
            raise ConnectionFailed(f"cannot open {self.resource}: {_reason(exc)}") from None
        self._inst.read_termination = "\n"
        self._inst.write_termination = "\n"
        self._apply_timeout()
        if self.is_socket:
            self._check_connected()

    def _check_connected(self) -> None:
        """pyvisa-py's socket open reports success even when the connection was
        refused (its select sees the failed socket as ready); ask the socket."""
        try:
            sock = self._inst.visalib.sessions[self._inst.session].interface
            error = sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            if not error:
                sock.getpeername()
        except (AttributeError, KeyError, TypeError):
            return  # not pyvisa-py's socket session: nothing to ask
        except OSError as exc:
            error = exc.errno or -1
        if error:
            self._release()
            raise ConnectionFailed(
                f"cannot open {self.resource}: {os.strerror(error) if error > 0 else 'not connected'}"
            )

    def _apply_timeout(self) -> None:
        if self._inst is not None:
            self._inst.timeout = int(self.timeout_s * 1000)

    def _release(self) -> None:
        for thing in (self._inst, self._rm):
            if thing is not None:
                with contextlib.suppress(Exception):  # a broken session may not close cleanly
                    thing.close()
        self._inst = self._rm = None

    def _close(self) -> None:
        self._release()

    def _session(self):
        if self._inst is None:
            raise ConnectionLost(f"{self.resource} is not open")
        return self._inst

    def _write(self, message: bytes) -> None:
        import pyvisa

        try:
            self._session().write_raw(message + b"\n")
        except pyvisa.errors.VisaIOError as exc:
            raise _translate(exc, self.resource, "write") from None
        except OSError as exc:
            raise ConnectionLost(f"{self.resource}: write failed ({exc})") from None

    def _read_line(self) -> bytes:
        import pyvisa

        try:
            data = self._session().read_raw(MAX_LINE_BYTES)
        except pyvisa.errors.VisaIOError as exc:
            raise _translate(exc, self.resource, "read") from None
        except OSError as exc:
            raise ConnectionLost(f"{self.resource}: read failed ({exc})") from None
        return data.rstrip(b"\r\n")

    def _read_exact(self, count: int) -> bytes:
        import pyvisa

        try:
            return bytes(self._session().read_bytes(count, break_on_termchar=False))
        except pyvisa.errors.VisaIOError as exc:
            raise _translate(exc, self.resource, f"read of {count} bytes") from None
        except OSError as exc:
            raise ConnectionLost(f"{self.resource}: read failed ({exc})") from None

    def _clear(self) -> None:
        import pyvisa

        if self.is_socket:
            # A raw socket has no device clear; a fresh connection is the clean slate
            # (late replies of the old one can never be read as new ones).
            self.reconnect()
            return
        try:
            self._session().clear()
        except pyvisa.errors.VisaIOError as exc:
            from pyvisa import constants

            if exc.error_code == constants.StatusCode.error_nonsupported_operation:
                self.reconnect()  # serial and some gateways have no device clear
                return
            raise _translate(exc, self.resource, "device clear") from None


def _reason(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


def _translate(exc: Exception, resource: str, what: str) -> Exception:
    from pyvisa import constants

    code = getattr(exc, "error_code", None)
    if code == constants.StatusCode.error_timeout:
        return InstrumentTimeout(f"{resource}: {what} timed out")
    if code in (constants.StatusCode.error_connection_lost, constants.StatusCode.error_io):
        return ConnectionLost(f"{resource}: {what} failed, link lost ({_reason(exc)})")
    return ConnectionLost(f"{resource}: {what} failed ({_reason(exc)})")


def _lock_key(resource: str) -> str:
    """The physical link behind a VISA name: ``ASRL/dev/ttyUSB0::INSTR`` and a
    Prologix on /dev/ttyUSB0 share one serial port; other names compare without case."""
    upper = resource.strip().upper()
    if upper.startswith("ASRL") and "::" in resource:
        port = resource.strip()[4:].split("::")[0]
        if port.startswith("/"):
            return f"SERIAL::{os.path.realpath(port)}"
    return upper
