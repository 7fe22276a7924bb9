"""The simulated hammer: adjustable in-band and from the command line, validated."""

import pytest

from sims.hammer import HammerModel, adjusted
from tests.sims.wire import decode_trace


@pytest.mark.parametrize(
    ("spec", "fragment"),
    [
        ("peak=3", "keys peak_force_n"),
        ("peak_force_n", "keys peak_force_n"),
        ("peak_force_n=x", "not a number"),
        ("peak_force_n=nan", "finite"),
        ("peak_force_n=-1", "positive"),
        ("double_hit_probability=2", "probability"),
        ("rel_spread=-0.1", "rel_spread"),
    ],
)
def test_bad_hammer_settings_are_refused(spec, fragment):
    with pytest.raises(ValueError, match=fragment):
        adjusted(HammerModel(), spec)


def test_adjusted_changes_only_what_it_names():
    hammer = adjusted(HammerModel(), "peak_force_n=3, pulse_width_s=0.001")
    assert hammer.peak_force_n == 3.0
    assert hammer.pulse_width_s == 0.001
    assert hammer.double_hit_probability == HammerModel().double_hit_probability


def _contact_ms(connect, make_analyzer, width_s):
    conn = connect(make_analyzer("seed", seed=2, noise=False))
    conn.write(f"SIM:HAMMER pulse_width_s={width_s},rel_spread=0\n".encode())
    # Full span: the anti-alias filter is far above the pulse, the record shows its shape.
    conn.write(b"FRS 102.4 KHZ;TSRC CH1;TLVL 2 MV;TDLY -1 MS;RNG1 20 MV;RNG2 2 V;STRT\n")
    assert conn.query("ERR?") == b'0,"No error"\r\n'
    conn.write(b"TIM1;DDAN\n")
    header, force = decode_trace(conn.read(timeout_s=5.0))
    above = force > 0.5 * force.max()
    return above.sum() * header[55] * 1e3


def test_pulse_width_reaches_the_record(connect, make_analyzer):
    # A half-sine is above half its peak for 2/3 of its width; each hit's width
    # varies by up to 10 % (sims/hammer.py).
    assert _contact_ms(connect, make_analyzer, 0.002) == pytest.approx(2 * 2 / 3, rel=0.11)
    assert _contact_ms(connect, make_analyzer, 0.0005) == pytest.approx(0.5 * 2 / 3, rel=0.11)


def test_bad_in_band_hammer_setting_is_an_instrument_error(connect):
    conn = connect()
    conn.write(b"SIM:HAMMER peak=3\n")
    reply = conn.query("ERR?")
    assert reply.startswith(b'3,"Invalid parameter: hammer settings are key=value')
