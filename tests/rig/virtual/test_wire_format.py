"""The virtual devices' own encoders (rig/virtual/wire_format.py) against the manuals'
examples, and against the drivers' decoders: two codes written apart must agree."""

import itertools

import pytest

from flowcurve.rig.codecs import aed as driver_aed
from flowcurve.rig.codecs import dcon as driver_dcon
from flowcurve.rig.codecs import encoder as driver_encoder
from flowcurve.rig.virtual import wire_format


def test_dcon_checksum_manual_example():
    assert wire_format.dcon_checksum("$012") == "B7"  # docs/protocols.md: $012 → $012B7


@pytest.mark.parametrize("cof, length", [(0, 6), (2, 4), (3, 10), (9, 17), (32, 4), (34, 2)])
def test_aed_frame_lengths_from_the_manual(cof, length):
    # docs/protocols.md: COF0 6 bytes, COF2 4, COF3 10, COF9 17; +32 drops the CR LF
    assert len(wire_format.aed_frame(cof, -12345, status=9, address=31)) == length


def test_aed_frames_spelled_out():
    assert wire_format.aed_frame(9, 1_000_000, status=8, address=31) == b"+1000000,31,008\r\n"
    assert wire_format.aed_frame(3, -42) == b"-0000042\r\n"
    assert wire_format.aed_frame(0, 0x123456) == b"\x12\x34\x56\x00\r\n"
    assert wire_format.aed_frame(12, -2, status=3) == b"\xfe\xff\xff\x03\r\n"
    assert wire_format.aed_frame(6, 0x7FFF) == b"\xff\x7f\r\n"


def test_unknown_output_formats_are_refused():
    assert not wire_format.is_known_cof(10) and not wire_format.is_known_cof(3 + 32)
    assert wire_format.is_known_cof(9 + 128) and wire_format.is_known_cof(12 + 32 + 128)


COFS = [c for c in range(256) if wire_format.is_known_cof(c)]


@pytest.mark.parametrize("cof", COFS)
def test_every_frame_decodes_with_the_driver(cof):
    fmt = driver_aed.output_format(cof)  # the driver agrees which codes exist
    limit = 30_000 if wire_format.is_two_byte_cof(cof) else 6_400_000
    for counts, status in itertools.product((-limit, -1, 0, 1, 0x0D0A, limit), (0, 1, 8, 15)):
        value = driver_aed.decode_msv(wire_format.aed_frame(cof, counts, status=status, address=7), fmt)
        assert value.counts == counts
        assert wire_format.nominal_counts(cof, 500_000) == driver_aed.nominal_counts(fmt, 500_000)
        if fmt.has_status:
            assert value.status == status
        if fmt.has_address:
            assert value.address == 7


def test_the_driver_accepts_no_code_the_virtual_unit_refuses():
    known_to_driver = []
    for cof in range(256):
        try:
            driver_aed.output_format(cof)
        except ValueError:
            continue
        known_to_driver.append(cof)
    assert known_to_driver == COFS


def test_dcon_checksum_and_gray_code_agree_with_the_drivers():
    for text in ("$012", "#01", "~**", "%01020F0600", "@01DO01", "!01A2.0"):
        assert wire_format.dcon_checksum(text) == driver_dcon.checksum(text)
    for count in (0, 1, 2, 3, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFF, 123_456_789):
        assert driver_encoder.gray_to_binary(wire_format.gray_code(count)) == count
    assert wire_format.THERMOCOUPLE_FULL_SCALE_C[0x0F] == 1370.0  # docs/protocols.md: 0F K, +1370.0 °C
