"""A crosshead or furnace reading taken on a retry (the first reply dropped) is stamped inside its own
exchange: the request that was answered and its reply bracket it (issue 42)."""

from types import SimpleNamespace

from flowcurve.acquisition.session import DriverRig
from flowcurve.rig.encoder import CrossheadEncoder


def timed_writes(fake) -> list[float]:
    """The fake port's clock at each write, in a list that fills as the driver writes."""
    sent, write = [], fake.write

    def timed_write(data):
        sent.append(fake.clock.now())
        return write(data)

    fake.write = timed_write
    return sent


def test_a_reading_taken_on_the_retry_lies_within_the_answered_request_and_its_reply(fake_port):
    fake = fake_port([(b"#020\r", None), (b"#020\r", b">00000064\r")])  # the first reply is dropped
    sent = timed_writes(fake)
    enc = CrossheadEncoder("fake://enc", timeout_s=0.05, opener=fake.opener).open()
    rig = SimpleNamespace(timebase=fake.clock, encoder=enc, _to_clock=lambda t_host: t_host,
                          _narrowest_half_s=float("inf"), _position_kept_at=-float("inf"),
                          positions_doubted=0, position_half_width_s=0.0)
    rig._bracketed = lambda device, read: DriverRig._bracketed(rig, device, read)
    (t, mm), = DriverRig._read_position(rig)
    replied = fake.clock.now()
    assert len(sent) == 2 and sent[1] >= sent[0] + 0.05  # retried after the time-out
    assert mm == 100 / enc.counts_per_rev * enc.screw_lead_mm
    assert sent[1] <= t <= replied, f"stamped at {t} s, outside the answered exchange {sent[1]} .. {replied} s"


def test_a_temperature_taken_on_the_retry_lies_within_the_answered_request_and_its_reply(fake_port):
    from flowcurve.rig.furnace import Furnace

    fake = fake_port([(b"#01\r", None), (b"#01\r", b">+0600.25\r")])  # the first reply is dropped
    sent = timed_writes(fake)
    fur = Furnace("fake://fur", timeout_s=0.05, opener=fake.opener, max_temperature_C=900.0, data_format=0).open()
    checked = []
    rig = SimpleNamespace(timebase=fake.clock, furnace=fur, _to_clock=lambda t_host: t_host,
                          _check_furnace=checked.append)
    rig._bracketed = lambda device, read: DriverRig._bracketed(rig, device, read)
    (t, temperature), = DriverRig._read_temperature(rig)
    replied = fake.clock.now()
    assert temperature == 600.25 and checked == [600.25]  # the stuck-relay and address checks still see it
    assert len(sent) == 2 and sent[1] >= sent[0] + 0.05  # retried after the time-out
    assert sent[1] <= t <= replied, f"stamped at {t} s, outside the answered exchange {sent[1]} .. {replied} s"
