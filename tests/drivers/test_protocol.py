"""The exact bytes the driver sends for each operation (DESIGN.md section 4, the
command table in drivers/commands.py), written out by hand."""

import struct

import numpy as np
import pytest
from expected_protocol import ExpectedProtocol

from drivers.errors import InstrumentError, ProtocolError
from drivers.hp35660a import HP35660A
from drivers.settings import ChannelSetup, ImpactSettings, Window

NO_ERROR = b'0,"No error"\r\n'


def driver(steps, **kwargs):
    transport = ExpectedProtocol(steps)
    return HP35660A(transport, **kwargs), transport


def test_identify_reset_status():
    dsa, t = driver([(b"ID?", b"HP35660A\r\n"), (b"RST", None), (b"STA?", b"34\r\n")])
    assert dsa.identify() == "HP35660A"
    dsa.reset()
    status = dsa.status()
    assert status.hit_pending
    assert status.waiting_for_trigger
    assert not status.done
    t.done()


def test_errors_drain_the_queue_and_check_raises_the_oldest():
    dsa, t = driver(
        [
            (b"ERR?", b'1,"Undefined command: FOO"\r\n'),
            (b"ERR?", b'2,"Parameter out of range: FRS 1 MHZ"\r\n'),
            (b"ERR?", NO_ERROR),
        ]
    )
    with pytest.raises(InstrumentError, match=r"instrument error 1: Undefined command: FOO \(and 1 more\)"):
        dsa.check_errors()
    t.done()


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
    (b"WIN1 FORC", None),
    (b"FWD1 0.05 S", None),
    (b"EXD1 1 S", None),
    (b"SNS1 0.00225 V", None),
    (b"C1AC 0", None),
    (b"RNG1 0.02 V", None),
    (b"WIN2 EXPO", None),
    (b"FWD2 0.05 S", None),
    (b"EXD2 0.5 S", None),
    (b"SNS2 0.00102 V", None),
    (b"C2AC 0", None),
    (b"RNG2 1 V", None),
    (b"TSRC CH1", None),
    (b"TLVL 0.00225 V", None),
    (b"TSLP POS", None),
    (b"TDLY -0.02 S", None),
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
    (b"FWD1?", b"+5.000000000E-02\r\n"),
    (b"EXD1?", b"+1.000000000E+00\r\n"),
    (b"C1AC?", b"0\r\n"),
    (b"WIN2?", b"EXPO\r\n"),
    (b"SNS2?", b"+1.020000000E-03\r\n"),
    (b"AU2?", b"0\r\n"),
    (b"RNG2?", b"+1.000000000E+00\r\n"),
    (b"FWD2?", b"+5.000000000E-02\r\n"),
    (b"EXD2?", b"+5.000000000E-01\r\n"),
    (b"C2AC?", b"0\r\n"),
    (b"TSRC?", b"CH1\r\n"),
    (b"TLVL?", b"+2.250000000E-03\r\n"),
    (b"AVMD?", b"STBL\r\n"),
    (b"TSLP?", b"POS\r\n"),
    (b"TDLY?", b"-2.000000000E-02\r\n"),
    (b"NAVG?", b"5\r\n"),
    (b"PRVW?", b"1\r\n"),
]


def test_configure_sends_every_setting_then_reads_them_back():
    dsa, t = driver(DEFAULT_CONFIGURE + READ_BACK)
    actual = dsa.configure(ImpactSettings())
    t.done()
    assert actual.span_hz == 200.0
    assert actual.center_hz is None
    assert actual.hammer.range_v == pytest.approx(10 ** (-33 / 20), rel=1e-9)  # 20 mV -> -33 dBV
    assert actual.accelerometer.window is Window.EXPONENTIAL
    assert actual.trigger_level_eu == pytest.approx(1.0)
    assert actual.pre_trigger_s == pytest.approx(0.02)
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
    sent = [step[0] for step in DEFAULT_CONFIGURE if step[0] not in (b"CLER", b"ERR?", b"FRS?")]
    expected = [*sent[:2], b"FRS 12.5 HZ", b"CF 36 HZ"]
    expected += [b"WIN1 FORC", b"FWD1 0.05 S", b"EXD1 1 S", b"SNS1 0.00225 V", b"C1AC 1", b"AU1"]
    expected += sent[10:16]
    expected += [b"TSRC CH2", b"TLVL 0.0102 V", b"TSLP NEG", b"TDLY 0 S", b"NAVG 1", b"STBL", b"PRVW 0"]
    assert settings.commands() == expected


def test_configure_refused_by_the_instrument_raises():
    refused = b'2,"Parameter out of range: TDLY -0.02 S"\r\n'
    steps = [*DEFAULT_CONFIGURE[:-1], (b"ERR?", refused), (b"ERR?", NO_ERROR)]
    dsa, t = driver(steps)
    with pytest.raises(InstrumentError, match=r"instrument error 2: Parameter out of range: TDLY -0.02 S$"):
        dsa.configure(ImpactSettings())
    t.done()


def test_start_accept_reject():
    dsa, t = driver(
        [
            (b"FRS?", b"+2.000000000E+02\r\n"),
            (b"STRT", None),
            (b"STA?", b"2\r\n"),
            (b"ACPT", None),
            (b"STA?", b"2\r\n"),
            (b"RJCT", None),
            (b"STA?", b"2\r\n"),
        ]
    )
    dsa.start()
    dsa.accept()
    dsa.reject()
    t.done()


def test_start_refused_raises_the_instrument_error():
    dsa, t = driver(
        [
            (b"FRS?", b"+2.000000000E+02\r\n"),
            (b"STRT", None),
            (b"STA?", b"16\r\n"),
            (b"ERR?", b'7,"Hardware fault: input A/D converter does not respond"\r\n'),
            (b"ERR?", NO_ERROR),
        ]
    )
    with pytest.raises(InstrumentError) as info:
        dsa.start()
    assert info.value.code == 7
    t.done()


def _block(values):
    payload = struct.pack(f">{len(values)}d", *values)
    return b"#A" + struct.pack(">H", len(payload)) + payload


def _header(function_code, n, channel, domain, y_units, complex_data, half_fs, delta, start, averages=1):
    h = [0.0] * 66
    h[0], h[1], h[2], h[3], h[4] = function_code, n, n, averages, channel
    h[7], h[9], h[10], h[36], h[40] = domain, y_units, domain, 0.0 if complex_data else 1.0, 1.0
    h[52] = h[53] = half_fs
    h[55], h[64] = delta, start
    return h


def test_fetch_frf_sends_trace_select_and_dump_and_decodes_the_block():
    lines = np.arange(401) * 0.5
    data = []
    for k in range(401):
        data += [float(k), -float(k) / 2]
    block = _block(_header(7, 401, 3, 1, 3, True, 256.0, 0.5, 0.0, averages=5) + data)
    dsa, t = driver([(b"TRCA;FRSP;DDAN", block)])
    frf = dsa.fetch_frf()
    t.done()
    assert frf.header.display_function == "FRSP"
    assert frf.header.n_averages == 5
    assert frf.header.y_units == "(m/s^2)/N"
    np.testing.assert_array_equal(frf.x, lines)
    np.testing.assert_array_equal(frf.data, np.arange(401) - 0.5j * np.arange(401))


def test_fetch_time_records():
    force = [float(k % 7) for k in range(1024)]
    accel = [float(-k) for k in range(1024)]
    steps = [
        (b"TRCA;TIM1;DDAN", _block(_header(1, 1024, 1, 0, 1, False, 256.0, 1 / 512, -0.02) + force)),
        (b"TRCA;TIM2;DDAN", _block(_header(2, 1024, 2, 0, 2, False, 256.0, 1 / 512, -0.02) + accel)),
    ]
    dsa, t = driver(steps)
    f, a = dsa.fetch_time_records()
    t.done()
    assert f.header.sample_rate_hz == 512.0
    assert f.header.y_units == "N"
    assert a.header.y_units == "m/s^2"
    assert f.x[0] == -0.02
    np.testing.assert_array_equal(f.data, force)
    np.testing.assert_array_equal(a.data, accel)


def test_a_garbled_dump_is_retried_after_a_device_clear_then_reported():
    good = _block(_header(8, 401, 3, 1, 4, False, 256.0, 0.5, 0.0) + [1.0] * 401)
    dsa, t = driver([(b"TRCA;COHR;DDAN", b"\xff\xfe" + good), (b"TRCA;COHR;DDAN", good)], retries=1)
    assert dsa.fetch_coherence().data.tolist() == [1.0] * 401
    t.done()
    dsa, t = driver([(b"TRCA;COHR;DDAN", b"garbage!"), (b"TRCA;COHR;DDAN", b"garbage!")], retries=1)
    with pytest.raises(ProtocolError, match=r"DDAN of COHR: .*'#'.*\(after 2 attempts\)"):
        dsa.fetch_coherence()


@pytest.mark.parametrize(
    ("header_change", "message"),
    [
        ({1: 400.0, 2: 400.0}, "401 lines"),
        ({0: 3.0}, "holds LSP1"),
        ({9: 42.0}, "unknown code"),
        ({36: 0.5}, "0 or 1"),
    ],
)
def test_inconsistent_dumps_are_protocol_errors(header_change, message):
    h = _header(8, 401, 3, 1, 4, False, 256.0, 0.5, 0.0)
    for index, value in header_change.items():
        h[index] = value
    n = int(h[1])
    block = _block(h + [0.5] * n)
    dsa, _ = driver([(b"TRCA;COHR;DDAN", block)], retries=0)
    with pytest.raises(ProtocolError, match=message):
        dsa.fetch_coherence()


def test_accept_is_never_repeated():
    # A lost ACPT may or may not have reached the instrument: repeating it could put
    # a hit in the average twice. The driver reports instead.
    class Failing(ExpectedProtocol):
        def _write(self, message):
            from drivers.errors import ConnectionLost

            raise ConnectionLost("link lost")

    dsa = HP35660A(Failing([]), retries=3)
    from drivers.errors import ConnectionLost

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
