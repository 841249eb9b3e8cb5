"""Hollomon's power law σ = K·εp^n."""

from __future__ import annotations

import numpy as np

from flowcurve.identification.laws.base import Parameter, register
from flowcurve.identification.laws.static import STRAIN_GRID_POINTS, StaticLaw, best_rows


def hollomon(eps_p, K, n):
    """Hollomon: K·εp^n (MPa)."""
    eps_p = np.maximum(np.asarray(eps_p, dtype=float), 0.0)  # np.clip(…, 0, None) without its dispatch
    return K * np.power(eps_p, n)


@register
class Hollomon(StaticLaw):
    """Hollomon (1945): σ = K·εp^n."""

    name = "hollomon"
    display_name = "Hollomon"
    parameters = (
        Parameter("K", "K_MPa", "MPa", 0.0, np.inf, "strength coefficient (σ at εp = 1)"),
        Parameter("n", "n", "", 1e-4, 5.0, "hardening exponent"),
    )
    equation = "sigma_MPa = K*eps_p^n"
    latex = r"\sigma = K\,\varepsilon_p^{\,n}"
    source = "J. H. Hollomon, Tensile deformation, Trans. AIME 162 (1945) 268–290"
    function = staticmethod(hollomon)

    def profile(self, eps, sig, w):
        """n over 0.005–3 (log grid); K = Σw²xσ/Σw²x² with x = εp^n (a line through zero)."""
        grid = np.geomspace(0.005, 3.0, STRAIN_GRID_POINTS)
        X = np.power(eps[None, :], grid[:, None])
        w2 = w**2
        with np.errstate(divide="ignore", invalid="ignore"):
            K = (X @ (w2 * sig)) / ((X**2) @ w2)
            ss = ((K[:, None] * X - sig) ** 2) @ w2
        return best_rows(ss, lambda i: {"K": K[i], "n": grid[i]}, K > 0)

    def data_start(self, eps, sig):
        """ln σ = ln K + n·ln εp over the points with εp > 0 (log-linear)."""
        use = (eps > 0) & (sig > 0)
        if use.sum() >= 2 and np.ptp(np.log(eps[use])) > 0:
            n, lnK = np.polyfit(np.log(eps[use]), np.log(sig[use]), 1)
            return {"K": float(np.exp(lnK)), "n": float(np.clip(n, 1e-3, 2.0))}
        return {"K": float(np.max(sig)), "n": 0.2}
