"""CalculiX tension records with a real frame's artefacts (issue 29) identify, and their hardening
over the uniform range is the input law's within 2 %.

The records (:mod:`fe_records`) are continuous-yielding necking runs of the product's CalculiX
tension model recorded with a hold at zero force before the motion, frame compliance, a toe,
encoder counts and force noise. Before the fix the hold's noise was taken for an upper yield
point and identify ended in IndexError. The truth is the law CalculiX was given, not anything
the identification computes. The default test reads the vendored Voce record
(tests/tension/data/fe-voce-hold.csv, made by ``python -m tests.tension.fe_records voce …``);
the solver test makes Voce and Swift records anew, with and without the hold, over seeds.
"""

from __future__ import annotations

import io
import json
import shutil
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest

from flowcurve.cli import main
from flowcurve.record.format import write_record

from . import fe_records

VENDORED = Path(__file__).parent / "data" / "fe-voce-hold.csv"
TOLERANCE = 0.02


def identify_against_law(path: Path, name: str, out: Path, fracture_point: str = "exclude") -> dict:
    """Identify ``path`` with the input's law family; the largest relative error over the uniform
    range (εp from the fit range's start to the uniform plastic strain) of the true curve and of the
    fitted law against the input law. ``fracture_point`` 'exclude' fits the uniform range alone;
    'auto' lets the identification add the neck-corrected fracture point when it fits."""
    buf = io.StringIO()
    with redirect_stdout(buf), redirect_stderr(buf):
        code = main(["identify", str(path), "--law", name, "--fracture-point", fracture_point, "--no-plots", "--out", str(out)])
    assert code == 0, buf.getvalue()
    folder = out / path.stem
    result = json.loads((folder / "result.json").read_text())
    hard = result["hardening"]
    lo, hi = hard["fit_range"][0], result["uniform_true_plastic_strain"]
    curve = np.loadtxt(folder / "true_curve.csv", delimiter=",", skiprows=1)
    ep, sigma = curve[:, 0], curve[:, 1]
    uniform = (ep >= lo) & (ep <= hi)
    truth = fe_records.law(name)
    from flowcurve.identification.laws.hardening import static_form  # the fitted law, evaluated by the product's own function

    spec = static_form(name)
    fitted = spec.func(ep[uniform], **{n: hard[k] for n, k in zip(spec.names, spec.keys)})
    return {"yield_point": result["yield_point"], "E_MPa": result["E_MPa"], "range": (lo, hi), "fracture_point": hard["fracture_point"],
            "curve_error": float(np.max(np.abs(sigma[uniform] / truth(ep[uniform]) - 1.0))),
            "law_error": float(np.max(np.abs(fitted / truth(ep[uniform]) - 1.0))), "fit_error_pct": hard["fit_error_pct"]}


def test_the_vendored_calculix_record_identifies_within_2_percent(tmp_path):
    got = identify_against_law(VENDORED, "voce", tmp_path)
    assert got["yield_point"] is False  # continuous yielding: the hold's noise is no upper yield point
    assert got["range"][1] > 0.15
    assert got["curve_error"] < TOLERANCE and got["law_error"] < TOLERANCE, got


@pytest.mark.slow
@pytest.mark.solver
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")
@pytest.mark.parametrize("name", ["voce", "swift"])
def test_calculix_records_identify_within_2_percent(name, tmp_path):
    """The true curve and the law fitted to the uniform range within 2 % of the input; with the
    fracture point left to the identification ('auto') the law is printed, not bounded: a Swift
    law pulled through the neck-corrected fracture point misses the start of the range by ~3 %."""
    print("\n| record | law | uniform range εp | true curve, max % | law (uniform range), max % | law (fracture point auto), max % | E, MPa |")
    for hold_s in (0.0, 3.0):
        for seed in (1, 2, 3):
            path = write_record(tmp_path / f"fe-{name}-{hold_s:g}s-{seed}.csv", fe_records.fe_tension_record(name, hold_s=hold_s, seed=seed))
            got = identify_against_law(path, name, tmp_path / "out")
            auto = identify_against_law(path, name, tmp_path / "auto", fracture_point="auto")
            print(f"| {path.name} | {name} | {got['range'][0]:.4f}–{got['range'][1]:.4f} | {100 * got['curve_error']:.2f} | "
                  f"{100 * got['law_error']:.2f} | {100 * auto['law_error']:.2f} ({auto['fracture_point']}) | {got['E_MPa']:.0f} |")
            assert got["yield_point"] is False and auto["yield_point"] is False
            assert got["curve_error"] < TOLERANCE and got["law_error"] < TOLERANCE, (path.name, got)


@pytest.mark.parametrize("sample, change_N", [(60, 20_000.0), (60, None), (400, 20_000.0), (400, -20_000.0), (2400, None), (3600, 20_000.0)])
def test_a_single_bad_load_cell_frame(sample, change_N, tmp_path):
    """One corrupt frame (+20 kN, −20 kN, or 0 N: None) on the vendored record: before, an
    IndexError (0 N, −20 kN: a "yield point" whose plateau fell to zero) or a confident wrong
    answer (+20 kN taken as Fm); now the frame is left out with a warning naming it and the
    results are those of the clean record."""
    from flowcurve.record.format import read_record

    record = read_record(VENDORED)
    force = record.data["force_N"].to_numpy(copy=True)
    force[sample] = 0.0 if change_N is None else force[sample] + change_N
    record.data["force_N"] = force
    path = write_record(tmp_path / "bad-frame.csv", record)
    got = identify_against_law(path, "voce", tmp_path / "out")
    clean = json.loads((identify_against_law(VENDORED, "voce", tmp_path / "clean") and (tmp_path / "clean" / VENDORED.stem / "result.json")).read_text())
    result = json.loads((tmp_path / "out" / "bad-frame" / "result.json").read_text())
    assert any(f"sample {sample + 1} (" in w and "corrupt load-cell frame" in w for w in result["warnings"])
    for key in ("Rm_MPa", "Rp02_MPa", "E_MPa", "Ag_pct"):
        assert result[key] == pytest.approx(clean[key], rel=1e-3), key
    assert got["yield_point"] is False and got["law_error"] < TOLERANCE
