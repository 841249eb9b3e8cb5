"""Other labs' exports (Bluehill, testXpert, MTS) read as they are written, and identified.

The files come from :mod:`lab_exports`: a Ramberg–Osgood tension test written in each
vendor's layout, units, separators and encodings. The samples read back must equal the
generated ones (converted by hand-written factors here, not by the unit table), and the
identification through the command line must give the E, Rp0.2 and Rm the curve was built with.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from flowcurve.errors import RecordError
from flowcurve.record.importers import load_record
from flowcurve.record.importers_csv import recognise_quantity
from flowcurve.record.importers_text import split_name_unit

from .cli_run import one_error, run_cli
from .lab_exports import tension_truth, write_bluehill, write_mts, write_testxpert

LE = {"specimen.extensometer_gauge_mm": "25"}


@pytest.fixture(scope="module")
def truth():
    return tension_truth()




# -- names and units -------------------------------------------------------------------------


@pytest.mark.parametrize("cell, expected", [
    ("Time (s)", ("Time", "s")), ("Load [kN]", ("Load", "kN")), ("Extension (mm)", ("Extension", "mm")),
    ("Strain (%)", ("Strain", "%")), ("Axial Strain [mm/mm]", ("Axial Strain", "mm/mm")), ("Load[N]", ("Load", "N")),
    ("Tensile strain (Strain 1)", ("Tensile strain (Strain 1)", None)),  # a channel name, not a unit
    ("Tensile strain (Strain 1) (%)", ("Tensile strain (Strain 1)", "%")), ("Load", ("Load", None)),
])
def test_unit_written_in_the_column_name(cell, expected):
    assert split_name_unit(cell) == expected


@pytest.mark.parametrize("name, quantity", [
    ("Time", "time"), ("Prüfzeit", "time"), ("Running Time", "time"), ("Load", "force"), ("Standardkraft", "force"),
    ("Axial Force", "force"), ("Extension", "crosshead"), ("Traversenweg absolut", "crosshead"), ("Axial Displacement", "crosshead"),
    ("Grip to grip separation", "crosshead"), ("Tensile strain (Strain 1)", "extensometer"), ("Dehnung", "extensometer"),
    ("Extensometer", "extensometer"), ("Temperature", "temperature"),
    # derived or crosshead-based: never taken for a measured channel
    ("Tensile stress", None), ("True Strain", None), ("Tensile strain (Extension)", None), ("Nominal strain", None),
    ("Strain rate", None), ("Specimen label", None), ("Breitenänderung", None),
    ("Standardweg", None),  # testXpert's standard travel: the extensometer when fitted, else the crosshead
])
def test_recognised_names(name, quantity):
    assert recognise_quantity(name) == quantity


# -- the samples read back -------------------------------------------------------------------


def _assert_samples(rec, truth, *, crosshead=True):
    np.testing.assert_allclose(rec.column("time_s"), truth.time_s, atol=1e-6)
    np.testing.assert_allclose(rec.column("force_N"), truth.force_N, atol=2e-3)  # 6 decimals of kN, 9 digits of lbf
    np.testing.assert_allclose(rec.column("extensometer_mm"), truth.extensometer_mm, atol=1e-6)  # 6 decimals of % × 25 mm
    if crosshead:
        np.testing.assert_allclose(rec.column("crosshead_mm"), truth.crosshead_mm, atol=1e-5)
    else:
        assert "crosshead_mm" not in rec.data.columns


def test_bluehill_quoted_units_row_strain_in_percent(tmp_path, truth):
    rec = load_record(write_bluehill(tmp_path / "bluehill.csv", truth), meta=LE)
    _assert_samples(rec, truth)
    assert rec.warnings == []


def test_testxpert_utf16_tab_decimal_comma(tmp_path, truth):
    path = write_testxpert(tmp_path / "zwick.txt", truth)
    assert path.read_bytes()[:2] == b"\xff\xfe"  # Excel's "Unicode text": UTF-16 LE with a BOM
    rec = load_record(path, meta=LE)
    _assert_samples(rec, truth)
    assert rec.warnings == ["column 'Standardweg' left aside: it is the extensometer when one is fitted, else the crosshead "
                            "(to use it: --column extensometer=Standardweg:UNIT ...)"]
    # named by the user, the standard travel is the extensometer elongation itself (mm, no Le needed)
    rec = load_record(path, columns={"force": ("Standardkraft", None), "extensometer": ("Standardweg", None), "time": ("Prüfzeit", None)})
    np.testing.assert_allclose(rec.column("extensometer_mm"), truth.extensometer_mm, atol=1e-6)


def test_standard_travel_alone_asks_which_it_is(tmp_path):
    path = tmp_path / "zwick.csv"
    path.write_text("Prüfzeit;Standardkraft;Standardweg\ns;N;mm\n0;0;0\n1;100;0,01\n")
    with pytest.raises(RecordError, match=r"line 1: column 'Standardweg' is the extensometer when one is fitted, else the crosshead: say which"):
        load_record(path)


def test_testxpert_windows_1252_semicolons(tmp_path, truth):
    rec = load_record(write_testxpert(tmp_path / "zwick.csv", truth, encoding="cp1252", sep=";"), meta=LE)
    _assert_samples(rec, truth)
    assert any("Windows-1252" in w for w in rec.warnings)


def test_mts_us_units_after_a_preamble_with_utf8_bom(tmp_path, truth):
    rec = load_record(write_mts(tmp_path / "mts.csv", truth), meta=LE)
    _assert_samples(rec, truth)


def test_extensometer_only_file(tmp_path, truth):
    rec = load_record(write_bluehill(tmp_path / "ext_only.csv", truth, strain=False, crosshead=False))
    _assert_samples(rec, truth, crosshead=False)


def test_units_in_the_names_row_without_a_units_row(tmp_path, truth):
    path = tmp_path / "sheet.csv"
    rows = ["Time (s),Load [kN],Extension (mm),Strain (%)"]
    rows += [f"{a:.6f},{b / 1e3:.6f},{c:.6f},{100 * d:.6f}" for a, b, c, d in zip(truth.time_s, truth.force_N, truth.crosshead_mm, truth.strain)]
    path.write_text("\n".join(rows) + "\n")
    _assert_samples(load_record(path, meta=LE), truth)
    # a mapping may name the column without its unit: the unit comes from the name
    rec = load_record(path, columns={"force": ("Load", None), "extensometer": ("Strain", None), "time": ("Time", "s")}, meta=LE)
    np.testing.assert_allclose(rec.column("force_N"), truth.force_N, atol=2e-3)
    with pytest.raises(RecordError, match=r"column 'Load \[kN\]': the mapping says 'N' but the file's column name says 'kN'; check units"):
        load_record(path, columns={"force": ("Load", "N"), "extensometer": ("Strain", None)}, meta=LE)


def test_strain_as_ratio_mm_per_mm_and_dash(tmp_path, truth):
    for unit in ("mm/mm", "-"):
        path = tmp_path / "ratio.csv"
        rows = ["Time;Load;Strain", f"s;N;{unit}"]
        rows += [f"{a:.6f};{b:.4f};{d:.9f}".replace(".", ",") for a, b, d in zip(truth.time_s, truth.force_N, truth.strain)]
        path.write_text("\n".join(rows) + "\n")
        rec = load_record(path, meta=LE)
        np.testing.assert_allclose(rec.column("extensometer_mm"), truth.extensometer_mm, atol=1e-7)


# -- through the command line: identified as the curve was built ------------------------------

WRITERS = {
    "bluehill": lambda p, t: write_bluehill(p / "bluehill.csv", t),
    "testxpert_utf16": lambda p, t: write_testxpert(p / "zwick.txt", t),
    "mts": lambda p, t: write_mts(p / "mts.csv", t),
    "extensometer_only": lambda p, t: write_bluehill(p / "ext.csv", t, strain=False, crosshead=False),
}


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("vendor", list(WRITERS))
def test_identified_from_vendor_export(vendor, tmp_path, truth, capsys):
    path = WRITERS[vendor](tmp_path, truth)
    code, out, err = run_cli(capsys, ["identify", str(path), "--test", "tension", "--d0", "6", "--l0", "30", "--le", "25",
                                   "--out", str(tmp_path / "out"), "--no-plots"])
    assert code == 0, err
    result = json.loads((tmp_path / "out" / path.stem / "result.json").read_text())
    assert result["methods"]["strain_source"] == "extensometer"
    assert result["Rm_MPa"] == pytest.approx(truth.Rm_MPa, rel=1e-5)
    assert result["Rp02_MPa"] == pytest.approx(truth.Rp02_MPa, rel=0.01)
    assert result["E_MPa"] == pytest.approx(truth.E_MPa, rel=0.02)
    # A: plastic extension at the last sample before the fracture drop, from the curve's own numbers
    k = int(np.nonzero(truth.force_N > 0.5 * truth.force_N.max())[0][-1])
    A = 100.0 * (truth.strain[k] - truth.force_N[k] / truth.s0_mm2 / truth.E_MPa)
    assert result["A_pct"] == pytest.approx(A, rel=0.01)


# -- errors: one line, naming the file, the column and the option ------------------------------


def test_strain_column_without_le_names_the_option(tmp_path, truth, capsys):
    path = write_bluehill(tmp_path / "bluehill.csv", truth)
    code, out, err = run_cli(capsys, ["identify", str(path), "--test", "tension", "--d0", "6", "--l0", "30", "--out", str(tmp_path / "o"), "--no-plots"])
    assert code != 0
    line = one_error(code, out, err)
    assert f"{path}, column 'Tensile strain (Strain 1)': holds strain" in line and "give --le" in line


def _plain(tmp_path, header: str, units: str | None = None):
    path = tmp_path / "plain.csv"
    rows = [header] + ([units] if units else []) + [f"{i * 0.1:.1f},{i * 100.0:.1f},{i * 0.01:.3f},{i * 0.002:.4f}" for i in range(40)]
    path.write_text("\n".join(rows) + "\n")
    return path


@pytest.mark.parametrize("header, units, pattern", [
    ("Time,Load,Extension,Strain", None, r"column 'Time': no unit: neither in the column name .* nor in a units row under it; give it: --column time=Time:UNIT"),
    ("Time (s),Load (kgs),Extension (mm),Strain (%)", None, r"column 'Load \(kgs\)': no unit: .* --column force=Load \(kgs\):UNIT"),
    ("Time (s),Load [kgs],Extension (mm),Strain (%)", None, r"column 'Load \[kgs\]': unknown unit 'kgs' \(known force units: .*kN"),
    ("Time (s),Load [kN],Extension (mm),Strain (mm)", "s,kN,mm,%", r"line 2, column 'Strain \(mm\)': the name says 'mm' but the units row says '%'; check units"),
    ("Time (s),Load [kN],Extension (mm),Strain (°C)", None, r"column 'Strain \(°C\)': unit '°C' is neither a length nor a strain unit"),
    ("Time (s),Load [kN],Crosshead (mm),Position (mm)", None, r"line 1: columns 'Crosshead \(mm\)', 'Position \(mm\)' all look like the crosshead; choose one: --column crosshead="),
    ("t,P,x,e", "s,kN,mm,%", r"no column row I recognise .* --column force=Load:kN .*holds: t, P, x, e"),
])
def test_unreadable_columns_one_line(tmp_path, capsys, header, units, pattern):
    path = _plain(tmp_path, header, units)
    code, out, err = run_cli(capsys, ["identify", str(path), "--test", "tension", "--d0", "6", "--l0", "30", "--le", "25", "--out", str(tmp_path / "o"), "--no-plots"])
    assert code != 0
    line = one_error(code, out, err)
    assert line.startswith(f"flowcurve: error: {path}") and re.search(pattern, line), line


def test_thousands_separators_both_ways(tmp_path, truth):
    """Bluehill quotes "1,004.8" in a comma file; a German export writes 1.004,8 with semicolons."""
    path = tmp_path / "german.csv"
    rows = ["Zeit;Kraft;Traverse", "s;N;mm"]
    for a, b, c in zip(truth.time_s, truth.force_N, truth.crosshead_mm):
        rows.append(";".join(f"{v:,.6f}".replace(",", " ").replace(".", ",").replace(" ", ".") for v in (a, b, c)))
    path.write_text("\n".join(rows) + "\n", encoding="cp1252")
    assert any(re.fullmatch(r"\d\.\d{3},\d{6}", r.split(";")[1]) for r in rows[2:])  # forces written 9.764,031000
    rec = load_record(path)
    np.testing.assert_allclose(rec.column("force_N"), truth.force_N, atol=1e-5)
    np.testing.assert_allclose(rec.column("crosshead_mm"), truth.crosshead_mm, atol=1e-6)
    text = write_bluehill(tmp_path / "b.csv", truth).read_text()
    assert re.search(r'"\d,\d{3}\.\d{6}"', text)  # the Bluehill writer does write "1,004.803280"
