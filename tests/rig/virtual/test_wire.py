"""Plain pyserial scripts following docs/protocols.md and docs/encoder-protocol.md — no project
code on the host side — talk to each virtual device, opened in-process (``virtual://``,
pyserial's ``serial_for_url``) on model time, or on its pty in real time (``-m pty``)."""

import pytest
import serial

from flowcurve.rig.virtual.aed import AEDAmplifier
from flowcurve.rig.virtual.dcon import I7011
from flowcurve.rig.virtual.encoder_box import EncoderBox


class Source:
    """A settable force for a stand-alone amplifier."""

    def __init__(self, force_N=0.0, standstill=True):
        self.force_N, self.standstill, self.t = force_N, standstill, 0.0

    def __call__(self):
        self.t += 0.01
        return self.t, self.force_N, self.standstill


def cs(text: str) -> str:  # DCON checksum, written out here from the document
    return f"{sum(text.encode()) % 256:02X}"


@pytest.fixture
def aed(device_link):
    src = Source()
    dev = AEDAmplifier(src, nominal_load_N=100e3, settings={"asf": 0}, **device_link).start()
    port = serial.serial_for_url(dev.port, 9600, parity=serial.PARITY_EVEN, timeout=0.3)
    yield dev, src, port
    port.close()
    dev.close()


def ask(port, cmd: bytes, n: int | None = None) -> bytes:
    port.reset_input_buffer()
    port.write(b";" + cmd + b";")
    return port.read(n) if n else port.read_until(b"\r\n")


def test_aed_identification_settings_and_ascii_value(aed):
    dev, src, port = aed
    idn = ask(port, b"IDN?")
    assert idn.startswith(b'HBM,"AED104') and idn.endswith(b"\r\n")
    assert ask(port, b"cof3") == b"0\r\n"  # case-insensitive
    src.force_N = 12_345.0
    assert int(ask(port, b"MSV?", 10)) == 123_450  # nominal 100 kN reads 1 000 000
    assert ask(port, b"ICR9") == b"?\r\n"
    assert ask(port, b"ESR?").strip() != b"0"
    assert ask(port, b"ICR?") == b"0\r\n"
    assert ask(port, b"BDR?") == b"9600,1\r\n"
    # line noise before a command: the leading ';' ends it as a (refused) command of its own
    port.write(b"XYZ;COF?;")
    assert port.read_until(b"\r\n") == b"?\r\n" and port.read_until(b"\r\n") == b"3\r\n"


def test_aed_binary_frames_with_cr_lf_inside_parsed_by_length(aed):
    dev, src, port = aed
    counts = 0x0D0A0D  # CR LF CR in the value bytes
    src.force_N = counts / 5_120_000 * 100e3
    assert ask(port, b"COF0") == b"0\r\n"
    port.write(b";MSV?3;")
    frames = port.read(18)
    assert len(frames) == 18
    for i in range(3):
        f = frames[6 * i:6 * i + 6]
        assert f[:3] == b"\x0d\x0a\x0d" and f[4:] == b"\r\n"
        assert int.from_bytes(f[:3], "big", signed=True) == counts
    # LSB first with status, 2-byte, no-CRLF variants
    ask(port, b"COF12")
    f = ask(port, b"MSV?", 6)
    assert int.from_bytes(f[:3], "little", signed=True) == counts and f[3] & 0x08  # standstill
    ask(port, b"COF2")
    f = ask(port, b"MSV?", 4)
    assert int.from_bytes(f[:2], "big", signed=True) == round(counts / 5_120_000 * 20_000)
    ask(port, b"COF32")
    assert len(ask(port, b"MSV?", 10)) == 4
    ask(port, b"COF9")
    f = ask(port, b"MSV?")
    assert len(f) == 17 and f.split(b",")[1] == b"31"


def test_aed_overflow_status_stream_and_stop(aed):
    dev, src, port = aed
    ask(port, b"COF9")
    src.force_N = 110e3  # beyond nominal
    value, address, status = ask(port, b"MSV?").strip().split(b",")
    assert int(status) & 0x03 == 0x03 and not int(status) & 0x04
    src.force_N = 200e3  # beyond the ±2.5 mV/V input range
    value, address, status = ask(port, b"MSV?").strip().split(b",")
    assert int(status) & 0x04 and int(value) == 1_250_000
    src.force_N = 1000.0
    ask(port, b"ICR0")
    port.write(b";MSV?0;")
    data = port.read(17 * 10)
    assert len(data) == 170 and data.count(b"\r\n") == 10
    port.write(b";STP;")
    dev.clock.sleep(0.1)
    port.reset_input_buffer()
    assert port.read(17) == b""


def test_aed_addressing_tare_and_bus_polling(aed):
    dev, src, port = aed
    src.force_N = 5000.0
    port.write(b";S05;MSV?;")  # another unit addressed: silence
    assert port.read(10) == b""
    assert ask(port, b"S31;TAR") == b"0\r\n"
    assert abs(int(ask(port, b"MSV?", 10))) < 2
    assert int(ask(port, b"TAV?")) == 50_000
    assert ask(port, b"TAS1") == b"0\r\n"
    assert int(ask(port, b"MSV?", 10)) == 50_000
    port.write(b";S98;MSV?;")  # trigger all: nobody answers
    assert port.read(10) == b""
    port.write(b";S31;")  # collect
    assert int(port.read(10)) == 50_000


def test_dcon_furnace_module_plain_script(device_link):
    state = {"heater": None}
    dev = I7011(lambda: 612.345, lambda on: state.update(heater=on), address=0x01, **device_link).start()
    with serial.serial_for_url(dev.port, 9600, timeout=0.3) as p:
        def ask_(text):
            p.write(text.encode() + b"\r")
            return p.read_until(b"\r")
        assert ask_("#01") == b">+0612.35\r"
        assert ask_("$012") == b"!010F0600\r"
        assert ask_("#02") == b""  # wrong address: silence
        assert ask_("$01X") == b""  # unknown syntax: silence
        assert ask_("@01DO01") == b"!01\r" and state["heater"] is True
        assert ask_("@01DI") == b"!0100100\r"
        assert ask_("@01DO07") == b"?01\r"
        assert ask_("$01M") == b"!017011\r"
        assert ask_("$01B") == b"!010\r"
        assert ask_("%0101070600") == b"?01\r"  # baud change without INIT: refused
        assert ask_("%0101") == b""
    dev.close()


def test_dcon_checksum_mode(device_link):
    dev = I7011(lambda: 25.12, lambda on: None, address=0x01, checksum_on=True, **device_link).start()
    with serial.serial_for_url(dev.port, 9600, timeout=0.3) as p:
        assert cs("$012") == "B7"  # docs/protocols.md example
        p.write(b"$012B7\r")
        reply = p.read_until(b"\r")[:-1].decode()
        assert reply[:-2] == "!010F0640" and reply[-2:] == cs(reply[:-2])
        p.write(b"$01200\r")  # bad checksum: silence
        assert p.read_until(b"\r") == b""
        p.write(b"$012\r")  # missing checksum: silence
        assert p.read_until(b"\r") == b""
        p.write(("#01" + cs("#01") + "\r").encode())
        reply = p.read_until(b"\r")[:-1].decode()
        assert reply == ">+0025.12" + cs(">+0025.12")
    dev.close()


def test_encoder_box_plain_script(device_link):
    box_counts = {"n": 0}
    dev = EncoderBox(lambda: box_counts["n"], address=0x02, initial_count=2**32 - 3, **device_link).start()

    def gray_to_binary(g):  # from the document
        b = g
        while g := g >> 1:
            b ^= g
        return b

    with serial.serial_for_url(dev.port, 9600, timeout=0.3) as p:
        def ask_(text):
            p.write(text.encode() + b"\r")
            return p.read_until(b"\r")
        assert ask_("#020") == b">FFFFFFFD\r"
        box_counts["n"] = 10
        raw = int(ask_("#020")[1:9], 16)
        assert raw == 7  # wrapped past 2**32
        assert ((raw - 0xFFFFFFFD + 2**31) % 2**32) - 2**31 == 10  # host unwrapping
        box_counts["n"] = 123_456
        assert gray_to_binary(int(ask_("$02G0")[1:9], 16)) == (2**32 - 3 + 123_456) % 2**32
        p.write(b"#**\r")
        assert p.read(1) == b""  # latch: no reply
        box_counts["n"] = 200_000
        assert int(ask_("$02Z0")[1:9], 16) == (2**32 - 3 + 123_456) % 2**32
        assert ask_("$0260") == b"!02\r"
        assert ask_("#020") == b">00000000\r"
        assert ask_("$022") == b"!02000600\r"
        assert ask_("$02M") == b"!027083FC\r"
        assert ask_("#030") == b""  # wrong address: silence
    dev.close()


def test_virtual_rig_devices_share_one_model_clock(rig_factory):
    rig = rig_factory("12Kh18N10T", time_scale=200, force_noise_N=0.0, aed_settings={"asf": 0})
    lc = serial.serial_for_url(rig.ports["loadcell"], 9600, timeout=0.5)
    en = serial.serial_for_url(rig.ports["encoder"], 9600, timeout=0.5)
    rig.start_crosshead()
    rig.clock.sleep(0.3)
    rig.stop_crosshead()  # hold still so both reads see the same state
    lc.write(b";MSV?;")
    force = int(lc.read(10)) / 1e6 * 100e3
    en.write(b"#020\r")
    count = int(en.read_until(b"\r")[1:9], 16)
    m = rig.model
    assert count == int(m.crosshead_mm * 100) and count > 0
    assert force == pytest.approx(m.force_N, abs=0.2)
    lc.close()
    en.close()
