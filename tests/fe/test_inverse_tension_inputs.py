"""The tension inverse FE without the solver: its flow-curve family against closed forms, and
the records it refuses before any run (no fracture, too short a necking range)."""

from __future__ import annotations

import numpy as np
import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification.identify import identify_inverse_fe
from flowcurve.identification.fe.inverse_tension import extended_curve
from flowcurve.identification.fe.synthetic import tension_record
from flowcurve.identification.fe.model.tension import TensionModel, TensionResult


def test_the_extension_is_voce_swift_or_the_logarithm_in_closed_form():
    """Beyond ε_a the slope decays as H·(1 + β·c·d)^(−1/c): Voce's σ_a + H·(1 − e^(−βd))/β at c = 0
    (and continuously as c → 0); Swift's K·(ε0 + ε)^n exactly at c = 1/(1 − n), β = (1 − n)/(ε0 + ε_a);
    H·ln(1 + β·d)/β at c = 1 (and continuously through it)."""
    from flowcurve.identification.fe.inverse_tension import hardening_beyond
    from flowcurve.identification.fe.synthetic import swift_flow

    ue, us = np.array([0.0, 0.05, 0.2]), np.array([300.0, 450.0, 600.0])
    assert extended_curve(0.1, ue, us, 580.0, 4.0, 0.7) == pytest.approx(np.interp(0.1, ue, us))
    assert extended_curve(0.2, ue, us, 580.0, 4.0, 0.7) == pytest.approx(600.0)
    h = 1e-7
    assert (extended_curve(0.2 + h, ue, us, 580.0, 4.0, 0.7) - 600.0) / h == pytest.approx(580.0, rel=1e-5)  # dσ/dε_p at ε_a
    d = np.linspace(0.0, 0.6, 13)
    slope = (hardening_beyond(d + h, 580.0, 4.0, 0.7) - hardening_beyond(d, 580.0, 4.0, 0.7)) / h
    np.testing.assert_allclose(slope, 580.0 * (1.0 + 4.0 * 0.7 * d) ** (-1.0 / 0.7), rtol=1e-5)
    # Voce at c = 0 and as c → 0
    voce = 1500.0 * -np.expm1(-8.0 * d) / 8.0
    np.testing.assert_allclose(hardening_beyond(d, 1500.0, 8.0, 0.0), voce, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(hardening_beyond(d, 1500.0, 8.0, 1e-7), voce, rtol=1e-5, atol=1e-9)
    # Swift from ε_a
    K, eps0, n, eps_a = 900.0, 0.01, 0.2, 0.09
    H = K * n * (eps0 + eps_a) ** (n - 1.0)
    np.testing.assert_allclose(swift_flow(eps_a + d, K, eps0, n) - swift_flow(eps_a, K, eps0, n),
                               hardening_beyond(d, H, (1.0 - n) / (eps0 + eps_a), 1.0 / (1.0 - n)), rtol=1e-12, atol=1e-9)
    # the logarithm at c = 1, and continuously through it
    np.testing.assert_allclose(hardening_beyond(d, 700.0, 5.0, 1.0), 700.0 * np.log1p(5.0 * d) / 5.0, rtol=1e-12)
    np.testing.assert_allclose(hardening_beyond(d, 700.0, 5.0, 1.0 + 1e-7), hardening_beyond(d, 700.0, 5.0, 1.0), rtol=1e-6)


def test_the_warm_start_family_follows_voce_swift_and_johnson_cook_to_fracture():
    """family_start on each law's curve from ε_pu/2 to fracture: within 0.01 %, Voce at c = 0."""
    from functools import partial

    from flowcurve.identification.fe.inverse_tension import family_start, hardening_beyond
    from flowcurve.identification.fe.synthetic import johnson_cook_flow, swift_flow, voce_flow

    starts = {}
    for name, flow, eps_a, eps_f in (("voce", partial(voce_flow, s0=300.0, q=400.0, b=8.0), 0.096, 0.55),
                                     ("swift", partial(swift_flow, K=900.0, eps0=0.01, n=0.2), 0.088, 0.6),
                                     ("jc", partial(johnson_cook_flow, A=350.0, B=600.0, n=0.45), 0.088, 0.53)):
        e = np.linspace(eps_a, eps_f, 60)
        starts[name] = x = family_start(e, flow(e), eps_a, float(flow(eps_a)))
        assert np.max(np.abs((flow(eps_a) + hardening_beyond(e - eps_a, *x)) / flow(e) - 1.0)) < 1e-4
    # and finds each law's own parameters where the family holds it exactly
    assert starts["voce"][1] == pytest.approx(8.0, rel=1e-3) and starts["voce"][2] < 1e-3
    assert starts["swift"][1] == pytest.approx(0.8 / 0.098, rel=1e-3) and starts["swift"][2] == pytest.approx(1.25, rel=1e-3)


def _record(force_end_fraction: float):
    """A tension record of a made-up run (no solver): rises to Fm, then falls to a fraction of it."""
    m = TensionModel(6.0, 30.0, 6.0, (0.0, 1.0), (300.0, 900.0))
    t = np.linspace(0.01, 1.0, 300)
    e = 6.0 * t
    fm = 15000.0
    force = np.where(t < 0.02, fm * t / 0.02 * 0.6, 0.6 * fm + 0.4 * fm * np.sin(np.clip((t - 0.02) / 0.6, 0, 1) * np.pi / 2))
    force = np.where(t > 0.62, fm - (1.0 - force_end_fraction) * fm * (t - 0.62) / 0.38, force)
    run = TensionResult(m, t, e, force, np.full(t.size, 2.2), True, 0.0)
    return tension_record(run)


def test_a_record_without_fracture_is_refused_before_any_solver_run(monkeypatch):
    import flowcurve.identification.fe.inverse_tension as inv

    def no_solver(*a, **k):
        raise AssertionError("the solver must not run")

    monkeypatch.setattr(inv, "fit_with_solver", no_solver)
    rec = _record(0.95)
    rec.data.loc[rec.data.index[-5:], "force_N"] = rec.data["force_N"].iloc[-6]  # no break: the force stays up
    with pytest.raises(IdentificationError, match="reaches fracture"):
        identify_inverse_fe(rec)


def test_the_measured_rows_end_on_the_curve_not_a_bin_width_below_it():
    """A Voce curve sampled with noise up to ε_a: the end row's σ is the curve's at ε_a within
    0.05 %; the last bin's mean placed at ε_a (the rows before stop 26) read 2.4 % low at ε 0.19."""
    from flowcurve.identification.fe.inverse_tension import uniform_rows
    from flowcurve.identification.fe.synthetic import voce_flow

    eps_end = 0.19
    ep = np.linspace(0.0, eps_end, 900)
    flow = voce_flow(ep, 300.0, 400.0, 8.0)
    sig = flow + np.random.default_rng(3).normal(0.0, 0.3, ep.size)
    rows_e, rows_s = uniform_rows(ep, sig, eps_end)
    assert rows_e[-1] == eps_end and np.all(np.diff(rows_e) > 0) and np.all(np.diff(rows_s) >= 0)
    assert rows_s[-1] == pytest.approx(float(voce_flow(eps_end, 300.0, 400.0, 8.0)), rel=5e-4)
    # every row lies on the curve (bin means of a locally straight curve)
    assert np.max(np.abs(np.array(rows_s[1:]) / voce_flow(np.array(rows_e[1:]), 300.0, 400.0, 8.0) - 1.0)) < 0.003
    last_bin_mean = sig[ep > eps_end / 300.0 ** (1.0 / 19.0)].mean()  # what the end row was
    assert last_bin_mean < 0.98 * rows_s[-1]


def test_the_fracture_stress_error_is_the_covariance_carried_through_the_extension():
    """√(gᵀCg) against the scatter of the extension at ε_f over draws of (H, b, m) from C (small
    enough for the linearisation to hold)."""
    from flowcurve.identification.fe.inverse_tension import fracture_stress_stderr, hardening_beyond

    x, d = np.array([1100.0, 8.0, 1.25]), 0.5
    se = np.array([10.0, 0.3, 0.03])
    corr = np.array([[1.0, 0.5, -0.3], [0.5, 1.0, 0.6], [-0.3, 0.6, 1.0]])
    cov = corr * np.outer(se, se)
    draws = np.random.default_rng(5).multivariate_normal(x, cov, 200_000)
    at_fracture = hardening_beyond(d, draws[:, 0], draws[:, 1], draws[:, 2])
    assert fracture_stress_stderr(cov, x, d) == pytest.approx(float(at_fracture.std()), rel=0.01)
    # the cross terms count: the same standard errors uncorrelated give another figure
    assert abs(fracture_stress_stderr(np.diag(se**2), x, d) / fracture_stress_stderr(cov, x, d) - 1.0) > 0.05
    # no covariance, or an undetermined parameter in it: no standard error
    assert fracture_stress_stderr(None, x, d) is None
    assert fracture_stress_stderr(np.full((4, 4), np.nan), x, d) is None


def test_a_model_that_cannot_follow_the_record_is_said_so_not_returned_quietly(monkeypatch):
    """Stand-in runs that miss the record's force by 3 % whatever the parameters (no solver): the
    result warns of the misfit and of every parameter the residuals do not tell, and gives no
    fracture-stress error rather than a made-up one."""
    import flowcurve.identification.fe.inverse_tension as inv

    from flowcurve.identification.tension.identify import identify_tension

    rec = _record(0.7)
    diagram = identify_tension(rec).curves["corrected_diagram"]
    elong, force = diagram["elongation_mm"].to_numpy(), diagram["force_N"].to_numpy()

    def off_by_3_pct(problem, x):
        return inv._Run(elong, 1.03 * force, np.full(elong.size, 2.2), 0.0, False)

    monkeypatch.setattr(inv, "_run", off_by_3_pct)
    result = identify_inverse_fe(rec, workers=1).result
    warnings = " | ".join(result["warnings"])
    assert "the model does not follow the record" in warnings and "force residual 3.0" in warnings
    for name in ("H", "beta", "c", "taper"):
        assert f"does not determine {name} at the fit" in warnings
    assert result["inverse_fe"]["fracture_true_stress_MPa_stderr"] is None
    assert result["inverse_fe"]["failed_solver_runs"] == 0 and "did not converge" not in warnings  # every stand-in run returned
    assert result["hardening"]["quality"] == "poor"  # the refitted law may follow the curve; the curve is not to be trusted
