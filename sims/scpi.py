"""The SCPI dialect of the simulated 35670A and 35665A (docs/instrument-scpi.md):
message parsing with SCPI's path rule, settings, queries and traces, over the
measurement every model shares (sims/measurement.py).

Replies: every query's answer in a message joined by ``;``, then LF; a query that
fails sends nothing and queues its error (SYST:ERR?).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from sims.reply import Reply
from sims.scpi_status import FROM_MNEMONIC_CODE, ScpiStatus
from sims.scpi_table import ScpiCommand, ScpiError, match, split_units
from sims.scpi_traces import POWER_FEEDS, coordinates, encode, n_points, points
from sims.settings import AnalyzerSettings, check_center, coerce_range, coerce_span
from sims.traces import NoData
from sims.units import format_number

if TYPE_CHECKING:
    from sims.instrument import Analyzer

MAX_COMMAND_CHARS = 4096
#: SCPI window names <-> the simulator's (sims/dsp.py).
WINDOWS = {"HANN": "HANN", "FLAT": "FLAT", "UNIF": "UNIF", "FORC": "FORC", "EXP": "EXPO"}
TRIGGER_SOURCES = {"IMM": "FREE", "INT1": "CH1", "INT2": "CH2"}
LABELS = {1: "N", 2: "M/S2"}  # the physics' units: force in N, acceleration in m/s^2
HARDWARE_FAULT = "input A/D converter does not respond"
PRESET_FEEDS = {1: "XFR:POW:RAT 2,1", 2: "XFR:POW:COH 1,2", 3: "XTIM:VOLT 1", 4: "XTIM:VOLT 2"}


@dataclass
class ScpiState:
    """What the SCPI model holds beyond the shared AnalyzerSettings; defaults = *RST."""

    data_format: str = "ASC"
    feeds: dict[int, str] = field(default_factory=lambda: dict(PRESET_FEEDS))
    formats: dict[int, str] = field(default_factory=lambda: {1: "MLOG", 2: "MLIN", 3: "REAL", 4: "REAL"})
    eu: dict[int, int] = field(default_factory=lambda: {1: 1, 2: 1})


class ScpiDialect:
    def __init__(self, analyzer: Analyzer) -> None:
        self.analyzer = analyzer
        self.status = ScpiStatus()
        self.state = ScpiState()

    @property
    def m(self):
        return self.analyzer.measurement

    @property
    def errors(self):
        return self.status.errors

    def preset(self) -> None:
        """*RST: settings and SCPI state to the preset; the measurement forgotten."""
        self.m.settings = AnalyzerSettings.preset(self.analyzer.model)
        self.state = ScpiState()
        self.m.reset()

    # ----------------------------------------------------------- errors, status
    def push_error(self, code: int, detail: str) -> None:
        """Queue an error given by its mnemonic-dialect code (front ends, SIM: controls)."""
        self.status.push(FROM_MNEMONIC_CODE[code], detail)

    def source_error(self, detail: str) -> None:
        self.status.push(-221, detail)

    def hardware_fault(self) -> None:
        self.status.push(-240, HARDWARE_FAULT)

    def _look(self) -> None:
        self.m.advance()
        self.status.look(self.m, self.m.state in ("waiting", "measuring", "pending"))

    def serial_poll(self) -> int:
        self._look()
        return self.status.stb()

    def start(self, never_hit: bool = False) -> None:
        if self.analyzer.hardware_fault:
            self.status.push(-240, HARDWARE_FAULT)
            return
        self.m.start(never_hit)

    # ------------------------------------------------------------------ messages
    def execute(self, message: str, on_start: Callable[[], bool] | None = None) -> list[Reply]:
        answers: list[bytes] = []
        binary = False
        ready: Callable[[], bool] | None = None
        path: list[str] = []
        self._look()
        for unit in split_units(message):
            if len(unit) > MAX_COMMAND_CHARS:
                self.status.push(-363, f"command of {len(unit)} characters")
                continue
            try:
                answer, path = self._unit(unit, path, on_start)
            except ScpiError as exc:
                self.status.push(exc.code, exc.detail)
                continue
            finally:
                self._look()
            if answer is not None:
                answers.append(answer.data)
                binary |= answer.binary
                ready = answer.ready or ready
        if not answers:
            return []
        return [Reply(b";".join(answers) + b"\n", binary, ready)]

    def _unit(
        self, unit: str, path: list[str], on_start: Callable[[], bool] | None
    ) -> tuple[Reply | None, list[str]]:
        """Run one command; (its answer or None, the path for the next command)."""
        header, _, text = unit.partition(" ")
        header, text = header.strip().upper(), text.strip()
        query = header.endswith("?")
        bare = header[:-1] if query else header
        if bare.startswith("*"):
            tokens, next_path = [bare], path
        else:
            absolute = bare.startswith(":")
            tokens = (bare[1:] if absolute else bare).split(":")
            if not all(tokens):
                raise ScpiError(-102, unit)
            tokens = tokens if absolute else path + tokens
            next_path = tokens[:-1]
        spelled = ":".join(tokens) + ("?" if query else "")
        found = match(tokens, query)
        if found is None:
            raise ScpiError(-113, spelled)
        command, suffixes = found
        n = suffixes[0] if suffixes else 0
        if suffixes and not 1 <= n <= command.suffix_max:
            raise ScpiError(-114, spelled)
        if query and text:
            raise ScpiError(-108, unit)
        if command.kind == "setting" and not query:
            if not text:
                raise ScpiError(-109, unit)
            assert command.param is not None
            try:
                value = command.param.parse(text)
            except ScpiError as exc:
                raise ScpiError(exc.code, f"{unit}: {exc.detail}") from None
            self._apply(command, n, value, unit)
            return None, next_path
        if command.kind == "action":
            if text:
                raise ScpiError(-108, unit)
            self._action(command.key, on_start, unit)
            return None, next_path
        return self._query(command, n), next_path

    # ---------------------------------------------------------------- actions
    def _action(self, key: str, on_start: Callable[[], bool] | None, unit: str) -> None:
        m = self.m
        if key == "rst":
            self.analyzer.hardware_fault = False
            self.preset()
        elif key == "cls":
            self.status.clear()
        elif key == "opc":
            self.status.opc_armed = True
        elif key == "abort":
            m.abort()
        elif key == "init":
            never_hit = bool(on_start()) if on_start is not None else False
            self.start(never_hit)
        elif key == "status_preset":
            self.status.preset()
        elif key in ("accept", "reject"):
            if m.state != "pending":
                raise ScpiError(-221, f"{unit}: no hit pending")
            m.accept_pending() if key == "accept" else m.reject_pending()
        else:  # pragma: no cover - every action of the table is handled above
            raise ScpiError(-113, key)

    # --------------------------------------------------------------- settings
    def _apply(self, command: ScpiCommand, n: int, value, unit: str) -> None:
        s, key = self.m.settings, command.key
        model = self.analyzer.model
        try:
            if key == "span":
                span = coerce_span(value, model)
                baseband = not s.zoom
                top = model.top_span_hz
                s.span_hz = span
                s.center_hz = span / 2 if baseband else min(max(s.center_hz, span / 2), top - span / 2)
                self._new_geometry()
            elif key == "center":
                s.center_hz = check_center(value, s.span_hz, model)
                self._new_geometry()
            elif key == "lines":
                if value not in model.lines_offered:
                    offered = ", ".join(str(x) for x in model.lines_offered)
                    raise ScpiError(-224, f"{unit}: lines must be one of {offered}")
                s.lines = value
                self._new_geometry()
            elif key == "range":
                setattr(s, f"range{n}_v", coerce_range(value, model))
                setattr(s, f"autorange{n}", 0)
            elif key == "trig_delay":
                if value < -s.record_length_s * (1 + 1e-9):
                    raise ValueError(f"pre-trigger is at most one record ({s.record_length_s:g} s)")
                s.trigger_delay_s = value  # one delay for both channels (docs/instrument-scpi.md)
            elif key == "label":
                if value != LABELS[n]:
                    raise ScpiError(-224, f"{unit}: channel {n} measures in {LABELS[n]}")
            else:
                self._store(key, n, value)
        except ValueError as exc:
            raise ScpiError(-222, f"{unit}: {exc}") from None

    def _store(self, key: str, n: int, value) -> None:
        s, st, status = self.m.settings, self.state, self.status
        simple = {
            "aver_count": "n_averages",
            "force_width": f"force_width{n}_s",
            "exp_decay": f"exp_decay{n}_s",
            "autorange": f"autorange{n}",
            "sensitivity": f"sensitivity{n}_v_per_eu",
            "trig_level": "trigger_level_v",
        }
        if key in simple:
            setattr(s, simple[key], value)
        elif key == "aver_state":
            s.averaging = "STBL" if value else "AVOF"
        elif key == "preview":
            s.preview = 1 if value == "MAN" else 0
        elif key == "window":
            setattr(s, f"window{n}", WINDOWS[value])
        elif key == "coupling":
            setattr(s, f"ac_coupled{n}", 1 if value == "AC" else 0)
        elif key == "eu":
            st.eu[n] = value
        elif key == "trig_source":
            s.trigger_source = TRIGGER_SOURCES[value]
        elif key == "trig_slope":
            s.trigger_slope = value
        elif key == "feed":
            st.feeds[n] = value
        elif key == "format":
            st.formats[n] = value
        elif key == "data_format":
            st.data_format = value
        elif key in ("ese", "sre", "oper_enable", "ques_enable"):
            setattr(status, key, int(value))
        # instrument (FFT), aver_type (RMS), aver_tcon (FRE): one value each, nothing to keep

    def _new_geometry(self) -> None:
        """Span, center or lines changed: the pre-trigger stays within a record and
        the measurement starts over."""
        s = self.m.settings
        s.trigger_delay_s = max(s.trigger_delay_s, -s.record_length_s)
        self.m.reset()

    # ---------------------------------------------------------------- queries
    def _query(self, command: ScpiCommand, n: int) -> Reply:
        key = command.key
        if key == "data" or key == "x_data":
            return self._trace(n, key == "x_data")
        if key == "opc?":
            return Reply(b"1", ready=lambda: not self.analyzer.measurement_pending())
        text = self._answer(key, n)
        return Reply(text.encode("ascii"))

    def _answer(self, key: str, n: int) -> str:
        m, s, st, status = self.m, self.m.settings, self.state, self.status
        per_channel = {
            "force_width": "force_width",
            "exp_decay": "exp_decay",
            "range": "range",
            "sensitivity": "sensitivity",
        }
        if key in per_channel:
            return format_number(float(s.channel(per_channel[key], n)))  # type: ignore[arg-type]
        numbers = {
            "span": s.span_hz,
            "center": s.center_hz,
            "trig_level": s.trigger_level_v,
            "trig_delay": s.trigger_delay_s,
        }
        if key in numbers:
            return format_number(float(numbers[key]))
        integers: dict[str, Callable[[], int]] = {
            "lines": lambda: s.lines,
            "aver_count": lambda: s.n_averages,
            "aver_done": lambda: m.average.count,
            "aver_state": lambda: int(s.averaging == "STBL"),
            "autorange": lambda: int(s.channel("autorange", n)),  # type: ignore[call-overload]
            "eu": lambda: st.eu[n],
            "ese": lambda: status.ese,
            "sre": lambda: status.sre,
            "oper_enable": lambda: status.oper_enable,
            "ques_enable": lambda: status.ques_enable,
            "oper_cond": lambda: status.oper_condition(m),
            "ques_cond": lambda: status.ques_condition(m),
            "volt_cond": lambda: status.volt_condition(m),
            "stb": status.stb,
            "tst": lambda: 0,
            "points": lambda: n_points(s, st.feeds[n]),
        }
        if key in integers:
            return str(int(integers[key]()))
        if key in ("oper_event", "ques_event", "volt_event", "esr"):
            value = getattr(status, key)
            setattr(status, key, 0)
            return str(value)
        if key == "idn":
            return self.analyzer.model.identity
        if key == "error":
            return status.pop()
        if key == "data_format":
            return "ASC,0" if st.data_format == "ASC" else st.data_format
        if key == "feed":
            return f'"{st.feeds[n]}"'
        choices: dict[str, Callable[[], str]] = {
            "format": lambda: st.formats[n],
            "instrument": lambda: "FFT",
            "aver_type": lambda: "RMS",
            "aver_tcon": lambda: "FRE",
            "preview": lambda: "MAN" if s.preview else "OFF",
            "window": lambda: {v: k for k, v in WINDOWS.items()}[str(s.channel("window", n))],
            "coupling": lambda: "AC" if s.channel("ac_coupled", n) else "DC",
            "label": lambda: LABELS[n],
            "trig_source": lambda: {v: k for k, v in TRIGGER_SOURCES.items()}[s.trigger_source],
            "trig_slope": lambda: s.trigger_slope,
        }
        return choices[key]()

    def _trace(self, n: int, x_axis: bool) -> Reply:
        m, st = self.m, self.state
        feed = st.feeds[n]
        try:
            x, z = points(m.settings, m.average, m.last_record, feed, (bool(st.eu[1]), bool(st.eu[2])))
        except NoData as exc:
            raise ScpiError(-230, str(exc)) from None
        values = x if x_axis else coordinates(z, st.formats[n], feed in POWER_FEEDS)
        data, binary = encode(values, st.data_format)
        return Reply(data, binary)
