"""Hockett–Sherby's saturating law σ = σs − (σs − σ0)·exp(−N·εp^p)."""

from __future__ import annotations

import numpy as np

from flowcurve.identification.laws.base import Parameter, register
from flowcurve.identification.laws.static import StaticLaw, best_rows, linear_on_grid
from flowcurve.identification.laws.voce import Voce


def hockett_sherby(eps_p, sigma_s, sigma0, N, p):
    """Hockett–Sherby: σs − (σs − σ0)·exp(−N·εp^p) (MPa)."""
    eps_p = np.maximum(np.asarray(eps_p, dtype=float), 0.0)  # np.clip(…, 0, None) without its dispatch
    return sigma_s - (sigma_s - sigma0) * np.exp(-N * np.power(eps_p, p))


@register
class HockettSherby(StaticLaw):
    """Hockett–Sherby (1975): σ = σs − (σs − σ0)·exp(−N·εp^p)."""

    name = "hockett_sherby"
    display_name = "Hockett–Sherby"
    parameters = (
        Parameter("sigma_s", "sigma_s_MPa", "MPa", 0.0, np.inf, "saturation stress"),
        Parameter("sigma0", "sigma0_MPa", "MPa", 0.0, np.inf, "yield stress"),
        Parameter("N", "N", "", 1e-6, 1e5, "saturation rate"),
        Parameter("p", "p", "", 0.05, 5.0, "strain exponent (p = 1: Voce)"),
    )
    equation = "sigma_MPa = sigma_s - (sigma_s - sigma0)*exp(-N*eps_p^p)"
    latex = r"\sigma = \sigma_s - (\sigma_s - \sigma_0)\,e^{-N\varepsilon_p^{\,p}}"
    source = "J. E. Hockett, O. D. Sherby, Large strain deformation of polycrystalline metals at low homologous temperatures, J. Mech. Phys. Solids 23 (1975) 87–98"
    function = staticmethod(hockett_sherby)

    def profile(self, eps, sig, w):
        """p over 0.1–3 × N·span^p over 0.05–2000 (log grids); σs ≥ 0 and σs − σ0 ≥ 0 solved linearly,
        rows with σ0 < 0 dropped."""
        span = max(np.max(eps), 1e-6)
        p, rate = np.meshgrid(np.geomspace(0.1, 3.0, 30), np.geomspace(0.05, 2000.0, 40), indexing="ij")
        p, N = p.ravel(), (rate / span ** p).ravel()
        X = -np.exp(-N[:, None] * np.power(eps[None, :], p[:, None]))
        s_s, drop, ss = linear_on_grid(X, sig, w, nonnegative_c0=True)
        with np.errstate(invalid="ignore"):  # a row whose X is flat has no line: nan, dropped below
            s0 = s_s - drop
        return best_rows(ss, lambda i: {"sigma_s": s_s[i], "sigma0": s0[i], "N": N[i], "p": p[i]}, (drop > 0) & (s0 >= 0))

    def data_start(self, eps, sig):
        """Voce's start read as p = 1: σs = σ0 + Q, N = b."""
        v = Voce().data_start(eps, sig)
        return {"sigma_s": v["sigma0"] + v["Q"], "sigma0": v["sigma0"], "N": v["b"], "p": 1.0}
