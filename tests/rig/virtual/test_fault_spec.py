"""The ``--fault DEVICE:KIND[:VALUE][@SECONDS]`` parser (pure), each new kind seen on the wire, and the
virtual furnace module's host watchdog counting the model's time (as the real module would see the
test) and going on with the cable pulled (issue 29: defect 6 and 'Also')."""

import pytest
import serial
from hypothesis import given, strategies as st

from flowcurve.errors import ConfigError
from flowcurve.rig.virtual.fault_spec import APPLIES_TO, DEFAULT_VALUES, KINDS, FaultSpec, help_text, parse_fault, parse_faults


def test_the_issue_examples():
    assert parse_fault("loadcell:garble:0.05") == FaultSpec("loadcell", "garble", 0.05, None)
    assert parse_fault("encoder:jump:50") == FaultSpec("encoder", "jump", 50.0, None)
    assert parse_fault("loadcell:corrupt@5") == FaultSpec("loadcell", "corrupt", 20000.0, 5.0)
    assert parse_fault("furnace:relay_stuck@0") == FaultSpec("furnace", "relay_stuck", None, 0.0)
    assert parse_fault(" Furnace:Wrong_Address:3 ") == FaultSpec("furnace", "wrong_address", 3.0, None)
    assert parse_faults(None) == () and len(parse_faults(["encoder:silence", "loadcell:unplug@2.5"])) == 2
    assert parse_fault("loadcell:spike:900@40") == FaultSpec("loadcell", "spike", 900.0, 40.0)
    assert parse_fault("loadcell:spike@40") == FaultSpec("loadcell", "spike", 900.0, 40.0)  # under 1 % of 100 kN


@pytest.mark.parametrize("text, says", [
    ("loadcell", "DEVICE:KIND"),
    ("heater:silence", "unknown device 'heater'"),
    ("loadcell:melt", "unknown fault 'melt'"),
    ("loadcell:jump:5", "applies to encoder, not the loadcell"),
    ("encoder:relay_stuck", "applies to furnace"),
    ("encoder:wrong_address", "applies to furnace"),
    ("furnace:spike", "applies to loadcell, not the furnace"),
    ("loadcell:spike:0", "not 0"),
    ("loadcell:garble:5", "fraction of replies"),
    ("loadcell:garble:0", "fraction of replies"),
    ("loadcell:silence:1", "takes no VALUE"),
    ("loadcell:delay:-1", "delay in s"),
    ("furnace:wrong_address:3.5", "address"),
    ("encoder:jump:0", "not 0"),
    ("loadcell:corrupt@-2", "SECONDS must be >= 0"),
    ("loadcell:corrupt@soon", "SECONDS is not a number"),
    ("loadcell:corrupt:nan", "must be finite"),
])
def test_malformed_faults_are_one_line_errors(text, says):
    with pytest.raises(ConfigError) as err:
        parse_fault(text)
    assert says in str(err.value) and text.strip() in str(err.value) and "\n" not in str(err.value)


@given(kind=st.sampled_from(sorted(KINDS)), data=st.data())
def test_describe_parses_back(kind, data):
    device = data.draw(st.sampled_from(APPLIES_TO[kind]))
    at = data.draw(st.none() | st.floats(0, 1e4, allow_nan=False).map(lambda x: round(x, 3)))
    value = DEFAULT_VALUES.get(kind, {}).get(device)
    spec = FaultSpec(device, kind, value, at)
    assert parse_fault(spec.describe()) == spec


def test_help_lists_which_kind_applies_to_which_device():
    text = help_text()
    for kind, devices in APPLIES_TO.items():
        assert kind in text
    assert "jump [encoder]" in text and "wrong_address [furnace]" in text and "relay_stuck [furnace]" in text
    assert "spike [loadcell]" in text and "default 900" in text


# -- the new kinds, on the wire (in-process ports, model time) --------------------------------

def dcon(port, text):
    port.reset_input_buffer()
    port.write(text.encode() + b"\r")
    return port.read_until(b"\r")


@pytest.fixture
def rig(rig_factory):
    return rig_factory("steel45", time_scale=50, seed=3)


def test_encoder_corrupt_is_one_reply_and_jump_stays(rig):
    with serial.serial_for_url(rig.ports["encoder"], timeout=0.2) as p:
        base = int(dcon(p, "#020")[1:9], 16)
        rig.schedule(parse_fault("encoder:corrupt:2"))
        assert int(dcon(p, "#020")[1:9], 16) - base == 200  # 2 mm at 100 counts/mm, once
        assert int(dcon(p, "#020")[1:9], 16) == base
        rig.schedule(parse_fault("encoder:jump:50"))
        assert int(dcon(p, "#020")[1:9], 16) - base == 5000
        assert int(dcon(p, "#020")[1:9], 16) - base == 5000


def test_furnace_wrong_address_answers_as_another_module(rig):
    with serial.serial_for_url(rig.ports["furnace"], timeout=0.2) as p:
        assert dcon(p, "$01M") == b"!017011\r"
        rig.schedule(parse_fault("furnace:wrong_address:3"))
        assert dcon(p, "$01M") == b"!037011\r"
        assert dcon(p, "@01DO00") == b"!03\r"


def test_loadcell_corrupt_is_one_wellformed_frame_and_waits_for_motion(rig):
    from flowcurve.rig.codecs import aed

    fmt = aed.output_format(3)  # the amplifier's default format

    with serial.serial_for_url(rig.ports["loadcell"], timeout=0.2) as p:
        def force():
            p.reset_input_buffer()
            p.write(b"MSV?;")
            value = aed.decode_msv(p.read(fmt.frame_length), fmt)  # a well-formed frame
            return float(aed.counts_to_newtons(value.counts, fmt, 100e3, 0))

        rig.schedule(parse_fault("loadcell:corrupt:20000@0.5"))
        assert abs(force()) < 100
        rig.start_crosshead()
        assert abs(force()) < 100  # not due yet: 0.5 model seconds after the start
        rig.clock.sleep(0.02)  # 1 model second at scale 50
        assert force() > 19_000
        assert force() < 10_000  # once (the real load is ~2 kN by now)
        assert [s.describe() for _, s in rig.faults_applied] == ["loadcell:corrupt:20000@0.5"]


def test_loadcell_spike_is_one_frame_a_little_high(rig):
    from flowcurve.rig.codecs import aed

    fmt = aed.output_format(3)

    with serial.serial_for_url(rig.ports["loadcell"], timeout=0.2) as p:
        def force():
            p.reset_input_buffer()
            p.write(b"MSV?;")
            return float(aed.counts_to_newtons(aed.decode_msv(p.read(fmt.frame_length), fmt).counts, fmt, 100e3, 0))

        before = force()  # the crosshead at rest: the force stays
        rig.schedule(parse_fault("loadcell:spike:900"))
        spiked, after = force(), force()
        assert 850 < spiked - before < 950 and abs(after - before) < 50  # one frame, then the true force
        assert [s.describe() for _, s in rig.faults_applied] == ["loadcell:spike:900"]


# -- the virtual furnace module's watchdog: model time, and alive unplugged -----------------------

@pytest.fixture
def slow_rig(model_time_rig):
    return model_time_rig("steel45", time_scale=20, seed=1)


def arm_and_heat(p):
    assert dcon(p, "~0150000") == b"!01\r"  # heater off at power-on and as the safe value
    assert dcon(p, "~0131FF") == b"!01\r"  # watchdog on, 25.5 s (1.3 host s at scale 20: above the host floor)
    assert dcon(p, "@01DO01") == b"!01\r"


def test_watchdog_trips_after_its_timeout_in_model_time(slow_rig):
    with serial.serial_for_url(slow_rig.ports["furnace"], timeout=0.2) as p:
        arm_and_heat(p)
        t_armed = slow_rig.now()
        while slow_rig.model.furnace.commanded_on and slow_rig.now() - t_armed < 600:
            slow_rig.clock.sleep(0.01)
        # 25.5 model seconds at scale 20 = 1.3 host s (before: 25.5 host s = 510 model s)
        assert slow_rig.now() - t_armed == pytest.approx(25.5, abs=0.5)
        assert dcon(p, "~010") == b"!0104\r"


def test_watchdog_trips_with_the_cable_pulled(slow_rig):
    with serial.serial_for_url(slow_rig.ports["furnace"], timeout=0.2) as p:
        arm_and_heat(p)
    t_pulled = slow_rig.now()
    slow_rig.inject("furnace", "unplug")
    slow_rig.clock.sleep(1.5)  # 30 model seconds
    assert not slow_rig.model.furnace.commanded_on
    assert slow_rig.devices["furnace"].watchdog_status & 0x04
    assert slow_rig.now() - t_pulled >= 25.5


def test_a_late_reply_is_discarded_never_taken_for_the_next_command(rig):
    """Issue 29, defect 3: replies 0.5 s late (time-out 0.2 s) — a retry used to take the first
    command's stale reply as its own."""
    from flowcurve.errors import DeviceError
    from flowcurve.rig.encoder import CrossheadEncoder

    with CrossheadEncoder(rig.ports["encoder"], timeout_s=0.2) as enc:
        assert enc.read_counts() == 0
        rig.inject("encoder", "delay", seconds=0.5)
        with pytest.raises(DeviceError, match="late and was discarded"):
            enc.read_counts()
        assert enc.transport.late_replies >= 1
        rig.clear("encoder")
        rig.clock.sleep(1.0)
        assert enc.read_counts() == 0  # in time again: answered
