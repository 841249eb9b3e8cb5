"""Encoder box and furnace drivers through command/reply pairs (DCON framing)."""

import pytest

from flowcurve.errors import DeviceError, SafetyError
from flowcurve.rig.encoder import CrossheadEncoder
from flowcurve.rig.furnace import Furnace


def encoder(fake, **kw):
    return CrossheadEncoder("fake://enc", timeout_s=0.05, opener=fake.opener, **kw)


def furnace(fake, **kw):
    kw.setdefault("max_temperature_C", 900.0)
    kw.setdefault("data_format", 0)  # engineering units (else learnt by $AA2 first)
    return Furnace("fake://fur", timeout_s=0.05, opener=fake.opener, **kw)


# -- encoder --------------------------------------------------------------------------
def test_encoder_reads_and_unwraps_across_the_32_bit_wrap(fake_port):
    fake = fake_port([(b"#020\r", b">FFFFFFF6\r"),   # -10
                      (b"#020\r", b">00000014\r"),   # +20: crossed the wrap upwards
                      (b"#020\r", b">FFFFFF9C\r")])  # -100
    enc = encoder(fake)
    assert [enc.read_counts() for _ in range(3)] == [-10, 20, -100]


def test_encoder_position_through_gear_and_lead(fake_port):
    fake = fake_port([(b"#020\r", b">00002710\r")])  # 10 000 counts = 1 encoder revolution
    assert encoder(fake, gear_ratio=2.0, screw_lead_mm=6.0).position_mm() == pytest.approx(3.0)


def test_encoder_zero_resets_the_unwrapping(fake_port):
    fake = fake_port([(b"#020\r", b">7FFFFFF0\r"), (b"$0260\r", b"!02\r"), (b"#020\r", b">00000003\r")])
    enc = encoder(fake)
    enc.read_counts()
    enc.zero()
    assert enc.read_counts() == 3


def test_encoder_gray_check(fake_port):
    count = 0x1234
    gray = count ^ (count >> 1)
    fake = fake_port([(b"$02G0\r", f">{gray:08X}\r".encode()), (b"#020\r", b">00001234\r"),
                      (b"$02G0\r", f">{count:08X}\r".encode()), (b"#020\r", b">00001234\r")])
    enc = encoder(fake)
    assert enc.gray_check() is True
    assert enc.gray_check() is False  # the box sent binary where Gray was due


def test_encoder_checksum_framing(fake_port):
    # "#020" = 0x23+0x30+0x32+0x30 = 0xB5; reply ">0000001E" with its own checksum
    reply = ">0000001E"
    cs = f"{sum(reply.encode()) % 256:02X}"
    fake = fake_port([(b"#020B5\r", (reply + cs + "\r").encode())])
    assert encoder(fake, checksum=True).read_raw() == 30


def test_encoder_silence_means_wrong_address_or_syntax(fake_port):
    fake = fake_port([(b"#020\r", None)] * 3)
    with pytest.raises(DeviceError, match=r"^crosshead encoder: no answer to '#020' within 0.05 s$"):
        encoder(fake).read_counts()


def test_encoder_garbled_count(fake_port):
    fake = fake_port([(b"#020\r", b">12G4\r")] * 3)
    with pytest.raises(DeviceError, match="crosshead encoder: garbled"):
        encoder(fake).read_counts()


def test_encoder_latch_and_read_latched(fake_port):
    fake = fake_port([(b"#**\r", None), (b"$02Z0\r", b">00000064\r")])
    enc = encoder(fake)
    enc.latch_all()
    assert enc.read_latched() == 100


# -- furnace --------------------------------------------------------------------------
def test_furnace_temperature(fake_port):
    fake = fake_port([(b"#01\r", b">+0600.25\r")])
    assert furnace(fake).temperature_C() == pytest.approx(600.25)


def test_furnace_open_thermocouple_confirmed_is_a_safety_error_and_heater_off(fake_port):
    fake = fake_port([(b"#01\r", b">+9999\r"), (b"$01B\r", b"!011\r"), (b"@01DO00\r", b"!\r")])
    with pytest.raises(SafetyError, match=r"^furnace: thermocouple open"):
        furnace(fake).temperature_C()


def test_furnace_over_range_without_open_flag_still_stops(fake_port):
    fake = fake_port([(b"#01\r", b">-0000\r"), (b"$01B\r", b"!010\r"), (b"@01DO00\r", b"!\r")])
    with pytest.raises(SafetyError, match="under range"):
        furnace(fake).temperature_C()


def test_heater_on_below_max(fake_port):
    fake = fake_port([(b"#01\r", b">+0500.00\r"), (b"@01DO02\r", b"!\r")])
    f = furnace(fake, heater_do_bit=1)
    f.heater(True)
    assert f.heater_is_on


def test_heater_refused_at_max(fake_port):
    fake = fake_port([(b"#01\r", b">+0900.00\r"), (b"@01DO00\r", b"!\r")])
    f = furnace(fake)
    with pytest.raises(SafetyError, match="at or above the maximum 900 C"):
        f.heater(True)
    assert not f.heater_is_on
    assert b"@01DO01\r" not in fake.log


def test_heater_off_retries_and_never_raises(fake_port):
    fake = fake_port([(b"@01DO00\r", None), (b"@01DO00\r", b"!\r")])
    assert furnace(fake).heater_off() is True
    silent = fake_port([(b"@01DO00\r", None)] * 9)  # 3 attempts x 3 tries each
    assert furnace(silent).heater_off() is False
    gone = fake_port()
    f = furnace(gone)
    f.open()
    gone.unplug()
    assert f.heater_off() is False


def test_alarm_owning_outputs_is_reported(fake_port):
    fake = fake_port([(b"@01DO00\r", b"?01\r"), (b"~010\r", b"!0100\r")])
    with pytest.raises(DeviceError, match="refused '@AADO' \\(the alarm owns"):
        furnace(fake).heater(False)


def test_refused_heater_off_counts_when_the_output_reads_off(fake_port):
    # after a watchdog trip the module refuses @AADO, but its safe value already switched
    # the heater off: @AADI shows DO0 clear
    fake = fake_port([(b"@01DO00\r", b"?01\r"), (b"~010\r", b"!0104\r"), (b"@01DI\r", b"!00000\r")])
    f = furnace(fake)
    f.heater_is_on = True
    assert f.heater_off() is True and not f.heater_is_on


def test_refused_heater_off_with_the_output_still_on_fails(fake_port):
    attempt = [(b"@01DO00\r", b"?01\r"), (b"~010\r", b"!0100\r"), (b"@01DI\r", b"!00100\r")]
    assert furnace(fake_port(attempt * 3)).heater_off() is False


def test_arm_watchdog_sets_heater_off_safe_value_then_enables(fake_port):
    fake = fake_port([(b"~0150000\r", b"!01\r"), (b"~013164\r", b"!01\r"), (b"~**\r", None),
                      (b"~010\r", b"!0104\r"), (b"~011\r", b"!01\r")])
    f = furnace(fake)
    f.arm_watchdog(10.0)
    assert f.watchdog_armed
    assert f.watchdog_status() == 4
    f.clear_watchdog()


def test_close_switches_the_heater_off(fake_port):
    fake = fake_port([(b"#01\r", b">+0100.00\r"), (b"@01DO01\r", b"!\r"), (b"@01DO00\r", b"!\r")])
    with furnace(fake) as f:
        f.heater(True)
    assert fake.closed and not f.heater_is_on


def test_configuration_and_identity(fake_port):
    fake = fake_port([(b"$012\r", b"!010F0600\r"), (b"$01M\r", b"!017011\r"), (b"$01F\r", b"!01A2.0\r")])
    f = furnace(fake)
    cfg = f.configuration()
    assert cfg.thermocouple == "K" and cfg.baud == 9600 and not cfg.checksum
    assert f.module_name() == "7011" and f.firmware() == "A2.0"


def test_set_configuration_changes_the_address_and_keeps_the_rest(fake_port):
    fake = fake_port([(b"$012\r", b"!010F0600\r"),
                      (b"%01050F0600\r", b"!05\r"),
                      (b"$052\r", b"!050F0600\r")])
    f = furnace(fake)
    cfg = f.set_configuration(new_address=5)
    assert f.address == 5 and cfg.address == 5 and cfg.thermocouple == "K"


def test_set_configuration_refused_without_the_init_pin(fake_port):
    fake = fake_port([(b"$012\r", b"!010F0600\r"), (b"%01010F0700\r", b"?01\r")])
    with pytest.raises(DeviceError, match=r"^furnace: refused '%01010F0700' \(answered '\?'\)$"):
        furnace(fake).set_configuration(baud=19200)


def test_watchdog_timeout_read(fake_port):
    fake = fake_port([(b"~012\r", b"!01164\r")])
    assert furnace(fake).watchdog_timeout() == (True, 10.0)


def test_any_reading_above_max_switches_the_heater_off(fake_port):
    fake = fake_port([(b"#01\r", b">+0500.00\r"), (b"@01DO01\r", b"!\r"),
                      (b"#01\r", b">+0910.00\r"), (b"@01DO00\r", b"!\r"),
                      (b"#01\r", b">+0905.00\r"), (b"@01DO00\r", b"!\r")])
    f = furnace(fake)
    f.heater(True)
    with pytest.raises(SafetyError, match=r"^furnace: over-temperature: 910.0 C above the maximum 900 C"):
        f.temperature_C()
    assert not f.heater_is_on
    assert f.temperature_C() == pytest.approx(905.0)  # heater already off: a reading, still off again


def test_data_format_is_learnt_from_the_module(fake_port):
    # $AA2 says hex format (FF bits 1:0 = 10) on a type-K input: >4000 is half of 1370 C
    fake = fake_port([(b"$012\r", b"!010F0602\r"), (b"#01\r", b">4000\r"), (b"#01\r", b">4000\r")])
    f = Furnace("fake://fur", timeout_s=0.05, opener=fake.opener)
    assert f.temperature_C() == pytest.approx(0x4000 / 0x7FFF * 1370.0)
    assert f.temperature_C() == pytest.approx(0x4000 / 0x7FFF * 1370.0)  # asked once
