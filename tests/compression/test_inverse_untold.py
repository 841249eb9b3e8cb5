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


def test_mu_is_no_better_known_than_the_shape_alone_tells(monkeypatch, seed_like_record):
    """The fit's covariance takes the force points as independent; μ's standard error is at least
    what dmax alone tells: σ_d/|∂dmax/∂μ| with σ_d = √(0.01² + (0.04·(dmax − d_n))²) mm. A fit
    whose dmax hardly moves with μ (0.2 mm per unit μ, as at h0/d0 1 near sticking) reports that
    floor, above ±0.02, with the "poorly told" warning; one whose dmax moves 2 mm per unit μ keeps
    the fit's 0.01."""
    import math

    record, _ = seed_like_record
    d0, h0 = (float(record.meta[k]) for k in ("specimen.d0_mm", "specimen.h0_mm"))
    hk, dmax = float(record.meta["post.hk_mm"]), float(record.meta["post.dmax_mm"])
    sigma_d = math.hypot(0.01, 0.04 * (dmax - d0 * math.sqrt(h0 / hk)))
    w = math.sqrt(inverse.FORCE_POINTS) / inverse.DMAX_SCALE_MM  # residual units of the dmax row per mm

    for ddmax_dmu, expected in ((0.2, sigma_d / 0.2), (2.0, 0.01)):
        def outcome(run, residuals_of, x0, lo, hi, *, n_residuals, **kw):
            jac = np.zeros((n_residuals, len(x0)))
            jac[: inverse.FORCE_POINTS, :] = 1.0
            jac[inverse.FORCE_POINTS, -1] = ddmax_dmu * w
            return SolverFit(x=np.asarray(x0, float), stderr=np.full(len(x0), 0.01), residuals=np.zeros(n_residuals), runs=9, solver_s=1.0,
                             wall_s=1.0, status=2, message="ftol", nfev=3, jac=jac)

        monkeypatch.setattr(inverse, "fit_with_solver", outcome)
        result = inverse.identify_inverse_fe(record, law="johnson_cook").result
        assert abs(result["inverse_fe"]["mu_stderr"] - expected) < 1e-9
        assert result["inverse_fe"]["mu_stderr_fit"] == 0.01
        assert any("poorly told" in w for w in result.get("warnings", [])) == (expected > inverse.MU_TOLD)
