"""One capture at a time, run in a thread of the service, decided from the web page.

The workflow is daq.workflows.capture.Capture, the same as ``daq capture``: the same checks,
the same runs. What differs is who decides each hit: the page or the API
(``decide``), or the checks when the capture was started with ``auto``. Every step
is published as an event (daq/service/events.py). However the capture ends, the
hits taken are sealed: complete, or as an incomplete run after Stop, a dropped
link or an instrument error. Only Abort discards them, as asked. Every hit and its
verdict is journaled in the store as it is taken (daq/store/journal.py), so a service
killed outright (SIGKILL, OOM, power cut) loses no decided hit either: the next start
of the service, or any command listing the store, seals the journal as an incomplete
run.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from daq.service.events import EventHub
from daq.store import Run, StoreError
from daq.workflows.capture import (
    Capture,
    CaptureError,
    Configured,
    Connected,
    Finished,
    HitArrived,
    HitDecided,
)
from daq.workflows.errors import WorkflowError
from daq.workflows.instrument_link import InstrumentLink
from daq.workflows.live_frf import live_frf
from daq.workflows.setup_codec import settings_to_dict
from daq.workflows.setups import ResolvedSetup
from daq.workflows.station_setups import check_for_model, connected_model
from daq.workflows.test import TestPoint, join
from drivers.errors import DriverError, Interrupted
from drivers.settings import ImpactSettings

log = logging.getLogger(__name__)

MAX_HITS_WANTED = 999
#: Seconds a decision made on the page is held before it goes to the analyzer, so that
#: a wrong click can be undone (POST /api/capture/undo). The service's option.
UNDO_WINDOW_S = 3.0


class Conflict(Exception):
    """The request does not fit the capture's state (HTTP 409); one line."""


class CaptureController:
    """start / decide / stop / abort from request threads; the capture runs in its own."""

    def __init__(
        self,
        link: InstrumentLink,
        store_dir: Path,
        hub: EventHub,
        on_sealed: Callable[[str], None],
        settings: ImpactSettings | None = None,
        undo_window_s: float = UNDO_WINDOW_S,
    ) -> None:
        if not undo_window_s >= 0:
            raise ValueError(f"undo_window_s must be >= 0, got {undo_window_s!r}")
        self.undo_window_s = float(undo_window_s)
        self.link = link
        self.store_dir = store_dir
        self.hub = hub
        self.on_sealed = on_sealed
        self.settings = settings or ImpactSettings()
        self._cond = threading.Condition()
        self._thread: threading.Thread | None = None
        self.where: TestPoint | None = None
        self.setup: ResolvedSetup | None = None
        self.practice: dict[str, Any] | None = None
        # The simulator's hammer and accelerometer before any test's point moved them.
        self._sim_home: tuple[float, float] | None = None
        self.state = "idle"
        self.last_run_id: str | None = None
        self.last_outcome: str | None = None
        self.last_error: str | None = None
        self.last_message: str | None = None
        self._reset(None, 0, False)

    def _reset(self, job: Capture | None, hits_wanted: int, auto: bool) -> None:
        self._job = job
        self.run_id = job.run_id if job is not None else None
        self.hits_wanted = hits_wanted
        self.auto = auto
        self.hits: list[dict[str, Any]] = []
        self.traces: list[tuple[np.ndarray, np.ndarray]] = []
        self.pending: int | None = None
        self.actual_settings: dict[str, Any] | None = None
        self.sample_rate_hz = 0.0
        self.start_s = 0.0
        self.center_hz = 0.0
        self._decision: tuple[bool, str] | None = None
        # A decision held for undo: until when (time.monotonic()), and for which hit.
        self._held_until = 0.0
        self._held_index: int | None = None
        self._job_driver: Any = None
        self._stop: str | None = None
        self._frf: dict[str, Any] | None = None

    # ------------------------------------------------------------ requests
    def start(
        self,
        hits_wanted: int,
        operator: str = "",
        note: str = "",
        auto: bool = False,
        where: TestPoint | None = None,
        setup: ResolvedSetup | None = None,
    ) -> str:
        """Open the analyzer and start a capture; its run id. Conflict if one runs;
        DriverError if the analyzer cannot be reached; ValueError (one line naming the
        field) when the simulator cannot play the test's point.

        where : the test and point the run measures (daq/workflows/test.py
            ``point_to_measure``): the run records its points and joins the test when
            sealed; on the simulator the hammer and accelerometer move there first.
        setup : the named setup (daq/workflows/setups.py ``resolve_setup``): its settings,
            transducers and cautions go to the run; checked against the connected model
            before the first hit (ValueError naming the field). None: the service's
            settings, no setup recorded."""
        if not 1 <= hits_wanted <= MAX_HITS_WANTED:
            raise ValueError(f"hits must be 1..{MAX_HITS_WANTED}")
        dsa, simulator = self._open_for(setup, where)
        options: dict[str, Any] = {}
        if setup is not None:
            options = {
                "transducers": dict(setup.transducers), "setup_name": setup.name,
                "setup_version": setup.version, "cautions": list(setup.cautions),
            }  # fmt: skip
        job = Capture(
            dsa, setup.settings if setup is not None else self.settings, hits_wanted,
            resource=self.link.resource, transport=self.link.transport_name,
            simulator=simulator, operator=operator, note=note, store_dir=self.store_dir,
            points=where.points if where is not None else None, **options,
        )  # fmt: skip
        with self._cond:
            self._reset(job, hits_wanted, auto)
            self.where = where
            self.setup = setup
            self.state = "running"
            self._thread = threading.Thread(target=self._run, args=(job, dsa), name="capture", daemon=True)
        started = {
            "run_id": job.run_id,
            "hits_wanted": hits_wanted,
            "auto": auto,
            "operator": operator,
            "note": note,
        }
        if where is not None:
            started["test"] = {"name": where.test, "point": where.point}
        self.hub.publish("capture_started", started)
        self._thread.start()
        return job.run_id

    def _open_for(self, setup: ResolvedSetup | None, where: Any) -> tuple[Any, dict[str, Any] | None]:
        """(the driver, the simulator's provenance or None) for a capture or practice:
        idle checked, the analyzer opened, ``setup`` checked against it, the simulated
        hammer and sensor at ``where`` (None: their own places). Conflict, DriverError or
        ValueError (naming the field) leave the controller idle and the driver closed."""
        with self._cond:
            self._refuse_unless_idle()
            self.state = "starting"
        try:
            dsa = self.link.open_driver()
        except DriverError:
            with self._cond:
                self.state = "idle"
            raise
        try:
            self._check_setup(dsa, setup)
            simulator = self.link.simulator_for_capture()
            if simulator is not None:
                simulator.update(self._place_simulator(dsa, where))
        except (DriverError, ValueError):
            with contextlib.suppress(Exception):
                dsa.close()
            with self._cond:
                self.state = "idle"
            raise
        return dsa, simulator

    def start_practice(self, setup: ResolvedSetup | None, n_hits: int) -> None:
        """Take ``n_hits`` practice hits (none kept) and choose the ranges and trigger
        level for ``setup`` (daq/workflows/auto_range.py); the answer lands in the
        snapshot's ``practice``. Conflict while a capture runs; DriverError when the
        analyzer cannot be reached."""
        if not 1 <= n_hits <= 100:
            raise ValueError("hits: must be 1..100")
        # As a capture's: a setup this analyzer cannot take is refused before any hit.
        dsa, _ = self._open_for(setup, None)
        settings = setup.settings if setup is not None else self.settings
        name = setup.name if setup is not None else None
        with self._cond:
            self._reset(None, 0, False)
            self._job_driver = dsa
            self.practice = {"state": "running", "setup": name, "hits_wanted": n_hits, "hits_taken": 0}
            self.state = "practice"
            self._thread = threading.Thread(
                target=self._practise, args=(dsa, settings, n_hits, name), name="practice", daemon=True
            )
        self.hub.publish("practice_started", {"setup": name, "hits_wanted": n_hits})
        self._thread.start()

    def _practise(self, dsa: Any, settings: ImpactSettings, n_hits: int, name: str | None) -> None:
        from daq.workflows.auto_range import practice_hits

        def on_hit(index: int, peak_force_n: float, peak_response_m_s2: float) -> None:
            with self._cond:
                if self.practice is not None:
                    self.practice["hits_taken"] = index + 1
            self.hub.publish(
                "practice_hit",
                {"index": index, "number": index + 1, "peak_force_n": peak_force_n,
                 "peak_response_m_s2": peak_response_m_s2},
            )  # fmt: skip

        result: dict[str, Any]
        try:
            found = practice_hits(dsa, settings, n_hits, on_hit=on_hit)
            result = {"state": "done", "setup": name, "hits_wanted": n_hits, **found.to_dict(), "error": None}
        except Interrupted:
            result = {"state": "stopped", "setup": name, "hits_wanted": n_hits, "error": None}
        except (DriverError, WorkflowError) as exc:
            if isinstance(exc, DriverError):
                self.link.note_error(str(exc))
            result = {"state": "failed", "setup": name, "hits_wanted": n_hits, "error": str(exc)}
        except Exception as exc:  # a bug: the service stays up and says so
            log.exception("practice hits failed")
            result = {
                "state": "failed",
                "setup": name,
                "hits_wanted": n_hits,
                "error": f"internal error: {exc}",
            }
        finally:
            with contextlib.suppress(Exception):
                dsa.close()
        with self._cond:
            taken = (self.practice or {}).get("hits_taken", 0)
            self.practice = {"hits_taken": taken, **result}
            self._job_driver = None
            self._stop = None
            self.state = "idle"
            self._cond.notify_all()
        self.hub.publish("practice_done", self.practice)

    def _refuse_unless_idle(self) -> None:
        """Conflict, saying what is under way and what to do, unless idle (under _cond)."""
        if self.state == "idle":
            return
        if self.state == "practice":
            raise Conflict("practice hits are being taken; stop them first (POST /api/capture/stop)")
        if self.state == "starting":
            raise Conflict("a capture or practice is starting (opening the analyzer); try again in a moment")
        run = f" (run {self.run_id})" if self.run_id else ""
        if self.state == "stopping":
            raise Conflict(f"a capture is stopping{run}; try again once it has ended")
        raise Conflict(f"a capture is {self.state}{run}; stop it first (POST /api/capture/stop)")

    @staticmethod
    def _check_setup(dsa: Any, setup: ResolvedSetup | None) -> None:
        """ValueError naming the field when the connected analyzer cannot take ``setup``."""
        if setup is not None:
            try:
                check_for_model(setup.settings, connected_model(dsa.dialect.name, dsa.identify()))
            except WorkflowError as exc:
                raise ValueError(str(exc)) from None

    def _place_simulator(self, dsa: Any, where: TestPoint | None) -> dict[str, Any]:
        """On the simulator: the hammer and accelerometer at the test's point (as ``daq
        capture --sim --test`` places them), else where they were before any test moved
        them; their positions for the run's provenance. ValueError naming the point
        when the simulated beam has no such position."""
        if self._sim_home is None:
            self._sim_home = (float(dsa.query("SIM:FORCE?")), float(dsa.query("SIM:SENSOR?")))
        force_at, sensor_at = self._sim_home
        if where is not None:
            force_at = where.force_at_m if where.force_at_m is not None else force_at
            sensor_at = where.sensor_at_m if where.sensor_at_m is not None else sensor_at
        dsa.send(f"SIM:FORCE {force_at!r}")
        dsa.send(f"SIM:SENSOR {sensor_at!r}")
        try:
            dsa.check_errors()
        except DriverError as exc:
            what = f"point: {where.point} of test {where.test}" if where is not None else "the simulator"
            raise ValueError(f"{what}: the simulated beam cannot take it ({exc})") from None
        return {"force_at_m": float(dsa.query("SIM:FORCE?")), "sensor_at_m": float(dsa.query("SIM:SENSOR?"))}

    def decide(self, index: int, accept: bool, reason: str = "") -> None:
        with self._cond:
            if self.state != "running" or self.pending is None:
                raise Conflict("no hit is waiting for a decision")
            if index != self.pending:
                raise Conflict(
                    f"hit of index {index} (hit {index + 1}) is not the one waiting "
                    f"(index {self.pending}, hit {self.pending + 1}, is)"
                )
            self._decision = (bool(accept), reason)
            held = self.undo_window_s > 0
            if held:
                # Held: the page may still take it back (undo); the capture thread hands
                # it to the analyzer when the window has passed.
                self._held_until = time.monotonic() + self.undo_window_s
                self._held_index = index
                self.pending = None
                self.hits[index].update(held=True, undo_until_s=self.undo_window_s)
            self._cond.notify_all()
            run_id = self.run_id
        if held:
            self.hub.publish(
                "decision_held",
                {"run_id": run_id, "index": index, "number": index + 1, "accepted": bool(accept),
                 "reason": reason, "undo_until_s": self.undo_window_s},
            )  # fmt: skip

    def undo(self) -> dict[str, Any]:
        """Take back the decision being held: the hit is pending again. Conflict when
        there is none, or when it has gone to the analyzer already."""
        with self._cond:
            if self.state != "running" or not self.hits:
                raise Conflict("no decision to undo")
            index = self._held_index
            if index is not None and self._decision is not None and time.monotonic() < self._held_until:
                accepted, _ = self._decision
                self._decision = None
                self._held_index = None
                self.pending = index
                self.hits[index].update(held=False, undo_until_s=None)
                self._cond.notify_all()
                run_id = self.run_id
            else:
                decided = [h for h in self.hits if h["decided"] or h.get("held")]
                if not decided:
                    raise Conflict("no decision to undo")
                last = decided[-1]
                accepted = self._decision[0] if last.get("held") and self._decision else last["accepted"]
                if accepted:
                    raise Conflict(f"hit {last['index'] + 1} is already in the analyzer's average")
                raise Conflict(f"hit {last['index'] + 1} is already rejected at the analyzer")
        undone = "accepted" if accepted else "rejected"
        self.hub.publish(
            "decision_undone", {"run_id": run_id, "index": index, "number": index + 1, "undone": undone}
        )
        return {"index": index, "number": index + 1, "undone": undone}

    def stop(self, how: str = "stop") -> None:
        """End the capture: ``stop`` seals the hits so far, ``abort`` discards them."""
        with self._cond:
            if self.state == "practice":
                self._stop = how
                driver = self._job_driver
                if driver is not None:
                    driver.interrupt.set()
                return
            if self.state not in ("running", "stopping"):
                raise Conflict("no capture is running")
            if self._stop is None or how == "abort":
                self._stop = how
            self.state = "stopping"
            job = self._job
            self._cond.notify_all()
        if job is not None:
            job.driver.interrupt.set()

    def wait_idle(self, timeout_s: float | None = None) -> bool:
        thread = self._thread
        if thread is not None:
            thread.join(timeout_s)
            return not thread.is_alive()
        return True

    # ------------------------------------------------------------ reading
    def snapshot(self) -> dict[str, Any]:
        with self._cond:
            left = None
            if self._held_index is not None and self._decision is not None:
                left = max(0.0, self._held_until - time.monotonic())
            hits = []
            for h in self.hits:
                hit = dict(h)
                if hit.get("held"):
                    hit["undo_until_s"] = left
                    # A page opened during the hold must show the verdict it holds.
                    if self._decision is not None and self._held_index == hit["index"]:
                        hit["held_accepted"] = self._decision[0]
                        hit["held_reason"] = self._decision[1]
                hits.append(hit)
            return {
                "hit_index_base": 0,
                "state": self.state,
                "run_id": self.run_id,
                "hits_wanted": self.hits_wanted,
                "accepted": sum(1 for h in self.hits if h["accepted"]),
                "auto": self.auto,
                "pending": self.pending,
                "undo_until_s": left,
                "undo_window_s": self.undo_window_s,
                "test": None if self.where is None else {"name": self.where.test, "point": self.where.point},
                "setup": None if self.setup is None else self.setup.provenance(),
                "transducers": {}
                if self.setup is None
                else {channel: t.to_dict() for channel, t in self.setup.transducers.items()},
                "cautions": [] if self.setup is None else list(self.setup.cautions),
                "practice": self.practice,
                "hits": hits,
                "settings": self.actual_settings,
                "last_run_id": self.last_run_id,
                "last_outcome": self.last_outcome,
                "last_error": self.last_error,
                "last_message": self.last_message,
            }

    def hit_traces(self, index: int) -> dict[str, Any] | None:
        with self._cond:
            if not 0 <= index < len(self.traces):
                return None
            force, response = self.traces[index]
            return {
                "index": index,
                "number": index + 1,
                "hit_index_base": 0,
                "sample_rate_hz": self.sample_rate_hz,
                "start_s": self.start_s,
                "force_n": np.real(force),
                "response_m_s2": np.real(response),
            }

    def hit_quality(self, index: int) -> dict[str, Any] | None:
        """Hit ``index``'s records with its quality view (daq/workflows/hit_quality.py):
        windows, force spectrum against the tip check's limit, its FRF, the running
        average after it. None when the capture has no such hit."""
        from daq.workflows.hit_quality import hit_quality

        with self._cond:
            if not 0 <= index < len(self.traces):
                return None
            records = list(self.traces)
            accepted = [h["accepted"] if h["decided"] else None for h in self.hits]
            settings = dict(self.actual_settings or {})
            rate, center = self.sample_rate_hz, self.center_hz
        out = self.hit_traces(index) or {}
        out.update(hit_quality(settings, records, accepted, index, rate, center))
        return out

    def frf(self) -> dict[str, Any] | None:
        with self._cond:
            return self._frf

    # ------------------------------------------------------------ the capture thread
    def _run(self, job: Capture, dsa: Any) -> None:
        outcome, message, sealed = "failed", "", None
        try:
            sealed = self._iterate(job)
            outcome, message = "sealed", f"{_hits(job.accepted)} averaged"
        except _Stopped:
            pass
        except Interrupted:
            pass
        except DriverError as exc:
            message = str(exc)
            self.link.note_error(message)
            self.hub.publish("instrument", self.link.status())
        except (CaptureError, StoreError) as exc:
            message = str(exc)
        except Exception as exc:  # a bug: the service stays up and says so
            log.exception("capture %s failed", job.run_id)
            message = f"internal error: {type(exc).__name__}: {exc}"
        finally:
            with contextlib.suppress(Exception):
                dsa.close()
        try:
            if sealed is None:
                outcome, message, sealed = self._keep_partial(job, outcome, message)
        except Exception as exc:  # a bug: never leave the capture "running" for good
            log.exception("capture %s could not be kept", job.run_id)
            outcome, message = "failed", f"{message or 'stopped'}; internal error keeping the hits: {exc}"
        finally:
            self._finish(job, outcome, message, sealed)

    def _finish(self, job: Capture, outcome: str, message: str, sealed: Run | None) -> None:
        """Back to idle; undecided hits get the verdict the run (or the abort) gave them."""
        reason = "discarded (capture aborted)" if outcome == "aborted" else "interrupted before a decision"
        with self._cond:
            undecided = [h for h in self.hits if not h["decided"]]
            for hit in undecided:
                hit.update(decided=True, accepted=False, reason=reason, held=False, undo_until_s=None)
            accepted_so_far = sum(1 for h in self.hits if h["accepted"])
            self.pending = None
            self._held_index = None
            self.last_run_id = sealed.run_id if sealed is not None else self.last_run_id
            self.last_outcome = outcome
            self.last_error = message if outcome in ("failed", "incomplete") and message else None
            self.last_message = message or None
            self.state = "idle"
            self._cond.notify_all()
        for hit in undecided:
            self.hub.publish(
                "hit_decided",
                {"run_id": job.run_id, "index": hit["index"], "number": hit["index"] + 1, "accepted": False,
                 "reason": reason, "accepted_against_checks": False, "accepted_so_far": accepted_so_far},
            )  # fmt: skip
        with self._cond:
            where = self.where
        if sealed is not None and where is not None:
            try:
                join(self.store_dir, where, sealed.run_id, accepted=sealed.complete)
                counted = "" if sealed.complete else ", not counted (incomplete)"
                message = f"{message}; joined test {where.test} at point {where.point}{counted}"
            except WorkflowError as exc:
                message = f"{message}; {exc}"
            with self._cond:
                self.last_message = message
        self.hub.publish("capture_ended", {"run_id": job.run_id, "outcome": outcome, "message": message})
        if sealed is not None:
            self.on_sealed(sealed.run_id)

    def _keep_partial(self, job: Capture, outcome: str, message: str) -> tuple[str, str, Run | None]:
        """After anything but a complete capture: seal the hits so far (unless aborted)."""
        with self._cond:
            how = self._stop
        if how == "abort":
            with self._cond:
                taken = len(self.hits)  # the hit waiting for a decision too
            job.discard_journal()
            return "aborted", f"{_hits(taken)} discarded", None
        why = message or "stopped"
        try:
            run = job.partial_run()
        except CaptureError as exc:
            job.release_journal()
            return "failed", f"{why}; the hits could not be kept: {exc}", None
        if run is None:
            job.discard_journal()
            return ("stopped" if how == "stop" else outcome), f"{why}; no hits to keep", None
        try:
            self._seal(run, job)
        except (StoreError, ValueError) as exc:
            job.release_journal()
            kept = f"; they stay in the hit journal {job.journal.path}" if job.journal is not None else ""
            lost = f"{why}; the {_hits(run.hits.n_hits)} so far could not be sealed: {exc}{kept}"
            return "failed", lost, None
        return "incomplete", f"{why}; {_hits(run.hits.n_hits)} kept as an incomplete run", run

    def _seal(self, run: Run, job: Capture) -> None:
        job.seal(run)
        self.hub.publish(
            "run_sealed",
            {"run_id": run.run_id, "complete": run.complete, "n_hits": run.hits.n_hits,
             "n_accepted": int(np.count_nonzero(run.hits.accepted))},
        )  # fmt: skip

    def _iterate(self, job: Capture) -> Run:
        for event in job:
            with self._cond:
                stopping = self._stop is not None
            if stopping and not isinstance(event, HitDecided):
                raise _Stopped
            if isinstance(event, Connected):
                self.link.note_ok(event.identification)
                self.hub.publish("instrument", self.link.status())
            elif isinstance(event, Configured):
                settings = settings_to_dict(event.settings)
                with self._cond:
                    self.actual_settings = settings
                    self.center_hz = float(event.settings.center_hz or 0.0)
                self.hub.publish(
                    "configured",
                    {"run_id": job.run_id, "identification": job.identification, "settings": settings},
                )
            elif isinstance(event, HitArrived):
                self._arrived(job, event)
                if not self.auto:
                    job.decide(*self._wait_for_decision(event.index))
            elif isinstance(event, HitDecided):
                self._decided(job, event)  # a decision held when Stop came is kept
                if stopping:
                    raise _Stopped
            elif isinstance(event, Finished):
                self._seal(event.run, job)
                return event.run
        raise CaptureError("the capture ended without a run")

    def _arrived(self, job: Capture, hit: HitArrived) -> None:
        summary = {
            "index": hit.index, "number": hit.index + 1, "decided": False, "accepted": None, "reason": "",
            "accepted_against_checks": False, "held": False, "undo_until_s": None,
            "peak_force_n": hit.peak_force_n, "overload": list(hit.overload),
            "timestamp_utc": hit.timestamp_utc, "passed": hit.passed,
            "suggested_reason": hit.suggested_reason,
            "checks": [{"name": c.name, "passed": c.passed, "detail": c.detail} for c in hit.checks],
        }  # fmt: skip
        with self._cond:
            self.sample_rate_hz, self.start_s = job.sample_rate_hz, job.start_s
            self.hits.append(summary)
            self.traces.append((hit.force_n, hit.response_m_s2))
            self.pending = None if self.auto else hit.index
            self._decision = None
        self.hub.publish(
            "hit",
            {**summary, "run_id": job.run_id, "accepted_so_far": hit.accepted_so_far,
             "sample_rate_hz": job.sample_rate_hz, "start_s": job.start_s,
             "force_n": np.real(hit.force_n), "response_m_s2": np.real(hit.response_m_s2)},
        )  # fmt: skip

    def _wait_for_decision(self, index: int) -> tuple[bool, str]:
        """The decision on hit ``index``, once its undo window has passed (at once on
        Stop: a decision made is kept; Abort discards everything anyway)."""
        with self._cond:
            while True:
                if self._stop == "abort" or (self._stop is not None and self._decision is None):
                    raise _Stopped
                if self._decision is not None:
                    left = self._held_until - time.monotonic() if self._held_index == index else 0.0
                    if left <= 0 or self._stop is not None:
                        break
                    self._cond.wait(left)
                else:
                    self._cond.wait()
            decision = self._decision
            self._decision = None
            self._held_index = None
            self.pending = None
            self.hits[index].update(held=False, undo_until_s=None)
            return decision

    def _decided(self, job: Capture, event: HitDecided) -> None:
        with self._cond:
            hit = self.hits[event.index]
            hit.update(
                decided=True, accepted=event.accepted, reason=event.reason,
                accepted_against_checks=bool(event.accepted and not hit["passed"]),
            )  # fmt: skip
            accepted = [self.traces[h["index"]] for h in self.hits if h["accepted"]]
        self.hub.publish(
            "hit_decided",
            {"run_id": job.run_id, "index": event.index, "number": event.index + 1,
             "accepted": event.accepted, "reason": event.reason,
             "accepted_against_checks": bool(event.accepted and not hit["passed"]),
             "accepted_so_far": event.accepted_so_far},
        )  # fmt: skip
        if event.accepted:
            frf = live_frf(self.actual_settings or {}, accepted, self.sample_rate_hz, self.center_hz)
            with self._cond:
                self._frf = frf
            self.hub.publish("frf", {"run_id": job.run_id, **frf})


def _hits(n: int) -> str:
    return f"{n} hit" if n == 1 else f"{n} hits"


class _Stopped(Exception):
    """Stop or Abort was asked while the capture waited."""
