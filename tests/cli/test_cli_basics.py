"""The `daq` command line's contract: help, version, one-line errors, exit statuses.

The real console script runs where only a process shows the behaviour (the
entry point, the exit status a shell sees, Ctrl-C); the rest runs in-process.
"""

import os
import signal
import socket
import subprocess
import time

import pytest
import typer

from daq import __version__
from daq.cli.app import app, help_hint
from tests.cli_helpers import DAQ, ENV, assert_one_line_error, invoke_daq, run_daq

#: Every command and group, as typed after `daq`.
COMMANDS = [(), ("model",), ("sim",), ("sim", "serve"), ("sim", "commands"), ("instruments",)]
COMMANDS += [("identify",), ("send",), ("query",), ("demo",), ("config",), ("capture",)]
COMMANDS += [("runs",), ("runs", "list"), ("runs", "show"), ("runs", "verify")]


# ------------------------------------------------------------ real process
def test_console_script_version():
    assert DAQ.exists()
    result = run_daq("--version")
    assert result.returncode == 0
    assert result.stdout == f"daq {__version__}\n"


def test_console_script_bare_prints_help_and_usage_error_exits_2():
    bare = run_daq()
    assert bare.returncode == 0, bare.stderr
    assert bare.stdout.startswith("Usage: daq [OPTIONS] COMMAND")
    result = run_daq("model", "--bogus")
    assert_one_line_error(result, "--bogus")
    assert result.returncode == 2


@pytest.mark.timeout(30)
def test_ctrl_c_is_one_line_and_exit_130(tmp_path):
    """Typer turns Ctrl-C inside a command into a silent exit 130; daq says so in one line."""
    # An "instrument" that accepts the connection and never answers: daq waits on it.
    with socket.create_server(("127.0.0.1", 0)) as silent:
        silent.settimeout(20)
        resource = f"TCPIP::127.0.0.1::{silent.getsockname()[1]}::SOCKET"
        proc = subprocess.Popen(
            [str(DAQ), "identify", "-r", resource, "--timeout", "20"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env={**os.environ, **ENV, "DAQ_LOCK_DIR": str(tmp_path)},
            # A child of a shell that ignores SIGINT would inherit that.
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        try:
            conn, _ = silent.accept()
            with conn:
                time.sleep(0.3)  # into the wait for the reply to ID?
                proc.send_signal(signal.SIGINT)
                out, err = proc.communicate(timeout=10)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.communicate(timeout=5)
    assert (proc.returncode, out, err) == (130, "", "daq: error: interrupted\n")


# -------------------------------------------------------------- in-process
def test_help_lists_every_command():
    for result in (invoke_daq("--help"), invoke_daq("-h"), invoke_daq()):
        assert result.returncode == 0, result.stderr
        assert result.stderr == ""
        for name in ("model", "sim", "instruments", "identify", "send", "query", "demo", "config", "runs"):
            assert f"\n  {name} " in result.stdout
    sim = invoke_daq("sim")
    assert sim.returncode == 0
    assert "serve" in sim.stdout
    assert "commands" in sim.stdout


@pytest.mark.parametrize("words", COMMANDS, ids=lambda w: " ".join(w) or "daq")
def test_help_reads_well(words):
    """What a newcomer stumbled on: flags shown as taking a <bool>, summaries cut
    mid-sentence, a required resource that an environment variable also gives."""
    result = invoke_daq(*words, "--help")
    assert result.returncode == 0, result.stderr
    text = result.stdout
    assert "<bool>" not in text
    assert "<str>" not in text.split("Options:")[-1]  # options name what they take
    assert "Default: $" not in text  # [env var: ...] says it once
    commands = text.partition("\nCommands:\n")[2]
    for line in commands.splitlines():
        assert line.rstrip().endswith("."), f"summary cut short: {line!r}"


def test_version_flag_takes_no_value():
    result = invoke_daq("--version", "model")  # eager: prints, exits before `model`
    assert result.stdout == f"daq {__version__}\n"
    assert result.returncode == 0


def test_unknown_command_is_one_line():
    result = invoke_daq("frobnicate")
    assert_one_line_error(result, "No such command", "(see 'daq --help')")
    assert result.returncode == 2


def test_usage_errors_point_at_the_commands_help():
    """Fails loudly if typer stops giving its usage errors the command's context
    (daq.cli.app.help_hint reads it through getattr, typer exporting no UsageError)."""
    result = invoke_daq("sim", "serve", "--bogus")
    assert_one_line_error(result, "--bogus", "(see 'daq sim serve --help')")
    assert result.returncode == 2
    with pytest.raises(typer.TyperException) as caught:
        typer.main.get_command(app).main(["model", "--bogus"], prog_name="daq", standalone_mode=False)
    assert caught.value.exit_code == 2
    assert help_hint(caught.value) == " (see 'daq model --help')"
    assert help_hint(typer.TyperException("not a usage error")) == ""


def test_bad_option_value_is_one_line():
    result = invoke_daq("model", "--modes-n", "three")
    assert_one_line_error(result, "--modes-n", "(see 'daq model --help')")
    assert result.returncode == 2


def test_verbose_logs_to_stderr_and_quiet_does_not():
    loud = invoke_daq("-vv", "identify", "-r", "sim")
    assert loud.returncode == 0, loud.stderr
    assert "drivers.wire DEBUG sim -> b'ID?'" in loud.stderr
    quiet = invoke_daq("identify", "-r", "sim")
    assert quiet.stderr == ""
    assert quiet.stdout.splitlines()[0] == "HP35660A at sim"


def test_interrupt_inside_a_command_is_one_line(monkeypatch):
    def interrupted():
        raise KeyboardInterrupt

    monkeypatch.setattr("drivers.resources.list_resources", interrupted)
    result = invoke_daq("instruments")
    assert_one_line_error(result, "interrupted")
    assert result.returncode == 130


def test_internal_errors_are_one_line_with_exit_70(monkeypatch):
    def broken():
        raise ZeroDivisionError("oops")

    monkeypatch.setattr("drivers.resources.list_resources", broken)
    result = invoke_daq("instruments")
    assert_one_line_error(result, "internal error: ZeroDivisionError: oops", "DAQ_DEBUG=1")
    assert result.returncode == 70
