"""The full Johnson–Cook flow stress (2.19) with its conventions made explicit (docs/methods.md §5).

    σ = (A + B·εp^n) · (1 + C·ln ε̇*) · (1 − T*^m),   ε̇* = ε̇/ε̇0,   T* = (T − T_r)/(T_m − T_r)

Conventions (the ones that trip users):

* T* is clamped to [0, 1]: no thermal softening below the reference temperature, zero
  stress above the melting temperature;
* no rate effect below the reference rate: ln ε̇* is clamped at 0;
* ε̇0 is per second here (a deck in another time unit converts it).

The static bracket is :func:`identification.hardening.johnson_cook_static`.
"""

from __future__ import annotations

import numpy as np

from flowcurve.identification.laws.base import Law, Parameter, register
from flowcurve.identification.laws.hardening import johnson_cook_static

CONVENTIONS = {
    "homologous_temperature": "Tstar = (T - T_ref)/(T_melt - T_ref) clamped to [0, 1]: no softening below T_ref, zero stress above T_melt",
    "strain_rate": "ln(rate/ref_rate) clamped at 0: no rate effect below the reference rate",
    "ref_rate_time_unit": "s",
    "temperature_unit": "C (Tstar uses differences: C and K give the same Tstar)",
}

EQUATION = ("sigma_MPa = (A + B*eps_p^n) * (1 + C*ln(max(rate/ref_rate, 1))) * (1 - Tstar^m), "
            "Tstar = clamp((T - T_ref)/(T_melt - T_ref), 0, 1)")


def homologous_temperature(temperature_C, ref_temperature_C: float, melt_temperature_C: float):
    """# (2.19) T* = (T − T_r)/(T_m − T_r), clamped to [0, 1]."""
    t = (np.asarray(temperature_C, dtype=float) - ref_temperature_C) / (melt_temperature_C - ref_temperature_C)
    return np.clip(t, 0.0, 1.0)


def log_rate_ratio(strain_rate_per_s, ref_strain_rate_per_s: float):
    """# (2.19) ln ε̇* = ln(ε̇/ε̇0), clamped at 0 (no rate effect below ε̇0)."""
    return np.maximum(np.log(np.asarray(strain_rate_per_s, dtype=float) / ref_strain_rate_per_s), 0.0)


def rate_factor(log_rate, C):
    """# (2.19) second bracket: 1 + C·ln ε̇* (ln ε̇* already clamped)."""
    return 1.0 + C * np.asarray(log_rate, dtype=float)


def thermal_factor(t_star, m):
    """# (2.19) third bracket: 1 − T*^m (T* already clamped to [0, 1])."""
    return 1.0 - np.power(np.asarray(t_star, dtype=float), m)


def johnson_cook_reduced(eps_p, log_rate, t_star, A, B, n, C, m):
    """# (2.19) σ from the reduced variables (clamped ln ε̇* and T*), MPa."""
    return johnson_cook_static(eps_p, A, B, n) * rate_factor(log_rate, C) * thermal_factor(t_star, m)


def johnson_cook(eps_p, strain_rate_per_s, temperature_C, *, A, B, n, C, m,
                 ref_strain_rate_per_s: float, ref_temperature_C: float, melt_temperature_C: float):
    """# (2.19) Johnson–Cook flow stress (MPa) at true plastic strain, strain rate (1/s), T (°C)."""
    return johnson_cook_reduced(eps_p,
                                log_rate_ratio(strain_rate_per_s, ref_strain_rate_per_s),
                                homologous_temperature(temperature_C, ref_temperature_C, melt_temperature_C),
                                A, B, n, C, m)


@register
class JohnsonCook(Law):
    """Johnson–Cook (2.19): σ = (A + B·εp^n)(1 + C·ln ε̇*)(1 − T*^m), clamped as :data:`CONVENTIONS`."""

    name = "johnson_cook"
    display_name = "Johnson–Cook"
    parameters = (
        Parameter("A", "A_MPa", "MPa", 0.0, np.inf, "yield stress at the reference condition"),
        Parameter("B", "B_MPa", "MPa", 0.0, np.inf, "hardening modulus"),
        Parameter("n", "n", "", 1e-3, 1.5, "hardening exponent"),
        Parameter("C", "C", "", 0.0, 5.0, "strain-rate sensitivity"),
        Parameter("m", "m", "", 1e-3, 20.0, "thermal softening exponent"),
    )
    conditions = (
        Parameter("ref_strain_rate_per_s", "ref_strain_rate_per_s", "1/s", 0.0, np.inf, "reference strain rate ε̇0"),
        Parameter("ref_temperature_C", "ref_temperature_C", "°C", -273.15, np.inf, "reference temperature T_r"),
        Parameter("melt_temperature_C", "melt_temperature_C", "°C", -273.15, np.inf, "melting temperature T_m"),
    )
    rate_dependent = True
    temperature_dependent = True
    equation = EQUATION
    latex = (r"\sigma = (A + B\varepsilon_p^n)\,(1 + C\ln\max(\dot\varepsilon/\dot\varepsilon_0, 1))\,(1 - T^{*m}),"
             r"\quad T^* = \mathrm{clamp}\big((T - T_r)/(T_m - T_r), 0, 1\big)")
    source = "G. R. Johnson, W. H. Cook, 7th Int. Symp. on Ballistics, The Hague, 1983, pp. 541–547"

    def evaluate(self, eps_p, strain_rate_per_s, temperature_C, *, A, B, n, C, m,
                 ref_strain_rate_per_s, ref_temperature_C, melt_temperature_C):
        """Johnson–Cook flow stress, MPa."""
        # (2.19)
        return johnson_cook(eps_p, strain_rate_per_s, temperature_C, A=A, B=B, n=n, C=C, m=m,
                            ref_strain_rate_per_s=ref_strain_rate_per_s, ref_temperature_C=ref_temperature_C,
                            melt_temperature_C=melt_temperature_C)

    def guess(self, eps_p, stress_MPa, strain_rate_per_s=None, temperature_C=None, **conditions):
        """A from the lowest-strain stress, B from the rise to the largest strain at n 0.3; C 0.01, m 1."""
        eps = np.asarray(eps_p, dtype=float)
        sig = np.asarray(stress_MPa, dtype=float)
        A = float(0.9 * sig[np.argmin(eps)])
        top = float(max(np.max(eps), 1e-3))
        B = float(max(np.max(sig) - A, 0.1 * A, 1.0) / top**0.3)
        return {"A": A, "B": B, "n": 0.3, "C": 0.01, "m": 1.0}
