"""The hardening fits' cheaper paths (issue 43) give the numbers of the paths they replace: the
forward-difference Jacobian is scipy's "2-point" one, bit for bit, inside and at the bounds."""

import numpy as np
import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.hardening import forward_jacobian, johnson_cook_static

EPS = np.linspace(0.004, 0.3, 30)
SIG = johnson_cook_static(EPS, 300.0, 600.0, 0.35)
LO, HI = np.array([0.0, 0.0, 0.01]), np.array([np.inf, np.inf, 2.0])


def residual(x):
    """Residuals of A + B·εp^n against the closed-form curve."""
    return johnson_cook_static(EPS, *x) - SIG


@pytest.mark.parametrize("x", [[310.0, 580.0, 0.4], [0.0, 580.0, 0.4], [310.0, 580.0, 2.0 - 1e-12], [310.0, 580.0, 0.01]],
                         ids=["inside", "on the lower bound", "at the upper bound", "on a lower bound > 0"])
def test_forward_jacobian_is_scipys_two_point_difference(x):
    from scipy.optimize._numdiff import approx_derivative

    x = np.array(x)
    expected = approx_derivative(residual, x, method="2-point", bounds=(LO, HI), f0=residual(x))
    got = forward_jacobian(residual, x, LO, HI)
    assert np.array_equal(got, expected)
    assert np.array_equal(forward_jacobian(residual, x, LO, HI, f0=residual(x)), expected)  # the residuals at x handed in
    assert got.flags.f_contiguous  # laid out as scipy's, so the solver's linear algebra rounds alike


def test_a_trust_region_fit_with_it_ends_where_scipys_own_difference_does():
    from scipy.optimize import least_squares

    x0 = np.array([250.0, 700.0, 0.5])
    plain = least_squares(residual, x0, bounds=(LO, HI), x_scale="jac")
    fast = least_squares(residual, x0, jac=lambda x: forward_jacobian(residual, x, LO, HI), bounds=(LO, HI), x_scale="jac")
    assert np.array_equal(plain.x, fast.x) and plain.nfev == fast.nfev
    assert fast.x == pytest.approx([300.0, 600.0, 0.35], rel=1e-6)


@pytest.mark.parametrize("law", ["johnson_cook", "voce", "hockett_sherby"])
def test_the_lmfit_refit_is_model_fits_to_the_last_digit(law):
    """lmfit.minimize on Model.fit's residual: the same constants, errors, correlations, AIC and report."""
    import lmfit

    from flowcurve.identification.laws.hardening import _lmfit_refit, static_form

    spec = static_form(law)
    rng = np.random.default_rng(3)
    eps = np.append(EPS, 0.8)
    sig = np.append(SIG + rng.normal(0.0, 1.0, EPS.size), johnson_cook_static(0.8, 300.0, 600.0, 0.35))
    w = np.append(np.ones(EPS.size), 30**0.5)  # a fracture point's weight
    start = spec.law.guess(eps, sig)
    start = spec.renamed(start) if set(start) != set(spec.names) else start
    model = lmfit.Model(spec.func, independent_vars=["eps_p"])
    params = model.make_params()
    for name in spec.names:
        lo, hi = spec.bounds[name]
        params[name].set(value=float(np.clip(start[name], lo, hi)), min=lo, max=hi)
    expected = model.fit(sig, params, eps_p=eps, weights=w, nan_policy="raise", max_nfev=500)
    got, report = _lmfit_refit(spec, start, eps, sig, w)
    for name in spec.names:
        assert got.params[name].value == expected.params[name].value
        assert got.params[name].stderr == expected.params[name].stderr
        assert got.params[name].correl == expected.params[name].correl
    assert got.aic == expected.aic
    assert report == expected.fit_report()


def test_the_laws_clip_a_negative_strain_to_zero_as_before():
    """np.maximum(εp, 0) is np.clip(εp, 0, None): same values, same scalar type for a scalar."""
    from flowcurve.identification.laws.hardening import static_form, static_law_names

    eps = np.array([-0.1, -0.0, 0.0, 0.05, 0.4])
    for law in static_law_names():
        spec = static_form(law)
        values = spec.law.guess(EPS, SIG)
        values = {mine: values[theirs] for mine, theirs in zip(spec.names, spec.law.names)}
        assert np.array_equal(spec.func(eps, **values), spec.func(np.clip(eps, 0.0, None), **values))
        assert type(spec.func(0.1, **values)) is np.float64


def test_a_profiles_rows_are_built_when_read_as_floats():
    """The lazy rows of a profile: every row the law's constants as floats, indexable like the list they replace."""
    from flowcurve.identification.laws.hardening import static_form, static_law_names
    from flowcurve.identification.laws.static import Rows

    built = []
    rows = Rows(3, lambda i: built.append(i) or {"K": np.float64(10.0 * i), "n": i})
    assert built == [] and len(rows) == 3
    assert rows[1] == {"K": 10.0, "n": 1.0} and type(rows[1]["K"]) is float and rows[-1] == rows[2]
    assert rows[0:2] == [rows[0], rows[1]] and list(rows) == [rows[0], rows[1], rows[2]]
    with pytest.raises(IndexError):
        rows[3]
    for law in static_law_names():
        spec = static_form(law)
        ss, cands = spec.law.profile(EPS, SIG, np.ones_like(EPS))
        assert len(cands) == ss.size
        best = cands[int(np.argmin(ss))]
        assert set(best) == set(spec.law.names) and all(type(v) is float for v in best.values())


def test_forward_jacobian_matches_scipy_at_random_points_near_and_on_the_bounds():
    from scipy.optimize._numdiff import approx_derivative

    rng = np.random.default_rng(11)
    lo, hi = np.array([-5.0, 0.0, 0.01]), np.array([5.0, np.inf, 1e-2 + 4e-8])  # a bound pair narrower than the step
    for _ in range(300):
        x = np.array([rng.choice([-5.0, 5.0, -5.0 + 1e-9, rng.uniform(-5, 5), 0.0]), rng.choice([0.0, 1e-12, rng.uniform(0, 1e3)]),
                      rng.choice([0.01, 0.01 + 2e-8, 0.01 + 4e-8])])

        def r(v):
            return np.array([v[0] * v[1], np.sin(v[0]) + v[2] ** 2, v[1] * v[2] - v[0]])

        expected = approx_derivative(r, x, method="2-point", bounds=(lo, hi), f0=r(x))
        assert np.array_equal(forward_jacobian(r, x, lo, hi), expected)


def _root_point_by_point(g, lo, hi):
    """_root as written before issue 43: g evaluated point by point over the grid."""
    from scipy.optimize import brentq

    grid = np.geomspace(lo, hi, 400)
    vals = np.array([g(x) for x in grid])
    sign = np.sign(vals)
    i = np.nonzero(np.isfinite(vals[:-1]) & np.isfinite(vals[1:]) & (sign[:-1] * sign[1:] <= 0))[0][0]
    return float(grid[i]) if vals[i] == 0 else float(brentq(g, grid[i], grid[i + 1], xtol=1e-14, rtol=1e-13, maxiter=200))


@pytest.mark.parametrize("law", ["johnson_cook", "voce", "swift"])
def test_the_three_point_root_scan_on_the_whole_grid_finds_the_point_by_point_root(law, monkeypatch):
    from flowcurve.identification.laws import hardening

    rng = np.random.default_rng(2)
    for _ in range(20):
        e = np.sort(rng.uniform(0.002, 0.6, 3))
        s = johnson_cook_static(e, rng.uniform(100, 500), rng.uniform(200, 900), rng.uniform(0.1, 0.6))
        try:
            fast = hardening.three_point_fit(list(zip(e, s)), law)
        except IdentificationError:
            continue
        with monkeypatch.context() as m:
            m.setattr(hardening, "_root", lambda g, lo, hi, what: _root_point_by_point(g, lo, hi))
            slow = hardening.three_point_fit(list(zip(e, s)), law)
        assert fast.params == slow.params
