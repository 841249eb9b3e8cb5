"""Acquisition throughput: samples recorded vs samples the virtual load cell sent, and CPU.

Runs ``flowcurve run tension --config ...`` as a separate process against a virtual rig
in this process (real time, time scale 1, load cell streaming ``MSV?0`` at its highest
rate ICR0 = 100 values/s) for ``--seconds``, stops it with Ctrl-C (SIGINT) like an
operator, then compares every frame the virtual amplifier sent with the record:

* recorded / sent, lost, duplicated (the record must equal the sent sequence, frame by
  frame, up to the frames still in flight when the stream was stopped);
* CPU share of the acquisition process (user + system time / wall time, from wait4), and
  the same for a reference process in the same run that only reads the same stream with
  the same driver and records nothing — the ratio is what recording, merging, the encoder
  and furnace threads and the live bookkeeping cost on top of reading.

Usage: python bench/acquisition_throughput.py [--seconds 60] [--format 3]
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from flowcurve.record.format import read_record
from flowcurve.rig.codecs import aed
from flowcurve.rig.config import to_toml, virtual_config
from flowcurve.rig.virtual.rig import VirtualRig

READER = """
import sys, time
from flowcurve.rig.config import load_config
cfg = load_config(sys.argv[1]); seconds = float(sys.argv[2])
cell = cfg.loadcell.create().open()
cell.configure(**cfg.loadcell.settings)
cell.start_stream()
n, end = 0, time.monotonic() + seconds
while time.monotonic() < end:
    n += len(cell.read_stream(20, 0.1))
cell.close()
print(n)
"""


class FrameCounter:
    """Wraps the virtual amplifier's frame source: every frame it sends, decoded to counts."""

    def __init__(self, device):
        self.device = device
        self.counts: list[int] = []
        self.times: list[float] = []
        self._orig = device.measured_frame
        self._lock = threading.Lock()
        device.measured_frame = self

    def __call__(self, *sample) -> bytes:
        frame = self._orig(*sample)
        value = aed.decode_msv(frame, aed.output_format(self.device.s["cof"]))
        with self._lock:
            self.counts.append(value.counts)
            self.times.append(time.monotonic())
        return frame

    def reset(self) -> None:
        with self._lock:
            self.counts.clear()
            self.times.clear()


def wait_for(predicate, timeout_s: float) -> None:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if predicate():
            return
        time.sleep(0.05)
    raise SystemExit("timed out waiting for the acquisition process")


def proc_cpu_s(pid: int) -> float:
    """CPU seconds (user + system) a running process has used so far (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def child_cpu_s(proc: subprocess.Popen) -> tuple[int, float]:
    """Wait for the child; its exit status and CPU seconds (user + system)."""
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    return proc.returncode, usage.ru_utime + usage.ru_stime


def run_acquisition(vr: VirtualRig, counter: FrameCounter, cfg: Path, out: Path, seconds: float) -> dict:
    cmd = [sys.executable, "-m", "flowcurve", "run", "tension", "--config", str(cfg), "--quiet", "--out", str(out),
           "--material", "steel45", "--d0", "6", "--l0", "30", "--speed", "0.01"]
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    wait_for(lambda: out.exists() and "tare" in out.read_text(), 60)
    vr.start_crosshead()
    t0, cpu0 = time.monotonic(), proc_cpu_s(proc.pid)
    time.sleep(seconds)
    cpu = proc_cpu_s(proc.pid) - cpu0  # while recording (start-up and imports left out)
    wall = time.monotonic() - t0
    proc.send_signal(signal.SIGINT)
    code, _ = child_cpu_s(proc)
    if code != 0:
        raise SystemExit(f"acquisition process exited with {code}: {proc.stderr.read().decode()[-500:]}")
    rec = read_record(out)
    per_count = vr.nominal_load_N / aed.output_format(vr.devices["loadcell"].s["cof"]).nominal_counts
    recorded = np.rint(rec.column("force_N") / per_count).astype(np.int64)
    sent = np.array(counter.counts, dtype=np.int64)
    n = recorded.size
    prefix_equal = n <= sent.size and bool(np.array_equal(sent[:n], recorded))
    if prefix_equal:
        lost = duplicated = 0
    else:  # count by values where the sequences part (only reached when something went wrong)
        first_bad = int(np.argmax(sent[: min(n, sent.size)] != recorded[: min(n, sent.size)]))
        lost = max(sent.size - n, 0)
        duplicated = max(n - sent.size, 0)
        print(f"  sequences differ from frame {first_bad}")
    return {"sent": int(sent.size), "recorded": int(n), "in_flight_at_stop": int(sent.size - n) if prefix_equal else None,
            "lost": lost, "duplicated": duplicated, "wall_s": wall, "cpu_s": cpu, "record": rec}


def run_reader(cfg: Path, seconds: float) -> dict:
    proc = subprocess.Popen([sys.executable, "-c", READER, str(cfg), str(seconds + 2.0)], stdout=subprocess.PIPE)
    time.sleep(1.5)  # past start-up: measure the steady read loop only
    t0, cpu0 = time.monotonic(), proc_cpu_s(proc.pid)
    time.sleep(seconds)
    cpu = proc_cpu_s(proc.pid) - cpu0
    wall = time.monotonic() - t0
    code, _ = child_cpu_s(proc)
    frames = int(proc.stdout.read().decode().strip() or 0)
    return {"frames": frames, "wall_s": wall, "cpu_s": cpu, "code": code}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="recording time, wall seconds (default 60)")
    parser.add_argument("--format", type=int, default=3, help="load-cell COF output format (3 ASCII, 4 binary LSB first, 12 binary+status)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="flowcurve-bench-") as tmp, VirtualRig("steel45", test="tension", speed_mm_per_s=0.01, time_scale=1.0) as vr:
        tmp = Path(tmp)
        cfg = tmp / "rig.toml"
        cfg.write_text(to_toml(virtual_config(**vr.config_kwargs(), loadcell_output_format=args.format)))
        counter = FrameCounter(vr.devices["loadcell"])
        print(f"acquisition throughput — virtual load cell ICR0 (100 values/s), COF{args.format}, {args.seconds:g} s")
        acq = run_acquisition(vr, counter, cfg, tmp / "rec.csv", args.seconds)
        rate = acq["recorded"] / acq["wall_s"]
        print(f"  sent by the load cell : {acq['sent']}")
        print(f"  recorded              : {acq['recorded']}  ({acq['recorded'] / max(acq['sent'], 1):.4f} of sent; {acq['in_flight_at_stop']} in flight at the stop)")
        print(f"  lost / duplicated     : {acq['lost']} / {acq['duplicated']}")
        print(f"  recorded rate         : {rate:.1f} samples/s over {acq['wall_s']:.1f} s (nominal 100)")
        share = acq["cpu_s"] / acq["wall_s"]
        print(f"  CPU, acquisition      : {acq['cpu_s']:.2f} s = {100 * share:.1f} % of one core while recording")
    # the reference on a fresh virtual rig: a virtual port cannot be reopened once closed
    with tempfile.TemporaryDirectory(prefix="flowcurve-bench-") as tmp, VirtualRig("steel45", test="tension", speed_mm_per_s=0.01, time_scale=1.0) as vr:
        cfg = Path(tmp) / "rig.toml"
        cfg.write_text(to_toml(virtual_config(**vr.config_kwargs(), loadcell_output_format=args.format)))
        vr.start_crosshead()
        ref = run_reader(cfg, args.seconds)
        ref_share = ref["cpu_s"] / ref["wall_s"]
        print(f"  CPU, bare stream read : {ref['cpu_s']:.2f} s = {100 * ref_share:.1f} % of one core while reading ({ref['frames']} frames, reference, same run)")
        print(f"  ratio acquisition / bare read CPU: {share / ref_share:.2f}")
    return 0 if acq["lost"] == 0 and acq["duplicated"] == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
