"""Records of issue 37's own kind (tests/fe/other_settings.py: the product's upsetting model with
stick slope 1e5, 4 boundary-layer elements, 200 increments; the rig's compliance, toe, noise,
counts): the default identification (fe_table) within ±0.02 in μ from the bulge and from the
end face, the flow curve within 2 % over ε_p 0.05–0.6 on C1 and C2 (C3's points beyond ε 0.4 carry
the record's fold-over: 2.2 %, the law within 0.5 %); the slow test regenerates them with CalculiX.
The inverse on them: tests/fe/test_inverse_held_out.py."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest


from .other_settings import CASES, simulate, write_record
from .second_model import assert_regenerated, identify_default

DATA = Path(__file__).parent / "data"
C3_CURVE = ("C3: the measured points beyond ε_p 0.4 carry the record's own fold-over force (+1.6 % at 0.45, 2.2 % at most); "
            "the law fitted to them is within 0.5 % of the truth there")


@pytest.mark.parametrize("end_face", [False, True], ids=["bulge", "end face"])
@pytest.mark.parametrize("name", ["C1", "C2", pytest.param("C3", marks=pytest.mark.xfail(strict=True, reason=C3_CURVE))])
def test_default_reads_records_of_the_issues_kind(tmp_path, name, end_face):
    result, err = identify_default(DATA / f"other_settings_{name}.csv", tmp_path, end_face=end_face)
    assert result["friction_mu"] == pytest.approx(CASES[name].mu, abs=0.02)
    assert err < 0.02, err


@pytest.mark.parametrize("end_face", [False, True], ids=["bulge", "end face"])
def test_default_mu_and_law_on_c3(tmp_path, end_face):
    """C3's μ within ±0.02 and its fitted law within 1 % of the truth over ε_p 0.05–0.5 (its points: above)."""
    result, _ = identify_default(DATA / "other_settings_C3.csv", tmp_path, end_face=end_face)
    case = CASES["C3"]
    assert result["friction_mu"] == pytest.approx(case.mu, abs=0.02)
    h = result["hardening"]
    e = np.linspace(0.05, 0.5, 50)
    assert np.max(np.abs((h["A_MPa"] + h["B_MPa"] * e ** h["n"]) / case.flow(e) - 1.0)) < 0.01


@pytest.mark.parametrize("end_face", [False, True], ids=["bulge", "end face"])
def test_c3_points_past_the_fold_over_say_how_sure_they_are(tmp_path, end_face):
    """C3's points beyond ε_p 0.4 are up to 2.2 % off (the xfail above): each within 2 of its stated
    uncertainty (true_curve.csv correction_uncertainty_pct), grown there to the fold-over's 3 % from the model
    form's 0.12·μ, and a warning names the strain from which the points carry the fold-over."""
    import pandas as pd

    from flowcurve.identification.fe.model.model_form import FOLD_OVER_SIGMA_FACTOR, FORCE_SIGMA_PCT, force_model_form

    result, _ = identify_default(DATA / "other_settings_C3.csv", tmp_path, end_face=end_face)
    curve = pd.read_csv(tmp_path / "other_settings_C3" / "true_curve.csv", comment="#")
    e, s, u = (curve[k].to_numpy() for k in ("true_plastic_strain", "true_stress_MPa", "correction_uncertainty_pct"))
    past = (e >= 0.4) & (e <= 0.6)
    z = np.abs(s[past] / CASES["C3"].flow(e[past]) - 1.0) / (u[past] / 100.0)
    assert z.max() <= 2.0, z.max()
    np.testing.assert_allclose(u[past], FOLD_OVER_SIGMA_FACTOR * FORCE_SIGMA_PCT)
    assert u.min() == pytest.approx(100 * force_model_form(result["friction_mu"]), rel=1e-4)
    assert any("fold" in w and "correction_uncertainty_pct" in w for w in result["warnings"]), result["warnings"]


@pytest.mark.slow
@pytest.mark.solver
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")
@pytest.mark.parametrize("name", list(CASES))
def test_other_settings_regenerate_the_vendored_records(tmp_path, monkeypatch, name):
    """CalculiX makes the vendored record again (post-test shape to 0.2 µm, forces to 0.5 N); 25–60 s each."""
    monkeypatch.setenv("FLOWCURVE_FE_CACHE", str(tmp_path / "cache"))
    made = write_record(simulate(CASES[name]), tmp_path / f"{name}.csv")
    assert_regenerated(made, DATA / f"other_settings_{name}.csv")
