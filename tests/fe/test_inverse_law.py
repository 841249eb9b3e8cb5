"""The inverse FE fit's law when none is given: the one that best fits the fast curve, checked on
closed-form curves of each law (with 0.3 % noise) — the law that made the curve must win; and a
fit that cannot be trusted says so."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from flowcurve.identification.fe.law_choice import best_law_for
from flowcurve.identification.fe.synthetic import johnson_cook_flow, swift_flow, voce_flow

CURVES = {
    "johnson_cook": lambda e: johnson_cook_flow(e, A=105.0, B=1392.0, n=0.642),
    "swift": lambda e: swift_flow(e, K=800.0, eps0=0.01, n=0.3),
    "voce": lambda e: voce_flow(e, s0=300.0, q=400.0, b=5.0),
}


@pytest.mark.parametrize("law", list(CURVES))
def test_the_law_that_made_the_curve_is_chosen(law):
    e = np.linspace(0.002, 0.65, 300)
    s = CURVES[law](e) * (1.0 + np.random.default_rng(3).normal(0.0, 0.003, e.size))
    chosen, rms = best_law_for(pd.DataFrame({"true_plastic_strain": e, "true_stress_MPa": s}))
    assert chosen == law, rms
    assert set(rms) == set(CURVES) and rms[law] < 0.5


# -- a fit that cannot be trusted says so (no solver needed: a closed-form "run") ----------------------------


class _Out:
    wall_s, cached = 0.0, False

    def __init__(self, y):
        self.y = y


def _line_run(x):
    """y = a·t + b at five t; None (a failed run) where a > 5."""
    return None if x[0] > 5.0 else _Out(x[0] * np.arange(5.0) + x[1])


def test_the_solver_fit_recovers_a_closed_form_and_refuses_a_failed_warm_start():
    from flowcurve.errors import IdentificationError
    from flowcurve.identification.fe.solver_fit import fit_with_solver

    target = 2.0 * np.arange(5.0) + 1.0
    kw = dict(n_residuals=5, steps=lambda x: np.full(2, 1e-4), x_scale=np.ones(2), workers=1)
    fit = fit_with_solver(_line_run, lambda out: out.y - target, [1.0, 0.0], [-10.0, -10.0], [10.0, 10.0], **kw)
    np.testing.assert_allclose(fit.x, [2.0, 1.0], atol=1e-6)
    with pytest.raises(IdentificationError, match="failed at the warm start") as info:
        fit_with_solver(_line_run, lambda out: out.y - target, [6.0, 0.0], [-10.0, -10.0], [10.0, 10.0], **kw)
    assert "\n" not in str(info.value)


def test_a_poor_inverse_fit_carries_warnings():
    from types import SimpleNamespace

    from flowcurve.identification.fe.inverse import MU_BOUNDS, _fit_warnings

    converged = SimpleNamespace(status=2, message="ftol")
    assert _fit_warnings(0.4, 0.004, 0.12, converged) == []
    assert any("misses the force by 1.9 %" in w for w in _fit_warnings(1.9, 0.004, 0.12, converged))
    assert any("misses dmax by +0.030 mm" in w for w in _fit_warnings(0.4, 0.03, 0.12, converged))
    # a misfit within twice its σ in the fit (the model form's share) is not one
    assert _fit_warnings(0.4, 0.03, 0.12, converged, dmax_sigma_mm=0.016) == []
    assert any("misses dmax" in w for w in _fit_warnings(0.4, 0.033, 0.12, converged, dmax_sigma_mm=0.016))
    assert any("on its bound" in w for w in _fit_warnings(0.4, 0.004, MU_BOUNDS[1], converged))
    assert any("before converging" in w for w in _fit_warnings(0.4, 0.004, 0.12, SimpleNamespace(status=0, message="max nfev")))


def _edge_run(x):
    """y = a·t + b at five t; None (a failed run) for a in 2.00002–2.0002, where a forward step of
    1e-4 from the solution a = 2 lands."""
    return None if 2.00002 < x[0] < 2.0002 else _Out(x[0] * np.arange(5.0) + x[1])


def test_the_solver_fit_moves_a_failed_start_and_steps_back_from_a_failed_run():
    from flowcurve.identification.fe.solver_fit import fit_with_solver

    target = 2.0 * np.arange(5.0) + 1.0
    kw = dict(n_residuals=5, steps=lambda x: np.full(2, 1e-4), x_scale=np.ones(2), workers=1)
    fit = fit_with_solver(_line_run, lambda out: out.y - target, [6.0, 0.0], [-10.0, -10.0], [10.0, 10.0], other_starts=[[5.5, 0.0], [1.0, 0.0]], **kw)
    np.testing.assert_allclose(fit.x, [2.0, 1.0], atol=1e-6)
    # at the solution the forward step of a fails: the Jacobian takes the backward one, and the fit still lands there
    fit = fit_with_solver(_edge_run, lambda out: out.y - target, [1.0, 0.0], [-10.0, -10.0], [10.0, 10.0], **kw)
    np.testing.assert_allclose(fit.x, [2.0, 1.0], atol=1e-4)
    assert np.all(np.abs(fit.residuals) < 1e-3)


def test_failed_runs_are_counted_and_a_fit_that_met_many_says_so():
    """The count is checked against the runs that returned None as the run function itself saw
    them (in-process with one worker); the warning comes from that share."""
    from flowcurve.identification.fe.solver_fit import FAILED_SHARE_WARN, fit_with_solver

    seen = []

    def counted(x):
        out = _line_run(x)
        seen.append(out is None)
        return out

    target = 2.0 * np.arange(5.0) + 1.0
    kw = dict(n_residuals=5, steps=lambda x: np.full(2, 1e-4), x_scale=np.ones(2), workers=1)
    fit = fit_with_solver(counted, lambda out: out.y - target, [6.0, 0.0], [-10.0, -10.0], [10.0, 10.0],
                          other_starts=[[5.5, 0.0], [1.0, 0.0]], **kw)
    assert fit.runs == len(seen) and fit.failed_runs == sum(seen) >= 2  # the two failed starts at least
    said = fit.failed_runs_warnings("inverse FE")
    assert bool(said) == (sum(seen) >= FAILED_SHARE_WARN * len(seen))
    seen.clear()
    clean = fit_with_solver(counted, lambda out: out.y - target, [1.0, 0.0], [-10.0, -10.0], [4.0, 10.0], **kw)
    assert clean.failed_runs == 0 == sum(seen) and clean.failed_runs_warnings() == []
    many = type(clean)(**{**clean.__dict__, "runs": 10, "failed_runs": 3})
    assert "3 of 10 solver runs did not converge" in many.failed_runs_warnings("inverse FE (tension)")[0]
