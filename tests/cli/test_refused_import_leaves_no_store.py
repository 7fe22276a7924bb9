"""A refused import leaves nothing behind: not even the store folder it made before
reading the file (a new user found an empty store folder after each refusal)."""

from __future__ import annotations

from tests.cli_helpers import daq_import, runs_in


def _not_a_table(tmp_path):
    path = tmp_path / "notes.csv"
    path.write_text("just some words\nand more words\n", encoding="utf-8")
    return path


def test_a_refused_import_into_a_new_store_leaves_no_folder(tmp_path):
    store = tmp_path / "new" / "runs"
    result = daq_import(store, _not_a_table(tmp_path))
    assert result.returncode != 0
    assert len(result.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "new").exists()


def test_a_refused_import_keeps_a_store_that_was_there(tmp_path):
    store = tmp_path / "runs"
    store.mkdir()
    assert daq_import(store, _not_a_table(tmp_path)).returncode != 0
    assert store.is_dir()


def test_an_accepted_import_makes_its_store(tmp_path):
    path = tmp_path / "frf.csv"
    rows = "\n".join(f"{k},{1.0 / (1 + k)},{0.1 * k}" for k in range(1, 64))
    path.write_text("Frequency (Hz),Re (m/s^2/N),Im (m/s^2/N)\n" + rows + "\n", encoding="utf-8")
    store = tmp_path / "new" / "runs"
    result = daq_import(store, path)
    assert result.returncode == 0, result.stderr
    assert len(runs_in(store)) == 1
