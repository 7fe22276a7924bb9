"""Running a Capture at the terminal: the live display, the accept/reject prompt, and
sealing what was taken, however the capture ends. Shared by ``daq capture`` and
``daq replay``.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from pathlib import Path
from typing import Any

import numpy as np

from daq.cli.errors import UserError
from daq.store import Run

SPARK = "▁▂▃▄▅▆▇█"


def sparkline(values: np.ndarray, width: int = 32) -> str:
    """|values| as a bar per bin (max of each), scaled to the largest."""
    magnitude = np.abs(np.asarray(values))
    bins = np.array_split(magnitude, min(width, magnitude.size))
    peaks = np.array([b.max() for b in bins])
    top = peaks.max()
    if not top > 0:
        return SPARK[0] * len(peaks)
    return "".join(SPARK[min(len(SPARK) - 1, int(p / top * (len(SPARK) - 1) + 0.5))] for p in peaks)


def drive(console: Any, job: Any, store_dir: Path, ask: bool) -> Run:
    """Run ``job`` (a daq.workflows.capture.Capture) to its end with a display, seal the run and
    return it. With ``ask`` the operator decides each hit at the keyboard, else the
    job's policy does. Every hit is journaled in the store as it is taken. Ctrl-C,
    SIGTERM, SIGHUP, a dropped link, an instrument error or no answer seal the hits so
    far as an incomplete run and raise UserError saying where it is (exit status 130
    for Ctrl-C, 128 + the signal's number for SIGTERM (143) and SIGHUP (129))."""
    from daq.store import StoreError

    if job.store_dir is None:
        job.store_dir = Path(store_dir)

    def seal_partial(why: str, exit_code: int) -> UserError:
        run = job.partial_run()
        if run is None:
            job.discard_journal()
            return UserError(f"{why}; no hits to keep", exit_code)
        try:
            path = job.seal(run)
        except StoreError as exc:
            journal = job.journal.path if job.journal is not None else None
            kept = f"; they stay in the hit journal {journal}" if journal is not None else ""
            return UserError(f"{why}; the {run.hits.n_hits} hits so far could not be sealed: {exc}{kept}", 1)
        return UserError(
            f"{why}; {run.hits.n_hits} hits kept as incomplete run {run.run_id} in {path}", exit_code
        )

    hits_wanted = job.hits_wanted
    with _one_interrupt():
        return _follow(console, job, store_dir, ask, hits_wanted, seal_partial)


class Signalled(KeyboardInterrupt):
    """SIGTERM or SIGHUP: the capture stops as on Ctrl-C, with exit status 128 + signum."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


#: What the error line says for each stopping signal.
_WHY = {
    signal.SIGINT: "interrupted",
    signal.SIGTERM: "terminated (SIGTERM)",
    signal.SIGHUP: "hung up (SIGHUP)",
}


@contextlib.contextmanager
def _one_interrupt():
    """The first Ctrl-C, SIGTERM or SIGHUP interrupts the capture; later ones, while the
    hits so far are sealed, are ignored: a technician pressing twice, or a system
    shutting down (SIGTERM then SIGHUP), must not lose the run. Outside the main thread
    (no signal handlers there) this does nothing. An ignored SIGINT or SIGHUP (a
    background job, nohup) stays ignored."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pressed = False

    def on_signal(signum: int, frame: Any) -> None:
        nonlocal pressed
        if pressed:
            return
        pressed = True
        if signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise Signalled(signum)

    previous = {}
    for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        old = signal.getsignal(signum)
        if signum != signal.SIGINT and old is signal.SIG_IGN:
            continue
        previous[signum] = signal.signal(signum, on_signal)
    try:
        yield
    finally:
        # Once interrupted the command is on its way out with the run sealed: another
        # signal now would only turn its exit status into a death by signal.
        for signum, old in previous.items():
            signal.signal(signum, signal.SIG_IGN if pressed else old)


def _follow(console: Any, job: Any, store_dir: Path, ask: bool, hits_wanted: int, seal_partial: Any) -> Run:
    from daq.store import StoreError
    from daq.workflows.capture import CaptureError, Configured, Connected, Finished, HitArrived, HitDecided
    from drivers.errors import DriverError

    try:
        for event in job:
            if isinstance(event, Connected):
                console.print(f"Analyzer: {event.identification}, dialect {event.dialect}")
            elif isinstance(event, Configured):
                s = event.settings
                console.print(
                    f"Span {s.span_hz:g} Hz, {s.lines} lines, {s.record_length_s:g} s records, trigger "
                    f"{s.trigger_level_eu:g} N, {hits_wanted} hits wanted. Hammer away."
                )
            elif isinstance(event, HitArrived):
                _show_hit(console, event, hits_wanted)
                if ask:
                    _ask(console, job, event)
            elif isinstance(event, HitDecided):
                verdict = "accepted" if event.accepted else f"rejected ({event.reason})"
                console.print(f"  -> {verdict}; {event.accepted_so_far}/{hits_wanted} accepted")
            elif isinstance(event, Finished):
                path = job.seal(event.run)
                state = "" if event.run.complete else " (incomplete, as its original)"
                console.print(f"Run {event.run.run_id} sealed{state}: {path}")
                return event.run
    except Signalled as exc:
        raise seal_partial(_WHY[exc.signum], 128 + exc.signum) from None
    except KeyboardInterrupt:
        raise seal_partial("interrupted", 130) from None
    except EOFError:
        raise seal_partial("no answer on stdin (use --yes to decide by the checks)", 1) from None
    except DriverError as exc:
        raise seal_partial(str(exc), 1) from None
    except StoreError as exc:  # no room, a journal that cannot be written, a seal that failed
        message = str(exc)
        if job.journal is not None and "journal" not in message:
            message += (
                f"; the hits stay in the hit journal {job.journal.path}, sealed as an incomplete run "
                "by the next daq command on this store once it can write there"
            )
        raise UserError(message) from None
    except CaptureError as exc:  # e.g. too many hits failed their checks: keep what was taken
        raise seal_partial(str(exc), 1) from None
    raise AssertionError("a capture ends with Finished or an exception")


def _show_hit(console: Any, hit: Any, hits_wanted: int) -> None:
    verdict = "checks pass" if hit.passed else f"FAILS: {hit.suggested_reason}"
    console.print(
        f"Hit {hit.index + 1}: peak {hit.peak_force_n:.3g} N, {hit.accepted_so_far}/{hits_wanted} "
        f"accepted, {verdict}"
    )
    for check in hit.checks:
        if not check.passed:
            console.print(f"  {check.name}: {check.detail}")
    console.print(f"  force    {sparkline(hit.force_n)}")
    console.print(f"  response {sparkline(hit.response_m_s2)}")


def _ask(console: Any, job: Any, hit: Any) -> None:
    from rich.prompt import Prompt

    default = "a" if hit.passed else "r"
    # Escaped: rich would read "[a]" and "[r]" as markup tags and show "ccept / eject".
    answer = Prompt.ask(r"  \[a]ccept / \[r]eject", choices=["a", "r"], default=default, console=console)
    if answer == "a":
        job.decide(True)
    else:
        job.decide(False, hit.suggested_reason or "rejected by operator")
