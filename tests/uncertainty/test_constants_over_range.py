"""The hardening constants' method term over the fit range (issue 43, docs/methods.md §2.12):
uncertainty.correlated_fit_u against independent methods (a Monte Carlo of correlated residuals, a
brute-force profile of a constant on its bound) and its place in constant_budget."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flowcurve.identification.laws import bounds as bounds_rule
from flowcurve.identification.quality import uncertainty as un


def line(x, a, b):
    return a + b * x  # σ = a + b·x


def _ar1(rng, n, rho, sd):
    """AR(1) noise of standard deviation sd and lag-1 correlation rho."""
    e = rng.normal(0.0, sd * math.sqrt(1.0 - rho**2), n)
    out = np.empty(n)
    out[0] = rng.normal(0.0, sd)
    for i in range(1, n):
        out[i] = rho * out[i - 1] + e[i]
    return out


def test_correlated_residuals_widen_the_slope_u_to_its_monte_carlo_spread():
    """Correlated noise (ρ = 0.9): the stated u of the slope matches the spread of the slopes of 400
    repeats (a Monte Carlo, not the formula) within 35 %; the white-noise standard error is about
    √((1 − ρ)/(1 + ρ)) = 0.23 of it, so the old term alone misses."""
    rng = np.random.default_rng(7)
    x = np.linspace(0.0, 1.0, 400)
    slopes, stated, white = [], [], []
    for _ in range(400):
        y = 100.0 + 50.0 * x + _ar1(rng, x.size, 0.9, 1.0)
        b, a = np.polyfit(x, y, 1)
        slopes.append(b)
        stated.append(un.correlated_fit_u(line, {"a": a, "b": b}, x, y)["b"])
        r = y - a - b * x
        white.append(math.sqrt(r @ r / (x.size - 2) / np.sum((x - x.mean()) ** 2)))  # OLS standard error (closed form)
    spread = float(np.std(slopes, ddof=1))
    assert abs(float(np.median(stated)) / spread - 1.0) < 0.35
    assert float(np.median(white)) < 0.4 * spread


def test_white_residuals_give_the_ordinary_standard_error():
    """Independent noise: u of the slope is the closed-form OLS standard error s/√Σ(x − x̄)² (within 20 %)."""
    rng = np.random.default_rng(3)
    x = np.linspace(0.0, 1.0, 500)
    y = 10.0 + 3.0 * x + rng.normal(0.0, 0.5, x.size)
    b, a = np.polyfit(x, y, 1)
    r = y - a - b * x
    closed = math.sqrt(r @ r / (x.size - 2) / np.sum((x - x.mean()) ** 2))
    assert abs(un.correlated_fit_u(line, {"a": a, "b": b}, x, y)["b"] / closed - 1.0) < 0.2


def _on_the_bound(x, y):
    """The line fitted with a ≥ 0 where its free fit wants a < 0: a = 0, b = Σxy/Σx² (closed form)."""
    return {"a": 0.0, "b": float(x @ y / (x @ x))}


def test_a_constant_on_its_bound_reaches_the_closed_form_of_its_unbounded_interval():
    """A line a + b·x with a ≥ 0 on its bound: the stated reach (k·u) is max(0, â + 2·se) of the
    unbounded least squares (closed form: the OLS intercept â, se = σ_n·√(Σx²/(N·Σ(x − x̄)²)), σ²_n
    from first differences), exact for a linear law; near the bound (â a little below 0) it is positive."""
    rng = np.random.default_rng(11)
    x = np.linspace(0.0, 1.0, 300)
    for true_a in (-0.05, -2.0):  # the noise can take it off the bound / it cannot
        y = true_a + 40.0 * x + rng.normal(0.0, 1.0, x.size)
        b1, a1 = np.polyfit(x, y, 1)  # the unbounded fit
        p = _on_the_bound(x, y)
        noise = float(np.sum(np.diff(y - p["b"] * x) ** 2)) / (2.0 * (x.size - 1))
        se = math.sqrt(noise * (x @ x) / (x.size * np.sum((x - x.mean()) ** 2)))
        reach = un.K_COVERAGE * un.correlated_fit_u(line, p, x, y, {"a": 1.0})["a"]
        closed = max(0.0, a1 + 2.0 * se)
        floor = bounds_rule.BOUND_REL_TOL * float(np.max(np.abs(p["b"] * x)))
        assert math.isclose(reach, max(closed, floor), rel_tol=1e-4), (true_a, reach, closed)  # J by central differences
    assert closed == 0.0 and math.isclose(reach, floor, rel_tol=1e-6)  # a = −2 (≈ 17 se below): the noise never takes it off its bound


def _coverage_of_the_bounded_fit(true_a: float, rng, repeats: int = 2000) -> tuple[float, float]:
    """(share of repeats whose stated interval holds a* = max(0, true_a), share on the bound): a line
    true_a + 10·x + N(0, 1) fitted with a ≥ 0; stated a ± U off the bound, [0, reach] on it."""
    x = np.linspace(0.0, 1.0, 60)
    truth = max(0.0, true_a)  # the law fitted with its bound to the noise-free line
    held = on = 0
    for _ in range(repeats):
        y = true_a + 10.0 * x + rng.normal(0.0, 1.0, x.size)
        b1, a1 = np.polyfit(x, y, 1)
        if a1 >= 0.0:
            held += abs(a1 - truth) <= 2.0 * un.correlated_fit_u(line, {"a": a1, "b": b1}, x, y)["a"]
        else:
            on += 1
            held += truth <= un.K_COVERAGE * un.correlated_fit_u(line, _on_the_bound(x, y), x, y, {"a": 1.0})["a"]
    return held / repeats, on / repeats


def test_the_bound_reach_holds_the_bounded_fits_truth_in_95_percent_of_repeats():
    """Monte Carlo: a line whose true intercept lies half a standard error above its bound (the bounded
    fit lands on the bound in ~30 % of repeats, its truth is not) or below it (~70 %, truth on the bound):
    the stated intervals hold the truth in ≥ 93 % of 2000 repeats each (k = 2; ≈ 95 % expected)."""
    rng = np.random.default_rng(5)
    x = np.linspace(0.0, 1.0, 60)
    se = math.sqrt((x @ x) / (x.size * np.sum((x - x.mean()) ** 2)))  # the intercept's standard error at σ = 1
    for true_a, landed in ((0.5 * se, (0.25, 0.36)), (-0.5 * se, (0.64, 0.75))):
        held, on = _coverage_of_the_bounded_fit(true_a, rng)
        assert landed[0] < on < landed[1] and held >= 0.93, (true_a, held, on)


def test_constants_on_bound_by_the_constants_own_scale():
    """A = 5·10⁻⁹ MPa on a 1000 MPa law is on its bound (the optimisers stop short of it; the old 10⁻⁹ absolute
    tolerance missed it); A = 0.1 MPa is not; n on its upper bound 5 reads −1."""
    def jc(e, A, B, n):
        return A + B * e**n  # σ = A + B·εⁿ

    eps = np.linspace(0.01, 0.2, 30)
    bounds = {"A": (0.0, math.inf), "B": (0.0, math.inf), "n": (1e-4, 5.0)}
    assert bounds_rule.constants_on_bound(jc, {"A": 5e-9, "B": 1000.0, "n": 0.2}, bounds, eps) == {"A": 1.0}
    assert bounds_rule.constants_on_bound(jc, {"A": 0.1, "B": 1000.0, "n": 0.2}, bounds, eps) == {}
    assert bounds_rule.constants_on_bound(jc, {"A": 300.0, "B": 1000.0, "n": 5.0 - 1e-7}, bounds, eps) == {"n": -1.0}
    scales = bounds_rule.constant_scales(jc, {"A": 300.0, "B": 1000.0, "n": 0.2}, eps)
    assert math.isclose(scales["A"], 300.0 + 1000.0 * 0.2**0.2, rel_tol=1e-6)  # ∂σ/∂A = 1: the stress level


def test_constant_budget_states_the_method_term_and_never_zero_on_a_bound():
    """A lack-of-fit u beyond the fit's standard error is a named method term (the budget's u is then
    √(lof² + shift²)); a constant whose fit gave no standard error (on its bound) still gets a budget, U > 0."""
    b = un.constant_budget(500.0, 5.0, 0.0, "MPa", zero_shift=3.0, lack_of_fit=12.0)
    names = [c["name"] for c in b["components"]]
    assert "method: constants over the fit range" in names
    assert math.isclose(b["u"], math.hypot(12.0, 3.0), rel_tol=1e-12)
    at_bound = un.constant_budget(0.0, None, 0.0, "MPa", lack_of_fit=4.0)
    assert at_bound is not None and math.isclose(at_bound["U"], 2.0 * 4.0, rel_tol=1e-12)
    on = un.constant_budget(0.0, 2000.0, 0.01, "MPa", zero_shift=3.0, lack_of_fit=4.0, on_bound="lower")
    assert [c["name"] for c in on["components"]] == ["method: constant on its lower bound", "method: strain zero ε0",
                                                     "stress scale (force class, d0)"]  # lmfit's 2000 at a bound is not its own
    assert math.isclose(on["U"], 2.0 * 5.0, rel_tol=1e-12) and on["interval"] == [0.0, on["U"]] and on["one_sided"] == "lower"
    assert math.isclose(on["u_method"], 5.0, rel_tol=1e-12)
    upper = un.constant_budget(5.0, None, 0.0, "1", lack_of_fit=0.5, on_bound="upper")
    assert upper["interval"] == [4.0, 5.0]
    assert "note" not in b
    assert "not determined" in un.constant_budget(300.0, 5.0, 0.0, "MPa", lack_of_fit=200.0)["note"]  # U = 400 ≥ the value
    unchanged = un.constant_budget(500.0, 5.0, 0.0, "MPa", lack_of_fit=2.0)  # below the standard error: no method term
    assert [c["name"] for c in unchanged["components"]] == ["fit (standard error)", "stress scale (force class, d0)"]


def test_a_constant_its_bound_holds_but_the_curve_does_not_says_so():
    """46NTAV's Johnson–Cook A sits on 0 with n 0.04: A and B·εⁿ trade off, its reach inward (6 000 MPa) passes the law's
    own scale for A (its stress level, 1 260 MPa): the note says the curve does not determine it; a pinned A (reach 0) says not."""
    loose = un.constant_budget(0.0, None, 0.005, "MPa", lack_of_fit=3014.6, on_bound="lower", scale=1256.9)
    pinned = un.constant_budget(0.0, None, 0.005, "MPa", lack_of_fit=5e-4, on_bound="lower", scale=1256.9)
    assert "does not determine it" in loose["note"] and loose["interval"] == [0.0, pytest.approx(loose["U"])]
    assert "does not determine" not in pinned["note"] and pinned["U"] < 1e-2
