"""`daq serve --undo-window`: the seconds a page decision is held for Undo, given on the
command line; wins over $DAQ_UNDO_WINDOW_S; out-of-range values refused in one line."""

from __future__ import annotations

import subprocess

import pytest

from tests.service.service_helpers import DAQ, service_env, serving

pytestmark = pytest.mark.slow


def test_the_option_sets_the_window_the_service_reports(tmp_path, monkeypatch):
    monkeypatch.setenv("DAQ_UNDO_WINDOW_S", "9")
    with serving(tmp_path, "--sim", "--time-scale", "0", "--undo-window", "0.7") as served:
        assert served.get("/api/capture").json()["undo_window_s"] == pytest.approx(0.7)


@pytest.mark.parametrize("value", ["-1", "61", "nan"])
def test_an_impossible_window_is_one_line_and_exit_2(tmp_path, value):
    done = subprocess.run(
        [str(DAQ), "serve", "--sim", "--port", "0", "--store", str(tmp_path / "s"), "--undo-window", value],
        capture_output=True, text=True, env=service_env(tmp_path), timeout=60,
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert "--undo-window" in lines[0], done.stderr
