"""Ludwik's power-law hardening σ = σ0 + K·εp^n — Johnson–Cook's static part (identify's
``johnson_cook`` fits this form with JC's names A, B, n)."""

from __future__ import annotations

import numpy as np

from flowcurve.identification.laws.base import Parameter, register
from flowcurve.identification.laws.static import STRAIN_GRID_POINTS, StaticLaw, best_rows, first_and_rise, linear_on_grid


def ludwik(eps_p, sigma0, K, n):
    """Ludwik: σ0 + K·εp^n (MPa)."""
    eps_p = np.maximum(np.asarray(eps_p, dtype=float), 0.0)  # np.clip(…, 0, None) without its dispatch
    return sigma0 + K * np.power(eps_p, n)


@register
class Ludwik(StaticLaw):
    """Ludwik (1909): σ = σ0 + K·εp^n."""

    name = "ludwik"
    display_name = "Ludwik"
    parameters = (
        Parameter("sigma0", "sigma0_MPa", "MPa", 0.0, np.inf, "yield stress (initial flow stress)"),
        Parameter("K", "K_MPa", "MPa", 0.0, np.inf, "hardening modulus"),
        Parameter("n", "n", "", 1e-4, 5.0, "hardening exponent"),
    )
    equation = "sigma_MPa = sigma0 + K*eps_p^n"
    latex = r"\sigma = \sigma_0 + K\,\varepsilon_p^{\,n}"
    source = "P. Ludwik, Elemente der technologischen Mechanik, Springer, Berlin, 1909"
    function = staticmethod(ludwik)

    def profile(self, eps, sig, w):
        """n over 0.005–3 (log grid); σ0 ≥ 0 and K by weighted linear least squares."""
        grid = np.geomspace(0.005, 3.0, STRAIN_GRID_POINTS)
        s0, K, ss = linear_on_grid(np.power(eps[None, :], grid[:, None]), sig, w, nonnegative_c0=True)
        return best_rows(ss, lambda i: {"sigma0": s0[i], "K": K[i], "n": grid[i]}, K > 0)

    def data_start(self, eps, sig):
        """σ0 just below the first point, K and n from the log–log slope of σ − σ0."""
        _, _, level, K, n = first_and_rise(eps, sig)
        return {"sigma0": level, "K": K, "n": n}
