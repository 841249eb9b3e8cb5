"""--specimens TABLE.csv: each record of a multi-file run gets its own dimensions.

The check is independent of flowcurve's arithmetic: Rm of each record must be its own
maximum force over π·d0²/4 with the d0 of its row (the records differ only in d0 and Le).
"""

from __future__ import annotations

import json
import math
import re

import pytest

from flowcurve.record.specimens import read_specimen_table

from .cli_run import one_error, run_cli
from .lab_exports import tension_truth, write_bluehill




@pytest.fixture
def run3(tmp_path):
    """Three Bluehill exports of specimens with d0 5.9, 6.0, 6.1 mm (force scaled with the area)."""
    paths, d0s = [], (5.9, 6.0, 6.1)
    for i, d0 in enumerate(d0s, start=1):
        paths.append(write_bluehill(tmp_path / f"T{i}.csv", tension_truth(d0_mm=d0)))
    return paths, d0s


def test_each_record_gets_its_row(tmp_path, run3, capsys):
    paths, d0s = run3
    table = tmp_path / "specimens.csv"
    # as a German spreadsheet saves it: semicolons, decimal commas, units in the names, stems in 'file'
    rows = ["File;d0 (mm);L0 [mm];Le (mm);Lu (mm);dk (mm)"]
    rows += [f"{p.stem};{d0:.2f};30;25;33,1;{0.7 * d0:.3f}".replace(".", ",") for p, d0 in zip(paths, d0s)]
    table.write_text("\n".join(rows) + "\n", encoding="utf-8-sig")
    code, out, err = run_cli(capsys, ["identify", *map(str, paths), "--specimens", str(table), "--test", "tension", "--out", str(tmp_path / "o"), "--no-plots"])
    assert code == 0, err
    for path, d0 in zip(paths, d0s):
        result = json.loads((tmp_path / "o" / path.stem / "result.json").read_text())
        truth = tension_truth(d0_mm=d0)
        assert result["Rm_MPa"] == pytest.approx(truth.force_N.max() / (math.pi * d0**2 / 4.0), rel=1e-5)
        assert result["A_pct"] == pytest.approx(100.0 * (33.1 - 30.0) / 30.0, rel=1e-9)  # from Lu, (3.8)
        assert result["Z_pct"] == pytest.approx(100.0 * (1.0 - 0.7**2), rel=1e-3)  # dk = 0.7·d0


def test_units_row_and_project_suffixes(tmp_path):
    table = tmp_path / "t.tsv"
    table.write_text("file\td0\tl0_mm\tle\ttemperature\nname\tin\t\tmm\tK\nA.csv\t0.25\t30\t25\t873.15\n", encoding="utf-16")
    row = read_specimen_table(table).row_for(tmp_path / "A.csv")
    assert float(row.meta["specimen.d0_mm"]) == pytest.approx(6.35)
    assert float(row.meta["specimen.l0_mm"]) == 30.0 and float(row.meta["nominal_temperature_C"]) == pytest.approx(600.0)


@pytest.mark.parametrize("text, argv, pattern", [
    ("file,d0,l0\nT1,6,30\n", [], r"specimens\.csv, line 1, column 'd0': no unit: write it in the name \('d0 \(mm\)' or 'd0_mm'\)"),
    ("file,d0 (mm),diameter (mm)\nT1,6,30\n", [], r"specimens\.csv, line 1, column 'diameter \(mm\)': unknown column \(known: file, d0, l0"),
    ("file,d0 (mm),l0 (mm)\nT1,6,30\nT2,6.x,30\nT3,6,30\n", [], r"specimens\.csv, line 3, column 'd0 \(mm\)': not a number: '6\.x'"),
    ("file,d0 (mm),l0 (mm)\nT1,6,30\nT2,-6,30\nT3,6,30\n", [], r"specimens\.csv, line 3, column 'd0 \(mm\)': '-6' is not a measurement"),
    ("file,d0 (mm),l0 (mm)\nT1,1e308,30\nT2,6,30\nT3,6,30\n", [], r"specimens\.csv, line 2, column 'd0 \(mm\)': '1e308' is not a measurement"),
    ("d0 (mm),l0 (mm)\n6,30\n", [], r"specimens\.csv, line 1: no column 'file' naming the record"),
    ("file,d0 (mm),l0 (mm)\nT1,6,30\nT1,6.1,30\n", [], r"specimens\.csv, line 3, column 'file': 'T1' is named twice \(also on line 2\)"),
    ("file,d0 (mm),l0 (mm)\nT1,6,30\nT2,6,30\nT3,6,30\n", ["--d0", "6.05"], r"specimens\.csv, column 'd0 \(mm\)': --d0 and this column both give 'specimen\.d0_mm'; keep one"),
    ("file,d0 [kgs],l0 (mm)\nT1,6,30\n", [], r"specimens\.csv, column 'd0 \[kgs\]': unknown unit 'kgs'"),
])
def test_table_errors_one_line(tmp_path, run3, capsys, text, argv, pattern):
    paths, _ = run3
    table = tmp_path / "specimens.csv"
    table.write_text(text)
    code, out, err = run_cli(capsys, ["identify", *map(str, paths), "--specimens", str(table), "--test", "tension", "--le", "25",
                                   "--out", str(tmp_path / "o"), "--no-plots", *argv])
    assert code != 0
    line = one_error(code, out, err)
    assert re.search(pattern, line), line


def test_record_without_a_row_and_missing_value_name_table_and_option(tmp_path, run3, capsys):
    paths, _ = run3
    table = tmp_path / "specimens.csv"
    table.write_text("file,d0 (mm),l0 (mm)\nT1.csv,6,30\nT2.csv,,30\nT9.csv,6,30\n")
    code, out, err = run_cli(capsys, ["identify", *map(str, paths), "--specimens", str(table), "--test", "tension", "--le", "25",
                                   "--out", str(tmp_path / "o"), "--no-plots"])
    assert code != 0
    errors = [line for line in err.splitlines() if line.startswith("flowcurve: error:")]
    assert len(errors) == 2 and "Traceback" not in err, err
    # T2: the empty d0 cell is no value; the message names the header key, the option and the column
    assert errors[0] == (f"flowcurve: error: {paths[1]}: required metadata 'specimen.d0_mm' is missing "
                         f"(add '# specimen.d0_mm: <value>' to the header or give --d0 or a column 'd0' in {table})")
    assert re.search(rf"{re.escape(str(table))}: no row for the record '{re.escape(str(paths[2]))}' in column 'file' \(it holds: T1\.csv, T2\.csv, T9\.csv\)", errors[1])
    assert f"flowcurve: warning: {table}, line 4: 'T9.csv' names none of the records given" in err
    assert (tmp_path / "o" / "T1" / "result.json").exists()
