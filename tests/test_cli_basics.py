from cli_helpers import DAQ, assert_one_line_error, run_daq

from daq import __version__


def test_console_script_is_installed():
    assert DAQ.exists()


def test_version():
    result = run_daq("--version")
    assert result.returncode == 0
    assert result.stdout.strip() == f"daq {__version__}"


def test_help_lists_the_model_command():
    result = run_daq("--help")
    assert result.returncode == 0
    assert "model" in result.stdout
    bare = run_daq()
    assert bare.returncode == 0
    assert "model" in bare.stdout


def test_unknown_command_is_one_line():
    assert_one_line_error(run_daq("frobnicate"), "No such command")
    assert run_daq("frobnicate").returncode == 2


def test_unknown_option_is_one_line():
    result = run_daq("model", "--bogus")
    assert_one_line_error(result, "--bogus")
    assert result.returncode == 2


def test_bad_option_value_is_one_line():
    assert_one_line_error(run_daq("model", "--modes-n", "three"), "--modes-n")
