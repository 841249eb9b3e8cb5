"""load_record: native records, the INSTRON export, and any CSV through a column mapping."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from flowcurve.record.format import Record, write_record
from flowcurve.errors import RecordError
from flowcurve.record.importers import load_record, parse_column_option
from flowcurve.record.importers_text import to_native, unit_conversion

INSTRON_DIR = Path(__file__).resolve().parents[1] / "data" / "42CrMoS4" / "original_data"  # in the repository, CC BY 4.0
INSTRON_FILE = INSTRON_DIR / "46NT71.csv"


def _native(tmp_path: Path, n: int = 50) -> tuple[Path, Record]:
    t = np.arange(n) * 0.1
    data = pd.DataFrame({"time_s": t, "force_N": 1000.0 * t, "crosshead_mm": 0.01 * t})
    rec = Record(meta={"flowcurve-record": "1", "test": "tension", "specimen.d0_mm": "6"}, data=data, source="x")
    return write_record(tmp_path / "native.csv", rec), rec


# -- units -----------------------------------------------------------------------------------


def test_unit_table_against_definitions():
    # the international pound and inch: 1 lbf = 0.45359237 kg * 9.80665 m/s², 1 in = 25.4 mm
    assert to_native(1.0, "lbf", "force") == pytest.approx(0.45359237 * 9.80665, rel=1e-12)
    assert to_native(2.0, "in", "length") == pytest.approx(50.8)
    # psi = lbf/in²; MPa = N/mm²
    assert to_native(1.0, "psi", "stress") == pytest.approx(0.45359237 * 9.80665 / 25.4**2, rel=1e-9)
    assert to_native(273.15, "K", "temperature") == pytest.approx(0.0, abs=1e-12)
    assert to_native(212.0, "°F", "temperature") == pytest.approx(100.0)
    assert to_native(1.0, "kN", "force") == 1000.0
    assert to_native(90.0, "mm/min", "speed") == pytest.approx(1.5)


def test_unknown_unit_and_wrong_quantity_are_errors():
    with pytest.raises(RecordError, match="unknown unit 'furlong'"):
        unit_conversion("furlong", "length")
    with pytest.raises(RecordError, match="measures length, not force"):
        unit_conversion("mm", "force")


def test_parse_column_option():
    assert parse_column_option("force=Load:kN") == ("force", ("Load", "kN"))
    assert parse_column_option("time=Time") == ("time", ("Time", None))
    assert parse_column_option("crosshead=Pos: raw:mm") == ("crosshead", ("Pos: raw", "mm"))
    with pytest.raises(RecordError, match="unknown quantity 'strain'"):
        parse_column_option("strain=E:mm")
    with pytest.raises(RecordError, match="QUANTITY=COLUMN"):
        parse_column_option("Load:kN")


# -- native ----------------------------------------------------------------------------------


def test_native_round_trip_and_meta_override(tmp_path):
    path, rec = _native(tmp_path)
    got = load_record(path, meta={"specimen.l0_mm": "30", "specimen.d0_mm": "5"})
    pd.testing.assert_frame_equal(got.data, rec.data, check_exact=False, rtol=1e-8)
    assert got.number("specimen.l0_mm") == 30.0 and got.number("specimen.d0_mm") == 5.0


# -- INSTRON ---------------------------------------------------------------------------------


def test_instron_export_mapped_and_converted():
    rec = load_record(INSTRON_FILE)
    assert rec.test == "tension"
    assert rec.meta["specimen.id"] == "46NT71" and rec.meta["material"] == "42CrMoS4"
    d0 = rec.number("specimen.d0_mm")
    # the lab's own S0 agrees with π d0²/4 from the diameter we mapped
    assert math.pi * d0**2 / 4 == pytest.approx(rec.number("specimen.s0_mm2"), rel=1e-9)
    assert rec.number("specimen.l0_mm") == 25.0 == rec.number("specimen.extensometer_gauge_mm")
    # dk from the area after fracture: S = π dk²/4
    assert math.pi * rec.number("post.dk_mm") ** 2 / 4 == pytest.approx(rec.number("post.sk_mm2"), rel=1e-12)
    assert rec.number("nominal_temperature_C") == 23.0 and any("RT" in w for w in rec.warnings)
    # force was in kN: Fmax / S0 must give the lab's published Rm (independent check of ×1000)
    rm = rec.column("force_N").max() / rec.number("specimen.s0_mm2")
    assert rm == pytest.approx(rec.number("published.Rm_MPa"), rel=1e-4)
    # every sample row is read (file lines minus 23 header lines, names row, units row)
    n_lines = sum(1 for _ in open(INSTRON_FILE, encoding="utf-8"))
    assert len(rec.data) == n_lines - 25 and rec.data["time_s"].iloc[0] == 0.0
    assert list(rec.data.columns) == ["time_s", "force_N", "crosshead_mm", "extensometer_mm"]
    # the engineering strain column of the file is Displacement / gauge length: cross-check
    raw = pd.read_csv(INSTRON_FILE, sep="\t", skiprows=[*range(23), 24])
    np.testing.assert_allclose(rec.column("extensometer_mm") / 25.0, raw["Engineering Strain"], rtol=1e-9, atol=1e-12)


# -- any CSV ---------------------------------------------------------------------------------


def test_mapped_csv_semicolon_decimal_comma_units_row(tmp_path):
    path = tmp_path / "vendor.csv"
    rows = ["Prüfbericht Zugversuch", "", "Zeit;Kraft;Weg;Temp", "s;kN;mm;K"]
    for i in range(30):
        rows.append(f"{i * 0.5:.1f};{i * 0.25:.2f};{i * 0.001:.3f};{293.15 + i:.2f}".replace(".", ","))
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    mapping = {"time": ("Zeit", "s"), "force": ("Kraft", None), "crosshead": ("Weg", "mm"), "temperature": ("Temp", "K")}
    rec = load_record(path, columns=mapping, meta={"test": "compression"})
    i = np.arange(30)
    np.testing.assert_allclose(rec.column("force_N"), 250.0 * i)
    np.testing.assert_allclose(rec.column("time_s"), 0.5 * i)
    np.testing.assert_allclose(rec.column("temperature_C"), 20.0 + i, atol=1e-9)
    assert rec.test == "compression"


def test_mapped_csv_comma_no_units_row(tmp_path):
    path = tmp_path / "plain.csv"
    path.write_text("Time,Load,Extension,Note\n0,0.1,0,a\n1,0.2,0.5,b\n2,0.3,1.0,c\n", encoding="utf-8")
    rec = load_record(path, columns={"time": ("Time", "min"), "force": ("Load", "lbf"), "crosshead": ("Extension", "in")})
    np.testing.assert_allclose(rec.column("time_s"), [0, 60, 120])
    np.testing.assert_allclose(rec.column("crosshead_mm"), [0, 12.7, 25.4])
    np.testing.assert_allclose(rec.column("force_N"), np.array([0.1, 0.2, 0.3]) * 4.4482216152605)


def test_mapped_csv_errors(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("Time,Load,Extension\n0,1,0\n1,abc,0.5\n", encoding="utf-8")
    cols = {"time": ("Time", "s"), "force": ("Load", "kN"), "crosshead": ("Extension", "mm")}
    with pytest.raises(RecordError, match=r"bad.csv, line 3, column 'Load': not a number: 'abc'"):
        load_record(path, columns=cols)
    with pytest.raises(RecordError, match=r"no column named 'Kraft' \(columns found: Time, Load, Extension\)"):
        load_record(path, columns={**cols, "force": ("Kraft", "kN")})
    with pytest.raises(RecordError, match="unknown unit 'kgs'"):
        load_record(path, columns={**cols, "force": ("Load", "kgs")})
    with pytest.raises(RecordError, match="lacks crosshead"):
        load_record(path, columns={"force": ("Load", "kN"), "time": ("Time", "s")})
    good = tmp_path / "good.csv"
    good.write_text("Time,Load,Extension\n0,1,0\n1,2,0.5\n", encoding="utf-8")
    with pytest.raises(RecordError, match="no time column mapped and no crosshead speed"):
        load_record(good, columns={"force": ("Load", "kN"), "crosshead": ("Extension", "mm")})
    units = tmp_path / "units.csv"
    units.write_text("Time,Load,Extension\ns,kN,mm\n0,1,0\n", encoding="utf-8")
    with pytest.raises(RecordError, match="the mapping says 'N' but the file's units row says 'kN'; check units"):
        load_record(units, columns={**cols, "force": ("Load", "N")})


def test_time_derived_from_crosshead_speed(tmp_path):
    path = tmp_path / "notime.csv"
    path.write_text("Load;Extension\nkN;mm\n0;0\n1;0,5\n2;1,5\n", encoding="utf-8")
    rec = load_record(path, columns={"force": ("Load", None), "crosshead": ("Extension", None)}, meta={"crosshead_speed_mm_per_s": "0.01"})
    np.testing.assert_allclose(rec.column("time_s"), [0.0, 50.0, 150.0])
    assert list(rec.data.columns)[0] == "time_s" and any("derived" in w for w in rec.warnings)


def test_file_level_errors(tmp_path):
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(RecordError, match="empty.csv: the file is empty"):
        load_record(empty)
    with pytest.raises(RecordError, match="is a folder"):
        load_record(tmp_path)
    with pytest.raises(RecordError, match="no such file"):
        load_record(tmp_path / "nope.csv")
    header = tmp_path / "header.csv"
    header.write_text("Time,Load,Extension\n")
    with pytest.raises(RecordError, match="header only"):
        load_record(header, columns={"time": ("Time", "s"), "force": ("Load", "N"), "crosshead": ("Extension", "mm")})
    with pytest.raises(RecordError, match="header only"):
        load_record(header)  # the names are recognised (time, force, crosshead), but no samples
    odd = tmp_path / "odd.csv"
    odd.write_text("t,P,x\n0,1,0\n1,2,0.5\n")
    with pytest.raises(RecordError, match=r"no column row I recognise.*--column force=.*holds: t, P, x"):
        load_record(odd)
