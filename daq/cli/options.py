"""Every option that more than one command takes, declared once: the store, --json, the
analyzer (resource, dialect, timeout), the simulator (scenario, seed, time scale, the
analyzer model simulated), worker processes and the Dask scheduler; and the old spellings
of renamed options, kept hidden for one release (renamed, given_once).

A command module imports its shared options from here and never from another command,
so that one option reads the same in every help and is changed in one place. Nothing
here imports more than typer: `daq --help` loads every command module.
"""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated

import typer

from daq.cli.errors import UserError

# ------------------------------------------------------------------ the store
StoreOption = Annotated[
    str | None,
    typer.Option(
        "--store",
        metavar="<dir>",
        show_default=False,
        help="The store folder; else $DAQ_STORE, the config file's store or the per-user data folder.",
    ),
]
JsonOption = Annotated[bool, typer.Option("--json", help="Print JSON instead of text.")]
#: A capture setup: a name in the store (daq setup list) or a path ending in .toml.
SetupOption = Annotated[
    str | None,
    typer.Option(
        "--setup",
        metavar="<name|file.toml>",
        show_default=False,
        help="A setup of the store (daq setup list), or a setup file (daq capture --print-setup).",
    ),
]

# --------------------------------------------------------------- the analyzer
# Optional for typer, so that a missing resource can say where else it may come from.
ResourceOption = Annotated[
    str | None,
    typer.Option(
        "--resource",
        "-r",
        envvar="DAQ_RESOURCE",
        show_envvar=True,
        metavar="<resource>",
        help="The analyzer: GPIB0::11::INSTR, TCPIP::<host>::<port>::SOCKET, "
        "PROLOGIX::<serial port>::<GPIB address>, or sim (the built-in simulator). Needed, "
        "here or in the environment.",
    ),
]
DialectOption = Annotated[
    str | None,
    typer.Option(
        "--dialect",
        envvar="DAQ_DIALECT",
        show_envvar=True,
        metavar="<35660A|3562A|SCPI>",
        help="Speak this dialect without asking the analyzer which it is (35665A and 35670A "
        "mean SCPI) [default: found out on connecting: *IDN?, then ID?].",
    ),
]
TimeoutOption = Annotated[
    float, typer.Option("--timeout", metavar="<seconds>", help="How long to wait for each reply.")
]


def check_dialect(dialect: str | None) -> str | None:
    """The --dialect value as a dialect's name; UserError (exit 2) for an unknown one."""
    if dialect is None:
        return None
    from drivers.dialects import dialect_named

    try:
        return dialect_named(dialect).name
    except ValueError as exc:
        raise UserError(f"--dialect: {exc}", exit_code=2) from None


# -------------------------------------------------------------- the simulator
class Scenario(StrEnum):
    seed = "seed"
    realistic = "realistic"


#: The specimen and the speed every command's simulator plays unless told otherwise
#: (daq sim serve, capture --sim, demo, serve --sim): the beam a lab measures, at a pace
#: a person at the keyboard does not wait on (docs/simulator.md, "Defaults").
DEFAULT_SCENARIO = Scenario.realistic
DEFAULT_TIME_SCALE = 0.05


class SimModel(StrEnum):
    """The models the simulator plays (sims/), by the name the CLI takes."""

    hp35660a = "35660A"
    hp3562a = "3562A"
    hp35670a = "35670A"
    hp35665a = "35665A"


#: "model" alone is the beam model (`daq model`); the analyzer's model is --analyzer.
MODEL_METAVAR = "35660A|3562A|35670A|35665A"
MODEL_HELP = (
    "The analyzer simulated: 35660A or 3562A (HP mnemonics, docs/instrument.md) or 35670A or 35665A "
    "(SCPI, docs/instrument-scpi.md)."
)
SCENARIO_HELP = (
    "The specimen simulated: seed (the paper's 3-function model and eq (18) damping) "
    "or realistic (the exact beam, 6 lightly damped modes)."
)
SEED_HELP = "Random seed of the simulated hammer and noise: the same seed gives the same data."
#: A seed not given is a fresh random one, always printed (and recorded in a run), so
#: that two captures never repeat each other's hits unless asked to.
FRESH_SEED_HELP = "[default: a fresh random one{}]"
TIME_SCALE_HELP = (
    "Speed of simulated time: 1 = real time (a hit every 0.5-2 s), 0.1 = ten times faster, 0 = instant."
)

#: The simulator options of a command that drives a real analyzer or, with --sim, the simulator.
SimScenarioOption = Annotated[
    Scenario | None,
    typer.Option(
        show_default=False, help=f"Simulator only. {SCENARIO_HELP} [default: {DEFAULT_SCENARIO.value}]"
    ),
]
SimSeedOption = Annotated[
    int | None,
    typer.Option(
        metavar="<int>",
        help=f"Simulator only. {SEED_HELP} " + FRESH_SEED_HELP.format(" per capture, recorded in its run"),
    ),
]
SimTimeScaleOption = Annotated[
    float | None,
    typer.Option(
        metavar="<factor>", help=f"Simulator only. {TIME_SCALE_HELP} [default: {DEFAULT_TIME_SCALE:g}]"
    ),
]
SimHammerOption = Annotated[
    str | None,
    typer.Option(
        metavar="<k=v,...>", help="Simulator only: the simulated hammer, e.g. double_hit_probability=1."
    ),
]
SimModelOption = Annotated[
    SimModel | None,
    typer.Option(
        "--analyzer",
        metavar=MODEL_METAVAR,
        show_default=False,
        help="Simulator only: the analyzer model simulated [default: 35660A].",
    ),
]
#: Where the simulated hammer strikes and the simulated accelerometer sits on the beam.
ForceAtOption = Annotated[
    float | None,
    typer.Option(
        "--force-at",
        metavar="<metres>",
        show_default=False,
        help="Simulator only: where the hammer strikes, metres from the clamp "
        "(0 < x <= 0.7, the beam's length) [default: the tip].",
    ),
]
SensorAtOption = Annotated[
    float | None,
    typer.Option(
        "--sensor-at",
        metavar="<metres>",
        show_default=False,
        help="Simulator only: where the accelerometer sits, metres from the clamp "
        "(0 < x <= 0.7, the beam's length) [default: the tip].",
    ),
]
#: --analyzer's old spelling, hidden; the commands take it as given_once("--analyzer", ...).
OldSimModelOption = Annotated[
    SimModel | None, typer.Option("--model", hidden=True, help="Old name of --analyzer.")
]

# ------------------------------------------------------------ where work runs
JobsOption = Annotated[
    int | None, typer.Option(metavar="<n>", help="Worker processes [default: one per core].")
]
SchedulerOption = Annotated[
    str | None,
    typer.Option(
        metavar="<tcp://host:port>",
        show_default=False,
        help="Run on this Dask cluster instead of the local cores [default: $DAQ_SCHEDULER if set].",
    ),
]


# ------------------------------------------------ renamed options, for one release
# An old spelling is a hidden option beside the new one and does the same. Its note is
# held until the command is over: main() prints it on stderr after a command that
# succeeded, and adds it to the one line of a failure (a failure stays one line).
_notes: list[str] = []


def renamed(old: str, new: str) -> None:
    """Say (once the command is over) that option ``old`` is now ``new``."""
    note = f"{old} is now {new}; {old} will go in the next release"
    if note not in _notes:
        _notes.append(note)


def take_notes() -> list[str]:
    """The notes held so far, in order; none are held afterwards."""
    notes = list(_notes)
    _notes.clear()
    return notes


def given_once(new: str, new_value: object, old: str, old_value: object) -> object:
    """The value of option ``new`` when its old spelling ``old`` may have been given
    instead (None: not given). Both given is a usage error; ``old`` alone is noted."""
    if old_value is None:
        return new_value
    if new_value is not None:
        raise UserError(f"{old} is the old name of {new}: give {new} only", exit_code=2)
    renamed(old, new)
    return old_value


#: A multi-point test and its point (daq capture and daq import, docs/modal-tests.md).
TestOption = Annotated[
    str | None,
    typer.Option(metavar="<name>", help="Measure one point of this multi-point test (daq test new)."),
]
PointOption = Annotated[str | None, typer.Option(metavar="<name>", help="With --test: the point measured.")]
NextPointOption = Annotated[
    bool, typer.Option("--next", help="With --test: the first point without an accepted run.")
]

#: The identification's choices (daq analyze, daq test analyze/fit/report).
BandOption = Annotated[
    str | None,
    typer.Option(
        metavar="<low:high>",
        show_default=False,
        help="Identify modes in this band only, Hz [default: where the hammer put energy and the "
        "coherence is usable].",
    ),
]
FrequenciesOption = Annotated[
    str | None,
    typer.Option(metavar="<f1,f2,...>", help="Frequencies of interest, Hz (else found automatically)."),
]
MaxOrderOption = Annotated[
    int | None,
    typer.Option(
        metavar="<2-200>",
        show_default=False,
        help="LSCF model order of every frequency zone [default: each zone's, from its peaks].",
    ),
]
