"""The weighted Swift–Voce law σ = α·Swift + (1 − α)·Voce (power-law and saturating hardening mixed)."""

from __future__ import annotations

import numpy as np

from flowcurve.identification.laws.base import Parameter, register
from flowcurve.identification.laws.static import StaticLaw, best_rows
from flowcurve.identification.laws.swift import Swift, swift
from flowcurve.identification.laws.voce import Voce, voce

ALPHA_GRID = np.linspace(0.0, 1.0, 41)


def swift_voce(eps_p, alpha, K, eps0, n, sigma0, Q, b):
    """Swift–Voce: α·K(ε0 + εp)^n + (1 − α)·(σ0 + Q(1 − e^(−b·εp))) (MPa)."""
    return alpha * swift(eps_p, K, eps0, n) + (1.0 - alpha) * voce(eps_p, sigma0, Q, b)


@register
class SwiftVoce(StaticLaw):
    """Swift–Voce (weighted): σ = α·K(ε0 + εp)^n + (1 − α)·(σ0 + Q(1 − e^(−b·εp)))."""

    name = "swift_voce"
    display_name = "Swift–Voce"
    parameters = (
        Parameter("alpha", "alpha", "", 0.0, 1.0, "weight of Swift's power law (1 − α: Voce's saturation)"),
        *Swift.parameters,
        *Voce.parameters,
    )
    equation = "sigma_MPa = alpha*K*(eps0 + eps_p)^n + (1 - alpha)*(sigma0 + Q*(1 - exp(-b*eps_p)))"
    latex = (r"\sigma = \alpha\,K(\varepsilon_0 + \varepsilon_p)^n"
             r" + (1 - \alpha)\big(\sigma_0 + Q(1 - e^{-b\varepsilon_p})\big)")
    source = ("H. W. Swift (1952) and E. Voce (1948) mixed linearly, as in D. Mohr, S. J. Marcadet, "
              "Int. J. Solids Struct. 67–68 (2015) 40–55")
    function = staticmethod(swift_voce)

    def profile(self, eps, sig, w):
        """Swift's and Voce's best profile rows, mixed over α in 0–1 (the two curves held)."""
        rows = []
        for law in (Swift(), Voce()):
            ss, cands = law.profile(eps, sig, w)
            rows.append(cands[int(np.argmin(ss))] if np.any(np.isfinite(ss)) else law.data_start(eps, sig))
        s_curve, v_curve = swift(eps, **rows[0]), voce(eps, **rows[1])
        pred = ALPHA_GRID[:, None] * s_curve[None, :] + (1.0 - ALPHA_GRID[:, None]) * v_curve[None, :]
        ss = ((pred - sig) ** 2) @ (w**2)
        return best_rows(ss, lambda i: {"alpha": ALPHA_GRID[i], **rows[0], **rows[1]}, np.ones_like(ss, dtype=bool))

    def data_start(self, eps, sig):
        """Half Swift's start, half Voce's."""
        return {"alpha": 0.5, **Swift().data_start(eps, sig), **Voce().data_start(eps, sig)}
