"""What the golden transcripts of every simulated model are made of.

A golden is a list of exchanges: (fake clock time or None, request, expected), where
expected is the exact bytes of the reply (b"" for none) or, for the few replies
whose floats are only known to a tolerance, a check of the bytes. Each dialect
(tests/sims/goldens/mnemonic.py: the 35660A and the 3562A; tests/sims/goldens/scpi.py:
the 35670A and 35665A) writes its goldens by hand from its documentation, never
read back from the simulator; tests/sims/test_golden_transcripts.py plays them all.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np

from sims.instrument import Analyzer
from sims.sources import RecordedHit

Expected = bytes | Callable[[bytes], bool]
Exchange = tuple[float | None, str, Expected]

TIME_START_S = -0.25  # the time hit's first sample, a quarter second before the trigger


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


@dataclass(frozen=True)
class Golden:
    covers: str  # the command (or its query form) this transcript pins
    exchanges: tuple[Exchange, ...]
    bench: str = "physics"  # which analyzer the dialect's make_bench builds


@dataclass(frozen=True)
class ErrorGolden:
    code: int  # the error code this transcript pins
    exchanges: tuple[Exchange, ...]  # the error made, read back, and the queue empty after


@dataclass(frozen=True)
class Dialect:
    """One model's goldens and how to build the analyzers they run on."""

    model: str
    goldens: tuple[Golden, ...]
    error_goldens: tuple[ErrorGolden, ...]
    make_bench: Callable[[str, FakeClock], Analyzer]
    required: frozenset[str]  # what its command table says must have a golden
    sends_what_it_covers: Callable[[Golden], bool]
    error_codes: frozenset[int]  # every code the model documents
    error_message_in_reply: Callable[[ErrorGolden], bool] = lambda _gold: True


@dataclass
class Book:
    """Collects a dialect's goldens in the order they are written."""

    goldens: list[Golden] = field(default_factory=list)

    def g(self, covers: str, *exchanges: tuple[str, Expected], bench: str = "physics") -> None:
        self.goldens.append(Golden(covers, tuple((None, req, rep) for req, rep in exchanges), bench))

    def g_timed(self, covers: str, *exchanges: tuple[float, str, Expected]) -> None:
        """Exchanges at fake clock times, on the "clock" bench."""
        self.goldens.append(Golden(covers, tuple(exchanges), "clock"))


@dataclass(frozen=True)
class Hits:
    """The replay source's hits whose every value is known in advance."""

    rate_hz: float
    n: int
    time_force: np.ndarray
    time_accel: np.ndarray
    time_hit: RecordedHit  # a distinct value in every sample, channel 1 overloaded
    delta_hit: RecordedHit  # force 2 N at sample 1, acceleration 3 m/s^2 at sample 5

    @classmethod
    def make(cls, seed: int, n: int, rate_hz: float) -> Hits:
        rng = np.random.default_rng(seed)
        force = np.round(rng.normal(0.0, 3.0, n), 6)
        accel = np.round(rng.normal(0.0, 40.0, n), 6)
        delta_force = np.zeros(n)
        delta_force[1] = 2.0
        delta_accel = np.zeros(n)
        delta_accel[5] = 3.0
        return cls(
            rate_hz,
            n,
            force,
            accel,
            RecordedHit(force, accel, rate_hz, TIME_START_S, overload=(True, False)),
            RecordedHit(delta_force, delta_accel, rate_hz),
        )


def mnemonics_in(requests: Iterable[str]) -> set[str]:
    """The upper-case mnemonic of every command in mnemonic-dialect messages."""
    return {
        part.strip().split(" ")[0].upper()
        for request in requests
        for part in request.replace("\n", ";").split(";")
        if part.strip()
    }


# --------------------------------------------------------------------------- the 3562A family's dumps
CRLF = b"\r\n"


def lines(*texts: str) -> bytes:
    """Reply lines of the mnemonic dialect, each ending CR LF."""
    return b"".join(t.encode("ascii") + CRLF for t in texts)


def block(values: list[float]) -> bytes:
    """``#A`` + 2-byte big-endian byte count + big-endian float64."""
    payload = struct.pack(f">{len(values)}d", *values)
    return b"#A" + struct.pack(">H", len(payload)) + payload


def ascii_dump(values: list[float]) -> bytes:
    """``#I``, the count of values, then the values ``{:+.16E}`` one per CR LF line."""
    return (
        b"#I"
        + CRLF
        + str(len(values)).encode("ascii")
        + CRLF
        + b"".join(f"{v:+.16E}".encode("ascii") + CRLF for v in values)
    )


def time_trace(hits: Hits, function_code: int, channel: int, overflow: int, y_code: int, data) -> list[float]:
    """A baseband TIM trace of ``hits``: the 66 header words of docs/instrument.md, then the data."""
    h = [0.0] * 66
    h[0] = function_code
    h[1] = h[2] = hits.n  # elements, elements displayed
    h[3] = 1  # averages (AVOF: one record)
    h[4] = channel
    h[5] = overflow
    h[6] = 0  # overlap %
    h[7] = 0  # time domain
    h[8] = 0  # peak
    h[9] = y_code
    h[10] = 4  # x in s
    h[35] = 0  # float
    h[36] = 1  # real
    h[40] = 1  # linear
    h[43] = 0  # linear resolution
    h[52] = h[53] = hits.rate_hz / 2
    h[55] = 1 / hits.rate_hz
    h[64] = TIME_START_S
    return h + [float(v) for v in data]


def state_with(state: list[float], **words: float) -> list[float]:
    """``state`` with some words changed: state_with(PRESET, w13=1.0)."""
    out = list(state)
    for key, value in words.items():
        out[int(key[1:])] = float(value)
    return out
