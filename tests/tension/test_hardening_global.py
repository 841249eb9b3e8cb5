"""Hardening fits that cannot fail silently: checked against an independent global search.

The curves are closed-form Johnson–Cook, Swift and Voce laws with noise, fitted by every law
(also the "wrong" ones, as on real records). The reference is scipy's differential evolution
over a wide box of the same three constants and the same least-squares objective, a method
that shares nothing with the fit's grid-plus-local stages.
"""

import numpy as np
import pytest
from scipy.optimize import differential_evolution

from flowcurve.identification.laws.hardening import POOR_FIT_PCT, fit_hardening, johnson_cook_static, static_form, swift, voce

EPS = np.linspace(0.002, 0.08, 30)
CURVES = {
    # a saturating steel (fast Voce): the case where the old JC fit gave A = 0, n = 0.02, 174 % error
    "voce_fast": lambda e: voce(e, 450.0, 300.0, 60.0),
    "swift_small_eps0": lambda e: swift(e, 1100.0, 0.0005, 0.12),
    "jc_steel45": lambda e: johnson_cook_static(e, 410.0, 280.0, 0.47),
    # a sharp knee then linear hardening: no law fits it exactly
    "knee": lambda e: 600.0 + 250.0 * (1.0 - np.exp(-e / 0.004)) + 500.0 * e,
}


def brute_force_rms_pct(law: str, eps, sig, extra=()) -> float:
    """RMS relative error (%) of the best fit of ``law`` found by differential evolution."""
    e = np.concatenate([eps, [p[0] for p in extra]])
    s = np.concatenate([sig, [p[1] for p in extra]])
    w = np.concatenate([np.ones_like(eps), [p[2] for p in extra]])
    top, span = float(np.max(s)), float(np.max(e))
    func = static_form(law).func
    if law == "johnson_cook":
        box, unpack = [(0, 2 * top), (0, 10 * top), (np.log(0.005), np.log(3.0))], lambda x: (x[0], x[1], np.exp(x[2]))
    elif law == "swift":
        box, unpack = [(0, 5 * top), (np.log(1e-8), 0.0), (np.log(1e-3), np.log(2.0))], lambda x: (x[0], np.exp(x[1]), np.exp(x[2]))
    else:
        box, unpack = [(0, 2 * top), (0, 2 * top), (np.log(0.05 / span), np.log(2000 / span))], lambda x: (x[0], x[1], np.exp(x[2]))

    def cost(x):
        with np.errstate(over="ignore", invalid="ignore"):
            r = np.sum((w * (func(e, *unpack(x)) - s)) ** 2)
        return r if np.isfinite(r) else 1e30

    best = differential_evolution(cost, box, seed=3, tol=1e-8, maxiter=150, popsize=12, polish=True)
    rel = func(e, *unpack(best.x)) / s - 1.0
    return float(100 * np.sqrt(np.mean(rel**2)))


@pytest.mark.parametrize("curve", list(CURVES))
@pytest.mark.parametrize("law", ("johnson_cook", "swift", "voce"))  # the laws brute_force_rms_pct boxes
def test_fit_is_as_good_as_an_independent_global_search(curve, law):
    rng = np.random.default_rng(11)
    sig = CURVES[curve](EPS) * (1 + 0.003 * rng.standard_normal(EPS.size))
    fit = fit_hardening(EPS, sig, law)
    reference = brute_force_rms_pct(law, EPS, sig)
    assert fit.rms_error_pct <= 1.5 * reference + 0.05, (fit.params, fit.rms_error_pct, reference)
    # its own figures are what it says: the law evaluated at the fitted constants
    rel = fit(EPS) / sig - 1.0
    assert fit.rms_error_pct == pytest.approx(100 * np.sqrt(np.mean(rel**2)))
    assert fit.quality == ("poor" if fit.fit_error_pct > POOR_FIT_PCT else "good")


def test_with_a_far_fracture_point_still_as_good_as_the_global_search():
    rng = np.random.default_rng(5)
    sig = CURVES["voce_fast"](EPS) * (1 + 0.003 * rng.standard_normal(EPS.size))
    extra = [(0.6, 760.0, np.sqrt(30.0))]
    fit = fit_hardening(EPS, sig, "johnson_cook", extra_points=extra)
    reference = brute_force_rms_pct("johnson_cook", EPS, sig, extra)
    assert fit.rms_error_pct <= 1.5 * reference + 0.05


def test_a_constant_on_its_bound_and_a_poor_fit_are_said():
    # Voce saturation fitted by JC up to a far point on the plateau: the best JC has A = 0 (its
    # bound) and a max error above 10 %
    sig = CURVES["voce_fast"](EPS)
    fit = fit_hardening(EPS, sig, "johnson_cook", extra_points=[(0.6, 760.0, np.sqrt(30.0))])
    assert fit.params["A"] == pytest.approx(0.0, abs=1e-6)
    assert any("A_MPa" in w and "bound" in w for w in fit.warnings)
    assert fit.fit_error_pct > POOR_FIT_PCT and fit.quality == "poor"
    assert any("poor" in w for w in fit.warnings)
    d = fit.as_dict()
    assert d["quality"] == "poor" and d["warnings"] == fit.warnings


def test_exact_law_is_good_and_silent():
    fit = fit_hardening(EPS, CURVES["jc_steel45"](EPS), "johnson_cook")
    assert fit.quality == "good" and fit.warnings == []
    assert fit.params["n"] == pytest.approx(0.47, rel=1e-5)
