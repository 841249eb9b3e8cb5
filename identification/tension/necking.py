"""Neck corrections: from the average axial stress in the neck to the equivalent flow stress.

docs/methods.md §3: Davidenkov–Spiridonov (3.10)–(3.11) (the default), Bridgman, Mirone's MLR.
When the neck radius R was not measured, a/R is estimated with Le Roy et al. (1981).
The seed's (3.12) is deliberately absent: as printed it gives η ≈ 0.25 with no neck.

a is the neck (minimum-section) radius, R the radius of curvature of the neck profile.
"""

from __future__ import annotations

import numpy as np

from flowcurve.errors import IdentificationError

METHODS = ("davidenkov", "bridgman", "mirone")


def le_roy_a_over_R(eps, eps_u):
    """Le Roy et al. (1981): a/R = 1.1·(ε − ε_u), zero before necking."""
    # (Le Roy 1981) a/R = 1.1 (ε − ε_u)
    return 1.1 * np.clip(np.asarray(eps, dtype=float) - eps_u, 0.0, None)


def davidenkov_factor(a_over_R):
    """Davidenkov–Spiridonov η = 1/(1 + a/(4R)) = 1/(1 + d_k/(8R))."""
    # (3.11) η = 1 / (1 + d_k/(8 R_neck))
    return 1.0 / (1.0 + np.asarray(a_over_R, dtype=float) / 4.0)


def bridgman_factor(a_over_R):
    """Bridgman: σ_eq/σ_avg = 1/((1 + 2R/a)·ln(1 + a/(2R))); 1 with no neck (a/R → 0)."""
    x = np.asarray(a_over_R, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        # Bridgman (1952) σ_eq = σ_avg / ((1 + 2R/a) ln(1 + a/(2R)))
        f = 1.0 / ((1.0 + 2.0 / x) * np.log1p(x / 2.0))
    return np.where(x > 1e-8, f, 1.0 - x / 4.0)  # series at small a/R avoids 0·∞


def mirone_factor(eps, eps_u):
    """Mirone's MLR: σ_eq/σ_avg = 1 − 0.6058x² + 0.6317x³ − 0.2107x⁴, x = ε − ε_u (≥ 0)."""
    x = np.clip(np.asarray(eps, dtype=float) - eps_u, 0.0, None)
    # (Mirone 2004, MLR) 1 − 0.6058 x² + 0.6317 x³ − 0.2107 x⁴
    return 1.0 - 0.6058 * x**2 + 0.6317 * x**3 - 0.2107 * x**4


def neck_corrections(avg_stress_MPa: float, eps_f: float, eps_u: float, *, d_k_mm: float | None = None,
                     neck_radius_mm: float | None = None) -> dict:
    """Every neck correction of the fracture stress, side by side.

    avg_stress_MPa: P_k/F_k, the average axial stress in the fracture section.
    eps_f: true fracture strain ln(F0/F_k); eps_u: true strain at maximum force.
    d_k_mm and neck_radius_mm: the measured neck (when the radius is missing, a/R from Le Roy).
    Returns ``{"a_over_R", "a_over_R_source", "<method>": {"factor", "stress_MPa"}}``.
    """
    if not avg_stress_MPa > 0:
        raise IdentificationError(f"the fracture stress must be > 0 MPa, got {avg_stress_MPa!r}")
    if eps_f < eps_u:
        raise IdentificationError(f"the fracture strain {eps_f:.4g} is below the strain at maximum force {eps_u:.4g}: check post.dk_mm")
    if neck_radius_mm is not None:
        if d_k_mm is None:
            raise IdentificationError("a measured neck radius needs the fracture diameter post.dk_mm as well")
        if not neck_radius_mm > 0:
            raise IdentificationError(f"post.neck_radius_mm must be > 0, got {neck_radius_mm!r}")
        a_over_R, source = (d_k_mm / 2.0) / neck_radius_mm, "measured neck radius"
    else:
        a_over_R, source = float(le_roy_a_over_R(eps_f, eps_u)), "Le Roy et al. (1981): a/R = 1.1(eps_f - eps_u)"
    factors = {
        "davidenkov": float(davidenkov_factor(a_over_R)),
        "bridgman": float(bridgman_factor(a_over_R)),
        "mirone": float(mirone_factor(eps_f, eps_u)),
    }
    out: dict = {"a_over_R": float(a_over_R), "a_over_R_source": source}
    for name, f in factors.items():
        out[name] = {"factor": f, "stress_MPa": f * avg_stress_MPa}
    return out
