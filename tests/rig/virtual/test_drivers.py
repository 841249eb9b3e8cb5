"""The real drivers (rig.loadcell, rig.encoder, rig.furnace) against the virtual devices,
opened in-process on model time, with every injected fault reported as a DeviceError naming
the device."""

import pytest

from flowcurve.errors import DeviceError, SafetyError
from flowcurve.rig.encoder import CrossheadEncoder
from flowcurve.rig.furnace import Furnace
from flowcurve.rig.loadcell import LoadCell


@pytest.fixture
def rig(rig_factory):
    return rig_factory("12Kh18N10T", time_scale=100, seed=5, force_noise_N=0.0, aed_settings={"asf": 0})


def test_drivers_read_the_model(rig):
    cfg = rig.config()
    assert cfg.frame.stiffness_N_per_um == 136.0
    with LoadCell(rig.ports["loadcell"], nominal_load_N=100e3, timeout_s=0.3) as lc, \
            CrossheadEncoder(rig.ports["encoder"], timeout_s=0.3) as enc:
        rig.start_crosshead()
        rig.clock.sleep(0.3)
        rig.stop_crosshead()
        sample = lc.read()
        x = enc.position_mm()
        assert x == pytest.approx(rig.model.crosshead_mm, abs=0.01) and x > 0.1
        assert sample.force_N == pytest.approx(rig.model.force_N, abs=0.2)
        assert enc.gray_check()


@pytest.mark.parametrize("fault", ["silence", "drop", "garble", "unplug"])
@pytest.mark.parametrize("device", ["loadcell", "encoder", "furnace"])
def test_every_wire_fault_is_a_device_error_naming_the_device(rig, device, fault):
    drivers = {
        "loadcell": lambda: LoadCell(rig.ports["loadcell"], nominal_load_N=100e3, timeout_s=0.1),
        "encoder": lambda: CrossheadEncoder(rig.ports["encoder"], timeout_s=0.1),
        "furnace": lambda: Furnace(rig.ports["furnace"], timeout_s=0.1),
    }
    read = {"loadcell": lambda d: d.read(), "encoder": lambda d: d.read_counts(),
            "furnace": lambda d: d.temperature_C()}
    drv = drivers[device]()
    drv.open()
    try:
        read[device](drv)  # works before the fault
        rig.inject(device, fault)
        t0 = rig.clock.now()
        with pytest.raises(DeviceError) as err:
            read[device](drv)
        assert rig.clock.now() - t0 < 3.0  # nothing hangs: the drivers give up on their time-outs
        assert err.value.device == drv.name
    finally:
        drv.close()


def test_furnace_driver_heater_off_on_open_thermocouple(rig):
    with Furnace(rig.ports["furnace"], timeout_s=0.2) as fu:
        fu.heater(True)
        assert rig.model.furnace.commanded_on
        rig.inject("furnace", "open_thermocouple")
        with pytest.raises(SafetyError):
            fu.temperature_C()
        assert not rig.model.furnace.commanded_on


def test_furnace_driver_watchdog_drops_heater_when_host_stops(rig):
    with Furnace(rig.ports["furnace"], timeout_s=0.2) as fu:
        fu.arm_watchdog(0.3)
        fu.heater(True)
        assert rig.model.furnace.commanded_on
        rig.clock.sleep(0.6)  # the PC stops talking
        assert not rig.model.furnace.commanded_on
        assert fu.watchdog_status() & 0x04


def test_furnace_driver_reads_digital_io_in_the_manual_format(rig):
    with Furnace(rig.ports["furnace"], timeout_s=0.2) as fu:
        fu.heater(True)
        assert fu.digital_io()["outputs"] == 0x01
