"""The exact bytes the driver sends for each operation (docs/instrument.md, the
command table in drivers/commands.py), written out by hand.

Every test runs its script in ``expected(...)``, which fails the test if an
exchange of the script did not happen. The dumps are in test_protocol_dumps.py.
"""

import pytest

from drivers.errors import ConnectionLost, InstrumentError, InstrumentTimeout, ProtocolError
from drivers.settings import ChannelSetup, ImpactSettings, Window
from tests.drivers.expected_protocol import expected, link_lost

NO_ERROR = b'0,"No error"\r\n'


def test_identify_reset_status():
    with expected([(b"ID?", b"HP35660A\r\n"), (b"RST", None), (b"STA?", b"34\r\n")]) as dsa:
        assert dsa.identify() == "HP35660A"
        dsa.reset()
        status = dsa.status()
    assert status.hit_pending
    assert status.waiting_for_trigger
    assert not status.done


def test_a_missing_exchange_fails_the_script():
    script = [(b"ID?", b"HP35660A\r\n"), (b"RST", None)]
    with pytest.raises(AssertionError, match="only 1 of 2 steps happened"), expected(script) as dsa:
        dsa.identify()


def test_errors_drain_the_queue_and_check_raises_the_oldest():
    steps = [
        (b"ERR?", b'1,"Undefined command: FOO"\r\n'),
        (b"ERR?", b'2,"Parameter out of range: FRS 1 MHZ"\r\n'),
        (b"ERR?", NO_ERROR),
    ]
    with (
        expected(steps) as dsa,
        pytest.raises(InstrumentError, match=r"instrument error 1: Undefined command: FOO \(and 1 more\)"),
    ):
        dsa.check_errors()


def test_after_a_timeout_the_probe_is_id_and_the_error_queue_is_left_alone():
    """FRS? goes unanswered once: the driver clears, asks ID? (answered: the
    instrument is alive) and asks FRS? again. It never sends ERR?, which would pop
    an error queued by someone else's command and blame this query for it."""
    steps = [(b"FRS?", None), (b"ID?", b"HP35660A\r\n"), (b"FRS?", b"+2.000000000E+02\r\n")]
    with expected(steps, retries=1) as dsa:
        assert dsa.read("FRS") == 200.0


def test_a_silent_instrument_is_reported_after_one_probe():
    with (
        expected([(b"FRS?", None), (b"ID?", None)], retries=3) as dsa,
        pytest.raises(InstrumentTimeout, match=r"answers nothing, not even ID\?") as caught,
    ):
        dsa.query("FRS?")
    assert caught.value.instrument_answers is False


def test_set_and_read_spell_and_parse_by_the_table():
    steps = [
        (b"FRS 200 HZ", None),
        (b"TDLY -0.02 S", None),
        (b"RNG1 0.5 V", None),
        (b"NAVG 12", None),
        (b"PRVW 1", None),
        (b"WIN2 HANN", None),
        (b"FRS?", b"+2.000000000E+02\r\n"),
        (b"NAVG?", b"12\r\n"),
        (b"PRVW?", b"1\r\n"),
        (b"WIN2?", b"HANN\r\n"),
        (b"AVMD?", b"STBL\r\n"),
    ]
    with expected(steps) as dsa:
        dsa.set("FRS", 200.0)
        dsa.set("TDLY", -0.02)
        dsa.set("RNG1", 0.5)
        dsa.set("NAVG", 12)
        dsa.set("PRVW", True)
        dsa.set("WIN2", "HANN")
        assert dsa.read("FRS") == 200.0
        assert dsa.read("NAVG") == 12
        assert dsa.read("PRVW") is True
        assert dsa.read("WIN2") == "HANN"
        assert dsa.read("AVMD?") == "STBL"


@pytest.mark.parametrize(
    ("mnemonic", "value", "message"),
    [
        ("WIN1", "BOXCAR", "WIN1 takes one of UNIF, HANN, FLAT, FORC, EXPO"),
        ("NAVG", 2.5, "NAVG takes an integer"),
        ("NAVG", 0, "NAVG takes 1 to 9999"),
        ("FRS", 200e3, "FRS takes 0.001 to 102400 HZ"),
        ("FRS", float("nan"), "FRS takes"),
        ("FRS", "wide", "FRS takes a number"),
        ("C1AC", 2, "C1AC takes 0 or 1"),
        ("STBL", 1, "STBL takes no argument"),
    ],
)
def test_bad_arguments_are_refused_before_anything_is_sent(mnemonic, value, message):
    with expected([]) as dsa, pytest.raises(ValueError, match=message):
        dsa.set(mnemonic, value)


@pytest.mark.parametrize(
    ("mnemonic", "reply", "reason"),
    [("AVMD?", b"MEAN", "expected one of STBL, AVOF"), ("NAVG", b"2.5", "integer"), ("PRVW", b"2", "0 or 1")],
)
def test_a_reply_the_table_does_not_allow_is_a_protocol_error(mnemonic, reply, reason):
    query = mnemonic if mnemonic.endswith("?") else mnemonic + "?"
    with (
        expected([(query.encode(), reply + b"\r\n")], retries=0) as dsa,
        pytest.raises(ProtocolError, match=reason),
    ):
        dsa.read(mnemonic)


DEFAULT_CONFIGURE = [
    (b"CLER", None),  # errors left by earlier commands are not these settings' fault
    (b"FRQR", None),
    (b"LNRS", None),
    (b"FRS 200 HZ", None),
    (b"ERR?", NO_ERROR),
    # The analyzer rounds the span up: the driver asks which span it chose and
    # centres a baseband measurement on half of that.
    (b"FRS?", b"+2.000000000E+02\r\n"),
    (b"CF 100 HZ", None),
    # Windows and pre-trigger the settings leave open are sized to the 2 s record
    # (docs/instrument.md, "Impact defaults"): force window 1/16, exponential 1/6,
    # pre-trigger 1/32 of it.
    (b"WIN1 FORC", None),
    (b"FWD1 0.125 S", None),
    (b"EXD1 0.333333333333 S", None),
    (b"SNS1 0.00225 V", None),
    (b"C1AC 0", None),
    (b"RNG1 0.02 V", None),
    (b"WIN2 EXPO", None),
    (b"FWD2 0.125 S", None),
    (b"EXD2 0.333333333333 S", None),
    (b"SNS2 0.00102 V", None),
    (b"C2AC 0", None),
    (b"RNG2 1 V", None),
    (b"TSRC CH1", None),
    (b"TLVL 0.00225 V", None),
    (b"TSLP POS", None),
    (b"TDLY -0.0625 S", None),
    (b"NAVG 5", None),
    (b"STBL", None),
    (b"PRVW 1", None),
    (b"ERR?", NO_ERROR),
]

READ_BACK = [
    (b"FRS?", b"+2.000000000E+02\r\n"),
    (b"CF?", b"+1.000000000E+02\r\n"),
    (b"WIN1?", b"FORC\r\n"),
    (b"SNS1?", b"+2.250000000E-03\r\n"),
    (b"AU1?", b"0\r\n"),
    (b"RNG1?", b"+2.238721139E-02\r\n"),
    (b"FWD1?", b"+1.250000000E-01\r\n"),
    (b"EXD1?", b"+3.333333333E-01\r\n"),
    (b"C1AC?", b"0\r\n"),
    (b"WIN2?", b"EXPO\r\n"),
    (b"SNS2?", b"+1.020000000E-03\r\n"),
    (b"AU2?", b"0\r\n"),
    (b"RNG2?", b"+1.000000000E+00\r\n"),
    (b"FWD2?", b"+1.250000000E-01\r\n"),
    (b"EXD2?", b"+3.333333333E-01\r\n"),
    (b"C2AC?", b"0\r\n"),
    (b"TSRC?", b"CH1\r\n"),
    (b"TLVL?", b"+2.250000000E-03\r\n"),
    (b"AVMD?", b"STBL\r\n"),
    (b"TSLP?", b"POS\r\n"),
    (b"TDLY?", b"-6.250000000E-02\r\n"),
    (b"NAVG?", b"5\r\n"),
    (b"PRVW?", b"1\r\n"),
]


def test_configure_sends_every_setting_then_reads_them_back():
    with expected(DEFAULT_CONFIGURE + READ_BACK) as dsa:
        actual = dsa.configure(ImpactSettings())
    assert actual.span_hz == 200.0
    assert actual.center_hz is None
    assert actual.hammer.range_v == pytest.approx(10 ** (-33 / 20), rel=1e-9)  # 20 mV -> -33 dBV
    assert actual.accelerometer.window is Window.EXPONENTIAL
    assert actual.trigger_level_eu == pytest.approx(1.0)
    assert actual.pre_trigger_s == pytest.approx(2.0 / 32)
    assert actual.hammer.force_width_s == pytest.approx(2.0 / 16)
    assert actual.accelerometer.exp_decay_s == pytest.approx(2.0 / 6, rel=1e-9)
    assert actual.averages == 5
    assert actual.preview is True


def test_configure_autorange_zoom_and_ac_coupling():
    settings = ImpactSettings(
        span_hz=12.5,
        center_hz=36.0,
        hammer=ChannelSetup(Window.FORCE, 2.25e-3, range_v=None, ac_coupled=True),
        trigger_source="CH2",
        trigger_level_eu=10.0,
        trigger_slope="NEG",
        pre_trigger_s=0.0,
        averages=1,
        preview=False,
    )
    sent = [
        (b"CLER", None),
        (b"FRQR", None),
        (b"LNRS", None),
        (b"FRS 12.5 HZ", None),
        (b"ERR?", NO_ERROR),
        (b"FRS?", b"+1.250000000E+01\r\n"),
        (b"CF 36 HZ", None),
        (b"WIN1 FORC", None),
        (b"FWD1 2 S", None),  # 1/16 of the 32 s record
        (b"EXD1 5.33333333333 S", None),  # 1/6 of it
        (b"SNS1 0.00225 V", None),
        (b"C1AC 1", None),
        (b"AU1", None),
        (b"WIN2 EXPO", None),
        (b"FWD2 2 S", None),
        (b"EXD2 5.33333333333 S", None),
        (b"SNS2 0.00102 V", None),
        (b"C2AC 0", None),
        (b"RNG2 1 V", None),
        (b"TSRC CH2", None),
        (b"TLVL 0.0102 V", None),
        (b"TSLP NEG", None),
        (b"TDLY 0 S", None),
        (b"NAVG 1", None),
        (b"STBL", None),
        (b"PRVW 0", None),
        (b"ERR?", NO_ERROR),
    ]
    read_back = [
        (b"FRS?", b"+1.250000000E+01\r\n"),
        (b"CF?", b"+3.600000000E+01\r\n"),
        (b"WIN1?", b"FORC\r\n"),
        (b"SNS1?", b"+2.250000000E-03\r\n"),
        (b"AU1?", b"1\r\n"),  # autorange: no RNG1? asked
        (b"FWD1?", b"+2.000000000E+00\r\n"),
        (b"EXD1?", b"+5.333333333E+00\r\n"),
        (b"C1AC?", b"1\r\n"),
        (b"WIN2?", b"EXPO\r\n"),
        (b"SNS2?", b"+1.020000000E-03\r\n"),
        (b"AU2?", b"0\r\n"),
        (b"RNG2?", b"+1.000000000E+00\r\n"),
        (b"FWD2?", b"+2.000000000E+00\r\n"),
        (b"EXD2?", b"+5.333333333E+00\r\n"),
        (b"C2AC?", b"0\r\n"),
        (b"TSRC?", b"CH2\r\n"),
        (b"TLVL?", b"+1.020000000E-02\r\n"),
        (b"AVMD?", b"STBL\r\n"),
        (b"TSLP?", b"NEG\r\n"),
        (b"TDLY?", b"+0.000000000E+00\r\n"),
        (b"NAVG?", b"1\r\n"),
        (b"PRVW?", b"0\r\n"),
    ]
    with expected(sent + read_back) as dsa:
        actual = dsa.configure(settings)
    assert actual.center_hz == 36.0
    assert actual.hammer.range_v is None
    assert actual.hammer.ac_coupled is True
    assert actual.trigger_source == "CH2"
    assert actual.trigger_level_eu == pytest.approx(10.0)  # 10.2 mV at 1.02 mV per m/s^2
    assert actual.trigger_slope == "NEG"
    assert actual.pre_trigger_s == 0.0
    assert actual.preview is False


def test_configure_refused_by_the_instrument_raises():
    refused = b'2,"Parameter out of range: TDLY -0.0625 S"\r\n'
    steps = [*DEFAULT_CONFIGURE[:-1], (b"ERR?", refused), (b"ERR?", NO_ERROR)]
    with (
        expected(steps) as dsa,
        pytest.raises(InstrumentError, match=r"instrument error 2: Parameter out of range: TDLY -0.0625 S$"),
    ):
        dsa.configure(ImpactSettings())


def test_start_accept_reject():
    steps = [
        (b"FRS?", b"+2.000000000E+02\r\n"),
        (b"STRT", None),
        (b"STA?", b"2\r\n"),
        (b"ACPT", None),
        (b"STA?", b"2\r\n"),
        (b"RJCT", None),
        (b"STA?", b"2\r\n"),
    ]
    with expected(steps) as dsa:
        dsa.start()
        dsa.accept()
        dsa.reject()


def test_start_refused_raises_the_instrument_error():
    steps = [
        (b"FRS?", b"+2.000000000E+02\r\n"),
        (b"STRT", None),
        (b"STA?", b"16\r\n"),
        (b"ERR?", b'7,"Hardware fault: input A/D converter does not respond"\r\n'),
        (b"ERR?", NO_ERROR),
    ]
    with expected(steps) as dsa, pytest.raises(InstrumentError) as info:
        dsa.start()
    assert info.value.code == 7


def test_accept_is_never_repeated():
    # A lost ACPT may or may not have reached the instrument: repeating it could put
    # a hit in the average twice. The driver reports instead.
    dsa = link_lost(retries=3)
    with pytest.raises(ConnectionLost, match=r"link lost$"):
        dsa.accept()


def test_settings_validation():
    with pytest.raises(ValueError, match="pre_trigger_s"):
        ImpactSettings(span_hz=200.0, pre_trigger_s=3.0)
    with pytest.raises(ValueError, match="center_hz"):
        ImpactSettings(span_hz=200.0, center_hz=50.0)
    with pytest.raises(ValueError, match="averages"):
        ImpactSettings(averages=0)
    with pytest.raises(ValueError, match="sensitivity"):
        ChannelSetup(Window.FORCE, 0.0)
    with pytest.raises(ValueError, match="BOXCAR"):
        ChannelSetup("BOXCAR", 1.0)  # type: ignore[arg-type]


def test_a_query_the_instrument_will_not_answer_points_to_its_error_queue():
    """ID? is answered after each timed-out attempt: the instrument lives but does not
    answer this query, so the error says where the reason is, without fetching it."""
    steps = [(b"FRS?", None), (b"ID?", b"HP35660A\r\n"), (b"FRS?", None)]
    with (
        expected(steps, retries=1) as dsa,
        pytest.raises(InstrumentTimeout, match=r"it answers ID\?, errors\(\)") as caught,
    ):
        dsa.query("FRS?")
    assert caught.value.instrument_answers is True
