"""Every injected fault is observable from the wire (plain pyserial on the in-process
``virtual://`` ports, on model time), and the DCON host watchdog switches the heater off
when the host goes quiet; with ``-m pty`` the same on ptys in real time (the unplug of a pty,
EIO, in the default selection too)."""

import pytest
import serial


@pytest.fixture
def rig(rig_factory):
    return rig_factory("steel45", time_scale=50, seed=3)


def open_port(url, **kwargs):
    return serial.serial_for_url(url, **kwargs)


def dcon(port, text):
    port.reset_input_buffer()
    port.write(text.encode() + b"\r")
    return port.read_until(b"\r")


def test_silence_and_drop_time_out(rig):
    with open_port(rig.ports["furnace"], timeout=0.2) as p:
        assert dcon(p, "#01").startswith(b">+00")
        rig.inject("furnace", "silence")
        assert dcon(p, "#01") == b""
        rig.clear("furnace")
        assert dcon(p, "#01").startswith(b">")
        rig.inject("furnace", "drop", fraction=1.0)
        assert dcon(p, "$01M") == b""


def test_garbled_reply_is_a_bad_frame(rig):
    with open_port(rig.ports["encoder"], timeout=0.2) as p:
        rig.inject("encoder", "garble")
        reply = dcon(p, "#020")
        assert reply and (len(reply) != 10 or any(b > 0x7F for b in reply))
        with pytest.raises(UnicodeDecodeError):
            reply.decode("ascii")
    with open_port(rig.ports["loadcell"], timeout=0.2) as p:
        p.write(b";COF0;")
        assert p.read_until(b"\r\n") == b"0\r\n"
        rig.inject("loadcell", "garble")
        p.write(b";MSV?;")
        frame = p.read(7)
        assert len(frame) == 7  # one byte too many: framing by length breaks


@pytest.mark.parametrize("device_link", ["inprocess", "pty"], indirect=True)  # a pty's EIO: default selection
def test_unplug_raises_eio_on_the_host(rig):
    p = open_port(rig.ports["loadcell"], timeout=0.2)
    try:
        rig.inject("loadcell", "unplug")
        with pytest.raises(OSError) as err:  # pyserial's SerialException is an OSError
            p.write(b";MSV?;")
            p.read(10)
        assert "Errno 5" in str(err.value) or "disconnected" in str(err.value)
    finally:
        p.close()


def test_open_thermocouple_and_stuck_relay(rig):
    with open_port(rig.ports["furnace"], timeout=0.2) as p:
        rig.inject("furnace", "open_thermocouple")
        assert dcon(p, "#01") == b">+9999\r"
        assert dcon(p, "$01B") == b"!011\r"
        rig.clear("furnace")
        assert dcon(p, "$01B") == b"!010\r"
        rig.inject("furnace", "relay_stuck")
        assert dcon(p, "@01DO00") == b"!01\r"
        assert rig.model.furnace.relay_on and not rig.model.furnace.commanded_on


def test_delay_makes_a_late_reply(rig):
    with open_port(rig.ports["furnace"], timeout=0.1) as p:
        rig.inject("furnace", "delay", seconds=0.3)
        assert dcon(p, "$01M") == b""
        p.timeout = 0.5
        assert p.read_until(b"\r") == b"!017011\r"


def test_watchdog_switches_heater_off_when_host_goes_quiet(rig):
    with open_port(rig.ports["furnace"], timeout=0.2) as p:
        assert dcon(p, "~0150000") == b"!01\r"  # DO power-on 00, safe 00
        assert dcon(p, "~013103") == b"!01\r"  # enabled, 0.3 s
        assert dcon(p, "@01DO01") == b"!01\r"
        for _ in range(8):  # a talking host keeps it alive
            p.write(b"~**\r")
            rig.clock.sleep(0.08)
        assert rig.model.furnace.commanded_on
        rig.clock.sleep(0.5)  # the host goes quiet
        assert not rig.model.furnace.commanded_on
        assert dcon(p, "~010") == b"!0104\r"
        assert dcon(p, "@01DO01") == b"?01\r"  # refused until the status is cleared
        assert dcon(p, "~011") == b"!01\r"
        p.write(b"~**\r")
        assert dcon(p, "@01DO01") == b"!01\r" and rig.model.furnace.commanded_on
