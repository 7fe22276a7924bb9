"""Named setups in the store (daq/store/setups.py): round trip, versions and history,
version conflicts, bad files refused in one line naming the file and the field, and
the run listing and verify untouched by the setups folder and the transducer table."""

from __future__ import annotations

import pytest

from daq.store import Store, StoreError
from daq.store.setups import DEFAULT_DATA, SetupStore, VersionConflict
from daq.store.transducers import TransducerTable
from daq.store.verify import leftover_temporaries

DATA = {"span_hz": 400.0, "averages": 3, "hammer": {"transducer": "h-12", "range_v": 0.05}}


def test_a_setup_round_trips_and_keeps_every_version(tmp_path):
    setups = SetupStore(tmp_path)
    assert setups.names() == ["default"]
    first = setups.put("beam", DATA, expected_version=0)
    assert (first.name, first.version) == ("beam", 1)
    assert setups.get("beam").data == DATA
    second = setups.put("beam", {**DATA, "span_hz": 800.0}, expected_version=1)
    assert second.version == 2
    assert setups.get("beam").data["span_hz"] == 800.0
    assert setups.get("beam", version=1).data == DATA
    assert [s.version for s in setups.history("beam")] == [1, 2]
    assert (tmp_path / "setups" / ".history" / "beam.v1.toml").is_file()
    assert setups.names() == ["beam", "default"]
    assert setups.put("beam", {"span_hz": 100.0}).version == 3  # no expected version: no check


def test_a_save_from_an_old_version_is_a_conflict_and_writes_nothing(tmp_path):
    setups = SetupStore(tmp_path)
    setups.put("beam", DATA, expected_version=0)
    setups.put("beam", DATA, expected_version=1)
    with pytest.raises(VersionConflict, match="setup beam: version 1 was changed, but it is at version 2"):
        setups.put("beam", {"span_hz": 1.0}, expected_version=1)
    with pytest.raises(VersionConflict):
        setups.put("beam", DATA, expected_version=0)  # 0: must be new
    with pytest.raises(VersionConflict, match="does not exist yet"):
        setups.put("other", DATA, expected_version=3)
    assert setups.get("beam").version == 2
    assert issubclass(VersionConflict, StoreError)


def test_the_built_in_default_names_the_built_in_transducers(tmp_path):
    default = SetupStore(tmp_path).get("default")
    assert (default.version, default.data) == (0, DEFAULT_DATA)
    assert not (tmp_path / "setups").exists()  # nothing written for a built-in
    saved = SetupStore(tmp_path).put("default", {"span_hz": 100.0}, expected_version=0)
    assert saved.version == 1


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("span_hz = [1, 2]\n[saved]\nname = 'beam'\nversion = 1\nsaved_utc = 'x'\n", "span_hz: must be"),
        ("span_hz = 1.0\n", "[saved]: missing"),
        ("[saved]\nname = 'beam'\nversion = 'one'\nsaved_utc = 'x'\n", "saved.version: must be"),
        ("[saved]\nname = 'other'\nversion = 1\nsaved_utc = 'x'\n", "saved.name: names setup 'other'"),
        ("span_hz = \n", "not valid TOML"),
    ],
)
def test_a_bad_setup_file_is_refused_naming_the_file_and_field(tmp_path, text, fragment):
    folder = tmp_path / "setups"
    folder.mkdir()
    (folder / "beam.toml").write_text(text)
    with pytest.raises(StoreError) as info:
        SetupStore(tmp_path).get("beam")
    message = str(info.value)
    assert "\n" not in message
    assert str(folder / "beam.toml") in message
    assert fragment in message


@pytest.mark.parametrize(
    ("name", "data", "fragment"),
    [
        ("../x", DATA, "not a plain name"),
        (".hidden", DATA, "not a plain name"),
        ("beam.toml", DATA, "without .toml"),
        ("beam", {"span_hz": float("nan")}, "span_hz: must be a finite number"),
        ("beam", {"hammer": {"x": {"y": 1}}}, "hammer.x: must be"),
        ("beam", {"saved": {}}, "saved: a name the store keeps"),
        ("beam", [1], "must be a table"),
    ],
)
def test_bad_names_and_data_are_refused_before_anything_is_written(tmp_path, name, data, fragment):
    with pytest.raises(StoreError, match=None) as info:
        SetupStore(tmp_path).put(name, data)
    assert fragment in str(info.value)
    assert not (tmp_path / "setups" / "beam.toml").exists()


def test_an_unknown_setup_lists_the_known_ones(tmp_path):
    SetupStore(tmp_path).put("beam", DATA)
    with pytest.raises(StoreError, match=r"no setup 'plate' in .* \(known: beam, default\)"):
        SetupStore(tmp_path).get("plate")


def test_the_run_listing_and_verify_ignore_setups_and_transducers(tmp_path):
    from tests.cli_helpers import capture_sim

    store = tmp_path / "runs"
    run_id = capture_sim(store, "seed", 1, hits=2)
    SetupStore(store).put("beam", DATA)
    SetupStore(store).put("beam", DATA)
    from daq.store.transducers import Transducer

    TransducerTable(store).put(Transducer("h-12", "hammer", "PCB", "1", 2.3, "mV/N"))
    assert [s.run_id for s in Store(store).list()] == [run_id]
    assert all(not s.error for s in Store(store).list())
    assert leftover_temporaries(store, older_than_s=0) == []
