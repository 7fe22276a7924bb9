"""Setups for a capture (daq/workflows/setups.py): resolving a name or a file with its
transducers and cautions, refusals naming the field (check_setup_data,
validate_for_model), and a capture on the simulator whose sealed run holds the setup,
the transducers and the caution."""

from __future__ import annotations

from datetime import date

import pytest

from daq.store import open_run
from daq.store.setups import SetupStore
from daq.store.transducers import Transducer, TransducerTable
from daq.workflows.capture import Capture
from daq.workflows.connect import open_analyzer
from daq.workflows.errors import WorkflowError
from daq.workflows.setup_codec import settings_from_stored
from daq.workflows.setups import (
    check_setup_data,
    resolve_setup,
    save_setup,
    transducer_record,
    validate_for_model,
)
from drivers.settings import ChannelSetup, ImpactSettings, Window

OVERDUE = Transducer("h-12", "hammer", "PCB 086C03", "SN 4711", 2.31, "mV/N", "2025-01-01", "2026-01-01")
ACCEL = Transducer("a-3", "accelerometer", "PCB 352C23", "SN 9", 5.0, "mV/g", "2026-01-01", "2099-01-01")


def _store_with_setup(tmp_path):
    TransducerTable(tmp_path).put(OVERDUE)
    TransducerTable(tmp_path).put(ACCEL)
    data = {"span_hz": 200.0, "hammer": {"transducer": "h-12"}, "accelerometer": {"transducer": "a-3"}}
    SetupStore(tmp_path).put("beam", data, expected_version=0)
    return tmp_path


def test_a_named_setup_takes_its_transducers_sensitivities_and_cautions(tmp_path):
    store = _store_with_setup(tmp_path)
    resolved = resolve_setup(store, "beam", today=date(2026, 6, 1))
    assert (resolved.name, resolved.version) == ("beam", 1)
    assert resolved.settings.hammer.sensitivity_v_per_eu == pytest.approx(2.31e-3)
    assert resolved.settings.accelerometer.sensitivity_v_per_eu == pytest.approx(5e-3 / 9.80665)
    assert resolved.transducers == {"hammer": OVERDUE, "accelerometer": ACCEL}
    assert resolved.cautions == ["hammer transducer h-12 calibration was due 2026-01-01"]


def test_the_default_setup_is_the_capture_defaults_with_the_built_in_transducers(tmp_path):
    resolved = resolve_setup(tmp_path, "default")
    assert resolved.version == 0
    assert resolved.settings.hammer == ImpactSettings().hammer
    assert resolved.settings.accelerometer.sensitivity_v_per_eu == pytest.approx(1.02e-3, rel=1e-3)
    assert resolved.cautions == []


def test_a_toml_path_is_read_as_a_file(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text('span_hz = 400.0\n[hammer]\ntransducer = "hammer-default"\nrange_v = 0.05\n')
    resolved = resolve_setup(tmp_path, str(path))
    assert (resolved.name, resolved.version, resolved.settings.span_hz) == (str(path), 0, 400.0)
    assert resolved.transducers["hammer"].id == "hammer-default"


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"span_hz": -5.0}, "span_hz: must be a positive number, got -5.0"),
        ({"span_hz": "wide"}, "span_hz: must be a number, got 'wide'"),
        ({"span": 1}, "span: unknown key; known: span_hz"),
        (
            {"hammer": {"window": "BOX"}},
            "hammer.window: 'BOX' is not a window; one of UNIF, HANN, FLAT, FORC, EXPO",
        ),
        ({"hammer": {"range_v": "big"}}, 'hammer.range_v: must be a number or "auto"'),
        ({"hammer": 3}, "hammer: must be a table"),
        ({"hammer": {"sensitivity_v_per_eu": 0.0}}, "hammer.sensitivity_v_per_eu: must be a positive"),
        ({"hammer": {"transducer": "a b"}}, "hammer.transducer: 'a b' is not a plain name"),
    ],
)
def test_check_setup_data_names_the_field_first(data, message):
    with pytest.raises(WorkflowError) as info:
        check_setup_data(data)
    assert str(info.value).startswith(message)


def test_a_missing_or_misplaced_transducer_is_refused_naming_the_setup_and_field(tmp_path):
    SetupStore(tmp_path).put("a", {"hammer": {"transducer": "nope"}})
    with pytest.raises(WorkflowError, match=r"^setup a: hammer.transducer: no transducer 'nope' \(known: "):
        resolve_setup(tmp_path, "a")
    SetupStore(tmp_path).put("b", {"hammer": {"transducer": "accel-default"}})
    with pytest.raises(
        WorkflowError, match=r"^setup b: hammer\.transducer: accel-default is an accelerometer, not a hammer$"
    ):
        resolve_setup(tmp_path, "b")
    with pytest.raises(WorkflowError, match=r"^no setup 'c' in .* \(known: a, b, default\)"):
        resolve_setup(tmp_path, "c")


@pytest.mark.parametrize(
    ("settings", "model", "message"),
    [
        (ImpactSettings(lines=800), "35660A", "lines: the 35660A offers 400 lines only"),
        (ImpactSettings(lines=400), "3562A", "lines: the 3562A offers 800 lines only"),
        (ImpactSettings(lines=1600), "35665A", "lines: the 35665A offers 100, 200, 400, 800 lines, not 1600"),
        (ImpactSettings(span_hz=250_000.0), "35670A", "span_hz: 250000 Hz is above the 35670A's 51.2 kHz"),
        (
            ImpactSettings(span_hz=200_000.0),
            "HP 35660A",
            "span_hz: 200000 Hz is above the 35660A's 102.4 kHz",
        ),
        (
            ImpactSettings(span_hz=1000.0, center_hz=51_000.0),
            "35670A",
            "center_hz: a 1000 Hz band around 51000 Hz reaches above the 35670A's 51.2 kHz",
        ),
        (
            ImpactSettings(hammer=ChannelSetup(Window.FORCE, 2.25e-3, range_v=50.0), trigger_level_eu=1.0),
            "35660A",
            "hammer.range_v: 50 V is above the analyzer's largest range",
        ),
        (
            ImpactSettings(trigger_level_eu=1000.0),
            "35660A",
            "trigger_level_eu: 1000 N is above the hammer's range (8.89 N = 0.02 V / 2.25 mV/N)",
        ),
        (ImpactSettings(), "HP 1234A", "model: unknown analyzer 'HP 1234A'"),
    ],
)
def test_validate_for_model_refuses_what_the_analyzer_cannot_measure(settings, model, message):
    with pytest.raises(WorkflowError) as info:
        validate_for_model(settings, model)
    assert str(info.value).startswith(message)


@pytest.mark.parametrize("model", ["35660A", "3562A", "3563A", "35665A", "35670A", "HP 35670A"])
def test_the_defaults_suit_every_model(model):
    validate_for_model(ImpactSettings(), model)
    validate_for_model(
        ImpactSettings(span_hz=51_200.0, lines=None if "3562A" in model or "3563A" in model else 400), model
    )


def test_a_capture_with_a_named_setup_stores_setup_transducers_and_caution(tmp_path):
    store = _store_with_setup(tmp_path / "runs")
    resolved = resolve_setup(store, "beam")
    validate_for_model(resolved.settings, "35660A")
    with open_analyzer("sim", seed=1) as dsa:
        job = Capture(
            dsa, resolved.settings, 2, store_dir=store, transducers=resolved.transducers,
            setup_name=resolved.name, setup_version=resolved.version, cautions=resolved.cautions,
        )  # fmt: skip
        events = list(job)
        path = job.seal(events[-1].run)
    run = open_run(path)
    assert run.provenance["setup"] == {"name": "beam", "version": 1}
    assert run.provenance["cautions"] == ["hammer transducer h-12 calibration was due 2026-01-01"]
    hammer = run.instrument.settings["hammer"]
    assert hammer["transducer"]["serial"] == "SN 4711"
    assert hammer["transducer"]["calibration_date"] == "2025-01-01"
    assert hammer["transducer"]["due_date"] == "2026-01-01"
    assert hammer["transducer"]["overdue"] is True
    assert hammer["sensitivity_v_per_eu"] == pytest.approx(2.31e-3)
    assert run.instrument.settings["accelerometer"]["transducer"]["id"] == "a-3"
    # The stored settings still read back, the transducer records skipped.
    assert settings_from_stored(run.instrument.settings).hammer.sensitivity_v_per_eu == pytest.approx(2.31e-3)


def test_transducer_record_carries_what_the_report_reads():
    record = transducer_record({"hammer": OVERDUE}, today=date(2025, 6, 1))
    assert set(record["hammer"]) >= {
        "id", "model", "serial", "sensitivity", "sensitivity_unit", "calibration_date", "due_date", "overdue",
    }  # fmt: skip
    assert record["hammer"]["overdue"] is False


def test_save_setup_checks_data_transducers_and_model_before_writing(tmp_path):
    from daq.store.setups import VersionConflict
    from daq.workflows.setups import save_setup, setup_view

    with pytest.raises(WorkflowError, match=r"^hammer\.transducer: no transducer 'zz'"):
        save_setup(tmp_path, "beam", {"hammer": {"transducer": "zz"}}, 0)
    with pytest.raises(WorkflowError, match=r"^lines: the 35660A offers 400 lines only"):
        save_setup(tmp_path, "beam", {"lines": 800}, 0, model="HP 35660A")
    with pytest.raises(WorkflowError, match="not a plain name"):
        save_setup(tmp_path, "../x", {}, 0)
    assert SetupStore(tmp_path).names() == ["default"]
    resolved = save_setup(tmp_path, "beam", {"lines": 800}, 0, model="35670A")
    assert (resolved.name, resolved.version, resolved.settings.lines) == ("beam", 1, 800)
    with pytest.raises(VersionConflict):
        save_setup(tmp_path, "beam", {"lines": 400}, 0)
    view = setup_view(tmp_path, "beam")
    assert (view["version"], view["setup"], view["settings"]["lines"]) == (1, {"lines": 800}, 800)


def test_the_service_save_refuses_a_kind_change_that_would_break_a_setup(tmp_path):
    from daq.store.transducers import Transducer, TransducerTable
    from daq.workflows.station_setups import save_transducer

    TransducerTable(tmp_path).put(Transducer("a-7", "accelerometer", "", "", 10.0, "mV/g"))
    SetupStore(tmp_path).put("beam", {"accelerometer": {"transducer": "a-7"}})
    fields = {"kind": "hammer", "sensitivity": 2.25, "sensitivity_unit": "mV/N"}
    with pytest.raises(WorkflowError, match=r"^kind: a-7 is the accelerometer of setup beam; "):
        save_transducer(tmp_path, "a-7", fields)
    assert resolve_setup(tmp_path, "beam").transducers["accelerometer"].id == "a-7"


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"lines": 3}, "lines: no analyzer offers 3 lines; one of 100, 200, 400, 800, 1600"),
        (
            {"trigger_level_eu": 1000.0},
            "trigger_level_eu: 1000 N is above the hammer's range (8.89 N = 0.02 V / 2.25 mV/N)",
        ),
        (
            {"trigger_level_eu": -1000.0},
            "trigger_level_eu: -1000 N is beyond the hammer's range (±8.89 N = 0.02 V / 2.25 mV/N)",
        ),
        ({"span_hz": 250_000.0}, "span_hz: 250000 Hz is above the widest span of any analyzer (102.4 kHz"),
        ({"hammer": {"range_v": 50.0}}, "hammer.range_v: 50 V is above the largest range of any analyzer"),
    ],
)
def test_save_setup_refuses_what_no_model_could_measure_without_an_analyzer(tmp_path, data, message):
    with pytest.raises(WorkflowError) as info:
        save_setup(tmp_path, "beam", data)
    assert str(info.value).startswith(message)
    assert SetupStore(tmp_path).names() == ["default"]  # nothing written


def test_save_setup_takes_what_some_model_measures(tmp_path):
    for data in (
        {"lines": 1600},
        {"trigger_level_eu": -5.0},
        {"hammer": {"range_v": "auto"}, "trigger_level_eu": 1e3},
    ):
        save_setup(tmp_path, "beam", data)


def test_the_built_in_default_setup_is_exactly_the_capture_without_a_setup(tmp_path):
    assert resolve_setup(tmp_path, "default").settings == ImpactSettings()
