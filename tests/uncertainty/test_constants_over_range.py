"""The hardening constants' method term over the fit range (issue 43, docs/methods.md §2.12):
uncertainty.correlated_fit_u against independent methods (a Monte Carlo of correlated residuals, a
brute-force profile of a constant on its bound) and its place in constant_budget."""

from __future__ import annotations

import math

import numpy as np

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


def test_a_constant_on_its_bound_gets_the_distance_a_brute_force_profile_gives():
    """a ≥ 0 on data whose free fit wants a < 0: the fit sits at a = 0. The stated u (δ/2) against a brute-force
    profile: a = δ held, b refitted exactly, SSR(δ) − SSR(0) = σ²_noise (first differences); never 0."""
    rng = np.random.default_rng(11)
    x = np.linspace(0.0, 1.0, 300)
    y = -2.0 + 40.0 * x + rng.normal(0.0, 1.0, x.size)
    b0 = float(x @ y / (x @ x))  # a = 0 on its bound, b by least squares
    u = un.correlated_fit_u(line, {"a": 0.0, "b": b0}, x, y, {"a": 1.0})["a"]
    r0 = y - b0 * x
    noise = float(np.sum(np.diff(r0) ** 2)) / (2.0 * (x.size - 1))

    def rise(d):
        b = float(x @ (y - d) / (x @ x))
        r = y - d - b * x
        return float(r @ r - r0 @ r0)

    from scipy.optimize import brentq

    delta = brentq(lambda d: rise(d) - noise, 0.0, 5.0, xtol=1e-12)
    assert u > 0
    assert abs(2.0 * u / delta - 1.0) < 1e-3


def test_constant_budget_states_the_method_term_and_never_zero_on_a_bound():
    """A lack-of-fit u beyond the fit's standard error is a named method term (the budget's u is then
    √(lof² + shift²)); a constant whose fit gave no standard error (on its bound) still gets a budget, U > 0."""
    b = un.constant_budget(500.0, 5.0, 0.0, "MPa", zero_shift=3.0, lack_of_fit=12.0)
    names = [c["name"] for c in b["components"]]
    assert "method: constants over the fit range" in names
    assert math.isclose(b["u"], math.hypot(12.0, 3.0), rel_tol=1e-12)
    at_bound = un.constant_budget(0.0, None, 0.0, "MPa", lack_of_fit=4.0)
    assert at_bound is not None and math.isclose(at_bound["U"], 2.0 * 4.0, rel_tol=1e-12)
    assert "note" not in b
    assert "not determined" in un.constant_budget(300.0, 5.0, 0.0, "MPa", lack_of_fit=200.0)["note"]  # U = 400 ≥ the value
    unchanged = un.constant_budget(500.0, 5.0, 0.0, "MPa", lack_of_fit=2.0)  # below the standard error: no method term
    assert [c["name"] for c in unchanged["components"]] == ["fit (standard error)", "stress scale (force class, d0)"]
