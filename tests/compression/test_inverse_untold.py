"""An inverse FE fit whose μ the record does not tell (runs stopped on both sides of it, or a
null direction of the Jacobian) must not leave as "μ ± 0.0000": its standard error is null in
result.json, and a warning and the hardening quality say why. The solver fit is replaced by its
outcome (no CalculiX needed); the fit itself is tested in tests/fe/test_solver_fit.py."""

from __future__ import annotations

import numpy as np

import flowcurve.identification.fe.inverse as inverse
from flowcurve.identification.fe.solver_fit import SolverFit
from flowcurve.identification.outcome import to_jsonable


def test_an_untold_mu_is_null_with_a_warning(monkeypatch, seed_like_record):
    record, truth = seed_like_record

    def outcome(run, residuals_of, x0, lo, hi, *, n_residuals, **kw):
        se = np.full(len(x0), 0.01)
        se[-1] = np.nan
        return SolverFit(x=np.asarray(x0, float), stderr=se, residuals=np.zeros(n_residuals), runs=9, solver_s=1.0, wall_s=1.0,
                         status=2, message="ftol", nfev=3, undetermined=(len(x0) - 1,))

    monkeypatch.setattr(inverse, "fit_with_solver", outcome)
    result = inverse.identify_inverse_fe(record, law="johnson_cook").result
    assert any("does not determine μ" in w for w in result["warnings"])
    assert result["hardening"]["quality"] == "poor"
    written = to_jsonable(result)
    assert written["inverse_fe"]["mu_stderr"] is None and written["hardening"]["A_MPa_stderr"] == 0.01


def test_a_told_mu_has_no_such_warning(monkeypatch, seed_like_record):
    record, _ = seed_like_record

    def outcome(run, residuals_of, x0, lo, hi, *, n_residuals, **kw):
        return SolverFit(x=np.asarray(x0, float), stderr=np.full(len(x0), 0.01), residuals=np.zeros(n_residuals), runs=9, solver_s=1.0,
                         wall_s=1.0, status=2, message="ftol", nfev=3)

    monkeypatch.setattr(inverse, "fit_with_solver", outcome)
    result = inverse.identify_inverse_fe(record, law="johnson_cook").result
    assert not any("does not determine" in w for w in result.get("warnings", []))
    assert to_jsonable(result)["inverse_fe"]["mu_stderr"] == 0.01
