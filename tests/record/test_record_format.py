"""The flowcurve-record v1 format: round trip, crash safety, amendments, clear errors."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pandas as pd
import pytest

from flowcurve.record.format import (
    Record,
    RecordWriter,
    amend_record,
    read_record,
    recover_record,
    write_record,
)
from flowcurve.errors import RecordError

COLUMNS = ["time_s", "force_N", "crosshead_mm", "temperature_C"]


def _samples(n: int, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 100.0
    return np.column_stack([t, 1000 * rng.random(n), 0.01 * np.arange(n), 20 + rng.random(n)])


def test_writer_round_trip_keeps_values_metadata_and_events(tmp_path):
    path = tmp_path / "t.csv"
    rows = _samples(250)
    meta = {"test": "tension", "specimen.d0_mm": 6.0, "specimen.l0_mm": 30.0, "material": "steel 45"}
    with RecordWriter(path, meta, COLUMNS) as rec:
        rec.append_rows(rows[:100])
        rec.event(1.0, "heater_on", "set-point 600 C")
        rec.append_rows(rows[100:])
    record = read_record(path)
    np.testing.assert_allclose(record.data.to_numpy(), rows, atol=5e-7)
    assert record.meta["status"] == "complete"
    assert record.meta["samples"] == "250"
    assert record.number("specimen.d0_mm") == 6.0
    assert record.test == "tension"
    assert [(e.time_s, e.name, e.text) for e in record.events] == [(1.0, "heater_on", "set-point 600 C")]
    assert not record.truncated and record.warnings == []


def test_exception_inside_writer_marks_record_aborted_and_keeps_samples(tmp_path):
    path = tmp_path / "t.csv"
    with pytest.raises(RuntimeError):
        with RecordWriter(path, {"test": "compression"}, COLUMNS) as rec:
            rec.append_rows(_samples(10))
            raise RuntimeError("load cell: no answer")
    record = read_record(path)
    assert record.meta["status"] == "aborted"
    assert "load cell: no answer" in record.meta["abort_reason"]
    assert len(record.data) == 10


def test_missing_values_are_written_empty_and_read_as_nan(tmp_path):
    path = tmp_path / "t.csv"
    rows = _samples(3)
    rows[1, 3] = np.nan
    with RecordWriter(path, {"test": "tension"}, COLUMNS) as rec:
        rec.append_rows(rows)
    assert path.read_text().splitlines()[-2].endswith(",")  # written as an empty cell
    data = read_record(path).data
    assert np.isnan(data["temperature_C"].iloc[1]) and not np.isnan(data["temperature_C"].iloc[0])


def test_kill_9_loses_at_most_the_last_second_and_recovery_completes_header(tmp_path):
    """A writer killed with SIGKILL: the file is readable, says it was cut short, and holds
    every sample written more than one second (the fsync period) before the kill."""
    path = tmp_path / "killed.csv"
    script = textwrap.dedent(
        f"""
        import sys, time
        import numpy as np
        from flowcurve.record.format import RecordWriter
        rec = RecordWriter({str(path)!r}, {{"test": "tension"}}, ["time_s", "force_N", "crosshead_mm"])
        i = 0
        t0 = time.monotonic()
        while True:
            rec.append_rows([[i * 0.01, float(i), i * 1e-3]])
            if i == 50:
                print("writing", flush=True)
            i += 1
            time.sleep(0.002)
        """
    )
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "writing"
    time.sleep(1.5)
    # what the writer had certainly produced 1 s before the kill is at least what is on disk now
    on_disk_before = path.read_text().count("\n")
    time.sleep(1.0)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    record = read_record(path)
    assert record.truncated
    assert any("cut short" in w for w in record.warnings)
    header_lines = 3  # format line, status, test
    assert len(record.data) >= on_disk_before - header_lines - 1
    # samples are consecutive: nothing lost in the middle, nothing duplicated
    np.testing.assert_array_equal(record.data["force_N"].to_numpy(), np.arange(len(record.data)))
    _, recovered = recover_record(path)
    assert recovered.meta["status"] == "aborted" and not recovered.truncated
    assert len(recovered.data) == len(record.data)


def test_partial_last_line_is_dropped_with_a_warning(tmp_path):
    path = tmp_path / "t.csv"
    with RecordWriter(path, {"test": "tension"}, COLUMNS[:3]) as rec:
        rec.append_rows(_samples(5)[:, :3])
    with open(path, "a") as fh:
        fh.write("0.05,12.")
    record = read_record(path)
    assert len(record.data) == 5
    assert record.truncated and "incomplete" in record.warnings[0]


def test_amend_adds_post_test_measurements_and_keeps_samples_byte_for_byte(tmp_path):
    path = tmp_path / "t.csv"
    with RecordWriter(path, {"test": "compression", "specimen.h0_mm": 6.982}, COLUMNS) as rec:
        rec.append_rows(_samples(20))
    body_before = path.read_text().split("time_s,", 1)[1]
    amend_record(path, {"post.hk_mm": 3.55, "post.dmax_mm": 8.6})
    text = path.read_text()
    assert text.split("time_s,", 1)[1] == body_before
    record = read_record(path)
    assert record.number("post.hk_mm") == 3.55 and record.number("post.dmax_mm") == 8.6


def test_write_record_then_read_back(tmp_path):
    data = pd.DataFrame(_samples(7), columns=COLUMNS)
    rec = Record(meta={"flowcurve-record": "1", "test": "tension", "specimen.d0_mm": "5.0"}, data=data)
    path = write_record(tmp_path / "w.csv", rec)
    back = read_record(path)
    np.testing.assert_allclose(back.data.to_numpy(), data.to_numpy(), rtol=1e-8)


@pytest.mark.parametrize(
    "text, line, column, words",
    [
        ("", None, None, "empty"),
        ("# flowcurve-record: 1\n# test: tension\n", 2, None, "no column row"),
        ("# flowcurve-record: 1\ntime_s,force_N,crosshead_mm\n", 2, None, "no samples"),
        ("# flowcurve-record: 1\ntime_s,force_N\n0,1\n", 2, None, "missing column(s) crosshead_mm"),
        ("# flowcurve-record: 1\ntime_s,force_N,crosshead_mm\n0,1,2\n0.1,x1,2\n", 4, "force_N", "not a number: 'x1'"),
        ("# flowcurve-record: 1\ntime_s,force_N,crosshead_mm\n0,1,2\n0.1,2\n0.2,3,4\n", 4, None, "2 cells"),
        ("# flowcurve-record: 2\ntime_s,force_N,crosshead_mm\n0,1,2\n", 1, None, "version '2' is not supported"),
        ("time_s,force_N,crosshead_mm\n0,1,2\n", 1, None, "not a flowcurve-record file"),
    ],
)
def test_malformed_records_name_file_line_and_column(tmp_path, text, line, column, words):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(RecordError) as err:
        read_record(path)
    message = str(err.value)
    assert str(path) in message and words in message
    assert err.value.line == line and err.value.column == column
    assert "\n" not in message


def test_missing_required_metadata_is_named():
    rec = Record(meta={"test": "tension"}, data=pd.DataFrame(_samples(2), columns=COLUMNS), source="x.csv")
    with pytest.raises(RecordError, match="required metadata 'specimen.d0_mm' is missing"):
        rec.number("specimen.d0_mm", required=True)
    rec.meta["specimen.d0_mm"] = "six"
    with pytest.raises(RecordError, match="not a number"):
        rec.number("specimen.d0_mm")
    rec.meta["test"] = "torsion"
    with pytest.raises(RecordError, match="tension, compression"):
        rec.test


def test_has_is_true_for_a_column_with_any_value_and_false_for_an_empty_one():
    """Record.has reads the first value before a pass over the column: a column that starts empty still counts."""
    n = 1000
    data = pd.DataFrame({"full": np.arange(n, dtype=float), "late": np.r_[np.full(n - 1, np.nan), 1.0],
                         "empty": np.full(n, np.nan), "text": ["x"] * n})
    record = Record(meta={}, data=data, source="t")
    assert [record.has(c) for c in ("full", "late", "empty", "text", "absent")] == [True, True, False, True, False]
    assert not Record(meta={}, data=pd.DataFrame({"full": []}), source="t").has("full")
    nullable = pd.DataFrame({"late": pd.array([None, 1.0], dtype="Float64"), "empty": pd.array([None, None], dtype="Float64")})
    assert [Record(meta={}, data=nullable, source="t").has(c) for c in ("late", "empty")] == [True, False]


@pytest.mark.parametrize("start, stop", [(0, 0), (0, 5), (3, 3_000_001), (1_048_575, 2_097_153), (0, 3_000_003)])
def test_count_byte_counts_what_bytes_count_does(start, stop):
    from flowcurve.record.format import count_byte

    raw = bytes(np.random.default_rng(start).choice(np.frombuffer(b"0123,\\n.-", dtype=np.uint8), 3_000_003))
    assert count_byte(raw, b",", start, stop) == raw.count(b",", start, stop)
