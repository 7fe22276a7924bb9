"""A trace the analyzer dumped: its decoded 66-value header and its data.

Header words (docs/instrument.md; documented for the 3562A family unless marked
proj): 0 display function (DISPLAY_CODES), 1 number of elements, 2 elements
displayed, 3 number of averages, 4 channel (proj: 1, 2, 3 = ch2/ch1), 5 overflow,
6 overlap %, 7 domain (0 time, 1 frequency), 8 peak/rms, 9 y units (proj codes:
Y_UNITS), 10 x units (1 Hz, 4 s), 35 float/integer, 36 complex/real (0 complex),
40 log/linear, 43 measurement mode, 52/53 half the sample rate, 55 delta x,
64 start x (start frequency, or start time = trigger delay for a time record).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drivers.errors import ProtocolError

HEADER_LENGTH = 66

#: Header word 0: the documented display-function codes, under our display mnemonics
#: (8 and 9 are the linear spectra, 6 and 7 the time records; 5 cross spectrum and
#: 10 impulse response exist but the driver never selects them).
DISPLAY_CODES = {1: "FRSP", 2: "PSP1", 3: "PSP2", 4: "COHR", 6: "TIM1", 7: "TIM2", 8: "LSP1", 9: "LSP2"}
#: Header word 7 (documented).
DOMAIN_TIME, DOMAIN_FREQUENCY = 0, 1
#: Header word 10 (documented).
X_UNITS = {1: "Hz", 4: "s"}
#: Header word 9: the documents give no codes, these are ours (proj).
Y_UNITS = {0: "V", 1: "N", 2: "m/s^2", 3: "(m/s^2)/N", 4: "", 5: "N^2", 6: "(m/s^2)^2"}


def _code(values: np.ndarray, index: int, table: dict[int, str], what: str, command: str) -> str:
    word = values[index]
    if word != int(word) or int(word) not in table:
        raise ProtocolError(command, f"header word {index} ({what}) holds unknown code {word!r}")
    return table[int(word)]


def _flag(values: np.ndarray, index: int, what: str, command: str) -> bool:
    word = values[index]
    if word not in (0.0, 1.0):
        raise ProtocolError(command, f"header word {index} ({what}) must be 0 or 1, got {word!r}")
    return bool(word)


@dataclass(frozen=True)
class TraceHeader:
    """The header of a dumped trace, decoded and checked.

    sample_rate_hz : of the time record behind the trace, Hz (2 x word 52).
    delta_x, start_x : s for time traces, Hz for frequency traces.
    """

    display_function: str
    n_points: int
    n_averages: int
    channel: int
    overflow: bool
    time_domain: bool
    y_units: str
    x_units: str
    complex_data: bool
    sample_rate_hz: float
    delta_x: float
    start_x: float

    @classmethod
    def decode(cls, values: np.ndarray, command: str) -> TraceHeader:
        if values.size < HEADER_LENGTH:
            raise ProtocolError(
                command, f"a trace needs a {HEADER_LENGTH}-value header, got {values.size} values"
            )
        h = values[:HEADER_LENGTH]
        n_points = h[1]
        if n_points != int(n_points) or n_points < 1:
            raise ProtocolError(command, f"header word 1 (number of elements) is {n_points!r}")
        if h[3] != int(h[3]) or h[3] < 0:
            raise ProtocolError(command, f"header word 3 (averages) is {h[3]!r}")
        if h[4] not in (1.0, 2.0, 3.0):
            raise ProtocolError(command, f"header word 4 (channel) is {h[4]!r}")
        if not (h[52] > 0 and h[55] > 0):
            raise ProtocolError(
                command, "header words 52 (half sample rate) and 55 (delta-x) must be positive"
            )
        _flag(h, 7, "domain", command)  # checks the word is 0 or 1
        time_domain = bool(h[7] == DOMAIN_TIME)
        x_units = _code(h, 10, X_UNITS, "x units", command)
        if (x_units == "s") != time_domain:
            raise ProtocolError(command, f"header: x units {x_units} do not fit the domain")
        return cls(
            display_function=_code(h, 0, DISPLAY_CODES, "display function", command),
            n_points=int(n_points),
            n_averages=int(h[3]),
            channel=int(h[4]),
            overflow=_flag(h, 5, "overflow", command),
            time_domain=time_domain,
            y_units=_code(h, 9, Y_UNITS, "y units", command),
            x_units=x_units,
            complex_data=not _flag(h, 36, "complex/real", command),
            sample_rate_hz=2.0 * float(h[52]),
            delta_x=float(h[55]),
            start_x=float(h[64]),
        )

    @property
    def n_values(self) -> int:
        """Float values that follow the header: two per point for complex data."""
        return self.n_points * (2 if self.complex_data else 1)


@dataclass(frozen=True)
class Trace:
    """header and data: (n_points,) float64 or complex128, in ``header.y_units``."""

    header: TraceHeader
    data: np.ndarray

    @property
    def x(self) -> np.ndarray:
        """Time (s) or frequency (Hz) of each point, (n_points,)."""
        return self.header.start_x + np.arange(self.header.n_points) * self.header.delta_x

    @classmethod
    def from_values(cls, values: np.ndarray, command: str) -> Trace:
        """Header + data as dumped (complex data interleaved re, im)."""
        header = TraceHeader.decode(values, command)
        body = values[HEADER_LENGTH:]
        if body.size != header.n_values:
            raise ProtocolError(
                command, f"header announces {header.n_values} data values, the dump holds {body.size}"
            )
        data = body[0::2] + 1j * body[1::2] if header.complex_data else body.copy()
        return cls(header, data)
