"""One name per idea: the renamed options, and their old spellings kept hidden for one release.

    daq model --modes-n            -> --functions  (the number of Ritz functions, as daq fit)
    daq serve --workers            -> --jobs       (worker processes, as daq analyze and fit)
    --model 35670A (the analyzer)  -> --analyzer   (daq capture, serve, sim serve, sim commands;
                                                    "model" alone is the beam model, daq model)

The old spelling does what the new one does, and says so on stderr once the command is
over: a note after a command that succeeded, folded into the one line of a failure.
The new spelling says nothing.
"""

from __future__ import annotations

import json

import pytest

from daq.cli.commands import capture as capture_command
from daq.cli.commands import serve as serve_command
from tests.cli_helpers import assert_one_line_error, invoke_daq


def note(old: str, new: str) -> str:
    return f"daq: note: {old} is now {new}; {old} will go in the next release\n"


def folded(old: str, new: str) -> str:
    return f"(note: {old} is now {new}; {old} will go in the next release)"


# ----------------------------------------------------------------- daq model --modes-n
def test_model_modes_n_is_functions_with_a_note():
    new = invoke_daq("model", "--functions", "4", "--json")
    old = invoke_daq("model", "--modes-n", "4", "--json")
    assert new.returncode == old.returncode == 0, (new.stderr, old.stderr)
    assert old.stdout == new.stdout
    assert len(json.loads(new.stdout)["table2"]["rows"]) == 4
    assert new.stderr == ""
    assert old.stderr == note("--modes-n", "--functions")


def test_model_short_n_is_functions_and_says_nothing():
    short = invoke_daq("model", "-n", "4", "--json")
    assert short.returncode == 0
    assert short.stderr == ""
    assert short.stdout == invoke_daq("model", "--functions", "4", "--json").stdout


def test_model_help_names_functions_only():
    text = invoke_daq("model", "--help").stdout
    assert "--functions" in text
    assert "--modes-n" not in text


@pytest.mark.parametrize(
    ("args", "fragments", "noted"),
    [
        (("--functions", "0"), ("--functions must be between 1 and 60, got 0",), False),
        (("--modes-n", "0"), ("--modes-n must be between 1 and 60, got 0",), True),
        (("--modes-n", "three"), ("--modes-n",), False),  # a parse error: before the command runs
    ],
)
def test_model_bad_values_stay_one_line(args, fragments, noted):
    result = invoke_daq("model", *args)
    assert result.returncode == 2
    assert_one_line_error(result, *fragments)
    assert (folded("--modes-n", "--functions") in result.stderr) is noted


def test_model_both_spellings_is_a_usage_error():
    result = invoke_daq("model", "--functions", "4", "--modes-n", "4")
    assert_one_line_error(result, "--modes-n is the old name of --functions")
    assert result.returncode == 2


# ---------------------------------------------------------------- daq serve --workers
@pytest.fixture
def service_calls(monkeypatch, tmp_path):
    """run_service's arguments, recorded instead of serving."""
    calls: list[tuple[tuple, dict]] = []
    monkeypatch.setattr(serve_command, "run_service", lambda *a, **k: calls.append((a, k)))
    monkeypatch.setenv("DAQ_TOKEN_FILE", str(tmp_path / "token"))
    assert invoke_daq("serve", "--show-token").returncode == 0  # made now, not by the first call
    return calls


def test_serve_workers_is_jobs_with_a_note(service_calls, tmp_path):
    base = ("serve", "--sim", "--store", str(tmp_path / "store"))
    new = invoke_daq(*base, "--jobs", "2")
    old = invoke_daq(*base, "--workers", "2")
    assert new.returncode == old.returncode == 0, (new.stderr, old.stderr)
    assert new.stderr == ""
    assert old.stderr == note("--workers", "--jobs")
    assert service_calls[0] == service_calls[1]
    assert 2 in service_calls[0][0]  # the worker count reached the service


@pytest.mark.parametrize(("flag", "noted"), [("--jobs", False), ("--workers", True)])
def test_serve_bad_worker_count_stays_one_line(service_calls, tmp_path, flag, noted):
    result = invoke_daq("serve", "--sim", "--store", str(tmp_path / "store"), flag, "0")
    assert_one_line_error(result, f"{flag} must be at least 1")
    assert result.returncode == 2
    assert (folded("--workers", "--jobs") in result.stderr) is noted
    assert service_calls == []


def test_serve_help_names_jobs_and_analyzer_only():
    text = invoke_daq("serve", "--help").stdout
    assert "--jobs <n>" in text
    assert "Analysis worker processes [default: cores -" in text
    assert "--analyzer 35660A|3562A|35670A|35665A" in text
    assert "--workers" not in text
    assert "--model" not in text


# ------------------------------------------------------- the analyzer's model: --analyzer
def test_serve_model_is_analyzer_with_a_note(service_calls, tmp_path):
    base = ("serve", "--sim", "--store", str(tmp_path / "store"))
    new = invoke_daq(*base, "--analyzer", "35670A")
    old = invoke_daq(*base, "--model", "35670A")
    assert new.returncode == old.returncode == 0, (new.stderr, old.stderr)
    assert new.stderr == ""
    assert old.stderr == note("--model", "--analyzer")
    assert service_calls[0] == service_calls[1]
    assert service_calls[0][1]["model"] == "35670A"


@pytest.fixture
def capture_calls(monkeypatch):
    """run_capture's arguments, recorded instead of capturing."""
    calls: list[tuple[tuple, dict]] = []
    monkeypatch.setattr(capture_command, "run_capture", lambda *a, **k: calls.append((a, k)))
    return calls


def test_capture_model_is_analyzer_with_a_note(capture_calls, tmp_path):
    base = ("capture", "--sim", "--yes", "--hits", "2", "--store", str(tmp_path))
    new = invoke_daq(*base, "--analyzer", "3562A")
    old = invoke_daq(*base, "--model", "3562A")
    assert new.returncode == old.returncode == 0, (new.stderr, old.stderr)
    assert new.stderr == ""
    assert old.stderr == note("--model", "--analyzer")
    assert capture_calls[0] == capture_calls[1]
    assert capture_calls[0][1]["model"] == "3562A"


@pytest.mark.parametrize("flag", ["--analyzer", "--model"])
def test_capture_analyzer_without_sim_names_the_spelling_given(capture_calls, flag):
    result = invoke_daq("capture", "--resource", "TCPIP::192.0.2.1::5025::SOCKET", flag, "35670A")
    assert_one_line_error(result, f"{flag} only apply to the simulator")
    assert result.returncode == 2
    assert (folded("--model", "--analyzer") in result.stderr) is (flag == "--model")
    assert capture_calls == []


def test_capture_help_names_analyzer_only():
    text = invoke_daq("capture", "--help").stdout
    assert "--analyzer 35660A|3562A|35670A|35665A" in text
    assert "--model" not in text


def test_sim_commands_model_is_analyzer_with_a_note():
    new = invoke_daq("sim", "commands", "--analyzer", "35670A")
    old = invoke_daq("sim", "commands", "--model", "35670A")
    assert new.returncode == old.returncode == 0, (new.stderr, old.stderr)
    assert old.stdout == new.stdout
    assert "HP 35670A command set" in new.stdout
    assert new.stderr == ""
    assert old.stderr == note("--model", "--analyzer")


@pytest.mark.parametrize("command", ["serve", "commands"])
@pytest.mark.parametrize("flag", ["--analyzer", "--model"])
def test_sim_bad_analyzer_stays_one_line(command, flag):
    result = invoke_daq("sim", command, flag, "35661A")
    assert_one_line_error(result, flag, "35661A", "35670A")
    assert result.returncode == 2
    assert (folded("--model", "--analyzer") in result.stderr) is (flag == "--model")


@pytest.mark.parametrize("command", ["serve", "commands"])
def test_sim_help_names_analyzer_only(command):
    text = invoke_daq("sim", command, "--help").stdout
    assert "--analyzer 35660A|3562A|35670A|35665A" in text
    assert "--model" not in text


def test_sim_both_spellings_is_a_usage_error():
    result = invoke_daq("sim", "commands", "--analyzer", "35670A", "--model", "3562A")
    assert_one_line_error(result, "--model is the old name of --analyzer")
    assert result.returncode == 2
