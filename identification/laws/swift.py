"""Swift's pre-strained power law σ = K·(ε0 + εp)^n."""

from __future__ import annotations

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.base import Parameter, register
from flowcurve.identification.laws.static import STRAIN_GRID_POINTS, StaticLaw, best_rows, first_and_rise, linear_on_grid


def swift(eps_p, K, eps0, n):
    """Swift hardening: K·(ε0 + εp)^n (MPa)."""
    eps_p = np.maximum(np.asarray(eps_p, dtype=float), 0.0)  # np.clip(…, 0, None) without its dispatch
    return K * np.power(eps0 + eps_p, n)


@register
class Swift(StaticLaw):
    """Swift (1952): σ = K·(ε0 + εp)^n."""

    name = "swift"
    display_name = "Swift"
    parameters = (
        Parameter("K", "K_MPa", "MPa", 0.0, np.inf, "strength coefficient"),
        Parameter("eps0", "eps0", "", 1e-9, 10.0, "pre-strain (sets the yield stress K·ε0^n)"),
        Parameter("n", "n", "", 1e-4, 5.0, "hardening exponent"),
    )
    equation = "sigma_MPa = K*(eps0 + eps_p)^n"
    latex = r"\sigma = K\,(\varepsilon_0 + \varepsilon_p)^{n}"
    source = "H. W. Swift, Plastic instability under plane stress, J. Mech. Phys. Solids 1 (1952) 1–18"
    function = staticmethod(swift)

    def profile(self, eps, sig, w):
        """ε0 over 1e-7–1 (log grid); ln σ = ln K + n·ln(ε0 + εp) solved, scored in MPa."""
        if np.min(sig) <= 0:
            raise IdentificationError("Swift law needs positive stresses")
        grid = np.geomspace(1e-7, 1.0, STRAIN_GRID_POINTS)
        base = grid[:, None] + eps[None, :]
        lnK, n, _ = linear_on_grid(np.log(base), np.log(sig), w)
        with np.errstate(over="ignore", invalid="ignore"):
            pred = np.exp(lnK)[:, None] * np.power(base, n[:, None])
        ss = np.where(np.isfinite(pred).all(axis=1), ((pred - sig) ** 2) @ (w**2), np.inf)
        return best_rows(ss, lambda i: {"K": float(np.exp(lnK[i])), "eps0": grid[i], "n": n[i]}, n > 0)

    def data_start(self, eps, sig):
        """ε0 1e-3; K and n from ln σ against ln εp (log-linear)."""
        e, s, *_ = first_and_rise(eps, sig)
        ln_e = np.log(np.clip(e, 1e-9, None))
        n, lnK = np.polyfit(ln_e, np.log(np.clip(s, 1e-9, None)), 1) if np.ptp(ln_e) > 0 else (0.2, np.log(float(s[0])))
        return {"K": float(np.exp(lnK)), "eps0": 1e-3, "n": float(np.clip(n, 1e-3, 2.0))}
