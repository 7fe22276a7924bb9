"""The capture workflow, free of any user interface: hits in, a Run out.

``Capture(driver, settings, hits_wanted)`` is an iterator of events. After each
``HitArrived`` the caller decides (``decide(accept, reason)``) before asking for the
next event; without a decision the policy decides (default: the checks' verdict).
The analyzer runs in preview, so its own average holds only the accepted hits; after
``hits_wanted`` accepted hits its averaged FRF and coherence are fetched and
``Finished(run)`` is the last event. The caller seals the run (``seal``). After an
interruption (Ctrl-C, a driver error) ``partial_run()`` gives the hits so far as an
incomplete run.

With ``store_dir`` set, every hit and every verdict is also appended to a hit journal in
the store and fsynced before the capture goes on (daq/store/journal.py): the run's
metadata once the analyzer is configured, each hit as it arrives, each verdict before
the analyzer is told. ``seal`` turns the capture into a run and removes the journal; a
capture that dies without sealing leaves the journal, which the next command on the
store seals as an incomplete run.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from analysis.beam import TABLE_1
from analysis.hit_checks import HitCheck, failed_names, run_checks
from daq.store import Hits, Instrument, MeasuredFrf, Run, RunPoints, Sample, Store, StoreError, new_run_id
from daq.store.journal import Journal, run_bytes_needed
from daq.workflows.article import sample_for
from daq.workflows.setup_codec import settings_to_dict
from drivers.analyzer import SignalAnalyzer
from drivers.dialects import model_of
from drivers.settings import ImpactSettings

#: The reason stored for a hit rejected by hand with no reason given.
OPERATOR_REJECT = "rejected by operator"


class CaptureError(Exception):
    """The capture cannot go on (e.g. too many hits rejected); one line for the user."""


#: Control characters other than tab and line breaks: refused in the text a run stores
#: (a NUL cannot be stored at all, an escape sequence would drive a terminal listing
#: runs). The same rule as the service's (daq/service/app.py).
_CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")


def check_plain_text(value: str, what: str, one_line: bool) -> str:
    """``value`` if it is valid UTF-8 text without control characters (nor tab or line
    breaks when ``one_line``), else ValueError naming ``what``. Bytes that are not UTF-8
    on the command line reach Python as lone surrogates: those are refused too."""
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        raise ValueError(f"{what} is not valid UTF-8 text (check the terminal's encoding)") from None
    if _CONTROL.search(value) or (one_line and re.search(r"[\r\n\t]", value)):
        extra = " (one line of text)" if one_line else ""
        raise ValueError(f"{what}: control characters are not allowed{extra}")
    return value


@dataclass(frozen=True)
class Connected:
    """identification : the instrument's reply; dialect : the dialect spoken and why."""

    identification: str
    dialect: str = ""


@dataclass(frozen=True)
class Configured:
    """settings : as the analyzer holds them (span and ranges rounded up)."""

    settings: ImpactSettings


@dataclass(frozen=True)
class HitArrived:
    """One hit, waiting for a decision.

    index : 0-based among all hits of the run. force_n, response_m_s2 : (n_samples,)
    N and m/s^2 (complex in zoom). overload : (force, response) flags.
    peak_force_n : peak |force|, N. suggested_reason : the failed checks, "" if none.
    """

    index: int
    force_n: np.ndarray
    response_m_s2: np.ndarray
    checks: list[HitCheck]
    overload: tuple[bool, bool]
    timestamp_utc: str
    peak_force_n: float
    accepted_so_far: int

    @property
    def suggested_reason(self) -> str:
        return failed_names(self.checks)

    @property
    def passed(self) -> bool:
        return not self.suggested_reason


@dataclass(frozen=True)
class HitDecided:
    index: int
    accepted: bool
    reason: str
    accepted_so_far: int


@dataclass(frozen=True)
class Finished:
    run: Run


Event = Connected | Configured | HitArrived | HitDecided | Finished
#: A policy: (hit) -> (accept, reason).
Policy = Callable[[HitArrived], tuple[bool, str]]


def checks_policy(hit: HitArrived) -> tuple[bool, str]:
    """Accept every hit that passes the checks, reject the others naming the failed checks."""
    return hit.passed, hit.suggested_reason


def utc_now() -> str:
    """Now, ISO 8601 UTC to the millisecond, ending in Z."""
    return datetime.now(UTC).isoformat(timespec="milliseconds").replace("+00:00", "Z")


def table1_sample() -> Sample:
    """The seed's Table 1 beam with force and accelerometer at the tip."""
    return Sample(**TABLE_1.to_dict(), force_position_m=TABLE_1.length_m, sensor_position_m=TABLE_1.length_m)


@dataclass
class _Hit:
    force_n: np.ndarray
    response_m_s2: np.ndarray
    accepted: bool
    reason: str
    overload: tuple[bool, bool]
    peak_force_n: float
    timestamp_utc: str
    checks: dict[str, Any]


@dataclass
class Capture:
    """Take ``hits_wanted`` accepted hits with ``driver``; iterate for the events.

    resource, transport : how the analyzer was reached (stored with the run).
    simulator : None for a real analyzer, else the simulator's provenance (scenario, seed...).
    max_hits : give up (CaptureError) after this many hits without enough accepted;
        default 4 x hits_wanted + 10.
    hit_timeout_s : how long to wait for each hit; None = the driver's allowance.
    stop_after_hits : end after this many hits even if fewer were accepted (replay of
        an incomplete run); the run is then incomplete, without the analyzer's FRF.
    replayed_from : the original run's provenance when this is a replay (kind "replayed").
    points : where the run is measured (a test's point: its article, force and response
        points); None records ``sample`` (default the seed's beam at the tip; None: no
        test article, as a replay of an imported run records).
    store_dir : the run store; when set, the hits are journaled there as they are taken
        (and the store is checked for room for the whole run before the first hit).
    transducers : {"hammer"|"accelerometer": Transducer} the setup names; each is stored
        in the run's settings[channel]["transducer"] (daq/workflows/setups.py,
        transducer_record).
    setup_name, setup_version : the named setup (or setup file) the settings came from;
        stored as provenance["setup"] = {"name", "version"} when a name is given.
    cautions : sentences the run carries (a calibration past due), provenance["cautions"].
    auto_range : when practice hits chose the ranges and trigger level
        (daq/workflows/auto_range.py, AutoRange.record), what they chose and the setup's
        own values; stored as provenance["auto_range"].
    """

    driver: SignalAnalyzer
    settings: ImpactSettings
    hits_wanted: int
    policy: Policy = checks_policy
    resource: str = ""
    transport: str = ""
    simulator: dict[str, Any] | None = None
    operator: str = ""
    note: str = ""
    sample: Sample | None = field(default_factory=table1_sample)
    points: RunPoints | None = None
    max_hits: int | None = None
    hit_timeout_s: float | None = None
    stop_after_hits: int | None = None
    replayed_from: dict[str, Any] | None = None
    store_dir: Path | None = None
    transducers: dict[str, Any] | None = None
    setup_name: str = ""
    setup_version: int | None = None
    cautions: list[str] = field(default_factory=list)
    auto_range: dict[str, Any] | None = None

    def __post_init__(self) -> None:
        if not 1 <= self.hits_wanted <= 9999:
            raise ValueError(f"hits_wanted must be 1..9999, got {self.hits_wanted}")
        if self.points is not None:
            # A run at a test's point records that beam with force and sensor where they are.
            self.sample = sample_for(self.points) or self.sample
        self.max_hits = self.max_hits or 4 * self.hits_wanted + 10
        self.run_id = new_run_id()
        self.start_time = utc_now()
        self.identification = ""
        self.actual: ImpactSettings | None = None
        self.hits: list[_Hit] = []
        self.sample_rate_hz = 0.0
        self.start_s = 0.0
        self._pending: HitArrived | None = None
        self._decision: tuple[bool, str] | None = None
        self.journal: Journal | None = None

    @property
    def accepted(self) -> int:
        return sum(h.accepted for h in self.hits)

    def decide(self, accept: bool, reason: str = "") -> None:
        """Decide the hit just offered (HitArrived); a rejection without a reason gets one."""
        if self._pending is None:
            raise RuntimeError("no hit is waiting for a decision")
        self._decision = (bool(accept), reason)

    def __iter__(self) -> Iterator[Event]:
        dsa = self.driver
        self.identification = dsa.identify()
        yield Connected(self.identification, f"{dsa.dialect.name} ({dsa.detection})")
        wanted = replace(self.settings, averages=self.hits_wanted, preview=True)
        try:
            self.actual = dsa.configure(wanted)
        except ValueError as exc:  # settings this analyzer cannot take (lines, pre-trigger)
            raise CaptureError(f"{dsa.dialect.name} analyzer: {exc}") from None
        if self.store_dir is not None:
            self._start_journal()
        yield Configured(self.actual)
        range_v = self.actual.hammer.range_v
        range_n = None if range_v is None else range_v / self.actual.hammer.sensitivity_v_per_eu
        if self.actual.center_hz:
            # In zoom the record is the narrow band mixed down: its peak is a small part
            # of the pulse the input range saw, so "too weak" would fail every hit (and
            # lowering the range then overloads). The overload flag still judges range.
            range_n = None
        dsa.start()
        while self.accepted < self.hits_wanted:
            if self.stop_after_hits is not None and len(self.hits) >= self.stop_after_hits:
                yield Finished(self._run(complete=False, analyzer=None))
                return
            if len(self.hits) >= self.max_hits:
                raise CaptureError(
                    f"{len(self.hits)} hits taken, only {self.accepted} of {self.hits_wanted} accepted: "
                    "giving up (check the hammer tip, the ranges and the trigger)"
                )
            dsa.wait_for_hit(timeout_s=self.hit_timeout_s)
            force, response = dsa.fetch_time_records()
            self.sample_rate_hz = force.header.sample_rate_hz
            self.start_s = force.header.start_x
            flags = (force.header.overflow, response.header.overflow)
            checks = run_checks(force.data, self.sample_rate_hz, self.actual.span_hz, flags, range_n)
            hit = HitArrived(
                index=len(self.hits),
                force_n=force.data,
                response_m_s2=response.data,
                checks=checks,
                overload=flags,
                timestamp_utc=utc_now(),
                peak_force_n=float(np.max(np.abs(force.data))),
                accepted_so_far=self.accepted,
            )
            if self.journal is not None:
                self.journal.add_hit(hit.index, self._hit_info(hit), hit.force_n, hit.response_m_s2)
            self._pending, self._decision = hit, None
            yield hit
            accept, reason = self._decision if self._decision is not None else self.policy(hit)
            reason = "" if accept else (reason.strip() or OPERATOR_REJECT)
            if self.journal is not None:
                self.journal.add_verdict(hit.index, accept, reason)
            if accept:
                dsa.accept()
            else:
                dsa.reject()
            self._keep(hit, accept, reason)
            yield HitDecided(hit.index, accept, reason, self.accepted)
        dsa.wait_until_done(timeout_s=10.0 + 2 * self.actual.record_length_s)
        frf, coherence = dsa.fetch_frf(), dsa.fetch_coherence()
        analyzer = MeasuredFrf(
            frequency_hz=frf.x, frf=frf.data[np.newaxis, :], coherence=coherence.data[np.newaxis, :],
            labels=["H21"],
        )  # fmt: skip
        yield Finished(self._run(complete=True, analyzer=analyzer))

    def _start_journal(self) -> None:
        """The journal, with the run's metadata, once the analyzer's settings are known;
        StoreError when the store has no room for the whole run."""
        assert self.actual is not None
        assert self.store_dir is not None
        points = round(2.56 * (self.actual.lines or 400))
        need = run_bytes_needed(self.hits_wanted, points, complex_records=bool(self.actual.center_hz))
        meta = {
            "run_id": self.run_id, "kind": self._kind(), "start_time": self.start_time,
            "operator": self.operator, "note": self.note, "provenance": self._provenance(),
            "instrument": asdict(self._instrument()),
            "sample": asdict(self.sample) if self.sample is not None else None,
            "points": self.points.to_dicts() if self.points is not None else None,
        }  # fmt: skip
        self.journal = Journal.create(self.store_dir, self.run_id, meta, need_bytes=need)

    def _hit_info(self, hit: HitArrived) -> dict[str, Any]:
        assert self.actual is not None
        return {
            "overload": [bool(f) for f in hit.overload], "peak_force_n": hit.peak_force_n,
            "timestamp_utc": hit.timestamp_utc, "checks": {c.name: c.as_dict() for c in hit.checks},
            "sample_rate_hz": self.sample_rate_hz, "start_s": self.start_s,
            "center_hz": self.actual.center_hz or 0.0,
        }  # fmt: skip

    def seal(self, run: Run) -> Path:
        """Seal ``run`` into ``store_dir`` and remove the journal; its path. If sealing
        fails (StoreError), the journal is kept and unlocked, so the next command on the
        store seals it as an incomplete run."""
        if self.store_dir is None:
            raise ValueError("this capture has no store_dir to seal into")
        try:
            path = Store(self.store_dir).seal(run)
        except StoreError:
            self.release_journal()
            raise
        if self.journal is not None:
            self.journal.remove()
            self.journal = None
        return path

    def discard_journal(self) -> None:
        """The hits are thrown away on purpose (the service's Abort): delete the journal."""
        if self.journal is not None:
            self.journal.remove()
            self.journal = None

    def release_journal(self) -> None:
        """Keep the journal on disk for recovery, and stop holding it."""
        if self.journal is not None:
            self.journal.release()

    def _keep(self, hit: HitArrived, accept: bool, reason: str) -> None:
        self._pending = None
        self.hits.append(
            _Hit(
                hit.force_n,
                hit.response_m_s2,
                accept,
                reason,
                hit.overload,
                hit.peak_force_n,
                hit.timestamp_utc,
                {c.name: c.as_dict() for c in hit.checks},
            )
        )

    def partial_run(self) -> Run | None:
        """The hits so far as an incomplete run (a hit still undecided is kept, rejected
        as "interrupted"); None when there is nothing to keep."""
        if self._pending is not None:
            self._keep(self._pending, False, "interrupted before a decision")
        if not self.hits:
            return None
        return self._run(complete=False, analyzer=None)

    def _run(self, complete: bool, analyzer: MeasuredFrf | None) -> Run:
        assert self.actual is not None
        n_samples = {h.force_n.size for h in self.hits}
        if len(n_samples) != 1:
            raise CaptureError(f"hits of different lengths {sorted(n_samples)}: cannot store them together")
        hits = Hits(
            force_n=np.stack([h.force_n for h in self.hits]),
            response_m_s2=np.stack([h.response_m_s2 for h in self.hits]),
            sample_rate_hz=self.sample_rate_hz,
            start_s=self.start_s,
            center_hz=self.actual.center_hz or 0.0,
            accepted=np.array([h.accepted for h in self.hits]),
            reject_reason=[h.reason for h in self.hits],
            overload=np.array([h.overload for h in self.hits], dtype=bool),
            peak_force_n=np.array([h.peak_force_n for h in self.hits]),
            timestamp_utc=[h.timestamp_utc for h in self.hits],
            checks=[h.checks for h in self.hits],
        )
        return Run(
            run_id=self.run_id,
            kind=self._kind(),
            complete=complete,
            start_time=self.start_time,
            end_time=utc_now(),
            operator=self.operator,
            note=self.note,
            provenance=self._provenance(),
            instrument=self._instrument(),
            sample=self.sample,
            points=self.points,
            hits=hits,
            analyzer=analyzer,
        )

    def _instrument(self) -> Instrument:
        assert self.actual is not None
        return Instrument(
            model=model_of(self.driver.dialect, self.identification),
            identification=self.identification,
            resource=self.resource,
            transport=self.transport,
            dialect=self.driver.dialect.name,
            settings=self._settings_record(),
        )

    def _settings_record(self) -> dict[str, Any]:
        """The settings as the analyzer holds them, each channel with its transducer."""
        assert self.actual is not None
        settings = settings_to_dict(self.actual)
        if self.transducers:
            from daq.workflows.setups import transducer_record

            for channel, record in transducer_record(self.transducers).items():
                settings[channel]["transducer"] = record
        return settings

    def _provenance(self) -> dict[str, Any]:
        provenance: dict[str, Any] = {"hits_wanted": self.hits_wanted}
        if self.simulator is not None:
            provenance["simulator"] = self.simulator
        if self.replayed_from is not None:
            provenance["replayed_from"] = self.replayed_from
        if self.setup_name:
            provenance["setup"] = {"name": self.setup_name, "version": self.setup_version}
        if self.cautions:
            provenance["cautions"] = list(self.cautions)
        if self.auto_range is not None:
            provenance["auto_range"] = dict(self.auto_range)
        return provenance

    def _kind(self) -> str:
        if self.replayed_from is not None:
            return "replayed"
        return "simulated" if self.simulator is not None else "captured"
