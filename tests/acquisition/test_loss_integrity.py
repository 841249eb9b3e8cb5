"""Issue 42's must-show: what survives a lost or garbled load-cell frame is still true.

A 12Kh18N12M3TL tension test to 3 mm on the virtual rig, in process, against the same test
fault-free: the force at every crosshead position from 0.5 to 2.9 mm within 1 %, the last
crosshead within 0.05 mm, Fm within 0.3 %. Before the fix the stream's stamps closed every gap a
lost frame left, so from the first loss on each force sat against an earlier crosshead position:
with ``loadcell:drop:0.2@1`` the force was 8.1 % high and Fm +7.6 %; ``loadcell:garble:0.05`` lost
24 % of the frames to stream restarts, force 10.9 % high. The comparison is
:mod:`tests.acquisition.curves` (``compare_curves``), for any other fault case too.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from flowcurve.acquisition.procedure import TestSpec
from flowcurve.acquisition.stopping import TARGET_TICK_MIN_S, StopCriteria, loop_tick_s, target_reached
from flowcurve.acquisition.session import run_virtual_test
from flowcurve.clock import WALL, ModelClock
from flowcurve.identification.identify import old_writer_warning
from flowcurve.record.format import WRITER_STAMPING, WRITER_STAMPING_KEY, read_record
from flowcurve.rig.loadcell import LoadCell
from flowcurve.rig.virtual.fault_spec import parse_faults
from flowcurve.rig.virtual.physics import Specimen
from tests.acquisition.curves import compare_curves
from tests.scenarios.matrix import _note_hits

MATERIAL = "12Kh18N12M3TL"
TARGET_MM = 3.0
FORCE_TOLERANCE = 0.01
LAST_CROSSHEAD_MM = 0.05
FM_TOLERANCE = 0.003


def tension_to_target(path, *, time_scale=3.0, faults=(), on_model_time=True):
    """The test on the virtual rig in this process: (record, frames the twin's wire fault took
    while the driver read the stream)."""
    s = Specimen.tension()
    spec = TestSpec("tension", material=MATERIAL, geometry_mm={"d0_mm": s.d0_mm, "l0_mm": s.length0_mm},
                    speed_mm_per_s=0.05, stop=StopCriteria(target_displacement_mm=TARGET_MM))
    hits, reads = [], []

    def count_hits(vr):  # the twin's frames the fault took, by host time; the driver's last frame read
        _note_hits(vr.devices["loadcell"], hits)
        read_stream = LoadCell.read_stream

        def read(cell, *args, **kwargs):
            got = read_stream(cell, *args, **kwargs)
            if got:
                reads.append(vr.clock.now())
            return got

        LoadCell.read_stream = read

    link = {"clock": ModelClock(), "link": "inprocess"} if on_model_time else {"clock": WALL, "link": "pty"}
    try:
        run_virtual_test(spec, path, material=MATERIAL, time_scale=time_scale, faults=parse_faults(list(faults)),
                         rig_setup=count_hits, **link)
    finally:
        LoadCell.read_stream = read_stream_unpatched
    return read_record(path), sum(1 for t in hits if reads and t < reads[-1])


read_stream_unpatched = LoadCell.read_stream


@pytest.fixture(scope="module")
def fault_free(tmp_path_factory):
    rec, _ = tension_to_target(tmp_path_factory.mktemp("loss") / "fault-free.csv")
    assert rec.meta["stop_reason"] == f"target displacement {TARGET_MM:g} mm reached"
    return rec


def assert_true_to(reference, rec, what):
    diff = compare_curves(reference, rec)
    assert diff.worst_force < FORCE_TOLERANCE, f"{what}: {diff}"
    assert abs(diff.last_crosshead_mm) < LAST_CROSSHEAD_MM, f"{what}: {diff}"
    assert abs(diff.fm) < FM_TOLERANCE, f"{what}: {diff}"
    return diff


def test_a_fifth_of_the_frames_lost_moves_no_force_against_the_crosshead(fault_free, tmp_path):
    rec, dropped = tension_to_target(tmp_path / "drop.csv", faults=["loadcell:drop:0.2@1"])
    assert_true_to(fault_free, rec, "loadcell:drop:0.2@1")
    assert dropped > 300
    # one count of frames: what the twin dropped while the driver read is what the record declares
    declared = int(rec.meta["samples_missing"])
    assert abs(declared - dropped) <= 2, (declared, dropped)
    said = [e.text for e in rec.events if e.name == "frames_missing"]
    assert said and f"({declared} so far" in said[-1]
    assert rec.meta[WRITER_STAMPING_KEY] == str(WRITER_STAMPING)


def test_a_garbled_frame_costs_that_frame(fault_free, tmp_path):
    rec, garbled = tension_to_target(tmp_path / "garble.csv", faults=["loadcell:garble:0.05"])
    assert_true_to(fault_free, rec, "loadcell:garble:0.05")
    lost = int(rec.meta.get("samples_missing") or 0) / (len(rec.data) + int(rec.meta.get("samples_missing") or 0))
    assert 0.03 < lost < 0.07, f"{100 * lost:.1f} % of the frames lost for 5 % garbled"  # was 24 %: a restart each
    assert not any(e.name == "stream_restart" for e in rec.events)
    assert abs(int(rec.meta["samples_missing"]) - garbled) <= 2, (rec.meta["samples_missing"], garbled)


def test_the_target_is_judged_on_the_crosshead_reading(fault_free):
    """The stop comes at the reading that reaches the target, not at the rows released later (the
    old stop ran 0.03 mm past 3 mm at time scale 3, and on a busy machine 67 s of test late)."""
    last = float(fault_free.column("crosshead_mm")[-1])
    assert TARGET_MM <= last < TARGET_MM + 0.01
    crit = StopCriteria(target_displacement_mm=2.0)
    assert target_reached((10.0, 1.999), crit) is None and target_reached(None, crit) is None
    assert target_reached((10.0, -2.0), crit) == "target displacement 2 mm reached"  # compression: downwards


def test_the_loop_ticks_faster_near_the_target():
    """Half the host time left to the target, at least TARGET_TICK_MIN_S: at time scale 15 and
    0.05 mm/s a 0.05 s tick is 0.0375 mm of crosshead, the stop's overshoot before."""
    crit, tick = StopCriteria(target_displacement_mm=3.0), 0.05
    assert loop_tick_s((1.0, 2.0), crit, 0.05, 15.0, tick) == tick  # 1.33 s host away
    assert loop_tick_s((1.0, 2.985), crit, 0.05, 15.0, tick) == pytest.approx(0.5 * 0.015 / 0.75)
    assert loop_tick_s((1.0, -2.9999), crit, 0.05, 15.0, tick) == TARGET_TICK_MIN_S  # compression: downwards
    assert loop_tick_s(None, crit, 0.05, 15.0, tick) == tick
    assert loop_tick_s((1.0, 2.99), StopCriteria(), 0.05, 15.0, tick) == tick


def test_a_faster_time_scale_reads_the_same_curve(fault_free, tmp_path):
    """Time scale 15 (the default) on model time: the load cell's frames are 0.15 model seconds
    apart, the same force against the crosshead (the stop may run one procedure tick further)."""
    rec, _ = tension_to_target(tmp_path / "x15.csv", time_scale=15.0)
    diff = compare_curves(fault_free, rec)
    assert diff.worst_force < FORCE_TOLERANCE, str(diff)


@pytest.mark.slow
def test_a_busy_machine_at_the_default_time_scale_reads_the_same_curve(fault_free, tmp_path):
    """Wall clock, ptys, time scale 15, two CPU-bound processes beside it (issue 42: 33 of 443
    frames skipped by the starved twin and the force 3.3 % off against the crosshead).

    Here the twins' threads share the acquisition's interpreter lock, which they do not as
    ``flowcurve rig virtual`` (their own process) nor as real devices: at the default 5 ms switch
    interval a twin thread waits up to 5 ms per busy thread for its turn, and its frames and
    replies leave that late. A 0.5 ms interval stands in for the twins' own process (measured, 5
    busy runs each: the old twin 0.70-1.13 % off, 4 of 5 beyond 1 %; this twin 0.43-0.67 %)."""
    hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]
    switch = sys.getswitchinterval()
    sys.setswitchinterval(0.0005)
    try:
        rec, _ = tension_to_target(tmp_path / "busy.csv", time_scale=15.0, on_model_time=False)
    finally:
        sys.setswitchinterval(switch)
        for hog in hogs:
            hog.kill()
            hog.wait()
    diff = compare_curves(fault_free, rec)
    assert diff.worst_force < FORCE_TOLERANCE, str(diff)


def test_identify_names_records_of_the_old_writer_that_lost_frames(fault_free, tmp_path):
    rec, _ = tension_to_target(tmp_path / "drop.csv", faults=["loadcell:drop:0.05@1"])
    assert old_writer_warning(rec) is None  # this writer's stamps leave the gaps
    del rec.meta[WRITER_STAMPING_KEY]  # as the writer before the fix wrote it
    said = old_writer_warning(rec)
    assert said and "shifted against the crosshead after the first loss" in said
    assert f"{rec.meta['samples_missing']} lost load-cell frames" in said
    first = next(e for e in rec.events if e.name == "frames_missing")
    assert f"from {first.time_s:.1f} s" in said
    del fault_free.meta[WRITER_STAMPING_KEY]  # an old record that lost nothing carries no shift
    assert old_writer_warning(fault_free) is None
    fault_free.meta[WRITER_STAMPING_KEY] = str(WRITER_STAMPING)


def test_identify_names_records_of_stamping_2_whose_encoder_reads_were_retried(fault_free):
    import copy

    from flowcurve.record.format import Event

    rec = copy.deepcopy(fault_free)
    rec.meta[WRITER_STAMPING_KEY] = "2"
    assert old_writer_warning(rec) is None  # no retried crosshead read: nothing was drawn across a gap
    rec.events.append(Event(4.2, "retry", "crosshead encoder: 1 retry after a silent, garbled or wrongly addressed reply"))
    said = old_writer_warning(rec)
    assert said and "straight across the gap" in said and "from 4.2 s" in said
    rec.events[-1] = Event(4.2, "retry", "furnace: 1 retry after a silent reply")
    assert old_writer_warning(rec) is None  # the furnace's retries do not move the crosshead
    rec.events[-1] = Event(4.2, "retry", "crosshead encoder: 1 retry after a silent reply")
    rec.meta[WRITER_STAMPING_KEY] = str(WRITER_STAMPING)
    assert old_writer_warning(rec) is None  # this writer's rows stand across the gap
