"""LoadCell driver through command/reply pairs (the AED command set of docs/protocols.md)."""

import numpy as np
import pytest

from flowcurve.clock import ModelClock
from flowcurve.errors import DeviceError
from flowcurve.rig.codecs import aed
from flowcurve.rig.loadcell import LoadCell


def cell(fake, **kw):
    kw.setdefault("nominal_load_N", 100_000.0)
    return LoadCell("fake://amp", timeout_s=0.05, opener=fake.opener, **kw)


def test_identify(fake_port):
    fake = fake_port([(b";IDN?;", b'HBM,"AED104         ","1234   ",P20\r\n')])
    assert cell(fake).identify()["model"] == "AED104"
    assert fake.open_kwargs["parity"] == "E" and fake.open_kwargs["baudrate"] == 9600


def test_configure_sends_settings_and_checks_acks(fake_port):
    fake = fake_port([(b";ICR0;", b"0\r\n"), (b";ASF3;", b"0\r\n"), (b";COF8;", b"0\r\n"),
                      (b";NOV?;", b"0\r\n")])
    lc = cell(fake)
    lc.configure(rate_code=0, filter=3, fmt=8)
    assert lc.fmt.frame_length == 6 and lc.fmt.has_status


def test_refused_setting_is_a_device_error(fake_port):
    fake = fake_port()  # an impossible code is caught before anything is sent
    with pytest.raises(ValueError):
        cell(fake).configure(rate_code=9)
    assert fake.log == []
    fake2 = fake_port([(b";ASF5;", b"?\r\n")])
    with pytest.raises(DeviceError, match=r"^load cell: refused 'ASF5'"):
        cell(fake2).configure(filter=5)


def test_tare_is_retried_after_silence(fake_port):
    fake = fake_port([(b";TAR;", None), (b";TAR;", b"0\r\n")])
    cell(fake).tare()


def test_read_ascii_in_newtons(fake_port):
    # COF3: nominal load = 1 000 000 counts; 250 000 counts of a 100 kN cell = 25 kN
    fake = fake_port([(b";MSV?;", b"+0250000\r\n")])
    s = cell(fake).read()
    assert s.force_N == pytest.approx(25_000.0) and s.counts == 250_000 and not s.overload


def test_read_binary_with_status_and_overload(fake_port):
    fmt = aed.output_format(8)
    frame = aed.encode_msv(-2_560_000, fmt, status=aed.GROSS_OVERFLOW)  # -nominal/2, overflow
    fake = fake_port([(b";MSV?;", frame)])
    s = cell(fake, output_format=8).read()
    assert s.force_N == pytest.approx(-50_000.0) and s.overload and s.status == aed.GROSS_OVERFLOW
    fake2 = fake_port([(b";MSV?;", frame)])
    with pytest.raises(DeviceError, match="overload"):
        cell(fake2, output_format=8, raise_on_overload=True).read()


def test_calibration_per_count_is_on_the_4_byte_scale(fake_port):
    fake = fake_port([(b";MSV?;", b"+1000000\r\n")])
    # 0.01 N per count of 5 120 000 → nominal 51 200 N, read in ASCII at full scale
    s = cell(fake, nominal_load_N=None, calibration_N_per_count=0.01).read()
    assert s.force_N == pytest.approx(51_200.0)


def test_silence_names_the_device_and_command(fake_port):
    fake = fake_port([(b";MSV?;", None)] * 3)
    with pytest.raises(DeviceError, match=r"^load cell: no answer to 'MSV\?' within 0.05 s$"):
        cell(fake).read()


def test_stream_framed_by_length_even_with_crlf_inside(fake_port):
    fmt = aed.output_format(0)
    counts = [0x0D0A0D, -5, 5_120_000, 0x0A0D0A]  # values whose bytes are CR/LF
    fake = fake_port([(b";MSV?0;", b"".join(aed.encode_msv(c, fmt) for c in counts[:3])),
                      (b";STP;", None)])
    lc = cell(fake, output_format=0)
    lc.start_stream()
    with pytest.raises(DeviceError, match="while streaming"):
        lc.read()
    first = lc.read_stream(2, timeout=0.2)
    fake.feed(aed.encode_msv(counts[3], fmt)[:3])  # a frame cut in the middle ...
    rest = lc.read_stream(10, timeout=0.05)
    fake.feed(aed.encode_msv(counts[3], fmt)[3:])  # ... completes in the next call
    last = lc.read_stream(10, timeout=0.05)
    assert [s.counts for s in first + rest + last] == counts
    assert all(a.t_monotonic_s <= b.t_monotonic_s for a, b in zip(first, first[1:]))
    lc.stop_stream()
    assert not lc.streaming


def test_silent_stream_raises(fake_port):
    fake = fake_port([(b";MSV?0;", None)])
    lc = cell(fake, output_format=3)
    lc.start_stream()
    lc.stream_silence_s = 0.05
    with pytest.raises(DeviceError, match="silent"):
        lc.read_stream(5, timeout=0.1)


def test_bus_address_selected_once_before_the_first_command(fake_port):
    fake = fake_port([(b";S07;", None), (b";MSV?;", b"+0001000\r\n"), (b";MSV?;", b"+0002000\r\n")])
    lc = cell(fake, address=7, select_address=True)
    assert [lc.read().counts for _ in range(2)] == [1000, 2000]
    assert fake.log[0] == b";S07;" and fake.log.count(b";S07;") == 1


def test_stream_burst_keeps_the_output_spacing(fake_port):
    fmt = aed.output_format(3)
    fake = fake_port([(b";ICR0;", b"0\r\n"), (b";NOV?;", b"0\r\n"), (b";MSV?0;", None)])
    lc = cell(fake)
    lc.configure(rate_code=0)  # 100 values/s
    lc.start_stream()
    fake.feed(b"".join(aed.encode_msv(c, fmt) for c in range(10)))  # ten frames arrive at once
    before = fake.clock.now()  # the port's clock stamps the frames
    got = lc.read_stream(10, timeout=0.5)
    after = fake.clock.now()
    times = [s.t_monotonic_s for s in got]
    steps = [b - a for a, b in zip(times, times[1:])]
    assert [s.counts for s in got] == list(range(10))
    assert all(step == pytest.approx(0.01, abs=0.002) for step in steps)  # the 100/s spacing
    assert before - 0.002 <= times[-1] <= after  # the last one is stamped on arrival


def test_nov_scale_read_by_configure_rescales_ascii_only(fake_port):
    # NOV500000: nominal load reads 500 000 in ASCII; 250 000 counts are then half load
    fake = fake_port([(b";ASF0;", b"0\r\n"), (b";NOV?;", b"500000\r\n"),
                      (b";MSV?;", b"+0250000\r\n"),
                      (b";COF0;", b"0\r\n"), (b";NOV?;", b"500000\r\n"),
                      (b";MSV?;", aed.encode_msv(2_560_000, aed.output_format(0)))])
    lc = cell(fake)
    lc.configure(filter=0)
    assert lc.read().force_N == pytest.approx(50_000.0)  # not 25 kN at the factory scale
    lc.configure(fmt=0)
    assert lc.read().force_N == pytest.approx(50_000.0)  # binary keeps 5 120 000 = nominal


def test_nov_refused_means_factory_scale(fake_port):
    fake = fake_port([(b";ASF0;", b"0\r\n"), (b";NOV?;", b"?\r\n"), (b";MSV?;", b"+1000000\r\n")])
    lc = cell(fake)
    lc.configure(filter=0)
    assert lc.read().force_N == pytest.approx(100_000.0)


class LineDevice:
    """An amplifier that understands only bytes sent at its own baud rate and parity."""

    def __init__(self, baud, parity):
        self.baud, self.parity = baud, parity
        self.selected = True
        self.heard = []
        self.clock = ModelClock()  # a read with nothing to give advances it by its time-out

    def opener(self, url, **kw):
        device = self

        class Port:
            timeout = kw["timeout"]
            in_waiting = 0
            clock = device.clock

            def __init__(self):
                self.rx = bytearray()
                self.line = (kw["baudrate"], kw["parity"])

            def write(self, data):
                if self.line != (device.baud, device.parity):
                    return len(data)  # noise to the amplifier
                for cmd in data.decode().split(";"):
                    device.heard.append(cmd)
                    if cmd == "S98":
                        device.selected = False
                    elif cmd.startswith("S"):
                        device.selected = True
                    elif cmd.startswith("BDR"):
                        rate, par = cmd[3:].split(",")
                        device.baud, device.parity = int(rate), "NE"[int(par)]
                    elif cmd == "IDN?" and device.selected:
                        self.rx += b'HBM,"AED104         ","1234   ",P20\r\n'
                return len(data)

            def flush(self):
                pass

            def read(self, n=1):
                if not self.rx:
                    self.clock.sleep(self.timeout)
                data = bytes(self.rx[:n])
                del self.rx[:n]
                return data

            def reset_input_buffer(self):
                self.rx.clear()

            def close(self):
                pass

        return Port()


def test_recover_line_brings_the_amplifier_back_to_the_configured_rate():
    device = LineDevice(38400, "N")  # someone left it at 38 400 baud, no parity
    lc = LoadCell("fake://amp", nominal_load_N=1e5, baudrate=9600, parity="E", timeout_s=0.05,
                  address=31, opener=device.opener)
    with pytest.raises(DeviceError, match="no answer to 'IDN\\?'"):
        lc.identify()
    assert lc.recover_line()["model"] == "AED104"
    assert (device.baud, device.parity) == (9600, "E")
    assert "BDR9600,1" in device.heard and device.heard[-2:] == ["IDN?", ""] and "S31" in device.heard
    assert lc.identify()["serial"] == "1234"


def test_stream_with_an_extra_byte_costs_that_frame_without_a_restart(fake_port):
    """Issue 42: a garbled frame is skipped by realigning on the next frame; the stream goes on
    (the old driver sent STP and MSV?0 and lost several frames to each restart)."""
    fmt = aed.output_format(3)
    good = [aed.encode_msv(c, fmt) for c in (1, 2, 3, 4)]
    bad = good[1][:4] + b"\xa5" + good[1][4:]  # one byte too many in the second frame
    fake = fake_port([(b";MSV?0;", good[0] + bad + good[2] + good[3])])
    lc = cell(fake)
    lc.start_stream()
    got = lc.read_stream(3, timeout=0.5)
    assert [s.counts for s in got] == [1, 3, 4]  # the garbled frame alone is lost
    assert lc.stream_resyncs == 0 and lc.frames_garbled == 1 and lc.streaming
    assert fake.log == [b";MSV?0;"]  # no STP, no second MSV?0


@pytest.mark.parametrize("cof, garble", [
    (3, lambda f: f[:3] + f[4:]),  # ASCII, a byte lost
    (3, lambda f: f[:8] + b"\xee" + f[9:] + b"\x91"),  # ASCII, its CR replaced, a byte added
    (0, lambda f: f[:2] + b"\xd3" + f[2:]),  # 4-byte binary, a byte added
    (8, lambda f: f[:1] + f[2:]),  # 4-byte binary with status, a byte lost
    (2, lambda f: b"\x0a" + f),  # 2-byte binary, a stray byte before a frame: binary resumes after a CR LF
])
def test_each_format_with_cr_lf_realigns_on_the_next_frame(fake_port, cof, garble):
    fmt = aed.output_format(cof)
    counts = [0x0D0A, 0x0A0D, 300, 0x0D0A, 500, 600, 700]  # values whose bytes hold CR / LF
    if fmt.kind == "binary2":
        counts = [c % 20000 for c in counts]
    frames = [aed.encode_msv(c, fmt) for c in counts]
    fake = fake_port([(b";MSV?0;", b"".join(frames[:2]) + garble(frames[2]) + b"".join(frames[3:]))])
    lc = cell(fake, output_format=cof)
    lc.start_stream()
    got = lc.read_stream(7, timeout=0.5)
    assert [s.counts for s in got] == counts[:2] + counts[3:]
    assert lc.stream_resyncs == 0 and lc.frames_garbled == 1


def test_garbled_frames_are_counted_lost_on_the_streams_rhythm(fake_port):
    """The amplifier sends a frame every 10 ms, every fourth garbled: each costs one frame,
    counted in frames_lost, no restart, and the good frames' stamps keep the 100/s rhythm with a
    gap where the lost one was (the old driver restarted the stream for each)."""
    fmt = aed.output_format(3)
    fake = fake_port([(b";ICR0;", b"0\r\n"), (b";NOV?;", b"0\r\n"), (b";MSV?0;", None)])
    lc = cell(fake)
    lc.configure(rate_code=0)
    lc.start_stream()
    t0 = fake.clock.now()
    for k in range(40):
        frame = aed.encode_msv(k, fmt)
        frame = frame[:5] + b"\xf3" + frame[5:] if k % 4 == 2 else frame
        fake.clock.call_at(t0 + 0.0043 + 0.01 * k, lambda frame=frame: fake.feed(frame))
    got = lc.read_stream(40, timeout=0.45)
    kept = [k for k in range(40) if k % 4 != 2]
    assert [s.counts for s in got] == kept[:len(got)] and len(got) >= len(kept) - 1
    assert lc.stream_resyncs == 0 and lc.frames_garbled == sum(1 for k in range(got[-1].counts) if k % 4 == 2)
    assert lc.frames_lost == lc.frames_garbled
    times = np.array([s.t_monotonic_s for s in got])
    np.testing.assert_allclose(np.diff(times) / 0.01, np.diff([s.counts for s in got]), atol=0.2)


def test_stream_that_never_regains_framing_is_an_error(fake_port):
    junk = b"\xff" * 10
    fake = fake_port([(b";MSV?0;", junk)] + [(b";STP;", None), (b";MSV?0;", junk)] * 3)  # 3 restarts allowed
    lc = cell(fake)
    lc.start_stream()
    with pytest.raises(DeviceError, match=r"^load cell: garbled stream: 4 restarts in a row"):
        lc.read_stream(5, timeout=1.0)
