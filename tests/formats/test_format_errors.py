"""FormatError is the formats layer's own error, and the command line still reports
it as one line ``daq: error: ...`` with exit status 1 (daq/cli/errors.py)."""

from __future__ import annotations

import pytest

from daq.cli.errors import UserError, exit_code_and_message
from daq.formats import FormatError
from daq.formats.csv_text import read_csv
from daq.store import Store, StoreError
from daq.workflows.errors import WorkflowError
from drivers.errors import ConnectionFailed
from tests.cli_helpers import assert_one_line_error, invoke_daq


def test_format_error_is_not_the_command_lines_error():
    assert not issubclass(FormatError, UserError)
    assert FormatError("x").exit_code == 1


def test_format_error_message_is_one_line():
    assert str(FormatError("a.csv:\n  line 2\tis  bad ")) == "a.csv: line 2 is bad"


def test_daq_import_of_a_bad_file_is_one_line_and_exit_status_1(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("t;F;a\n1.234,5;2;3\n")
    with pytest.raises(FormatError) as info:
        read_csv(path)
    store = tmp_path / "store"
    result = invoke_daq("import", str(path), "--store", str(store))
    assert result.returncode == 1
    assert_one_line_error(result, "line 2 column 1: '1.234,5' is not a number")
    assert result.stderr.startswith(f"daq: error: {info.value} (read as csv: detected: ")
    assert not store.exists() or Store(store).list() == []


@pytest.mark.parametrize(
    ("error", "expected"),
    [
        (FormatError("bad.csv: not a number"), (1, "bad.csv: not a number")),
        (StoreError("run 01ab:\nnot found"), (1, "run 01ab: not found")),
        (WorkflowError("no hits to replay"), (1, "no hits to replay")),
        (WorkflowError("bad --dialect", 2), (2, "bad --dialect")),
        (UserError("bad  --operator", 2), (2, "bad --operator")),
        (ConnectionFailed("no instrument at\nGPIB0::11"), (1, "no instrument at GPIB0::11")),
    ],
)
def test_the_command_lines_map_of_the_layers_errors(error, expected):
    assert exit_code_and_message(error) == expected


def test_anything_else_is_not_the_users_to_fix():
    assert exit_code_and_message(ValueError("a bug")) is None
    assert exit_code_and_message(KeyboardInterrupt()) is None
