"""Codec tests on the manuals' own examples (docs/protocols.md, docs/encoder-protocol.md)."""

import math
import random

import pytest

from flowcurve.rig.codecs import ProtocolError, aed, dcon
from flowcurve.rig.codecs import encoder as enc


# -- AED ------------------------------------------------------------------------------
def test_aed_command_has_leading_clear_and_terminator():
    assert aed.command("MSV?") == b";MSV?;"
    assert aed.command("TAR;") == b";TAR;"
    with pytest.raises(ValueError):
        aed.command("ICR1;ASF2")


def test_aed_ack():
    assert aed.parse_ack(b"0\r\n") is True
    assert aed.parse_ack(b"?\r\n") is False
    with pytest.raises(ProtocolError):
        aed.parse_ack(b"x\r\n")


@pytest.mark.parametrize("cof, length", [(0, 6), (4, 6), (8, 6), (12, 6), (2, 4), (6, 4),
                                         (3, 10), (7, 10), (9, 17), (1, 13), (11, 14),
                                         (32, 4), (34, 2), (40, 4), (128 + 3, 10)])
def test_aed_reply_lengths_match_the_manual(cof, length):
    # the manual: COF0 6 bytes, COF2 4, COF3 10, COF9 17 ("xxxxxxxx,xx,xxx\r\n")
    assert aed.output_format(cof).frame_length == length


def test_aed_cof9_example_is_17_bytes_and_decodes():
    frame = b"+1000000,31,008\r\n"
    assert len(frame) == 17
    value = aed.decode_msv(frame, aed.output_format(9))
    assert (value.counts, value.address, value.status) == (1_000_000, 31, aed.STANDSTILL)
    assert not value.overflow


def test_aed_binary4_value_in_first_three_bytes_status_fourth():
    # -1 234 567 as signed 24 bit = 0xED2979; status 0x05 = net + ADC overflow
    msb = bytes([0xED, 0x29, 0x79, 0x05]) + b"\r\n"
    v = aed.decode_msv(msb, aed.output_format(8))
    assert v.counts == -1_234_567 and v.status == 5 and v.overflow
    lsb = bytes([0x79, 0x29, 0xED, 0x05]) + b"\r\n"
    assert aed.decode_msv(lsb, aed.output_format(12)).counts == -1_234_567
    # COF0 has no status: the fourth byte is not read as one
    assert aed.decode_msv(msb, aed.output_format(0)).status is None


def test_aed_binary_frames_may_contain_crlf_bytes():
    # 0x0D0A0D = 854 541 — a value made of CR LF CR bytes still decodes by length
    frame = bytes([0x0D, 0x0A, 0x0D, 0x00]) + b"\r\n"
    assert aed.decode_msv(frame, aed.output_format(0)).counts == 0x0D0A0D


def test_aed_two_byte_overflow_codes():
    fmt = aed.output_format(2)
    assert aed.decode_msv(b"\x7f\xff\r\n", fmt).overflow
    assert aed.decode_msv(b"\x80\x00\r\n", fmt).overflow
    v = aed.decode_msv(b"\x4e\x20\r\n", fmt)  # 20 000 = nominal
    assert v.counts == 20_000 and not v.overflow
    assert aed.decode_msv(b"\x20\x4e", aed.output_format(38)).counts == 20_000  # 6+32, LSB first


@pytest.mark.parametrize("cof", [0, 4, 8, 12, 2, 6, 3, 7, 1, 5, 9, 11, 32, 36, 40, 44, 34, 38])
def test_aed_encode_decode_round_trip(cof):
    fmt = aed.output_format(cof)
    rng = random.Random(cof)
    limit = {"binary4": 2**23 - 1, "binary2": 2**15 - 2, "ascii": 9_999_999}[fmt.kind]
    for counts in [0, 1, -1, limit, -limit] + [rng.randint(-limit, limit) for _ in range(50)]:
        frame = aed.encode_msv(counts, fmt, status=0x08, address=7)
        assert len(frame) == fmt.frame_length
        assert aed.decode_msv(frame, fmt).counts == counts


def test_aed_calibration_scales_agree_across_formats():
    # nominal load reads 5 120 000 (4-byte), 1 000 000 (ASCII), 20 000 (2-byte)
    for cof, counts in [(0, 5_120_000), (3, 1_000_000), (2, 20_000)]:
        assert aed.counts_to_newtons(counts, aed.output_format(cof), 100_000.0) == pytest.approx(100_000.0)


def test_aed_wrong_length_and_garbage_are_protocol_errors():
    with pytest.raises(ProtocolError):
        aed.decode_msv(b"+1000000\r\n\r\n", aed.output_format(3))
    with pytest.raises(ProtocolError):
        aed.decode_msv(b"+10x0000\r\n", aed.output_format(3))
    with pytest.raises(ValueError):
        aed.output_format(13)


def test_aed_idn_example():
    assert aed.parse_idn(b'HBM,"AED104         ","1234   ",P20\r\n') == {
        "manufacturer": "HBM", "model": "AED104", "serial": "1234", "firmware": "P20"}
    with pytest.raises(ProtocolError):
        aed.parse_idn(b"HBM AED104\r\n")


def test_aed_baud_answer():
    assert aed.parse_baud(b"9600,1\r\n") == (9600, "E")
    assert aed.parse_baud(b"19200,0\r\n") == (19200, "N")


# -- DCON -----------------------------------------------------------------------------
def test_dcon_checksum_manual_example():
    assert dcon.checksum("$012") == "B7"
    assert dcon.frame("$", 1, "2", use_checksum=True) == b"$012B7\r"
    assert dcon.frame("#", 1) == b"#01\r"
    assert dcon.frame("~", None, "") == b"~**\r"


def test_dcon_checksum_is_sum_mod_256():
    text = "#0A" + "Z" * 20
    assert int(dcon.checksum(text), 16) == sum(map(ord, text)) & 0xFF


def test_dcon_reply_checksum_checked():
    # '!' + '0' + '1' = 0x21 + 0x30 + 0x31 = 0x82
    assert dcon.parse_reply(b"!0182\r", use_checksum=True) == dcon.Reply("!", "01")
    with pytest.raises(ProtocolError):
        dcon.parse_reply(b"!0183\r", use_checksum=True)
    with pytest.raises(ProtocolError):
        dcon.parse_reply(b"01\r")


def test_dcon_analog_engineering_units_and_range_codes():
    assert dcon.parse_analog(dcon.parse_reply(b">+0025.12\r")) == pytest.approx(25.12)
    assert dcon.parse_analog(dcon.parse_reply(b">-0012.50\r")) == pytest.approx(-12.5)
    assert dcon.parse_analog(dcon.parse_reply(b">+9999\r")) == math.inf
    assert dcon.parse_analog(dcon.parse_reply(b">-0000\r")) == -math.inf
    assert dcon.parse_analog(dcon.parse_reply(b">-0000.00\r")) == 0.0  # a reading, not the code
    with pytest.raises(ProtocolError):
        dcon.parse_analog(dcon.parse_reply(b"?01\r"))


def test_dcon_analog_hex_format():
    # >4C53: 0x4C53 / 0x7FFF of the type-K full scale 1370.0 C
    value = dcon.parse_analog(dcon.parse_reply(b">4C53\r"), data_format=dcon.FORMAT_HEX)
    assert value == pytest.approx(0x4C53 / 0x7FFF * 1370.0)
    assert dcon.parse_analog(dcon.parse_reply(b">7FFF\r"), data_format=dcon.FORMAT_HEX) == math.inf
    assert dcon.parse_analog(dcon.parse_reply(b">FF00\r"), data_format=dcon.FORMAT_HEX) == pytest.approx(-256 / 0x7FFF * 1370.0)


def test_dcon_configuration():
    cfg = dcon.parse_configuration(dcon.parse_reply(b"!010F0600\r"))
    assert (cfg.address, cfg.thermocouple, cfg.baud, cfg.data_format, cfg.checksum) == (1, "K", 9600, 0, False)
    cfg = dcon.parse_configuration(dcon.parse_reply(b"!02000642\r"))
    assert cfg.checksum and cfg.data_format == dcon.FORMAT_HEX
    assert dcon.set_configuration_body(2, 0x0F, 9600, 0) == "020F0600"


def test_dcon_small_replies():
    assert dcon.parse_open_thermocouple(dcon.parse_reply(b"!011\r"), 1) is True
    assert dcon.parse_open_thermocouple(dcon.parse_reply(b"!010\r"), 1) is False
    with pytest.raises(ProtocolError):
        dcon.parse_open_thermocouple(dcon.parse_reply(b"!021\r"), 1)  # another module's reply
    assert dcon.parse_digital_io(dcon.parse_reply(b"!00100\r")) == {"alarm": 0, "outputs": 1, "inputs": 0}
    assert dcon.parse_digital_io(dcon.parse_reply(b"!0100103\r"), 1) == {"alarm": 0, "outputs": 1, "inputs": 3}
    with pytest.raises(ProtocolError):
        dcon.parse_digital_io(dcon.parse_reply(b"!0200100\r"), 1)  # another module's address
    assert dcon.digital_output_body(1) == "DO01"
    assert dcon.watchdog_body(True, 10.0) == "3164"  # the manual's ~013164 = enabled, 10.0 s
    assert dcon.frame("~", 1, dcon.watchdog_body(True, 10.0)) == b"~013164\r"
    assert dcon.parse_watchdog_timeout(dcon.parse_reply(b"!01164\r"), 1) == (True, 10.0)
    assert dcon.parse_watchdog_status(dcon.parse_reply(b"!0104\r"), 1) == dcon.WATCHDOG_TIMED_OUT
    assert dcon.safe_value_body(0, 0) == "50000"


# -- encoder box ----------------------------------------------------------------------
def test_encoder_count_reply_example():
    assert enc.parse_count(dcon.parse_reply(b">0000001E\r")) == 30
    with pytest.raises(ProtocolError):
        enc.parse_count(dcon.parse_reply(b">001E\r"))


def test_gray_code_round_trip_and_single_bit_steps():
    for b in list(range(4096)) + [2**32 - 1, 0x80000000, 123456789]:
        assert enc.gray_to_binary(enc.binary_to_gray(b)) == b
    for b in range(4095):  # neighbouring counts differ in exactly one Gray bit
        assert bin(enc.binary_to_gray(b) ^ enc.binary_to_gray(b + 1)).count("1") == 1
    assert [enc.binary_to_gray(b) for b in range(8)] == [0, 1, 3, 2, 6, 7, 5, 4]  # the textbook table


def test_wrap_around_unwrapping_follows_a_long_walk():
    rng = random.Random(1)
    true = 2**32 - 50  # start near the top; signed reading is -50
    u = enc.Unwrapper()
    assert u.update(true % 2**32) == -50
    position, wraps = -50, 0
    for _ in range(2000):
        step = rng.randint(-2**30, 2**30)
        wraps += (position // 2**32) != ((position + step) // 2**32)
        position += step
        assert u.update(position % 2**32) == position
    assert wraps > 100  # the walk really crossed the 32-bit wrap, many times


def test_wrap_delta_formula():
    assert enc.wrap_delta(5, 2**32 - 5) == 10
    assert enc.wrap_delta(2**32 - 5, 5) == -10
    assert enc.wrap_delta(7, 3, bits=4) == 4 and enc.wrap_delta(1, 15, bits=4) == 2


def test_counts_to_mm_default_is_10_um_per_count():
    assert enc.counts_to_mm(1, gear_ratio=1.0, screw_lead_mm=100.0) == pytest.approx(0.010)
    assert enc.counts_to_mm(10_000, gear_ratio=2.0, screw_lead_mm=6.0) == pytest.approx(3.0)
