"""Opening a transport from a resource name, and finding what is connected."""

from __future__ import annotations

import warnings

from drivers.prologix_transport import PrologixTransport
from drivers.transport import Transport
from drivers.visa_transport import VisaTransport


def open_transport(resource: str, timeout_s: float = 5.0, lock_file: bool = True) -> Transport:
    """``PROLOGIX::<port>::<address>`` through pyserial; anything else through pyvisa-py
    (``GPIB0::11::INSTR``, ``TCPIP::host::port::SOCKET``, ``ASRL/dev/ttyS0::INSTR``)."""
    resource = resource.strip()
    if not resource:
        raise ValueError("empty resource name")
    if resource.upper().startswith("PROLOGIX::"):
        transport: Transport = PrologixTransport(resource, timeout_s, lock_file)
    else:
        transport = VisaTransport(resource, timeout_s, lock_file=lock_file)
    transport.open()
    return transport


#: Interfaces whose discovery would send packets onto the network (VXI-11 UDP
#: broadcast, mDNS): never scanned; give such resources by name.
_NETWORK_INTERFACES = ("tcpip", "prlgx_tcpip", "vicp")


def list_resources() -> dict[str, list[str]]:
    """What this machine offers: local VISA resources (pyvisa-py: serial, GPIB, USB)
    and serial ports. Network instruments are not searched for: pyvisa-py's
    discovery broadcasts on every LAN the machine is on."""
    found: dict[str, list[str]] = {"visa": [], "serial": [], "notes": []}
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            from pyvisa import constants
            from pyvisa_py.sessions import Session

            skip = {getattr(constants.InterfaceType, name, None) for name in _NETWORK_INTERFACES}
            names: set[str] = set()
            for (interface, _), session_class in Session.iter_valid_session_classes():
                if interface in skip:
                    continue
                try:
                    names.update(session_class.list_resources())
                except Exception as exc:  # one broken bus must not hide the others
                    found["notes"].append(f"{interface.name}: {' '.join(str(exc).split())}")
            # pyvisa-py offers every serial port as a Prologix interface too; ours is
            # PROLOGIX::<port>::<address>, so those entries would only confuse.
            found["visa"] = sorted(n for n in names if not n.upper().startswith("PRLGX"))
        found["notes"] += [" ".join(str(w.message).split()) for w in caught]
    except Exception as exc:
        found["notes"].append("VISA resources not searched: " + " ".join(str(exc).split()))
    found["notes"].append("network instruments are not searched for; name them (TCPIP::host::port::SOCKET)")
    try:
        from serial.tools import list_ports

        found["serial"] = sorted(
            f"{p.device}  {p.description}" if p.description and p.description != "n/a" else p.device
            for p in list_ports.comports()
        )
    except Exception as exc:
        found["notes"].append("serial ports not searched: " + " ".join(str(exc).split()))
    return found


def lock_key_of(resource: str) -> str:
    """The name of the lock file ``open_transport(resource)`` would take, without
    opening anything: a process that owns the instrument for longer than one
    connection (``daq serve``) holds it itself and opens with ``lock_file=False``."""
    resource = resource.strip()
    if not resource:
        raise ValueError("empty resource name")
    if resource.upper().startswith("PROLOGIX::"):
        return PrologixTransport(resource, 5.0, lock_file=True).lock_key
    return VisaTransport(resource, 5.0, lock_file=True).lock_key
