"""The hyperbolic-sine (Sellars–Tegart) law with the Zener–Hollomon parameter, strain-compensated.

    Z = ε̇·exp(Q/(R·T)),   σ = (1/α)·asinh((Z/A)^(1/n)),   i.e. ε̇ = A·sinh(ασ)^n·exp(−Q/(R·T))

with α, n, Q and ln A each a polynomial of degree ≤ 5 in εp (α = Σ αi·εp^i, …), as the
hot-deformation literature compensates strain; T in K inside, Q in J/mol, A in 1/s.
"""

from __future__ import annotations

import numpy as np

from flowcurve.identification.laws.base import KELVIN_OFFSET, Law, Parameter, register
from flowcurve.identification.laws.zerilli_armstrong import series_points

GAS_CONSTANT_J_PER_MOL_K = 8.314462618
DEGREE = 5  # the polynomials' highest power of εp
ALPHA_GRID_PER_MPa = np.geomspace(1e-4, 0.5, 120)  # the guess's scan of α


def _series(symbol: str, key_unit: str, unit: str, lower0: float, upper0: float, meaning: str) -> tuple[Parameter, ...]:
    """symbol0…symbol5: the constant term bounded (lower0, upper0), the others free."""
    return tuple(Parameter(f"{symbol}{i}", f"{symbol}{i}{key_unit}", unit, lower0 if i == 0 else -np.inf, upper0 if i == 0 else np.inf,
                           f"{meaning}: coefficient of εp^{i}") for i in range(DEGREE + 1))


def polynomial(eps_p, coefficients):
    """Σ c_i·εp^i (numpy's polyval, lowest power first)."""
    return np.polynomial.polynomial.polyval(eps_p, np.asarray(coefficients, dtype=float))


def asinh_of_exp(log_x):
    """asinh(e^L) without overflow: L + ln(1 + √(1 + e^(−2L))) for L > 0, asinh(e^L) otherwise."""
    L = np.asarray(log_x, dtype=float)
    with np.errstate(over="ignore"):
        return np.where(L > 0, L + np.log1p(np.sqrt(1.0 + np.exp(-2.0 * np.abs(L)))), np.arcsinh(np.exp(np.minimum(L, 0.0))))


def hyperbolic_sine(eps_p, strain_rate_per_s, temperature_C, alpha, n, Q, lnA):
    """# Sellars–Tegart: σ = (1/α)·asinh((Z/A)^(1/n)), ln(Z/A) = ln ε̇ + Q/(R·T) − ln A (MPa)."""
    T = np.asarray(temperature_C, dtype=float) + KELVIN_OFFSET
    log_Z_over_A = np.log(np.asarray(strain_rate_per_s, dtype=float)) + Q / (GAS_CONSTANT_J_PER_MOL_K * T) - lnA
    return asinh_of_exp(log_Z_over_A / n) / alpha


@register
class HyperbolicSine(Law):
    """Hyperbolic sine with Zener–Hollomon: σ = (1/α)·asinh((Z/A)^(1/n)), Z = ε̇·exp(Q/(RT)); α, n, Q, ln A polynomials in εp."""

    name = "hyperbolic_sine"
    display_name = "Hyperbolic sine (Zener–Hollomon, strain-compensated)"
    parameters = (
        *_series("alpha", "_per_MPa", "1/MPa", 1e-6, 1.0, "stress multiplier α"),
        *_series("n", "", "", 0.2, 50.0, "stress exponent n"),
        *_series("Q", "_J_per_mol", "J/mol", 0.0, 2e6, "activation energy Q"),
        *_series("lnA", "", "", -200.0, 400.0, "ln of the material constant A (A in 1/s)"),
    )
    rate_dependent = True
    temperature_dependent = True
    equation = ("sigma_MPa = (1/alpha)*asinh((Z/A)^(1/n)), Z = rate*exp(Q/(R*T_K)), R = 8.314 J/(mol K), T_K = temperature_C + 273.15; "
                "alpha = sum(alpha_i*eps_p^i), n = sum(n_i*eps_p^i), Q = sum(Q_i*eps_p^i), ln A = sum(lnA_i*eps_p^i), i = 0..5")
    latex = (r"\sigma = \frac{1}{\alpha}\,\operatorname{asinh}\Big[\big(Z/A\big)^{1/n}\Big],\quad Z = \dot\varepsilon\,e^{Q/(RT)},"
             r"\quad \{\alpha, n, Q, \ln A\} = \textstyle\sum_{i=0}^{5} c_i\,\varepsilon_p^{\,i}")
    source = ("C. M. Sellars, W. J. McG. Tegart, Mém. Sci. Rev. Métall. 63 (1966) 731–746; C. Zener, J. H. Hollomon, J. Appl. Phys. 15 "
              "(1944) 22–32; strain compensation as in Y. C. Lin, M.-S. Chen, J. Zhong, Comput. Mater. Sci. 42 (2008) 470–477")

    def evaluate(self, eps_p, strain_rate_per_s, temperature_C, **values):
        """Strain-compensated hyperbolic-sine flow stress, MPa (coefficients polynomial in εp)."""
        # Sellars–Tegart with strain-compensated constants
        coeff = {s: polynomial(eps_p, [values[f"{s}{i}"] for i in range(DEGREE + 1)]) for s in ("alpha", "n", "Q", "lnA")}
        return hyperbolic_sine(eps_p, strain_rate_per_s, temperature_C, **coeff)

    def guess(self, eps_p, stress_MPa, strain_rate_per_s=None, temperature_C=None, **conditions):
        """Constant α, n, Q, ln A (the εp terms 0): for each α of a scan, ln ε̇ = ln A + n·ln sinh(ασ) − Q/(RT)
        by linear least squares; the α with the smallest residual kept."""
        eps, sig, rate, temp = series_points(self, eps_p, stress_MPa, strain_rate_per_s, temperature_C)
        ok = (sig > 0) & (rate > 0)
        y, inv_RT = np.log(rate[ok]), -1.0 / (GAS_CONSTANT_J_PER_MOL_K * (temp[ok] + KELVIN_OFFSET))
        best = None
        for alpha in ALPHA_GRID_PER_MPa:
            X = np.column_stack([np.ones_like(y), np.log(np.sinh(np.minimum(alpha * sig[ok], 700.0))), inv_RT])
            c, *_ = np.linalg.lstsq(X, y, rcond=None)
            ss = float(np.sum((X @ c - y) ** 2))
            if c[1] > 0 and (best is None or ss < best[0]):
                best = (ss, alpha, c)
        _, alpha, (lnA, n, Q) = best if best is not None else (0.0, 0.01, (20.0, 5.0, 2e5))
        out = {f"{s}{i}": 0.0 for s in ("alpha", "n", "Q", "lnA") for i in range(1, DEGREE + 1)}
        return {**out, "alpha0": float(alpha), "n0": float(n), "Q0": float(max(Q, 0.0)), "lnA0": float(lnA)}
