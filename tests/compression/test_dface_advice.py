"""When μ is poorly told by the bulge (a tall specimen near sticking) and no end face was measured,
the result says plainly that measuring post.dface_mm would settle μ: a warning and result.json's
``dface_advice``. With the end face measured, or where dmax tells μ, no such advice (issue 37)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

import flowcurve.identification.fe.inverse as inverse
from flowcurve.identification.identify import identify_inverse_fe
from flowcurve.identification.compression.identify import identify_compression
from flowcurve.identification.fe.solver_fit import SolverFit
from flowcurve.identification.outcome import to_jsonable
from flowcurve.identification.compression.friction import DFACE_ADVICE

from .conftest import make_compression

RECORD_E_MPa = 194_000.0  # conftest's E_HANDBOOK_MPa: the modulus the seed-like record was made with


def test_tall_near_sticking_record_is_advised_to_measure_the_face():
    """An analytic record (h0/d0 1.67, μ 0.3: the bulge no longer grows with μ) gets the advice."""
    record, _ = make_compression(mu=0.3, h0=10.0, hk_target=5.0)
    result = identify_compression(record).result
    assert result["friction_details"]["fe_table"]["sensitivity"]["mu_per_dmax_resolution"] is None  # the premise: dmax does not tell μ
    assert to_jsonable(result)["dface_advice"] == DFACE_ADVICE
    assert any("post.dface_mm" in w for w in result["warnings"])


def test_measured_face_or_a_telling_bulge_gets_no_advice():
    record, _ = make_compression(mu=0.3, h0=10.0, hk_target=5.0, meta_extra={"post.dface_mm": "6.0"})
    result = identify_compression(record).result
    assert result["friction_details"]["fe_table"]["mu_basis"] == "original end face (dface)"
    assert "dface_advice" not in to_jsonable(result)
    record, _ = make_compression(mu=0.11)  # h0/d0 1.17: one dmax step moves μ by ~0.01
    assert "dface_advice" not in to_jsonable(identify_compression(record).result)


def _fit_outcome(mu_stderr):
    def outcome(run, residuals_of, x0, lo, hi, *, n_residuals, **kw):
        se = np.full(len(x0), 0.01)
        se[-1] = mu_stderr
        return SolverFit(x=np.asarray(x0, float), stderr=se, residuals=np.zeros(n_residuals), runs=9, solver_s=1.0, wall_s=1.0,
                         status=2, message="ftol", nfev=3)
    return outcome


@pytest.mark.parametrize("mu_stderr, advised", [(0.05, True), (0.005, False)])
def test_inverse_advises_the_face_when_mu_is_poorly_told(monkeypatch, seed_like_record, mu_stderr, advised):
    """The inverse judges μ itself (its standard error against MU_TOLD); the solver fit is replaced by its outcome."""
    record, _ = seed_like_record
    monkeypatch.setattr(inverse, "fit_with_solver", _fit_outcome(mu_stderr))
    monkeypatch.setattr(inverse, "_warm_start_run", lambda problem, x0: None)  # no solver: the fold-over's onset unknown
    result = to_jsonable(identify_inverse_fe(record, law="johnson_cook", E_MPa=RECORD_E_MPa).result)
    assert (result.get("dface_advice") == DFACE_ADVICE) is advised
    assert any("post.dface_mm" in w for w in result.get("warnings", [])) is advised


@pytest.mark.slow
@pytest.mark.solver
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")
def test_tall_fe_record_voce_is_advised_and_the_face_settles_it():
    """The Voce FE record (h0/d0 1.8, μ 0.17; the bulge reads 0.211, one dmax step moves μ by 0.047):
    advised; with its end face measured, μ within 0.015 and no advice. ~2 min of CalculiX uncached."""
    from flowcurve.identification.fe.synthetic import VALIDATION_CASES, run_case, upsetting_record

    case = next(c for c in VALIDATION_CASES if c["name"].startswith("Voce"))
    run = run_case(case)
    bare = to_jsonable(identify_compression(upsetting_record(run, seed=3, toe_mm=0.0)).result)
    assert bare["dface_advice"] == DFACE_ADVICE
    faced = to_jsonable(identify_compression(upsetting_record(run, seed=3, toe_mm=0.0, end_face=True)).result)
    assert "dface_advice" not in faced and faced["friction_mu"] == pytest.approx(case["mu"], abs=0.015)
