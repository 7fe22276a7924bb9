"""`daq setup show NAME` says which sensitivity counts when a channel names a transducer
(the file's sensitivity_v_per_eu is then not used)."""

from __future__ import annotations

import subprocess
import sys


def _daq(tmp_path, *args):
    env = {"DAQ_STORE": str(tmp_path / "store"), "DAQ_LOCK_DIR": str(tmp_path / "locks"),
           "DAQ_CONFIG": str(tmp_path / "none.toml"), "PATH": "/usr/bin:/bin"}  # fmt: skip
    return subprocess.run(
        [sys.executable, "-m", "daq", *args], capture_output=True, text=True, env=env, timeout=120
    )


def test_show_names_the_transducer_sensitivity_that_counts(tmp_path):
    added = _daq(
        tmp_path, "transducer", "add", "h-7", "--kind", "hammer", "--model", "M", "--serial", "7",
        "--sensitivity", "4.1 mV/N", "--calibrated", "2026-01-01", "--due", "2099-01-01",
    )  # fmt: skip
    assert added.returncode == 0, added.stderr
    setup = tmp_path / "s.toml"
    setup.write_text(
        'span_hz = 400.0\n[hammer]\nwindow = "FORC"\ntransducer = "h-7"\nsensitivity_v_per_eu = 0.00225\n'
    )
    assert _daq(tmp_path, "setup", "save", "w", "--from", str(setup)).returncode == 0
    shown = _daq(tmp_path, "setup", "show", "w")
    assert shown.returncode == 0, shown.stderr
    assert "# hammer: transducer h-7 sets the sensitivity to 4.1 mV/N (0.0041 V per EU)" in shown.stdout
    assert "# accelerometer:" not in shown.stdout
    assert "sensitivity_v_per_eu above is not used" in shown.stdout


def test_show_says_nothing_of_a_sensitivity_the_file_does_not_hold(tmp_path):
    setup = tmp_path / "s.toml"
    setup.write_text('[accelerometer]\ntransducer = "accel-default"\n')
    assert _daq(tmp_path, "setup", "save", "w", "--from", str(setup)).returncode == 0
    shown = _daq(tmp_path, "setup", "show", "w")
    assert shown.returncode == 0, shown.stderr
    line = next(line for line in shown.stdout.splitlines() if line.startswith("# accelerometer:"))
    assert line == (
        "# accelerometer: transducer accel-default sets the sensitivity to 1.02 mV/(m/s^2) (0.00102 V per EU)"
    )
