"""The classes of issue 29's input campaign that ended in an internal error, each on real
records (examples/data and the lab exports of tests/identify): CR-only line endings, a line over
the csv module's 131 072 characters, a column scaled to zero; and a record that ended during
heating, refused with what happened. Each read gives a result or one clean line naming the file."""

from __future__ import annotations

import io
from contextlib import redirect_stderr, redirect_stdout

import pytest

from flowcurve.cli import main
from flowcurve.errors import RecordError
from flowcurve.record.format import parse_record_bytes
from flowcurve.record.importers import load_record

from ..property import mutated_records as mr


@pytest.fixture(scope="module")
def bases(tmp_path_factory):
    return {b.name: b for b in mr.bases(tmp_path_factory.mktemp("bases"))}


def identify(path, args=(), tmp_path=None, monkeypatch=None) -> tuple[int, str, str]:
    """`flowcurve identify` in-process with FLOWCURVE_DEBUG set (an internal error raises)."""
    monkeypatch.setenv("FLOWCURVE_DEBUG", "1")
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main(["identify", str(path), *args, "--no-plots", "--out", str(tmp_path / "out")])
    return code, out.getvalue(), err.getvalue()


def result_of(path, args, tmp_path, monkeypatch) -> str:
    code, out, err = identify(path, args, tmp_path, monkeypatch)
    assert code == 0, err
    return out


def clean_error(path, args, tmp_path, monkeypatch) -> str:
    code, out, err = identify(path, args, tmp_path, monkeypatch)
    lines = [line for line in err.splitlines() if line.startswith("flowcurve: error:")]
    assert code == 2 and len(lines) == 1 and str(path) in lines[0], err
    return lines[0]


# -- CR-only line endings: a foreign export (csv.Error "new-line character seen in unquoted field") --


@pytest.mark.parametrize("name", ["46NT71.csv", "bluehill.csv", "testxpert.txt", "mts.csv", "native-tension.csv", "compression-steel45.csv"])
def test_cr_only_line_endings_read_as_the_original(bases, name, tmp_path, monkeypatch):
    base = bases[name]
    plain, cr = tmp_path / f"plain-{name}", tmp_path / f"cr-{name}"
    plain.write_bytes(base.data)
    cr.write_bytes(mr.line_endings(base.data, "cr"))
    assert b"\n" not in mr.line_endings(base.data, "cr")
    le = {"specimen.extensometer_gauge_mm": "25"}  # the exports' extensometer reads strain
    a, b = load_record(plain, meta=le), load_record(cr, meta=le)
    assert a.meta == b.meta and a.data.equals(b.data)
    summary = result_of(cr, base.args, tmp_path, monkeypatch)
    assert summary.split("\n", 1)[1] == result_of(plain, base.args, tmp_path, monkeypatch).split("\n", 1)[1]


def test_mixed_line_endings_in_a_native_record(bases):
    base = bases["native-tension.csv"]
    mixed = parse_record_bytes(mr.line_endings(base.data, "mixed", seed=4), source="mixed.csv")
    assert mixed.data.equals(parse_record_bytes(base.data, source="plain.csv").data)


# -- a line over 131 072 characters (csv.Error "field larger than field limit") ----------------


@pytest.mark.parametrize("name", ["bluehill.csv", "mts.csv", "testxpert.txt"])
def test_a_long_line_in_an_exports_preamble_is_read_past(bases, name, tmp_path, monkeypatch):
    base = bases[name]
    path = tmp_path / name
    path.write_bytes(mr.reencode(mr.junk(mr.reencode(base.data, "utf-8"), 0.0, "long_line"), "utf-8"))
    result_of(path, base.args, tmp_path, monkeypatch)


@pytest.mark.parametrize("kind", ["long_line", "long_number"])
def test_a_long_line_among_the_samples_is_a_clean_error(bases, kind, tmp_path, monkeypatch):
    base = bases["bluehill.csv"]
    path = tmp_path / "bluehill.csv"
    path.write_bytes(mr.junk(base.data, 0.5, kind))
    line = clean_error(path, base.args, tmp_path, monkeypatch)
    assert ", line " in line  # the line is named


# -- a column scaled to zero (ValueError "zero-size array to reduction operation minimum") ------


@pytest.mark.parametrize("name, column", [("compression-steel45.csv", 2), ("compression-steel45.csv", 6), ("native-tension.csv", 1),
                                          ("native-tension.csv", 3), ("46NT71.csv", 2), ("bluehill.csv", 2)])
def test_a_column_scaled_to_zero_is_a_clean_error(bases, name, column, tmp_path, monkeypatch):
    """A dead force or displacement channel (every sample 0): the compression record's crosshead
    went into the encoder re-reading with no step to read between and raised ValueError."""
    base = bases[name]
    path = tmp_path / name
    path.write_bytes(mr.scale_column(base.data, column, 0.0))
    clean_error(path, base.args, tmp_path, monkeypatch)


# -- a record that ended during heating -------------------------------------------------------

HEATING_ABORTED = """\
# flowcurve-record: 1
# status: aborted
# test: tension
# specimen.id: v300
# nominal_temperature_C: 300.0
# specimen.d0_mm: 6.0
# specimen.l0_mm: 30.0
# stop_reason: stopped by SIGTERM
# samples: 0
time_s,force_N,crosshead_mm,temperature_C
# event: 0.003 heater_on set-point 300 C
# event: 498.914 heater_off stopped by SIGTERM
# event: 498.917 stop stopped by SIGTERM
"""


def test_a_record_that_ended_during_heating_says_so(tmp_path, monkeypatch):
    """As `flowcurve run tension --temperature 300` writes it when stopped while heating."""
    path = tmp_path / "heating.csv"
    path.write_text(HEATING_ABORTED)
    line = clean_error(path, (), tmp_path, monkeypatch)
    assert "ended during heating" in line and "set-point 300 °C" in line and "stopped by SIGTERM after 498.917 s" in line
    assert "no samples: nothing to identify" in line and "line 10" in line


def test_the_last_temperature_an_event_gives_is_named(tmp_path):
    text = HEATING_ABORTED.replace("heater_off stopped by SIGTERM", "heater_off over-temperature at 154.2 C")
    with pytest.raises(RecordError, match=r"ended during heating at 154\.2 °C \(set-point 300 °C; stopped by SIGTERM"):
        parse_record_bytes(text.encode(), source="heating.csv")


def test_a_record_that_ended_after_the_soak(tmp_path):
    text = HEATING_ABORTED.replace("# event: 498.914 heater_off", "# event: 400.0 soak_reached 299.6 C for 60 s\n# event: 498.914 heater_off")
    with pytest.raises(RecordError, match=r"ended after the soak at 299\.6 °C \(stopped by SIGTERM after 498\.917 s\), no samples"):
        parse_record_bytes(text.encode(), source="soaked.csv")
