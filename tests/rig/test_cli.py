"""``flowcurve rig check`` diagnoses per device; ``flowcurve rig virtual`` serves a config."""

import os
import pty
import signal
import subprocess
import sys
import time

import pytest

from flowcurve.cli import main
from flowcurve.rig.config import load_config, to_toml, virtual_config


@pytest.fixture
def silent_pty():
    """A serial port with nothing behind it: every command meets silence."""
    master, slave = pty.openpty()
    yield os.ttyname(slave)
    os.close(master)
    os.close(slave)


def test_check_diagnoses_missing_and_silent_ports(tmp_path, silent_pty, capsys):
    ports = {"loadcell": str(tmp_path / "ttyUSB7"), "encoder": silent_pty}
    path = tmp_path / "rig.toml"
    path.write_text(to_toml(virtual_config(ports, loadcell_timeout_s=0.05, encoder_timeout_s=0.05)))
    code = main(["rig", "check", "--no-probe", "--config", str(path)])
    out = capsys.readouterr()
    assert code == 3
    assert f"load cell on {tmp_path / 'ttyUSB7'}:\n  FAILED: port missing: " in out.out
    assert "crosshead encoder on" in out.out
    assert "FAILED: silent: no answer to '$022' within 0.05 s — wrong baud rate, parity or address?" in out.out
    assert "furnace: not configured" in out.out
    assert "2 device(s) failed the check" in out.err


def test_probe_finds_the_line_settings_a_silent_amplifier_answers_at(fake_port_class, monkeypatch):
    import flowcurve.cli.rig

    monkeypatch.setattr(flowcurve.cli.rig, "PROBE_TIMEOUT_S", 0.01)
    idn = b'HBM,"AED104         ","1234   ",P20\r\n'
    opened = []

    def opener(url, **kw):  # the amplifier was left at 19200 baud, even parity
        opened.append((kw["baudrate"], kw["parity"]))
        right = (kw["baudrate"], kw["parity"]) == (19200, "E")
        return fake_port_class([(b";IDN?;", idn)] if right else [], strict=False)

    config = virtual_config({"loadcell": "/dev/ttyUSB0", "encoder": "/dev/ttyUSB1"},
                            loadcell_timeout_s=0.01)
    lines = []
    flowcurve.cli.rig.check_rig(config, lines.append, opener=opener)
    text = "\n".join(lines)
    assert "FAILED: silent: no answer to 'IDN?'" in text
    assert 'probe: it answers at 19200 baud, parity E: set baud = 19200, parity = "E" in [loadcell]' in text
    assert (9600, "E") in opened and opened.index((19200, "E")) < len(opened)
    assert "probe: no answer at any other baud rate or parity either" in text  # the encoder


def test_check_with_a_bad_config_is_one_line(tmp_path, capsys):
    path = tmp_path / "rig.toml"
    path.write_text("[loadcell]\nport = 3\n[encoder]\nport = 'x'\n[frame]\n")
    assert main(["rig", "check", "--config", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "[loadcell] port: must be a string" in err


def test_check_passes_on_the_virtual_rig(tmp_path, capsys, rig_factory):
    rig = rig_factory()
    path = tmp_path / "rig.toml"
    path.write_text(to_toml(rig.config()))
    assert main(["rig", "check", "--config", str(path)]) == 0
    out = capsys.readouterr().out
    assert out.count("  ok\n") == 3
    assert "identity: HBM AED104" in out and "Gray check ok" in out and "input type K" in out


def test_check_finds_a_device_on_the_wrong_port(tmp_path, capsys, rig_factory):
    rig = rig_factory()
    # cables swapped: the furnace module sits where the load cell should be
    ports = {"loadcell": rig.ports["furnace"], "encoder": rig.ports["encoder"]}
    path = tmp_path / "rig.toml"
    path.write_text(to_toml(virtual_config(ports, loadcell_timeout_s=0.1)))
    assert main(["rig", "check", "--no-probe", "--config", str(path)]) == 3
    out = capsys.readouterr().out
    # a DCON module is silent to AED syntax; the encoder is still fine
    assert "FAILED: silent: no answer to 'IDN?' within 0.1 s" in out
    assert "Gray check ok" in out


def test_check_reports_garbled_replies_and_an_open_thermocouple(tmp_path, capsys, rig_factory):
    rig = rig_factory()
    rig.inject("loadcell", "garble")
    rig.inject("furnace", "open_thermocouple")
    path = tmp_path / "rig.toml"
    path.write_text(to_toml(rig.config()))
    assert main(["rig", "check", "--config", str(path)]) == 3
    out = capsys.readouterr().out
    assert "load cell on" in out and "FAILED: garbled replies" in out
    assert "FAILED: thermocouple open (over-range reading confirmed by $AAB); heater off" in out
    assert "Gray check ok" in out


def test_recover_loadcell_on_the_virtual_rig(tmp_path, capsys, rig_factory):
    rig = rig_factory()
    path = tmp_path / "rig.toml"
    path.write_text(to_toml(rig.config()))
    rig.devices["loadcell"].baud, rig.devices["loadcell"].parity = 19200, 0  # left at 19200/N
    assert main(["rig", "recover-loadcell", "--config", str(path)]) == 0
    assert (rig.devices["loadcell"].baud, rig.devices["loadcell"].parity) == (9600, 1)
    assert "answers: HBM AED104, serial 1234" in capsys.readouterr().out


def start_rig_virtual(path, *options):
    """``flowcurve rig virtual`` in a process of its own, serving ptys in real time."""
    # a runner started in the background has SIGINT ignored, and children inherit that:
    # give the command the terminal's default, as an operator's Ctrl-C would meet it
    return subprocess.Popen([sys.executable, "-m", "flowcurve", "rig", "virtual", "--config", str(path), *options],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def read_until_line(proc, prefix, timeout_s=30.0):
    """The lines the process printed up to the first starting with ``prefix``."""
    lines = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        lines.append(line)
        if line.startswith(prefix):
            return "".join(lines)
    raise AssertionError(f"no line starting with {prefix!r} in: {''.join(lines)}")


def stop_rig_virtual(proc, stop):
    proc.send_signal(stop)
    out, err = proc.communicate(timeout=20)
    assert proc.returncode == 0, err
    assert "virtual rig stopped" in out


def kill_if_running(proc):
    if proc.poll() is None:
        proc.kill()
        proc.wait()


@pytest.mark.parametrize("stop", [pytest.param(signal.SIGINT, marks=pytest.mark.pty), pytest.param(signal.SIGTERM, marks=pytest.mark.pty)])
def test_rig_virtual_runs_until_ctrl_c(tmp_path, stop):
    path = tmp_path / "virtual.toml"
    proc = start_rig_virtual(path)
    try:
        text = read_until_line(proc, "running")
        assert "loadcell" in text and "/dev/pts/" in text and f"configuration: {path}" in text
        cfg = load_config(path)
        assert cfg.loadcell.port.startswith("/dev/pts/") and cfg.furnace is not None
        stop_rig_virtual(proc, stop)
    finally:
        kill_if_running(proc)


def test_rig_virtual_serves_ptys_starts_its_motor_for_a_driver_in_another_process_and_stops_on_sigterm(tmp_path):
    """'run --config' against 'rig virtual' waits for crosshead motion, as on the real machine;
    the virtual operator's motor switch (--motor-start-after) must make the encoder move. The
    real-time pty path of the default selection: another process, real ports, and SIGTERM
    (kill, systemd), which the command turns into its Ctrl-C stop (both signals: -m pty)."""
    from flowcurve.rig.encoder import CrossheadEncoder

    path = tmp_path / "virtual.toml"
    proc = start_rig_virtual(path, "--test", "compression", "--time-scale", "20", "--motor-start-after", "0.2")
    try:
        text = read_until_line(proc, "crosshead motor started")
        assert "loadcell" in text and "/dev/pts/" in text and f"configuration: {path}" in text
        cfg = load_config(path)
        assert cfg.loadcell.port.startswith("/dev/pts/") and cfg.furnace is not None
        with CrossheadEncoder(cfg.encoder.port, timeout_s=0.3) as enc:
            first = enc.position_mm()
            deadline = time.monotonic() + 20.0  # at 0.01 mm/s x 20: 0.05 mm in a quarter second
            while abs(enc.position_mm() - first) < 0.05:
                assert time.monotonic() < deadline, "the crosshead does not move"
        stop_rig_virtual(proc, signal.SIGTERM)
    finally:
        kill_if_running(proc)


def test_rig_virtual_passes_the_response_options_to_the_rig(monkeypatch, tmp_path):
    import flowcurve.rig.virtual.rig as virtual_rig

    seen = {}

    class Built(Exception):
        pass

    def fake_rig(*args, **kwargs):
        seen.update(kwargs)
        raise Built

    monkeypatch.setattr(virtual_rig, "VirtualRig", fake_rig)
    with pytest.raises(Built):
        main(["rig", "virtual", "--config", str(tmp_path / "v.toml"), "--tension-response", "bridgman"])
    assert seen["tension_response"] == "bridgman" and seen["compression_response"] == "fe"


def test_rig_virtual_prints_the_post_test_measurements_when_the_crosshead_stops(capsys):
    """Issue 42: 'rig virtual' never offered the post-test measurements (demo, run in process and
    the console do). Its loop prints them once when the crosshead stops after moving — the
    operator stopping the motor here (failed on the old code: no such lines)."""
    from flowcurve.cli.rig import _report_end
    from flowcurve.clock import ModelClock
    from flowcurve.rig.virtual.rig import VirtualRig

    clock = ModelClock()
    with VirtualRig("steel45", test="compression", speed_mm_per_s=0.05, time_scale=20.0, clock=clock, link="inprocess",
                    compression_response="slab") as rig:
        seen: dict = {}
        _report_end(rig, seen)
        rig.start_crosshead()
        clock.advance(2.0)  # 40 model seconds: 2 mm
        _report_end(rig, seen)
        assert "post-test" not in capsys.readouterr().out  # nothing while it runs
        rig.stop_crosshead()
        _report_end(rig, seen)
        _report_end(rig, seen)
        out = capsys.readouterr().out
        truth = rig.post_test_measurements()
    assert out.count("post-test measurements") == 1 and "motor stopped" in out
    for key in ("post.hk_mm", "post.dmax_mm"):
        assert f"{key} = {truth[key]}" in out and f"--set {key}={truth[key]}" in out
    assert 6.982 - 2.0 < float(truth["post.hk_mm"]) < 6.982 - 1.5  # 2 mm of crosshead, less the frame's and the elastic share


@pytest.mark.pty
def test_the_readmes_workflow_with_rig_virtual_identifies(tmp_path):
    """README 'The virtual rig from another terminal', end to end in real time: 'rig virtual' at
    the test's speed, 'run --config', the motor stopped when run says so, the post-test
    measurements 'rig virtual' prints given with annotate, identify. The record's measured speed is
    the one asked for (issue 42: the twin ran its own 0.01 mm/s for --speed 0.1, unsaid)."""
    import re

    from flowcurve.record.format import read_record

    path, record = tmp_path / "virtual.toml", tmp_path / "c.csv"
    proc = start_rig_virtual(path, "--test", "compression", "--material", "steel45", "--speed", "0.1",
                             "--time-scale", "20", "--motor-start-after", "1.0")
    try:
        read_until_line(proc, "running")
        run = subprocess.run([sys.executable, "-m", "flowcurve", "run", "compression", "--config", str(path), "--d0", "5.989",
                              "--h0", "6.982", "--E", "200000", "--target", "3.3", "--speed", "0.1", "--time-scale", "20",
                              "--quiet", "--out", str(record)], capture_output=True, text=True, timeout=120)
        assert run.returncode in (0, 5), run.stderr
        assert "Stop the crosshead motor" in run.stdout + run.stderr
        proc.send_signal(signal.SIGUSR1)  # the operator stops the motor
        text = read_until_line(proc, "  (give them at")
        sets = re.search(r"flowcurve annotate RECORD (.*)\)", text).group(1).split()
        stop_rig_virtual(proc, signal.SIGTERM)
    finally:
        kill_if_running(proc)
    meta = read_record(record).meta
    assert float(meta["crosshead_speed_measured_mm_per_s"]) == pytest.approx(0.1, rel=0.05)
    assert main(["annotate", str(record), *sets]) == 0
    assert main(["identify", str(record), "--out", str(tmp_path / "results"), "--no-plots"]) == 0
