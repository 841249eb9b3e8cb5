"""The ``virtual://`` URL handler: pyserial's semantics in-process, on the device's clock."""

import errno

import pytest
import serial

from flowcurve.errors import DeviceError
from flowcurve.rig.encoder import CrossheadEncoder
from flowcurve.rig.virtual.aed import AEDAmplifier
from flowcurve.rig.virtual.encoder_box import EncoderBox


@pytest.fixture
def box(model_clock):
    dev = EncoderBox(lambda: 0, address=0x02, clock=model_clock, link="inprocess").start()
    yield dev
    dev.close()


@pytest.mark.parametrize("baud", [9600, 115200])
def test_a_reply_takes_the_line_time_of_command_and_reply(box, baud):
    with serial.serial_for_url(box.port, baud, timeout=1.0) as p:
        t0 = box.clock.now()
        p.write(b"#020\r")
        assert p.read_until(b"\r") == b">00000000\r"
        # 5 bytes out and 10 back at 10 bits a byte (start, 8 data, stop)
        assert box.clock.now() - t0 == pytest.approx((5 + 10) * 10 / baud, rel=1e-9)


def test_read_returns_what_came_within_the_time_out_on_the_clock(box):
    with serial.serial_for_url(box.port, timeout=0.25) as p:
        t0 = box.clock.now()
        p.write(b"#020\r")
        assert p.read(100) == b">00000000\r"  # fewer than asked: the time-out ran out
        assert box.clock.now() - t0 == pytest.approx(0.25)
        assert p.read(1) == b"" and p.in_waiting == 0


def test_output_nobody_reads_is_lost_beyond_a_full_buffer(model_clock):
    dev = AEDAmplifier(lambda: (0.0, 0.0, True), settings={"asf": 0, "icr": 0}, clock=model_clock,
                       link="inprocess").start()
    with serial.serial_for_url(dev.port, timeout=0.1) as p:
        p.write(b";MSV?0;")  # 100 ASCII frames of 10 bytes a second, unread for 10 s
        model_clock.advance(10.0)
        assert p.in_waiting == 4096
        assert p.read(10) == b"+0000000\r\n"  # whole frames from the start: the tail was lost
    dev.close()


def test_unplugged_or_closed_device_is_an_input_output_error(box):
    p = serial.serial_for_url(box.port, timeout=0.1)
    box.unplug()
    with pytest.raises(OSError) as err:
        p.write(b"#020\r")
    assert err.value.errno == errno.EIO
    p.close()
    with pytest.raises(serial.SerialException, match="no such virtual device"):
        serial.serial_for_url("virtual://nothing-here")


def test_a_driver_names_the_missing_virtual_port():
    with pytest.raises(DeviceError, match=r"crosshead encoder: cannot open port virtual://nothing-here"):
        CrossheadEncoder("virtual://nothing-here").read_counts()


def _heating_module(model_clock):
    """An in-process I-7011 whose host armed its 10 s watchdog and switched the heater on."""
    from flowcurve.rig.furnace import Furnace
    from flowcurve.rig.virtual.dcon import I7011

    relay = []
    module = I7011(lambda: 600.0, relay.append, address=0x01, clock=model_clock, link="inprocess").start()
    host = Furnace(module.port, address=0x01)
    host.arm_watchdog(10.0)
    host.heater(True)
    assert module.do == 1 and relay[-1] is True
    return module, host, relay


@pytest.mark.parametrize("silence", ["unplug", "host stops talking"])
def test_the_module_watchdog_runs_on_its_own_clock_when_the_host_goes_silent(model_clock, silence):
    """Issue 31 (b): nothing talks to the module any more; its time-out passes on its clock and the heater goes off."""
    module, host, relay = _heating_module(model_clock)
    if silence == "unplug":
        module.unplug()
    model_clock.advance(9.0)
    assert module.do == 1
    model_clock.advance(2.0)
    assert module.do == 0 and relay[-1] is False
    host.transport.close()
    module.close()


def test_a_module_left_heating_by_a_host_that_is_gone_still_times_out_after_the_session(model_clock):
    """Issue 31 (b): the virtual rig closes (the run returned) 1 s after the cable was pulled: the
    module stays powered, so its watchdog's time-out still passes and the heater output drops."""
    module, host, relay = _heating_module(model_clock)
    module.unplug()
    model_clock.advance(1.0)
    module.close()
    assert module.do == 0 and relay[-1] is False
    host.transport.close()


def test_a_disarmed_module_is_left_as_the_host_left_it(model_clock):
    module, host, relay = _heating_module(model_clock)
    host.heater_off()
    host.disarm_watchdog()
    host.transport.close()
    module.close()
    assert module.do == 0 and module.watchdog_status == 0  # no trip after a clean end
