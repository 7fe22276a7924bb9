"""The HP dynamic signal analyzer family: the driver of each dialect, and the one
factory, ``open_analyzer``, that finds out what answers (drivers/detection.py) and
drives it in its dialect (docs/dialects.md)."""

from __future__ import annotations

from drivers.base import SignalAnalyzer
from drivers.detection import DETECT_TIMEOUT_S, Detection, detect, open_driver
from drivers.detection import connect as connect_with
from drivers.dialects import Dialect
from drivers.errors import DriverError
from drivers.hp_mnemonic import HPMnemonicAnalyzer
from drivers.scpi_analyzer import ScpiAnalyzer
from drivers.transport import Transport

#: The driver of each family of dialects (``Dialect.family``).
DRIVERS: dict[str, type[SignalAnalyzer]] = {"hp": HPMnemonicAnalyzer, "scpi": ScpiAnalyzer}


def driver_for(dialect: Dialect) -> type[SignalAnalyzer]:
    return DRIVERS[dialect.family]


def connect(transport: Transport, dialect: Dialect | str | None = None, **kwargs: object) -> SignalAnalyzer:
    """The driver for the instrument behind the open ``transport``: of the dialect
    detection finds, or of ``dialect`` (a Dialect or its name) without asking."""
    return connect_with(transport, driver_for, dialect, **kwargs)


def open_analyzer(
    resource: str,
    timeout_s: float = 5.0,
    lock_file: bool = True,
    dialect: Dialect | str | None = None,
    **kwargs: object,
) -> SignalAnalyzer:
    """Open ``resource`` (drivers/resources.py) and ``connect`` to what answers."""
    return open_driver(resource, driver_for, timeout_s, lock_file, dialect, **kwargs)


__all__ = ["DETECT_TIMEOUT_S", "Detection", "DriverError", "connect", "detect", "open_analyzer"]
