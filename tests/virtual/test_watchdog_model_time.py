"""The virtual furnace module's host watchdog counts the model's time (as the real module would
see the test), and keeps counting with the cable pulled (issue 29: defect 6 and 'Also')."""

import pytest
import serial


def dcon(port, text):
    port.reset_input_buffer()
    port.write(text.encode() + b"\r")
    return port.read_until(b"\r")


@pytest.fixture
def rig(model_time_rig):
    return model_time_rig("steel45", time_scale=20, seed=1)


def arm_and_heat(p):
    assert dcon(p, "~0150000") == b"!01\r"  # heater off at power-on and as the safe value
    assert dcon(p, "~013164") == b"!01\r"  # watchdog on, 10.0 s
    assert dcon(p, "@01DO01") == b"!01\r"


def test_watchdog_trips_after_its_timeout_in_model_time(rig):
    with serial.serial_for_url(rig.ports["furnace"], timeout=0.2) as p:
        arm_and_heat(p)
        t_armed = rig.now()
        while rig.model.furnace.commanded_on and rig.now() - t_armed < 60:
            rig.clock.sleep(0.01)
        # 10 model seconds at scale 20 = 0.5 host s (before: 10 host s = 200 model s)
        assert rig.now() - t_armed == pytest.approx(10.0, abs=0.5)
        assert dcon(p, "~010") == b"!0104\r"


def test_watchdog_trips_with_the_cable_pulled(rig):
    with serial.serial_for_url(rig.ports["furnace"], timeout=0.2) as p:
        arm_and_heat(p)
    t_pulled = rig.now()
    rig.inject("furnace", "unplug")
    rig.clock.sleep(1.0)  # 20 model seconds
    assert not rig.model.furnace.commanded_on
    assert rig.devices["furnace"].watchdog_status & 0x04
    assert rig.now() - t_pulled >= 10.0
