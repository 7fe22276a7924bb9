"""`daq demo`: the whole chain as it stands, against the simulated analyzer.

The simulator serves on 127.0.0.1 (a real TCP socket), the driver talks to it
through pyvisa-py as it would to the lab's box: configure an impact test, take
hits with preview, fetch the analyzer's FRF and coherence, and set the peaks it
shows beside the beam model.
"""

from __future__ import annotations

from typing import Annotated

import typer

from daq.cli.errors import UserError
from daq.cli.options import (
    DEFAULT_SCENARIO,
    DEFAULT_TIME_SCALE,
    FRESH_SEED_HELP,
    SCENARIO_HELP,
    SEED_HELP,
    TIME_SCALE_HELP,
    Scenario,
)


def demo(
    hits: Annotated[int, typer.Option(metavar="<1-100>", help="Hits to average.")] = 5,
    scenario: Annotated[Scenario, typer.Option(help=SCENARIO_HELP)] = DEFAULT_SCENARIO,
    seed: Annotated[
        int | None,
        typer.Option(
            metavar="<int>", show_default=False, help=f"{SEED_HELP} {FRESH_SEED_HELP.format(', printed')}"
        ),
    ] = None,
    time_scale: Annotated[float, typer.Option(metavar="<factor>", help=TIME_SCALE_HELP)] = DEFAULT_TIME_SCALE,
) -> None:
    """Run a simulated impact test; compare it with the beam model.

    Starts the simulated analyzer on 127.0.0.1 and drives it through pyvisa-py as
    the lab's analyzer would be driven: configure an impact test, take the hits,
    fetch the FRF and coherence. Prints the FRF peaks beside the exact beam's and
    the Ritz model's natural frequencies.
    """
    import numpy as np
    from rich.console import Console
    from rich.progress import Progress
    from rich.table import Table

    from analysis.exact_beam import cantilever_frequencies_hz
    from analysis.ritz import ritz_frequencies_hz
    from daq.workflows.connect import fresh_seed, open_analyzer
    from drivers.settings import ImpactSettings
    from sims.instrument import Analyzer
    from sims.scenarios import SCENARIOS
    from sims.sources import PhysicsSource
    from sims.tcp_server import TcpServer

    if scenario.value not in SCENARIOS:  # Scenario and sims' list must not drift apart
        raise UserError(f"--scenario must be one of {', '.join(SCENARIOS)}", exit_code=2)
    if not 1 <= hits <= 100:
        raise UserError("--hits must be 1..100", exit_code=2)
    if not time_scale >= 0:
        raise UserError("--time-scale must be >= 0", exit_code=2)
    console = Console()
    seed = fresh_seed() if seed is None else seed
    analyzer = Analyzer(PhysicsSource(scenario.value, seed=seed), time_scale=time_scale)
    with TcpServer(analyzer) as server, open_analyzer(server.resource, timeout_s=5.0) as dsa:
        console.print(
            f"Simulated analyzer ({scenario.value} beam, seed {seed}, time scale {time_scale:g}) "
            f"at [bold]{server.resource}[/]: {dsa.identify()}"
        )
        settings = dsa.configure(ImpactSettings(span_hz=200.0, averages=hits, preview=True))
        console.print(
            f"Span {settings.span_hz:g} Hz, {settings.record_length_s:g} s records, force window "
            f"{settings.hammer.force_width_s:g} s, exponential {settings.accelerometer.exp_decay_s:g} s, "
            f"trigger {settings.trigger_level_eu:g} N, pre-trigger {settings.pre_trigger_s * 1e3:g} ms"
        )
        dsa.start()
        with Progress(console=console, transient=True) as progress:
            task = progress.add_task("hits (hammer away)", total=hits)
            while not dsa.status().done:
                dsa.wait_for_hit(timeout_s=30)
                force, accel = dsa.fetch_time_records()
                # The impulse survives the anti-alias filter; the peak force does not.
                impulse = float(np.sum(force.data)) * force.header.delta_x
                if force.header.overflow or accel.header.overflow:
                    console.print(f"  hit rejected: overload (impulse {impulse * 1e3:.2f} mN s)")
                    dsa.reject()
                    continue
                dsa.accept()
                progress.advance(task)
                console.print(f"  hit accepted: impulse {impulse * 1e3:.2f} mN s")
        frf, coherence = dsa.fetch_frf(), dsa.fetch_coherence()

    f, magnitude = frf.x, np.abs(frf.data)
    exact = cantilever_frequencies_hz(n_modes=4)
    ritz = ritz_frequencies_hz(n_functions=3)
    table = Table(
        title=f"FRF peaks of {frf.header.n_averages} averaged hits (line spacing {frf.header.delta_x:g} Hz)"
    )
    for column in ("Mode", "Peak (Hz)", "Exact beam (Hz)", "Ritz N=3 (Hz)", "|H| (m/s²/N)", "Coherence"):
        table.add_column(column, justify="right")
    for k, f_exact in enumerate(exact):
        near = np.abs(f - f_exact) < 0.08 * f_exact + 2 * frf.header.delta_x
        i = np.flatnonzero(near)[np.argmax(magnitude[near])]
        table.add_row(
            str(k + 1),
            f"{f[i]:.2f}",
            f"{f_exact:.3f}",
            f"{ritz[k]:.3f}" if k < ritz.size else "—",
            f"{magnitude[i]:.3g}",
            f"{coherence.data[i]:.3f}",
        )
    console.print(table)
    console.print(
        "The simulated analyzer stands in for the HP 35660A; point the same driver at the lab's "
        "box with --resource (daq identify -r GPIB0::11::INSTR)."
    )
