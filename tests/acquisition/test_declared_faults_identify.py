"""A fault the rig declared in the record reaches identify's warnings (issue 31's must-show):
``run tension --fault loadcell:garble:0.05`` loses the garbled frames (each costs that frame since
issue 42, no stream restart); the record names the loss in its events and ``identify`` repeats it
and marks the hardening poor past 5 % lost."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flowcurve.cli import main
from flowcurve.identification.identify import fault_warnings
from flowcurve.record.format import read_record


def test_a_garbled_load_cell_is_named_in_the_record_and_in_identify(tmp_path, capsys):
    record = tmp_path / "t.csv"
    code = main(["run", "tension", "--quiet", "--out", str(record), "--time-scale", "100", "--speed", "0.1",
                 "--fault", "loadcell:garble:0.05"])
    assert code in (0, 5)  # 5: the run declares lost samples
    rec = read_record(record)
    names = [e.name for e in rec.events]
    assert "frames_missing" in names and "stream_restart" not in names
    warnings, doubtful = fault_warnings(rec)
    assert any("frames_missing" in w for w in warnings)
    assert main(["identify", str(record), "--out", str(tmp_path / "res"), "--no-plots"]) == 0
    result = json.loads((tmp_path / "res" / "t" / "result.json").read_text())
    said = [w for w in result["warnings"] if "declares rig faults" in w]
    assert said and any("load cell" in w for w in said)
    lost = float(rec.meta.get("samples_missing") or 0) / (len(rec.data) + float(rec.meta.get("samples_missing") or 0))
    assert doubtful == (lost > 0.05)
    if doubtful:
        assert result["hardening"]["quality"] == "poor"


def test_a_clean_record_declares_nothing(tmp_path):
    record = tmp_path / "c.csv"
    assert main(["run", "compression", "--quiet", "--out", str(record), "--time-scale", "100", "--speed", "0.1"]) in (0, 5)
    rec = read_record(record)
    if not any(e.name in ("data_loss", "frames_missing", "stream_restart", "retry", "late_reply", "corrupt", "dropped") for e in rec.events):
        assert fault_warnings(rec) == ([], False)


def test_an_undecided_stream_gap_marks_the_curve_doubtful():
    # a gap neither latency nor lost frames could be told of (rig.loadcell.gap_after_verdict): the forces after it may
    # be a period off the crosshead, so the curve is not a confident one; one lost frame alone (1 of 41) does not mark it
    import pandas as pd

    from flowcurve.record.format import Event, Record

    t = [0.5 * k for k in range(40)]  # 40 rows, 1 frame missing: 2.4 %, under the 5 % that marks a curve poor
    data = pd.DataFrame({"time_s": t, "force_N": [100.0 * k for k in range(40)], "crosshead_mm": t})
    missing = Event(1.0, "frames_missing", "load cell: 1 frame missing from its stream (1 so far, from the gaps in its timing)")
    undecided = Event(1.0, "stream_gap_undecided", "load cell: a gap in its stream after 0.600 s (host) could be lost frames "
                                                   "or the line's latency growing")
    plain = Record(meta={"samples_missing": "1"}, data=data, events=[missing])
    assert fault_warnings(plain)[1] is False
    warnings, doubtful = fault_warnings(Record(meta={"samples_missing": "1"}, data=data, events=[missing, undecided]))
    assert doubtful and any("stream_gap_undecided" in w for w in warnings)


def test_a_gap_in_doubt_marks_the_curve_only_where_its_misalignment_costs_force():
    # the force within its noise across the gap (a plateau), then a fall: a stamp error of 0.5 s after 5 s costs
    # |dF/dt|·0.5 s there — against the closed form of the piecewise-linear force
    import pandas as pd

    from flowcurve.identification.identify import gap_in_doubt_warnings, misalignment_share
    from flowcurve.record.format import Event, Record

    t = np.arange(0.0, 20.0, 0.5)
    plateau = np.where(t < 10.0, 10000.0, 10000.0 - 300.0 * (t - 10.0))  # falls 150 N per 0.5 s from 10 s on
    assert misalignment_share(t, plateau, 5.0, 0.5) == pytest.approx(150.0 / plateau[-1])  # the last row: steepest share
    assert misalignment_share(t, np.full(t.size, 10000.0), 5.0, 0.5) == 0.0
    text = ("load cell: a gap in its stream after 5.000 s, across which the force stayed within its noise, taken as lost "
            "frames; had it been the line's latency growing, every later force is stamped up to 0.500 s late against the crosshead")
    data = pd.DataFrame({"time_s": t, "force_N": plateau, "crosshead_mm": 0.05 * t})
    warnings, doubtful = gap_in_doubt_warnings(Record(meta={}, data=data, events=[Event(12.0, "stream_gap_in_doubt", text)]))
    assert doubtful and "0.50 s" in warnings[0]
    flat = data.assign(force_N=10000.0 + 0.1 * t)  # 0.05 N per 0.5 s: far within 1 %
    assert gap_in_doubt_warnings(Record(meta={}, data=flat, events=[Event(12.0, "stream_gap_in_doubt", text)])) == ([], False)
