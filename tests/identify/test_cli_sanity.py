"""Sanity checks and messages through the real command: one line, the file or option named,
exit ≠ 0, no traceback, no raw numpy RuntimeWarning (the module runs with them as errors)."""

from __future__ import annotations

import csv
import json
import re
import subprocess
import sys
import warnings

import numpy as np
import pandas as pd
import pytest

from flowcurve.record.format import Record, write_record

from .cli_run import one_error, run_cli
from .lab_exports import tension_truth, write_bluehill

pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")

GEOMETRY = ["--test", "tension", "--d0", "6", "--l0", "30", "--le", "25"]




@pytest.fixture(scope="module")
def truth():
    return tension_truth()


@pytest.fixture
def bluehill(tmp_path, truth):
    return write_bluehill(tmp_path / "bluehill.csv", truth)


def _native(tmp_path, name, truth, meta=None, **columns):
    data = {"time_s": truth.time_s, "force_N": truth.force_N, "crosshead_mm": truth.crosshead_mm, **columns}
    header = {"flowcurve-record": "1", "status": "complete", "test": "tension", "specimen.d0_mm": "6", "specimen.l0_mm": "30",
              "rig.frame_stiffness_N_per_um": "60", **(meta or {})}
    return write_record(tmp_path / f"{name}.csv", Record(meta={k: v for k, v in header.items() if v is not None}, data=pd.DataFrame(data)))


# -- measurements after the test ---------------------------------------------------------------


@pytest.mark.parametrize("option, value, pattern", [
    ("--lu", "29.5", r"Lu = 29\.5 mm \(post\.lu_mm, --lu\) is shorter than L0 = 30 mm \(specimen\.l0_mm, --l0\)"),
    ("--dk", "6.2", r"dk = 6\.2 mm \(post\.dk_mm, --dk\) is larger than d0 = 6 mm \(specimen\.d0_mm, --d0\)"),
    ("--set", "post.du_mm=6.1", r"du = 6\.1 mm \(post\.du_mm\) is larger than d0 = 6 mm"),
])
def test_impossible_post_test_measurements(bluehill, tmp_path, capsys, option, value, pattern):
    line = one_error(*run_cli(capsys, ["identify", str(bluehill), *GEOMETRY, option, value, "--out", str(tmp_path / "o"), "--no-plots"]))
    assert line.startswith(f"flowcurve: error: {bluehill}: ") and re.search(pattern, line), line


def test_A_only_when_the_record_reaches_fracture(tmp_path, capsys):
    stopped = write_bluehill(tmp_path / "stopped.csv", tension_truth(fracture=False))  # ends at 1.2 × the strain at Fm
    code, out, err = run_cli(capsys, ["identify", str(stopped), *GEOMETRY, "--out", str(tmp_path / "o"), "--no-plots"])
    assert code == 0, err
    result = json.loads((tmp_path / "o" / "stopped" / "result.json").read_text())
    assert result["A_pct"] is None and result["Rm_MPa"] > 0
    assert any("without a fracture: A is not reported" in w for w in result["warnings"])
    assert "A — %" in out and "warning: the record ends at 100 % of Fm without a fracture" in out
    # the same record with Lu measured after the test: A from Lu (3.8), whatever the record shows
    code, out, err = run_cli(capsys, ["identify", str(stopped), *GEOMETRY, "--lu", "36", "--out", str(tmp_path / "o"), "--no-plots"])
    result = json.loads((tmp_path / "o" / "stopped" / "result.json").read_text())
    assert code == 0 and result["A_pct"] == pytest.approx(20.0)


# -- --out ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("sub", ["", "deeper/still"])
def test_out_that_is_a_file(bluehill, tmp_path, capsys, sub):
    blocker = tmp_path / "results.txt"
    blocker.write_text("not a folder\n")
    out_dir = blocker / sub if sub else blocker
    line = one_error(*run_cli(capsys, ["identify", str(bluehill), *GEOMETRY, "--out", str(out_dir), "--no-plots"]))
    assert line == f"flowcurve: error: --out {out_dir}: {'' if not sub else str(blocker) + ' '}is a file, not a folder; choose another --out"


# -- overflow and non-finite values -------------------------------------------------------------


@pytest.mark.parametrize("value, pattern", [
    ("1e308", r"metadata 'specimen\.d0_mm' = '1e308' is beyond any measurement"),
    ("1e309", r"metadata 'specimen\.d0_mm' is not finite: '1e309'"),
    ("nan", r"metadata 'specimen\.d0_mm' is not finite: 'nan'"),
    ("-inf", r"metadata 'specimen\.d0_mm' is not finite: '-inf'"),
    ("1e-300", r"metadata 'specimen\.d0_mm' = 1e-300 is below any measurement"),
])
def test_overflow_in_the_header(tmp_path, truth, capsys, value, pattern):
    path = _native(tmp_path, "overflow", truth, {"specimen.d0_mm": value})
    line = one_error(*run_cli(capsys, ["identify", str(path), "--out", str(tmp_path / "o"), "--no-plots"]))
    assert line.startswith(f"flowcurve: error: {path}: ") and re.search(pattern, line), line


@pytest.mark.parametrize("option, value", [("--d0", "1e308"), ("--d0", "inf"), ("--l0", "nan"), ("--E", "0"), ("--le", "-25")])
def test_overflow_in_an_option(bluehill, tmp_path, capsys, option, value):
    argv = ["identify", str(bluehill), "--test", "tension", "--d0", "6", "--l0", "30", "--le", "25", option, value, "--out", str(tmp_path / "o")]
    line = one_error(*run_cli(capsys, argv))
    assert line.startswith(f"flowcurve: error: {option} must be a positive number of at most 1e+12, got {float(value)!r}")


@pytest.mark.parametrize("cell", ["1e308", "inf", "-Infinity"])
def test_overflow_in_the_samples_names_line_and_column(tmp_path, truth, capsys, cell):
    path = write_bluehill(tmp_path / "bluehill.csv", truth)
    lines = path.read_text().splitlines()
    cells = next(csv.reader([lines[400]]))  # line 401: a sample (the preamble, names and units rows above)
    cells[2] = cell  # the Load column
    lines[400] = ",".join(f'"{c}"' for c in cells)
    path.write_text("\n".join(lines) + "\n")
    line = one_error(*run_cli(capsys, ["identify", str(path), *GEOMETRY, "--out", str(tmp_path / "o"), "--no-plots"]))
    assert line.startswith(f"flowcurve: error: {path}, line 401, column 'Load': ") and "beyond any measurement" in line, line


# -- numerical warnings ------------------------------------------------------------------------------


def test_a_numpy_warning_becomes_a_result_warning_not_raw_output(bluehill, tmp_path, capsys, monkeypatch):
    import flowcurve.identification.identify as identify_module

    real = identify_module.identify

    def noisy(record, **options):
        np.log(np.zeros(1))  # numpy warns: divide by zero encountered in log
        return real(record, **options)

    monkeypatch.setattr(identify_module, "identify", noisy)
    with warnings.catch_warnings():
        warnings.simplefilter("default", RuntimeWarning)  # as a user runs it, not as this module
        code, out, err = run_cli(capsys, ["identify", str(bluehill), *GEOMETRY, "--out", str(tmp_path / "o"), "--no-plots"])
    assert code == 0 and "RuntimeWarning" not in err and err == "", err
    assert "  warning: numerical warning: divide by zero encountered in log" in out
    result = json.loads((tmp_path / "o" / "bluehill" / "result.json").read_text())
    assert "numerical warning: divide by zero encountered in log" in result["warnings"]


def test_subprocess_with_runtime_warnings_as_errors(tmp_path, truth):
    """The installed command, warnings as errors: vendor file, bad geometry, gap — no traceback."""
    good = write_bluehill(tmp_path / "good.csv", truth)
    gap = _native(tmp_path, "gap", truth, crosshead_mm=np.where(np.arange(truth.force_N.size) > 300, np.nan, truth.crosshead_mm))
    proc = subprocess.run([sys.executable, "-W", "error::RuntimeWarning", "-m", "flowcurve", "identify", str(good), str(gap), *GEOMETRY,
                           "--out", str(tmp_path / "o"), "--no-plots"], capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert proc.returncode != 0 and "Traceback" not in proc.stderr + proc.stdout and "Warning" not in proc.stderr, proc.stderr
    assert f"flowcurve: error: {gap}, column 'crosshead_mm': the crosshead channel has no value at sample 302" in proc.stderr
    assert (tmp_path / "o" / "good" / "result.json").exists()


# -- messages that blame the right input ----------------------------------------------------------


def test_missing_bulge_names_both_options(tmp_path, capsys):
    h0, d0 = 7.0, 6.0
    t = np.arange(400) * 0.1
    force = 20e3 * np.clip(t / 10.0, 0, 1) ** 0.3 + 1.0 * t
    header = {"flowcurve-record": "1", "test": "compression", "specimen.d0_mm": str(d0), "specimen.h0_mm": str(h0), "post.hk_mm": "4.5"}
    path = write_record(tmp_path / "C1.csv", Record(meta=header, data=pd.DataFrame({"time_s": t, "force_N": force, "crosshead_mm": 0.006 * t})))
    line = one_error(*run_cli(capsys, ["identify", str(path), "--out", str(tmp_path / "o"), "--no-plots"]))
    assert line.endswith("required metadata 'post.dmax_mm' or 'post.smax_mm2' is missing (add '# post.dmax_mm: <value>' to the header or give --dmax or --smax)")


def test_three_point_blames_dk_only_when_it_is_missing(bluehill, tmp_path, capsys):
    argv = ["identify", str(bluehill), *GEOMETRY, "--hardening", "three-point", "--out", str(tmp_path / "o"), "--no-plots"]
    line = one_error(*run_cli(capsys, argv))
    assert "it needs the fracture point: post.dk_mm (--dk)" in line
    code, out, err = run_cli(capsys, [*argv, "--dk", "4.2"])
    assert code == 0, err


def test_why_no_fit_names_the_failure_when_the_input_is_there():
    from flowcurve.identification.tension.identify import _why_no_fit

    fracture = {"true_strain": 0.7}
    failure = "three-point voce fit failed: no root in the bracket"
    assert _why_no_fit("three_point", "voce", fracture, 400.0, ["something else", failure]) == failure
    assert "dk" not in _why_no_fit("least_squares", "swift", fracture, 400.0, [])
    assert "post.dk_mm" in _why_no_fit("three_point", "voce", {}, 400.0, [failure])


def test_extensometer_gap_without_crosshead_says_so(tmp_path, truth, capsys):
    path = tmp_path / "ext_only.csv"
    strain = np.where(np.arange(truth.force_N.size) > 900, np.nan, 100 * truth.strain)
    rows = ["Time (s),Load (kN),Strain (%)"] + [f"{a:.3f},{b / 1e3:.6f},{'' if np.isnan(c) else f'{c:.6f}'}" for a, b, c in zip(truth.time_s, truth.force_N, strain)]
    path.write_text("\n".join(rows) + "\n")
    line = one_error(*run_cli(capsys, ["identify", str(path), *GEOMETRY, "--out", str(tmp_path / "o"), "--no-plots"]))
    assert line == (f"flowcurve: error: {path}, column 'extensometer_mm': the extensometer channel has no value from sample 902 on "
                    "(removed before fracture?); the record has no crosshead column to identify from instead")
    line = one_error(*run_cli(capsys, ["identify", str(path), *GEOMETRY, "--no-extensometer", "--out", str(tmp_path / "o"), "--no-plots"]))
    assert "the record has no crosshead column: its strain can only come from the extensometer (leave out --no-extensometer)" in line
