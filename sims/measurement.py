"""The measurement state machine every simulated model shares: arm, trigger, record,
autorange, preview, average. The dialects (sims/hp_dialect.py, sims/scpi.py) drive it.

Time: the measurement advances lazily, on each command, from a monotonic clock
scaled by ``time_scale`` (1.0 = real time, 0 = every hit lands and records at
once). Physics is drawn when the analyzer arms, so the data depend only on the
seed and the command sequence, never on timing.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from sims.acquisition import Record
from sims.dsp import Average, line_spectrum, peak_scale, window
from sims.settings import AnalyzerSettings, coerce_range
from sims.sources import PhysicsSource, ReplaySource, SourceError

Source = PhysicsSource | ReplaySource

#: States: idle (nothing armed), waiting (for a trigger), measuring (recording a hit),
#: pending (a hit waits for accept/reject in preview), done (every average in).
STATES = ("idle", "waiting", "measuring", "pending", "done")


class Measurement:
    """Settings, the hit source and what has been measured with them.

    ``report(detail)`` is called when the source cannot serve a hit with these
    settings (a replay recorded otherwise); the dialect queues its own error.
    """

    def __init__(
        self,
        settings: AnalyzerSettings,
        source: Source,
        time_scale: float,
        clock: Callable[[], float],
        report: Callable[[str], None],
    ) -> None:
        self.settings = settings
        self.source: Source = source
        self.time_scale = float(time_scale)
        self.clock = clock
        self.report = report
        #: States entered since the dialect last looked (SCPI event registers latch them).
        self.entered: set[str] = set()
        self.reset()

    # ------------------------------------------------------------------ state
    def reset(self) -> None:
        """Forget the measurement: idle, no data (a preset or a new geometry)."""
        self._enter("idle")
        self.paused_at: float | None = None
        self.average = Average(self.settings.lines)
        self.last_record: Record | None = None
        self._next: Record | None = None
        self._trigger_at = math.inf
        self._done_at = math.inf
        self._never_hit = False

    def _enter(self, state: str) -> None:
        self.state = state
        self.entered.add(state)

    def target(self) -> int:
        """Hits the measurement takes: the average count, or 1 with averaging off."""
        return 1 if self.settings.averaging == "AVOF" else self.settings.n_averages

    def start(self, never_hit: bool = False) -> None:
        """Clear the average and arm; ``never_hit`` arms a hammer that never strikes."""
        self.average = Average(self.settings.lines)
        self.last_record = None
        self.paused_at = None
        self._never_hit = never_hit
        self.arm(self.clock())

    def abort(self) -> None:
        """Stop: nothing armed or pending; the average and the last record stay."""
        self._enter("idle")
        self.paused_at = None
        self._next, self._trigger_at, self._done_at = None, math.inf, math.inf

    def arm(self, at: float) -> None:
        """Draw the next hit and schedule its trigger and end of record."""
        self._enter("waiting")
        if self._never_hit:
            self._next, self._trigger_at, self._done_at = None, math.inf, math.inf
            return
        try:
            timed = self.source.next_record(self.settings)
        except SourceError as exc:
            self.report(str(exc))
            self._enter("idle")
            return
        if timed is None:
            self._next, self._trigger_at, self._done_at = None, math.inf, math.inf
            return
        self._next = timed.record
        s = self.time_scale
        self._trigger_at = at + timed.trigger_after_s * s
        record_end = self.settings.trigger_delay_s + self.settings.record_length_s
        self._done_at = self._trigger_at + max(0.0, record_end) * s

    def advance(self) -> None:
        """Bring the state up to the clock's now."""
        if self.paused_at is not None:
            return
        now = self.clock()
        while True:
            if self.state == "waiting" and now >= self._trigger_at:
                self._enter("measuring")
            if self.state != "measuring" or now < self._done_at:
                return
            record = self._next
            assert record is not None
            done_at = self._done_at
            self.last_record = record
            if self._autorange(record):
                self.arm(done_at)
                continue
            if self.settings.preview:
                self._enter("pending")
                return
            self.accept(record, done_at)

    def pause(self) -> None:
        if self.paused_at is None and self.state in ("waiting", "measuring"):
            self.paused_at = self.clock()

    def resume(self) -> None:
        if self.paused_at is not None:
            shift = self.clock() - self.paused_at
            self._trigger_at += shift
            self._done_at += shift
            self.paused_at = None

    def _autorange(self, record: Record) -> bool:
        """Up-range an overloaded channel that has autorange on; True if the record is
        dropped for a new one. At the top range there is nowhere to go: the
        overloaded record stays, flagged."""
        dropped = False
        model = self.settings.model
        for ch in (1, 2):
            if record.overload[ch - 1] and self.settings.channel("autorange", ch):
                current = float(self.settings.channel("range", ch))  # type: ignore[arg-type]
                peak = record.peak_v[ch - 1]
                wanted = max(current, peak) * 1.2 if math.isfinite(peak) else current * 2
                new = coerce_range(min(wanted, model.ranges_v[-1]), model)
                if new > current:
                    setattr(self.settings, f"range{ch}_v", new)
                    dropped = True
        return dropped

    def accept(self, record: Record, at: float) -> None:
        """Take ``record`` into the average; done, or arm for the next hit."""
        s = self.settings
        fs, n = record.sample_rate_hz, record.force_n.size
        zoom = np.iscomplexobj(record.force_n)
        win1 = window(s.window1, n, fs, s.force_width1_s, s.exp_decay1_s)
        win2 = window(s.window2, n, fs, s.force_width2_s, s.exp_decay2_s)
        lines = s.lines
        self.average.add(
            line_spectrum(record.force_n, win1, lines),
            line_spectrum(record.acceleration_m_s2, win2, lines),
            peak_scale(win1, zoom, lines),
            peak_scale(win2, zoom, lines),
            record.overload,
        )
        if self.average.count >= self.target():
            self._enter("done")
        else:
            self.arm(at)

    def accept_pending(self) -> None:
        """Preview: the pending hit into the average (the caller checks one is pending)."""
        assert self.last_record is not None
        self.accept(self.last_record, self.clock())

    def reject_pending(self) -> None:
        """Preview: throw the pending hit away and arm for the next."""
        self.arm(self.clock())

    @property
    def overload(self) -> tuple[bool, bool]:
        """Overload of the last record, (ch1, ch2)."""
        return self.last_record.overload if self.last_record is not None else (False, False)
