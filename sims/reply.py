"""What an instrument hands its front end to send."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass


@dataclass(frozen=True)
class Reply:
    """Bytes the instrument has to send; ``binary`` for blocks (``#A``, ``#<n>``).

    ``ready``, if given, holds the reply back until it returns True (SCPI ``*OPC?``
    answers when the measurement is done); front ends poll it.
    """

    data: bytes
    binary: bool = False
    ready: Callable[[], bool] | None = None
