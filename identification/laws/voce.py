"""Voce's saturating law σ = σ0 + Q·(1 − exp(−b·εp))."""

from __future__ import annotations

import numpy as np

from flowcurve.identification.laws.base import Parameter, register
from flowcurve.identification.laws.static import STRAIN_GRID_POINTS, StaticLaw, best_rows, first_and_rise, linear_on_grid


def voce(eps_p, sigma0, Q, b):
    """Voce saturation hardening: σ0 + Q·(1 − exp(−b·εp)) (MPa)."""
    eps_p = np.maximum(np.asarray(eps_p, dtype=float), 0.0)  # np.clip(…, 0, None) without its dispatch
    return sigma0 + Q * (1.0 - np.exp(-b * eps_p))


@register
class Voce(StaticLaw):
    """Voce (1948): σ = σ0 + Q·(1 − exp(−b·εp))."""

    name = "voce"
    display_name = "Voce"
    parameters = (
        Parameter("sigma0", "sigma0_MPa", "MPa", 0.0, np.inf, "yield stress"),
        Parameter("Q", "Q_MPa", "MPa", 0.0, np.inf, "saturation rise (σ → σ0 + Q)"),
        Parameter("b", "b", "", 1e-6, 1e5, "saturation rate (per unit plastic strain)"),
    )
    equation = "sigma_MPa = sigma0 + Q*(1 - exp(-b*eps_p))"
    latex = r"\sigma = \sigma_0 + Q\,\big(1 - e^{-b\,\varepsilon_p}\big)"
    source = "E. Voce, The relationship between stress and strain for homogeneous deformation, J. Inst. Met. 74 (1948) 537–562"
    function = staticmethod(voce)

    def profile(self, eps, sig, w):
        """b over 0.05–2000 per the strain span (log grid); σ0 ≥ 0 and Q by linear least squares."""
        span = max(np.max(eps), 1e-6)
        grid = np.geomspace(0.05 / span, 2000.0 / span, STRAIN_GRID_POINTS)
        s0, Q, ss = linear_on_grid(-np.expm1(-grid[:, None] * eps[None, :]), sig, w, nonnegative_c0=True)
        return best_rows(ss, lambda i: {"sigma0": s0[i], "Q": Q[i], "b": grid[i]}, Q > 0)

    def data_start(self, eps, sig):
        """σ0 just below the first point, Q the rise to the top, 1/b the strain at 63 % of it."""
        e, s, level, _, _ = first_and_rise(eps, sig)
        top = float(np.max(s))
        half = e[np.argmax(s >= level + 0.63 * (top - level))] if top > level else float(np.max(e))
        return {"sigma0": level, "Q": max(top - level, 1e-3), "b": 1.0 / max(half, 1e-6)}
