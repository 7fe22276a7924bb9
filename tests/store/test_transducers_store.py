"""The transducer table (daq/store/transducers.py): built-ins, units, round trip,
overdue calibrations and bad tables refused naming the file and the field."""

from __future__ import annotations

from datetime import date

import pytest

from daq.store import StoreError
from daq.store.transducers import Transducer, TransducerTable


def test_the_built_ins_are_there_without_a_file(tmp_path):
    table = TransducerTable(tmp_path)
    assert [t.id for t in table.all()] == ["accel-default", "hammer-default"]
    hammer = table.get("hammer-default")
    assert hammer.sensitivity_v_per_eu == pytest.approx(2.25e-3)
    assert table.get("accel-default").sensitivity_v_per_eu == pytest.approx(1.02e-3)
    assert not (tmp_path / "transducers.toml").exists()


@pytest.mark.parametrize(
    ("unit", "kind", "v_per_eu"),
    [
        ("mV/N", "hammer", 2e-3),
        ("V/N", "hammer", 2.0),
        ("mV/lbf", "hammer", 2e-3 / 4.4482216152605),
        ("mV/g", "accelerometer", 2e-3 / 9.80665),
        ("V/g", "accelerometer", 2 / 9.80665),
        ("mV/(m/s^2)", "accelerometer", 2e-3),
        ("V/(m/s^2)", "accelerometer", 2.0),
    ],
)
def test_every_unit_gives_volts_per_engineering_unit(unit, kind, v_per_eu):
    assert Transducer("t", kind, "m", "s", 2.0, unit).sensitivity_v_per_eu == pytest.approx(v_per_eu)


def test_a_transducer_round_trips_and_replaces_one_of_its_id(tmp_path):
    table = TransducerTable(tmp_path)
    h = Transducer("h-12", "hammer", 'PCB "086C03"', "SN 1", 2.31, "mV/N", "2025-01-10", "2026-01-10")
    table.put(h)
    assert TransducerTable(tmp_path).get("h-12") == h
    table.put(Transducer("h-12", "hammer", "PCB", "SN 1", 2.4, "mV/N"))
    assert table.get("h-12").sensitivity == 2.4
    table.put(Transducer("hammer-default", "hammer", "mine", "", 3.0, "mV/N"))  # overwrites the built-in
    assert table.get("hammer-default").model == "mine"
    assert [t.id for t in table.all()] == ["accel-default", "h-12", "hammer-default"]


def test_overdue_and_to_dict():
    h = Transducer("h-12", "hammer", "PCB", "1", 2.25, "mV/N", "2025-01-01", "2026-01-01")
    assert h.overdue(date(2026, 1, 2))
    assert not h.overdue(date(2026, 1, 1))
    d = h.to_dict(date(2026, 6, 1))
    assert d["overdue"] is True
    assert d["sensitivity_v_per_eu"] == pytest.approx(2.25e-3)
    assert Transducer.from_dict(d, "x") == h
    assert not Transducer("a", "hammer", "", "", 1.0, "mV/N").overdue(date(2099, 1, 1))


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"due": "2026-13-01"}, "transducer hammer-1: due: not a date YYYY-MM-DD"),
        ({"calibrated": 5}, "transducer hammer-1: calibrated: not a date YYYY-MM-DD"),
        ({"kind": "mic"}, "transducer hammer-1: kind: must be hammer or accelerometer"),
        (
            {"sensitivity_unit": "mV/g"},
            "transducer hammer-1: sensitivity_unit: mV/g is not a unit of a hammer",
        ),
        ({"sensitivity_unit": "pC/N"}, "transducer hammer-1: sensitivity_unit: must be one of"),
        ({"sensitivity": -1.0}, "transducer hammer-1: sensitivity: must be a positive number"),
        ({"sensitivity": True}, "transducer hammer-1: sensitivity: must be a positive number"),
        ({"id": "a b"}, "transducer hammer-1: id: 'a b' is not a plain name"),
        ({"colour": "red"}, "transducer hammer-1: colour: unknown field"),
        ({"calibrated": "2026-02-01", "due": "2026-01-01"}, "transducer hammer-1: due: 2026-01-01 is before"),
    ],
)
def test_bad_fields_are_named(fields, message):
    base = {"id": "hammer-1", "kind": "hammer", "model": "m", "serial": "s", "sensitivity": 2.25,
            "sensitivity_unit": "mV/N", "calibrated": "", "due": ""}  # fmt: skip
    with pytest.raises(StoreError) as info:
        Transducer.from_dict({**base, **fields}, "transducer hammer-1")
    assert str(info.value).startswith(message)


def test_a_bad_table_is_refused_naming_the_file_and_the_field(tmp_path):
    path = tmp_path / "transducers.toml"
    path.write_text(
        '[[transducer]]\nid = "h-1"\nkind = "hammer"\nsensitivity = 2.0\nsensitivity_unit = "mV/N"\n'
        "due = 2026-01-01\n"  # a TOML date is taken as the date it is
        '[[transducer]]\nid = "h-2"\nkind = "hammer"\nsensitivity = 2.0\nsensitivity_unit = "mV/N"\n'
        'due = "soon"\n'
    )
    with pytest.raises(StoreError) as info:
        TransducerTable(tmp_path).all()
    assert str(info.value) == f"{path}: transducer h-2: due: not a date YYYY-MM-DD ('soon')"
    with pytest.raises(StoreError, match="no transducer 'nope' \\(known: accel-default, hammer-default\\)"):
        TransducerTable(tmp_path / "empty").get("nope")


def test_a_kind_change_is_refused_while_a_setup_names_the_transducer_on_the_other_channel(tmp_path):
    from daq.store.setups import SetupStore

    table = TransducerTable(tmp_path)
    table.put(Transducer("a-7", "accelerometer", "PCB", "1", 10.0, "mV/g"))
    SetupStore(tmp_path).put("beam", {"accelerometer": {"transducer": "a-7"}})
    SetupStore(tmp_path).put("plate", {"accelerometer": {"transducer": "a-7"}})
    with pytest.raises(StoreError) as info:
        table.put(Transducer("a-7", "hammer", "PCB", "1", 2.25, "mV/N"))
    assert str(info.value).startswith(
        "transducer a-7: kind: a-7 is the accelerometer of setups beam, plate; it cannot become a hammer"
    )
    assert table.get("a-7").kind == "accelerometer"  # nothing written
    # The built-in default names accel-default as its accelerometer.
    with pytest.raises(StoreError, match="kind: accel-default is the accelerometer of setup default;"):
        table.put(Transducer("accel-default", "hammer", "", "", 2.25, "mV/N"))
    # The same kind replaces it; once no setup names it, the kind may change.
    table.put(Transducer("a-7", "accelerometer", "PCB", "2", 9.8, "mV/g"))
    SetupStore(tmp_path).put("beam", {"accelerometer": {"transducer": "accel-default"}})
    SetupStore(tmp_path).put("plate", {})
    assert table.put(Transducer("a-7", "hammer", "PCB", "1", 2.25, "mV/N")).kind == "hammer"


def test_a_calibration_date_in_the_future_is_refused(tmp_path):
    table = TransducerTable(tmp_path)
    future = Transducer("h-1", "hammer", "", "", 2.25, "mV/N", "2030-05-01")
    with pytest.raises(StoreError, match=r"^transducer h-1: calibrated: 2030-05-01 is in the future$"):
        table.put(future, today=date(2026, 1, 1))
    assert table.put(future, today=date(2030, 5, 1)) == future


def test_a_unit_of_the_other_kind_reads_as_english():
    with pytest.raises(StoreError, match="mV/N is not a unit of an accelerometer"):
        Transducer("a", "accelerometer", "", "", 2.25, "mV/N")
    with pytest.raises(StoreError, match="mV/g is not a unit of a hammer"):
        Transducer("h", "hammer", "", "", 10.0, "mV/g")


def test_the_built_ins_are_exactly_the_capture_defaults(tmp_path):
    from drivers.settings import ImpactSettings

    defaults = ImpactSettings()
    table = TransducerTable(tmp_path)
    assert table.get("hammer-default").sensitivity_v_per_eu == defaults.hammer.sensitivity_v_per_eu
    assert table.get("accel-default").sensitivity_v_per_eu == defaults.accelerometer.sensitivity_v_per_eu
