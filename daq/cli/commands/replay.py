"""`daq replay RUN...`: serve a stored run's hits through the simulated analyzer's
replay mode and capture them again, through the driver and a real TCP socket, into
a new run (kind "replayed") that records where it came from.

The new run's raw data must equal the original's bit for bit; the command says so,
or names the first hit that differs and exits 1 (the new run is sealed either way,
so the evidence is kept). Each hit gets the original's verdict (accepted, or
rejected with the same reason), so the analyzer averages the same hits.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from daq.cli.errors import UserError, exit_code_and_message
from daq.cli.options import StoreOption
from daq.workflows.errors import WorkflowError

if TYPE_CHECKING:
    from drivers.dialects import Dialect

#: The simulated models a replay may use, the first whose records fit the run's: a run
#: of another analyzer of the family replays through the model that records like it
#: (each model's dialect: replay_models). The simulator offers 20 spans of each (max / 2^n).
REPLAY_MODELS: tuple[str, ...] = ("35660A", "3562A", "35670A")
N_SPANS = 20


def replay_models() -> tuple[tuple[str, Dialect], ...]:
    """REPLAY_MODELS with the dialect each speaks (the drivers load here, not with the
    command line)."""
    from drivers.dialects import HP3562A, HP35660A, SCPI

    dialects = {"35660A": HP35660A, "3562A": HP3562A, "35670A": SCPI}
    return tuple((model, dialects[model]) for model in REPLAY_MODELS)


def register(app: typer.Typer) -> None:
    app.command(name="replay")(replay)


def replay(
    runs: Annotated[
        list[str],
        typer.Argument(
            metavar="RUN...",
            show_default=False,
            help="Run ids, unique prefixes, latest, or paths of run files.",
        ),
    ],
    store: StoreOption = None,
    operator: Annotated[
        str, typer.Option(metavar="<name>", help="Who ran the replay (stored with the new run).")
    ] = "",
    note: Annotated[
        str, typer.Option(metavar="<text>", help='Stored with the new run [default: "replay of <id>"].')
    ] = "",
) -> None:
    """Replay stored runs through the simulated analyzer into new runs, bit for bit.

    Every hit of each run (accepted and rejected) is served by the simulator's replay
    mode and captured again through the driver over a real socket, with the original's
    accept/reject verdicts. The new run (kind "replayed") records the original's id and
    SHA-256; the command checks that its raw data equals the original bit for bit.
    """
    from daq.store import Store, StoreError, resolve_store_dir

    store_dir, _ = resolve_store_dir(store)
    the_store = Store(store_dir)
    # Every name is resolved, and the store checked, before anything is replayed: a
    # typo in the third name must not leave two new runs behind.
    paths = [locate(the_store, name) for name in runs]
    try:
        the_store.ensure_writable()
    except StoreError as exc:
        raise UserError(str(exc)) from None
    failures = []
    for name, path in zip(runs, paths, strict=True):
        try:
            replay_one(the_store, path, operator, note)
        except Exception as exc:
            if len(runs) == 1 or exit_code_and_message(exc) is None:
                raise
            sys.stderr.write(f"daq replay: {exc}\n")
            failures.append(name)
    if failures:
        raise UserError(f"{len(failures)} of {len(runs)} replays failed: {', '.join(failures)}")


def locate(the_store: Any, name: str) -> Path:
    """A run named by path (an existing file) or by id / unique prefix in the store."""
    from daq.store import StoreError

    candidate = Path(name).expanduser()
    if "/" in name or (name.endswith(".h5") and candidate.exists()):
        if not candidate.exists():
            raise UserError(f"{name}: no such run file")
        if not candidate.is_file():
            raise UserError(f"{name} is not a regular file (a run file is one HDF5 file)")
        return candidate
    try:
        return the_store.resolve(name)
    except StoreError as exc:
        raise UserError(str(exc)) from None


def replay_one(the_store: Any, path: Path, operator: str, note: str) -> Any:
    """Replay the run file at ``path`` into ``the_store``; the new Run."""
    from rich.console import Console

    from daq.cli.capture_session import drive
    from daq.store import StoreError, open_run
    from daq.workflows.capture import Capture
    from daq.workflows.connect import open_analyzer, serve_simulator
    from daq.workflows.recorded_hits import recorded_hits
    from daq.workflows.setup_codec import settings_from_stored
    from sims.sources import ReplaySource

    try:
        original = open_run(path)
    except StoreError as exc:
        raise UserError(str(exc)) from None
    if original.hits is None:
        raise UserError(f"run {original.run_id} holds FRFs only, no time records: nothing to replay")
    hits = original.hits
    model, settings = replay_settings(original, settings_from_stored)
    n_accepted = int(hits.accepted.sum())
    import hashlib

    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    console = Console(highlight=False, soft_wrap=True)
    with contextlib.ExitStack() as stack:
        try:
            source = ReplaySource(recorded_hits(hits), model=model)
        except ValueError as exc:  # replay_model chose the model: this would be our bug, said plainly
            raise UserError(f"run {original.run_id}: the simulated {model} cannot serve it: {exc}") from None
        resource = serve_simulator(stack, source, time_scale=0.0, model=model)
        console.print(
            f"Replaying run {original.run_id} ({hits.n_hits} hits) "
            f"through the simulated {model} at {resource}"
        )
        dsa = stack.enter_context(open_analyzer(resource))

        def original_verdict(hit: Any) -> tuple[bool, str]:
            return bool(hits.accepted[hit.index]), str(hits.reject_reason[hit.index])

        job = Capture(
            dsa,
            settings,
            # A complete run ends at its last accepted hit; an incomplete one at its last hit.
            max(1, n_accepted if original.complete else n_accepted + 1),
            policy=original_verdict,
            resource=resource,
            transport=type(dsa.transport).__name__,
            simulator={"replay_of": original.run_id, "time_scale": 0.0, "model": model},
            operator=operator,
            note=note or f"replay of {original.run_id}",
            # A run that records no test article (an imported file) gets none: the
            # simulator's beam is not what was measured.
            sample=original.sample,
            max_hits=hits.n_hits + 1,
            stop_after_hits=hits.n_hits,
            replayed_from={
                "run_id": original.run_id,
                "kind": original.kind,
                "file": path.name,
                "sha256": digest,
                "complete": original.complete,
            },
        )
        new = drive(console, job, the_store.path, ask=False)
    difference = first_difference(original.hits, new.hits)
    if difference:
        raise UserError(
            f"replay of {original.run_id} into {new.run_id} differs from the original: {difference}"
        )
    console.print(f"Raw data of {new.run_id} equals {original.run_id} bit for bit ({hits.n_hits} hits)")
    return new


def replay_model(run: Any) -> tuple[str, int, float]:
    """(simulated model, lines, span Hz) that record like ``run``'s hits: 2.56 x lines
    real samples at 2.56 x span (half as many complex at 1.28 x span in zoom), span
    one of the model's. UserError naming the records when no model of the family fits."""
    from drivers.dialects import SAMPLE_RATE_PER_SPAN

    hits = run.hits
    zoom = hits.is_zoom
    per_span = SAMPLE_RATE_PER_SPAN / (2 if zoom else 1)
    span = hits.sample_rate_hz / per_span
    baseband_samples = hits.n_samples * (2 if zoom else 1)
    lines = baseband_samples * 100 // 256
    for model, dialect in replay_models():
        spans = [s for s in dialect.spans_hz(N_SPANS) if math.isclose(s, span, rel_tol=1e-9)]
        if lines * 256 == baseband_samples * 100 and lines in dialect.line_choices and spans:
            return model, lines, spans[0]
    raise UserError(
        f"run {run.run_id}: its records ({hits.n_samples} {'complex' if zoom else 'real'} samples "
        f"at {hits.sample_rate_hz:g} Hz) are not what an analyzer of the family records (2.56 x lines "
        "real samples at 2.56 x span, or half as many complex at 1.28 x span: 35660A 400 lines, "
        "spans 102.4 kHz / 2^n; 3562A 800 lines, 100 kHz / 2^n; 35670A 100 to 1600 lines, "
        "51.2 kHz / 2^n); replay cannot serve them"
    )


def replay_settings(run: Any, from_dict: Any) -> tuple[str, Any]:
    """The simulated model and the analyzer settings that serve ``run``'s records: its
    stored settings when they fit, else the geometry read off the records (replay_model)."""
    from drivers.settings import ImpactSettings

    model, lines, span = replay_model(run)
    hits = run.hits
    stored = None
    if run.instrument is not None and run.instrument.settings:
        with contextlib.suppress(WorkflowError):
            stored = from_dict(run.instrument.settings)
    center = hits.center_hz if hits.is_zoom else None
    if (
        stored is not None
        and stored.span_hz == span
        and stored.center_hz == center
        and stored.lines in (None, lines)
    ):
        return model, stored.with_lines(lines)
    pre_trigger = min(max(0.0, -hits.start_s), hits.n_samples / hits.sample_rate_hz)
    hammer, accelerometer = _recorded_windows(run)
    return model, ImpactSettings(
        span_hz=span, center_hz=center, pre_trigger_s=pre_trigger, lines=lines, hammer=hammer,
        accelerometer=accelerometer,
    )  # fmt: skip


def _recorded_windows(run: Any) -> tuple[Any, Any]:
    """(hammer, accelerometer) channel setups whose windows are those the original run's
    analysis uses (an imported file's, or uniform where it records none): a replay must
    not add windows the records never had, nor change what its analysis gives."""
    from daq.workflows.analysis import WINDOW_KINDS, window_specs
    from drivers.setting_table import Window
    from drivers.settings import ImpactSettings

    code = {kind: Window(c) for c, kind in WINDOW_KINDS.items()}
    defaults = ImpactSettings()
    setups = []
    for spec, default in zip(window_specs(run)[:2], (defaults.hammer, defaults.accelerometer), strict=True):
        widths = {"force_width_s": spec.force_width_s, "exp_decay_s": spec.exp_decay_s}
        setups.append(dataclasses.replace(default, window=code[spec.kind], **widths))
    return setups[0], setups[1]


def first_difference(a: Any, b: Any) -> str:
    """ "" when hits ``a`` and ``b`` hold the same raw data bit for bit, else what differs."""
    import numpy as np

    if b is None:
        return "the new run has no hits"
    if a.force_n.shape != b.force_n.shape or a.force_n.dtype != b.force_n.dtype:
        return f"records {a.force_n.shape} {a.force_n.dtype} became {b.force_n.shape} {b.force_n.dtype}"
    for name in ("sample_rate_hz", "start_s", "center_hz"):
        if np.float64(getattr(a, name)).tobytes() != np.float64(getattr(b, name)).tobytes():
            return f"{name} {getattr(a, name)!r} became {getattr(b, name)!r}"
    for i in range(a.n_hits):
        for what in ("force_n", "response_m_s2"):
            if getattr(a, what)[i].tobytes() != getattr(b, what)[i].tobytes():
                return f"hit {i + 1} {what.split('_')[0]} differs"
        if bool(a.accepted[i]) != bool(b.accepted[i]) or str(a.reject_reason[i]) != str(b.reject_reason[i]):
            return f"hit {i + 1} verdict differs"
        if a.overload[i].tolist() != b.overload[i].tolist():
            return f"hit {i + 1} overload flags differ"
    return ""
