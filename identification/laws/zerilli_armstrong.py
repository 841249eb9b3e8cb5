"""Zerilli–Armstrong's dislocation-mechanics laws for bcc and fcc metals (T in K inside).

    bcc: σ = C0 + C1·exp(−C3·T + C4·T·ln ε̇) + C5·εp^n
    fcc: σ = C0 + C2·εp^½·exp(−C3·T + C4·T·ln ε̇)

C0 = Δσ'_G + k·l^(−½) (the athermal stress with the grain-size term); ε̇ in 1/s.
"""

from __future__ import annotations

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.base import KELVIN_OFFSET, Law, Parameter, register

SOURCE = ("F. J. Zerilli, R. W. Armstrong, Dislocation-mechanics-based constitutive relations for material dynamics "
          "calculations, J. Appl. Phys. 61 (1987) 1816–1825")
# start values of the thermal constants (1/K): Zerilli–Armstrong's Armco iron and OFHC copper
BCC_THERMAL_START = (0.00698, 0.000415)
FCC_THERMAL_START = (0.0028, 0.000115)
EXPONENT_GRID = np.geomspace(0.05, 1.0, 40)


def thermal_activation(strain_rate_per_s, temperature_C, C3, C4):
    """# ZA (1987) exp(−C3·T + C4·T·ln ε̇), T in K."""
    T = np.asarray(temperature_C, dtype=float) + KELVIN_OFFSET
    return np.exp(-C3 * T + C4 * T * np.log(np.asarray(strain_rate_per_s, dtype=float)))


C0 = Parameter("C0", "C0_MPa", "MPa", 0.0, np.inf, "athermal stress Δσ'_G + k·l^(−½) (grain size)")
C3 = Parameter("C3", "C3_per_K", "1/K", 0.0, 1.0, "thermal softening constant")
C4 = Parameter("C4", "C4_per_K", "1/K", -1.0, 1.0, "rate–temperature coupling constant")


def series_points(law: Law, eps_p, stress_MPa, strain_rate_per_s, temperature_C) -> tuple[np.ndarray, ...]:
    """(εp, σ, ε̇, T °C) as broadcast float arrays for a rate/temperature law's guess; a one-line
    error when the rates or temperatures are not given."""
    if strain_rate_per_s is None or temperature_C is None:
        raise IdentificationError(f"{law.display_name}: a guess needs each point's strain rate and temperature")
    arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (eps_p, stress_MPa, strain_rate_per_s, temperature_C)))
    return tuple(a.ravel() for a in arrays)


def _linear_constants(columns: list[np.ndarray], sig: np.ndarray) -> tuple[np.ndarray, float]:
    """Non-negative-clipped least squares σ ≈ Σ c_k·column_k: (c, residual sum of squares)."""
    X = np.column_stack(columns)
    c = np.clip(np.linalg.lstsq(X, sig, rcond=None)[0], 0.0, None)
    return c, float(np.sum((X @ c - sig) ** 2))


class _ZerilliArmstrong(Law):
    """What both forms share (not registered itself)."""

    rate_dependent = True
    temperature_dependent = True
    source = SOURCE


@register
class ZerilliArmstrongBCC(_ZerilliArmstrong):
    """Zerilli–Armstrong, bcc: σ = C0 + C1·exp(−C3·T + C4·T·ln ε̇) + C5·εp^n (T in K)."""

    name = "zerilli_armstrong_bcc"
    display_name = "Zerilli–Armstrong (bcc)"
    parameters = (
        C0,
        Parameter("C1", "C1_MPa", "MPa", 0.0, np.inf, "thermal (Peierls) stress at 0 K"),
        C3, C4,
        Parameter("C5", "C5_MPa", "MPa", 0.0, np.inf, "strain hardening modulus"),
        Parameter("n", "n", "", 1e-3, 2.0, "strain hardening exponent"),
    )
    equation = "sigma_MPa = C0 + C1*exp(-C3*T_K + C4*T_K*ln(rate)) + C5*eps_p^n, T_K = temperature_C + 273.15"
    latex = r"\sigma = C_0 + C_1\,e^{-C_3 T + C_4 T\ln\dot\varepsilon} + C_5\,\varepsilon_p^{\,n}"

    def evaluate(self, eps_p, strain_rate_per_s, temperature_C, *, C0, C1, C3, C4, C5, n):
        """Zerilli–Armstrong (bcc) flow stress, MPa."""
        # ZA (1987) bcc
        return C0 + C1 * thermal_activation(strain_rate_per_s, temperature_C, C3, C4) + C5 * np.power(eps_p, n)

    def guess(self, eps_p, stress_MPa, strain_rate_per_s=None, temperature_C=None, **conditions):
        """C3, C4 at Armco iron's; C0, C1, C5 by linear least squares for each n of a grid, the best n kept."""
        eps, sig, rate, temp = series_points(self, eps_p, stress_MPa, strain_rate_per_s, temperature_C)
        c3, c4 = BCC_THERMAL_START
        act = thermal_activation(rate, temp, c3, c4)
        fits = [(_linear_constants([np.ones_like(eps), act, np.power(np.clip(eps, 0, None), n)], sig), n) for n in EXPONENT_GRID]
        (c, _), n = min(fits, key=lambda f: f[0][1])
        return {"C0": float(c[0]), "C1": float(c[1]), "C3": c3, "C4": c4, "C5": float(c[2]), "n": float(n)}


@register
class ZerilliArmstrongFCC(_ZerilliArmstrong):
    """Zerilli–Armstrong, fcc: σ = C0 + C2·εp^½·exp(−C3·T + C4·T·ln ε̇) (T in K)."""

    name = "zerilli_armstrong_fcc"
    display_name = "Zerilli–Armstrong (fcc)"
    parameters = (
        C0,
        Parameter("C2", "C2_MPa", "MPa", 0.0, np.inf, "strain hardening modulus at 0 K"),
        C3, C4,
    )
    equation = "sigma_MPa = C0 + C2*sqrt(eps_p)*exp(-C3*T_K + C4*T_K*ln(rate)), T_K = temperature_C + 273.15"
    latex = r"\sigma = C_0 + C_2\,\varepsilon_p^{1/2}\,e^{-C_3 T + C_4 T\ln\dot\varepsilon}"

    def evaluate(self, eps_p, strain_rate_per_s, temperature_C, *, C0, C2, C3, C4):
        """Zerilli–Armstrong (fcc) flow stress, MPa."""
        # ZA (1987) fcc
        return C0 + C2 * np.sqrt(eps_p) * thermal_activation(strain_rate_per_s, temperature_C, C3, C4)

    def guess(self, eps_p, stress_MPa, strain_rate_per_s=None, temperature_C=None, **conditions):
        """C3, C4 at OFHC copper's; C0 and C2 by linear least squares."""
        eps, sig, rate, temp = series_points(self, eps_p, stress_MPa, strain_rate_per_s, temperature_C)
        c3, c4 = FCC_THERMAL_START
        act = thermal_activation(rate, temp, c3, c4)
        c, _ = _linear_constants([np.ones_like(eps), np.sqrt(np.clip(eps, 0, None)) * act], sig)
        return {"C0": float(c[0]), "C2": float(c[1]), "C3": c3, "C4": c4}
