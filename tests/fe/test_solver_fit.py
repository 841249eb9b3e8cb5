"""The solver fit's standard errors: the Gauss–Newton covariance against the closed-form
standard errors of a straight-line fit, and no standard error (NaN, a warning) for a parameter
the residuals do not tell — where the explicit inverse of a singular JᵀJ gave a clipped 0
("μ ± 0.0000" on a record where μ is poorly told). Closed-form "runs", no solver."""

from __future__ import annotations

import numpy as np
import pytest

from flowcurve.identification.fe.solver_fit import fit_with_solver, parameter_covariance, parameter_stderr

T = np.linspace(0.0, 4.0, 9)
NOISE = np.random.default_rng(11).normal(0.0, 0.05, T.size)
TARGET = 2.0 * T + 1.0 + NOISE


class _Out:
    wall_s, cached = 0.0, False

    def __init__(self, y):
        self.y = y


def _line(x):
    return _Out(x[0] * T + x[1])


def _line_and_idle(x):
    """y = a·t + b; the third parameter does nothing."""
    return _Out(x[0] * T + x[1] + 0.0 * x[2])


def _line_and_fragile(x):
    """y = a·t + b; any run with the third parameter off 0.1 fails (a run that stops on both sides)."""
    return None if abs(x[2] - 0.1) > 1e-12 else _Out(x[0] * T + x[1])


def _ols_stderr():
    """Textbook standard errors of slope and intercept: s/√Sxx and s·√(1/n + t̄²/Sxx)."""
    n, tm = T.size, T.mean()
    sxx = float(((T - tm) ** 2).sum())
    slope = float(((T - tm) * (TARGET - TARGET.mean())).sum()) / sxx
    icpt = TARGET.mean() - slope * tm
    s = np.sqrt(float(((TARGET - slope * T - icpt) ** 2).sum()) / (n - 2))
    return np.array([slope, icpt]), np.array([s / np.sqrt(sxx), s * np.sqrt(1.0 / n + tm**2 / sxx)])


KW = dict(lo=[-10.0, -10.0], hi=[10.0, 10.0], n_residuals=T.size, steps=lambda x: np.full(x.size, 1e-4), workers=1)


def test_standard_errors_are_the_closed_form_ones_of_a_line():
    x_ols, se_ols = _ols_stderr()
    fit = fit_with_solver(_line, lambda o: o.y - TARGET, [1.0, 0.0], KW["lo"], KW["hi"], x_scale=np.array([1.0, 0.1]),
                          **{k: v for k, v in KW.items() if k not in ("lo", "hi")})
    np.testing.assert_allclose(fit.x, x_ols, atol=1e-6)
    np.testing.assert_allclose(fit.stderr, se_ols, rtol=1e-4)
    assert fit.undetermined == () and fit.undetermined_warnings(["a", "b"]) == []
    # the covariance of slope and intercept: −t̄·s²/Sxx (the textbook off-diagonal), so that a
    # derived value (the line at t) has the variance s²·(1/n + (t − t̄)²/Sxx) through it
    s2_over_sxx = se_ols[0] ** 2
    assert fit.covariance[0, 1] == pytest.approx(-T.mean() * s2_over_sxx, rel=1e-4)
    g = np.array([3.0, 1.0])  # ∂(a·t + b)/∂(a, b) at t = 3
    n, sxx = T.size, float(((T - T.mean()) ** 2).sum())
    s2 = s2_over_sxx * sxx
    assert float(g @ fit.covariance @ g) == pytest.approx(s2 * (1.0 / n + (3.0 - T.mean()) ** 2 / sxx), rel=1e-4)


def test_a_parameter_the_residuals_do_not_see_has_no_standard_error():
    J = np.column_stack([T, np.ones_like(T), np.zeros_like(T)])
    se, und = parameter_stderr(J, NOISE, [1.0, 1.0, 1.0])
    assert und == (2,) and np.isnan(se[2]) and np.all(np.isfinite(se[:2]))
    cov, _ = parameter_covariance(J, NOISE, [1.0, 1.0, 1.0])
    assert np.isnan(cov[2]).all() and np.isnan(cov[:, 2]).all() and np.isfinite(cov[:2, :2]).all()
    # two parameters that act only as their sum: neither is told, whatever their units
    se, und = parameter_stderr(np.column_stack([T, T * 1e3, np.ones_like(T)]), NOISE, [1.0, 1e-3, 1.0])
    assert und == (0, 1) and np.isnan(se[:2]).all() and np.isfinite(se[2])
    # the explicit inverse this replaces: a singular JᵀJ, and no usable variance from it
    with pytest.raises(np.linalg.LinAlgError):
        np.linalg.inv(J.T @ J)


def test_the_fit_reports_an_idle_parameter_undetermined():
    lo, hi = [-10.0, -10.0, -1.0], [10.0, 10.0, 1.0]
    kw = {k: v for k, v in KW.items() if k not in ("lo", "hi")}
    fit = fit_with_solver(_line_and_idle, lambda o: o.y - TARGET, [1.0, 0.0, 0.1], lo, hi, x_scale=np.ones(3), **kw)
    x_ols, se_ols = _ols_stderr()
    np.testing.assert_allclose(fit.x[:2], x_ols, atol=1e-6)
    np.testing.assert_allclose(fit.stderr[:2], se_ols, rtol=1e-4)
    assert fit.undetermined == (2,) and np.isnan(fit.stderr[2])
    (w,) = fit.undetermined_warnings(["a", "b", "μ"])
    assert "does not determine μ" in w


def test_runs_failing_on_both_sides_leave_the_parameter_undetermined_not_sharp():
    """Before: the column (1e3 − r)/h of the failed runs read as an enormous sensitivity, and the
    parameter came out with a standard error of 0."""
    lo, hi = [-10.0, -10.0, -1.0], [10.0, 10.0, 1.0]
    kw = {k: v for k, v in KW.items() if k not in ("lo", "hi")}
    fit = fit_with_solver(_line_and_fragile, lambda o: o.y - TARGET, [1.0, 0.0, 0.1], lo, hi, x_scale=np.ones(3), **kw)
    x_ols, se_ols = _ols_stderr()
    np.testing.assert_allclose(fit.x, [*x_ols, 0.1], atol=1e-6)  # the blind column did not push it anywhere
    np.testing.assert_allclose(fit.stderr[:2], se_ols, rtol=1e-4)
    assert fit.undetermined == (2,) and np.isnan(fit.stderr[2])


def test_a_row_of_known_sigma_weighs_by_it_and_not_by_the_others_scatter():
    """Rows of known σ (one measured diameter, say) against rows whose scatter is estimated: the
    covariance is (XᵀWX)⁻¹ with W = 1/σ² on the known row and 1/s² on the others, s² pooled over
    those alone (m − 2). Checked against the normal equations written out; a known row of huge σ
    counts as absent (the textbook line of the other rows); and pooled in, as before, a row known
    to ± 0.2 is weighed like the others' 0.05 scatter, which claims the line better known."""
    x_row, y_known = 10.0, 21.0  # a point beyond the others, on the line
    X = np.column_stack([np.append(T, x_row), np.ones(T.size + 1)])
    y = np.append(TARGET, y_known)
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ coef
    for sigma_known in (0.02, 0.2, 1e6):
        s2 = float(r[:-1] @ r[:-1]) / (T.size - 2)
        w = np.append(np.full(T.size, 1.0 / s2), 1.0 / sigma_known**2)
        cov = np.linalg.inv(X.T @ (w[:, None] * X))
        se, undetermined = parameter_stderr(X, r, row_sigma=np.append(np.full(T.size, np.nan), sigma_known))
        np.testing.assert_allclose(se, np.sqrt(np.diag(cov)), rtol=1e-9)
        assert undetermined == ()
    _, se_ols = _ols_stderr()
    se_far, _ = parameter_stderr(X, np.append(TARGET - X[:-1] @ _ols_stderr()[0], 0.0), row_sigma=np.append(np.full(T.size, np.nan), 1e6))
    np.testing.assert_allclose(se_far, se_ols, rtol=1e-6)
    # without row_sigma the known row is pooled in and weighed like the others: a smaller error than its σ allows
    se_pooled, _ = parameter_stderr(X, r)
    se_known, _ = parameter_stderr(X, r, row_sigma=np.append(np.full(T.size, np.nan), 0.2))
    assert se_known[1] > se_pooled[1]


def test_correlated_rows_inflate_the_pooled_variance_by_the_ar1_factor():
    """``correlated``: s² of the pooled rows times (1 + ρ)/(1 − ρ), ρ = ρ̂ + (1 + 3ρ̂)/m,
    ρ̂ = Σ r_i·r_i+1/Σ r_i² (written out here), held within [0, 0.9]."""
    from flowcurve.identification.fe.solver_fit import serial_correlation

    X = np.column_stack([T, np.ones_like(T)])
    smooth = 0.05 * np.sin(2.5 * T)  # a misfit that runs along the rows
    rho_hat = float(smooth[1:] @ smooth[:-1] / (smooth @ smooth))
    rho = rho_hat + (1 + 3 * rho_hat) / T.size
    assert 0.0 < rho < 0.9 and serial_correlation(smooth) == pytest.approx(rho)
    plain, _ = parameter_stderr(X, smooth)
    inflated, _ = parameter_stderr(X, smooth, correlated=True)
    np.testing.assert_allclose(inflated / plain, np.sqrt((1 + rho) / (1 - rho)), rtol=1e-12)
    alternating = 0.05 * (-1.0) ** np.arange(T.size)
    assert serial_correlation(alternating) == 0.0
    np.testing.assert_allclose(parameter_stderr(X, alternating, correlated=True)[0], parameter_stderr(X, alternating)[0])
    assert serial_correlation(np.ones(30)) == 0.9


def test_with_ar1_errors_the_inflated_standard_errors_cover_the_truth_far_better():
    """A straight line fitted to 30 points with AR(1) errors: over 2000 records, the slope's misses
    in units of its standard error. Independent errors (ρ 0): the inflation leaves them at ~1.
    ρ 0.6: taken as independent they scatter with 2.1; counted as correlated with 1.35 (ρ is
    estimated from 30 residuals, which still reads it low: honest would be 1)."""
    rng = np.random.default_rng(5)
    t = np.linspace(0.0, 1.0, 30)
    X = np.column_stack([t, np.ones_like(t)])
    for rho, plain_band, corr_band in ((0.0, (0.9, 1.1), (0.9, 1.1)), (0.6, (1.9, 2.3), (1.15, 1.45))):
        z_plain, z_corr = [], []
        for _ in range(2000):
            e = np.empty(t.size)
            e[0] = rng.normal()
            for i in range(1, t.size):
                e[i] = rho * e[i - 1] + rng.normal() * np.sqrt(1 - rho**2)
            y = 2.0 * t + 1.0 + 0.1 * e
            coef, *_ = np.linalg.lstsq(X, y, rcond=None)
            r = X @ coef - y
            z_plain.append((coef[0] - 2.0) / parameter_stderr(X, r)[0][0])
            z_corr.append((coef[0] - 2.0) / parameter_stderr(X, r, correlated=True)[0][0])
        assert plain_band[0] < np.std(z_plain) < plain_band[1]
        assert corr_band[0] < np.std(z_corr) < corr_band[1]


def test_best_start_runs_every_start_and_fits_from_the_one_that_misses_least():
    """y = sin(a·t) against a = 3 has other minima in a: from a = 0.5 the fit stays in one, from the
    nearest of the other starts (a failed one among them) it finds 3."""
    t = np.linspace(0.0, 6.0, 40)
    target = np.sin(3.0 * t)

    def wave(x):
        return None if x[0] > 5.0 else _Out(np.sin(x[0] * t))

    kw = dict(n_residuals=t.size, steps=lambda x: np.full(x.size, 1e-5), x_scale=np.ones(1), workers=1)
    stuck = fit_with_solver(wave, lambda o: o.y - target, [0.5], [0.0], [10.0], **kw)
    assert abs(stuck.x[0] - 3.0) > 0.5
    best = fit_with_solver(wave, lambda o: o.y - target, [0.5], [0.0], [10.0], other_starts=[[6.0], [2.8], [1.5]], best_start=True, **kw)
    assert best.x[0] == pytest.approx(3.0, abs=1e-6)
    assert best.runs >= 4  # every start was run
