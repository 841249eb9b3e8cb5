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
