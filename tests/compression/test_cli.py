"""``flowcurve identify`` on a synthetic compression record written in the native format."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from flowcurve.record.format import read_record, write_record
from flowcurve.cli import main


def test_identify_command_writes_the_compression_result(tmp_path, make_record, capsys):
    record, truth = make_record(seed=11)
    path = write_record(tmp_path / "C1.csv", record)
    out = tmp_path / "out"
    code = main(["identify", str(path), "--out", str(out), "--friction-method", "bulge_regression", "--friction-correction", "slab"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    folder = out / "C1"
    result = json.loads((folder / "result.json").read_text())
    for key in ("test", "E_MPa", "Rp02_MPa", "friction_mu", "friction", "hardening", "record", "warnings", "methods"):
        assert key in result, key
    assert result["test"] == "compression"
    assert result["friction_mu"] == pytest.approx(truth["mu"], abs=1e-3)
    assert set(result["friction"]) == {"fe_table", "bulge_regression", "ebrahimi_najafizadeh"}
    h = result["hardening"]
    assert {"law", "A_MPa", "B_MPa", "n", "fit_error_pct"} <= set(h)
    rec = result["record"]
    for key in ("path", "material", "nominal_temperature_C", "crosshead_speed_mm_per_s", "strain_rate_per_s", "specimen"):
        assert key in rec, key
    assert rec["specimen"]["h0_mm"] == pytest.approx(6.982)
    curve = pd.read_csv(folder / "true_curve.csv")
    # the applied correction's ∂σ/∂μ per point: a series fit weighs each point by u(μ)·|∂σ/∂μ| (docs/methods.md §5.10)
    assert list(curve.columns) == ["true_plastic_strain", "true_stress_MPa", "dsigma_dmu_MPa"]
    assert (curve["dsigma_dmu_MPa"] < 0).all()  # more friction: a lower flow stress from the same pressure
    assert curve["true_plastic_strain"].max() == pytest.approx(truth["eps_p_end"], abs=0.02)  # no E via CLI: total strain
    pngs = sorted(p.name for p in folder.glob("*.png"))
    assert "corrections.png" in pngs and "diagram.png" in pngs and "stress_strain.png" in pngs
    assert all((folder / p).stat().st_size > 1000 for p in pngs)
    assert "friction" in captured.out


def test_identify_command_missing_height_is_one_line(tmp_path, make_record, capsys):
    record, _ = make_record(drop=("post.hk_mm",))
    path = write_record(tmp_path / "C2.csv", record)
    code = main(["identify", str(path), "--out", str(tmp_path / "out"), "--no-plots", "--friction-method", "bulge_regression"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert any("post.hk_mm" in line and "C2.csv" in line for line in err)
    assert not any("Traceback" in line for line in err)


def test_identify_command_options_fill_the_post_measurements(tmp_path, make_record):
    record, truth = make_record(drop=("post.hk_mm", "post.dmax_mm"))
    path = write_record(tmp_path / "C3.csv", record)
    code = main(["identify", str(path), "--out", str(tmp_path / "out"), "--no-plots", "--friction-method", "bulge_regression", "--hk", f"{truth['hk']:.4f}", "--dmax", f"{truth['dmax']:.4f}"])
    assert code == 0
    result = json.loads((tmp_path / "out" / "C3" / "result.json").read_text())
    assert result["friction_mu"] == pytest.approx(truth["mu"], abs=1e-3)
    assert read_record(path).meta.get("post.hk_mm") is None  # options do not rewrite the record


def test_identify_command_passes_the_handbook_modulus(tmp_path, make_record):
    """--E strips the elastic strain with the given modulus: the curve then ends at the
    generating law's plastic strain, not at the total strain (as without --E above)."""
    record, truth = make_record(seed=12)
    path = write_record(tmp_path / "C4.csv", record)
    out = tmp_path / "out"
    code = main(["identify", str(path), "--out", str(out), "--no-plots", "--friction-method", "bulge_regression", "--friction-correction", "slab", "--E", repr(truth["E"])])
    assert code == 0
    result = json.loads((out / "C4" / "result.json").read_text())
    assert result["E_MPa"] == pytest.approx(truth["E"])
    curve = pd.read_csv(out / "C4" / "true_curve.csv")
    elastic_strain = truth["sigma_end"] / truth["E"]
    assert curve["true_plastic_strain"].max() == pytest.approx(truth["eps_p_end"], abs=elastic_strain / 2)


def test_identify_command_reads_mu_from_the_end_face_when_given(tmp_path, make_record, capsys):
    """--dface (post.dface_mm) routes the FE table's μ to the original end face; the bulge's μ
    stays beside it, and the screen names the basis of the μ range."""
    import math

    record, _ = make_record(seed=13)
    path = write_record(tmp_path / "C5.csv", record)
    d0, h0, hk = (float(record.meta[k]) for k in ("specimen.d0_mm", "specimen.h0_mm", "post.hk_mm"))
    dface = round(0.93 * d0 * math.sqrt(h0 / hk), 3)
    code = main(["identify", str(path), "--out", str(tmp_path / "out"), "--no-plots", "--dface", str(dface)])
    out = capsys.readouterr().out
    assert code == 0
    details = json.loads((tmp_path / "out" / "C5" / "result.json").read_text())["friction_details"]["fe_table"]
    assert details["mu_basis"] == "original end face (dface)" and details["inputs"]["dface_mm"] == dface
    assert 0.0 < details["mu"] < 0.35 and details["mu_from_bulge"] is not None
    assert "for the end face with dface ± 0.01 mm" in out
