"""Bad input through the real command: one line naming the file, exit ≠ 0, the others still done.

Every call also passes a good record (the INSTRON export 46NT71 of the 42CrMoS4 set) after the
bad one, and checks that its result folder was written.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from flowcurve.cli import main


def _run(capsys, argv):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def _error_lines(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("flowcurve: error:")]


def _case_empty(tmp_path, write_native):
    p = tmp_path / "empty.csv"
    p.write_text("")
    return p, [], r"empty\.csv: the file is empty"


def _case_header_only(tmp_path, write_native):
    p = tmp_path / "header_only.csv"
    p.write_text("# flowcurve-record: 1\n# test: tension\ntime_s,force_N,crosshead_mm\n")
    return p, [], r"header_only\.csv, line 3: the record has no samples \(header only\)"


def _case_non_numeric(tmp_path, write_native):
    p = write_native("non_numeric", np.linspace(0, 30000, 100))
    lines = p.read_text().splitlines()
    names_line = next(i for i, line in enumerate(lines) if line.startswith("time_s"))
    cells = lines[names_line + 57].split(",")
    cells[1] = "abc"
    lines[names_line + 57] = ",".join(cells)
    p.write_text("\n".join(lines) + "\n")
    return p, [], rf"non_numeric\.csv, line {names_line + 58}, column 'force_N': not a number: 'abc'"


def _case_missing_geometry(tmp_path, write_native):
    p = write_native("no_d0", np.linspace(0, 30000, 100), specimen__d0_mm=None)
    return p, [], r"no_d0\.csv: required metadata 'specimen\.d0_mm' is missing"


def _case_never_rises(tmp_path, write_native):
    rng = np.random.default_rng(1)
    p = write_native("flat", 15.0 + rng.normal(0.0, 2.0, 400))
    return p, [], r"flat\.csv, column 'force_N': force never rises above noise"


def _case_wrong_units(tmp_path, write_native):
    # a steel test (Rm ≈ 1200 MPa on d0 = 6 mm) whose force column is in kN, declared as N
    p = tmp_path / "kN_as_N.csv"
    t = np.arange(200) * 0.5
    f_kN = 34.0 * np.sin(np.linspace(0, 2.5, 200))
    rows = ["Time,Load,Extension"] + [f"{a:.2f},{b:.4f},{a * 0.01:.4f}" for a, b in zip(t, f_kN)]
    p.write_text("\n".join(rows) + "\n")
    argv = ["--column", "time=Time:s", "--column", "force=Load:N", "--column", "crosshead=Extension:mm", "--test", "tension", "--d0", "6", "--l0", "30"]
    return p, argv, r"kN_as_N\.csv: peak engineering stress 1\.2 MPa .* check units"


def _case_unknown_unit(tmp_path, write_native):
    p = tmp_path / "vendor.csv"
    p.write_text("Time,Load,Extension\n0,1,0\n1,2,0.5\n")
    argv = ["--column", "time=Time:s", "--column", "force=Load:kgs", "--column", "crosshead=Extension:mm"]
    return p, argv, r"vendor\.csv, column 'Load': unknown unit 'kgs'"


def _case_folder(tmp_path, write_native):
    p = tmp_path / "a_folder"
    p.mkdir()
    return p, [], r"a_folder: is a folder, not a record file"


CASES = [_case_empty, _case_header_only, _case_non_numeric, _case_missing_geometry, _case_never_rises,
         _case_wrong_units, _case_unknown_unit, _case_folder]


@pytest.mark.parametrize("case", CASES, ids=[c.__name__.removeprefix("_case_") for c in CASES])
def test_bad_record_one_line_error_others_done(case, tmp_path, write_native, instron_file, capsys):
    bad, extra, pattern = case(tmp_path, write_native)
    out_dir = tmp_path / "out"
    code, out, err = _run(capsys, ["identify", str(bad), str(instron_file), "--out", str(out_dir), "--no-plots", *extra])
    assert code != 0
    errors = _error_lines(err)
    assert len(errors) == 1, err
    import re

    assert re.search(pattern, errors[0]), errors[0]
    assert str(bad) in errors[0]
    assert "Traceback" not in err + out
    # the good record after the bad one was still identified
    result = json.loads((out_dir / instron_file.stem / "result.json").read_text())
    assert result["test"] == "tension" and result["Rm_MPa"] > 0


def test_subprocess_prints_no_traceback(tmp_path, instron_file):
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    proc = subprocess.run([sys.executable, "-m", "flowcurve", "identify", str(empty), str(instron_file), "--out", str(tmp_path / "o"), "--no-plots"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert proc.returncode != 0
    assert "Traceback" not in proc.stderr + proc.stdout
    assert f"flowcurve: error: {empty}: the file is empty" in proc.stderr
    assert (tmp_path / "o" / instron_file.stem / "result.json").exists()


def test_bad_column_option_is_one_line(capsys, tmp_path):
    code, out, err = _run(capsys, ["identify", str(tmp_path / "x.csv"), "--column", "Load:kN"])
    assert code != 0 and "Traceback" not in err
    assert _error_lines(err) == ["flowcurve: error: --column: 'Load:kN' is not QUANTITY=COLUMN[:UNIT] (e.g. force=Load:kN)"]
