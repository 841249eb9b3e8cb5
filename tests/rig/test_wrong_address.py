"""Every DCON reply from a wrong address is noted; a heater command answered so stops (issue 42).

One furnace reply ``!03`` instead of ``!01`` to ``@01DO01`` went unnoticed: the channel counted a
failed read and retried silently. Now the driver keeps every such reply (device, command, the
address that answered) for the record's events; a read asks again and never takes it; a heater
command raises :class:`WrongAddressError` at once (not retried: which module switched what is
unknown) and from then on the module's acknowledgements are not believed — heater-off is sent but
reported unconfirmed, so the host watchdog stays armed and switches the heater off.
"""

import pytest

from flowcurve.errors import DeviceError
from flowcurve.rig.encoder import CrossheadEncoder
from flowcurve.rig.furnace import Furnace
from flowcurve.rig.transport import WrongAddressError


def furnace(fake, **kw):
    kw.setdefault("max_temperature_C", 900.0)
    kw.setdefault("data_format", 0)
    return Furnace("fake://fur", timeout_s=0.05, opener=fake.opener, **kw)


def test_a_heater_command_answered_by_another_address_raises_at_once(fake_port):
    """Failed on the old code as the issue found it: the error was an ordinary device error, which the
    reading channel retried (three in a row to stop), and nothing kept it for the record."""
    fake = fake_port([(b"@01DO01\r", b"!03\r")])  # one write only: no retry of the command
    f = furnace(fake)
    with pytest.raises(WrongAddressError) as err:
        f.heater(True, reading_C=50.0)
    e = err.value
    assert e.commanded and e.answered == "03" and e.expected == 1 and e.command == "'@01DO01'"
    assert "reply to '@01DO01' from address 03, not 01" in str(e) and "[furnace] address" in str(e)
    assert [(cmd, addr, commanded) for _, cmd, addr, commanded in f.wrong_address_replies] == [("'@01DO01'", "03", True)]
    assert not f.acks_trusted and f.transport.retried_exchanges == 0


def test_after_it_the_acknowledgements_are_not_believed(fake_port):
    fake = fake_port([(b"@01DO01\r", b"!03\r"), (b"@01DO00\r", b"!01\r")])
    f = furnace(fake)
    with pytest.raises(WrongAddressError):
        f.heater(True, reading_C=50.0)
    assert f.heater_off() is False  # sent and acknowledged by 01, not believed: the watchdog stays armed
    assert fake.log[-1] == b"@01DO00\r"
    with pytest.raises(DeviceError, match="heater not switched on: a heater command was answered from another"):
        f.heater(True, reading_C=50.0)  # nothing written
    assert fake.log[-1] == b"@01DO00\r"


def test_a_heater_off_answered_by_another_address_is_not_confirmed(fake_port):
    fake = fake_port([(b"@01DO00\r", b"!03\r"), (b"@01DO00\r", b"!01\r")])
    f = furnace(fake)
    assert f.heater_off() is False
    assert [r[1:] for r in f.wrong_address_replies] == [("'@01DO00'", "03", True)]


def test_a_reading_answered_by_another_address_is_asked_again_and_not_taken(fake_port):
    fake = fake_port([(b"@01DI\r", b"!0300100\r"), (b"@01DI\r", b"!0100000\r"),
                      (b"$01B\r", b"!031\r"), (b"$01B\r", b"!010\r")])
    f = furnace(fake)
    assert f.digital_io()["outputs"] == 0  # module 03's outputs (01 = on) were not taken
    assert f.open_thermocouple() is False  # nor its open thermocouple
    assert [r[1:] for r in f.wrong_address_replies] == [("'@01DI'", "03", False), ("'$01B'", "03", False)]
    assert f.transport.retried_exchanges == 2 and f.transport.failed_after_retry == 0
    assert f.acks_trusted  # a read's reply is simply not taken


def test_a_reading_answered_only_by_another_address_fails_naming_it(fake_port):
    fake = fake_port([(b"@01DI\r", b"!0300000\r")] * 3)
    f = furnace(fake)
    with pytest.raises(WrongAddressError) as err:
        f.digital_io()
    assert not err.value.commanded and "reply to '@01DI' from address 03, not 01" in str(err.value)
    assert len(f.wrong_address_replies) == 3 and f.transport.failed_after_retry == 1


def test_the_address_less_digital_io_reply_is_still_taken(fake_port):
    fake = fake_port([(b"@01DI\r", b"!00100\r")])  # !SOOII of other family members: no address to check
    assert furnace(fake).digital_io()["outputs"] == 1


def test_the_encoder_box_notes_a_wrong_address_too(fake_port):
    fake = fake_port([(b"$0260\r", b"!05\r"), (b"$0260\r", b"!02\r")])
    enc = CrossheadEncoder("fake://enc", timeout_s=0.05, opener=fake.opener)
    enc.zero()
    assert [r[1:] for r in enc.wrong_address_replies] == [("'$0260'", "05", False)]


def test_retries_that_fail_too_are_counted_apart(fake_port):
    """The retry event says whether the readings were taken on the retry (issue 42's message fix)."""
    fake = fake_port([(b"#01\r", None), (b"#01\r", b">+0025.00\r"), (b"#01\r", None), (b"#01\r", None), (b"#01\r", None)])
    f = furnace(fake)
    assert f.temperature_C() == 25.0
    assert (f.transport.retried_exchanges, f.transport.failed_after_retry) == (1, 0)
    with pytest.raises(DeviceError, match="no answer"):
        f.temperature_C()
    assert (f.transport.retried_exchanges, f.transport.failed_after_retry) == (3, 1)


def test_on_the_virtual_module_one_stray_reply(rig_factory):
    """The virtual I-7011 on an in-process port answering one ``@01DO01`` as module 03."""
    vr = rig_factory("steel45", time_scale=50, seed=3)
    module = vr.devices["furnace"]
    real = module.command
    stray = []

    def once_from_03(lead, body):
        reply = real(lead, body)
        if (lead, body) == ("@", "DO01") and not stray:
            stray.append(reply)
            return "!03" + reply[3:]
        return reply

    module.command = once_from_03
    f = Furnace(vr.ports["furnace"], address=1, timeout_s=0.3, data_format=0)
    with f:
        with pytest.raises(WrongAddressError, match="from address 03, not 01"):
            f.heater(True, reading_C=25.0)
        assert module.do == 1  # module 01 did switch — the host cannot know: the test stops
        assert f.heater_off() is False and module.do == 0
    assert [r[1:] for r in f.wrong_address_replies] == [("'@01DO01'", "03", True)]
