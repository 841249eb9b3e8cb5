"""Hensel–Spittel: the forming codes' flow stress in °C (QForm, Simufact, FORGE), docs/methods.md §5.9.

    σ = A·e^(m1·T)·T^m9·εp^m2·e^(m4/εp)·(1+εp)^(m5·T)·e^(m7·εp)·ε̇^m3·ε̇^(m8·T),   T in °C

m6 is left out: in the codes' nine-constant form it is not used (FORGE and HyperXtrude list
A, m1…m5, m7…m9); the older forms that carry it differ from code to code. The law is singular at
εp = 0 (εp^m2, e^(m4/εp)): εp below :data:`MIN_STRAIN` is evaluated there.
"""

from __future__ import annotations

import numpy as np

from flowcurve.identification.laws.base import Law, Parameter, register

MIN_STRAIN = 1e-4  # εp at which the law is evaluated below it (the codes' minimum strain)
SAME_TEMPERATURE_C = 1.0  # two temperatures closer than this are one
SAME_LOG_RATE = 0.05  # two rates whose ln differ less than this are one

EQUATION = ("sigma_MPa = A*exp(m1*T)*T^m9*eps_p^m2*exp(m4/eps_p)*(1+eps_p)^(m5*T)*exp(m7*eps_p)"
            "*rate^m3*rate^(m8*T), T in C, rate in 1/s")


def _terms(eps_p, strain_rate_per_s, temperature_C):
    """# (HS) the columns of ln σ, linear in (ln A, m1, m9, m2, m4, m5, m7, m3, m8)."""
    e = np.maximum(np.asarray(eps_p, dtype=float), MIN_STRAIN)
    t = np.asarray(temperature_C, dtype=float)
    lr = np.log(np.asarray(strain_rate_per_s, dtype=float))
    with np.errstate(divide="ignore", invalid="ignore"):
        ln_t = np.log(t)
    return {"A": np.ones_like(e), "m1": t, "m9": ln_t, "m2": np.log(e), "m4": 1.0 / e, "m5": t * np.log1p(e),
            "m7": e, "m3": lr, "m8": t * lr}


def hensel_spittel(eps_p, strain_rate_per_s, temperature_C, *, A, m1, m2, m3, m4, m5, m7, m8, m9):
    """# (HS) σ (MPa) at true plastic strain, strain rate (1/s) and temperature (°C)."""
    cols = _terms(eps_p, strain_rate_per_s, temperature_C)
    values = {"m1": m1, "m9": m9, "m2": m2, "m4": m4, "m5": m5, "m7": m7, "m3": m3, "m8": m8}
    # a term with a zero constant is 1 whatever its column (T^0 at T ≤ 0 °C included)
    ln_s = sum(v * cols[k] for k, v in values.items() if v != 0.0)
    return A * np.exp(ln_s)


def unsupported_terms(strain_rate_per_s, temperature_C) -> dict[str, str]:
    """The constants a series at these conditions cannot tell, by name, with the reason (fixed at 0)."""
    temps = np.unique(np.round(np.asarray(temperature_C, dtype=float) / SAME_TEMPERATURE_C))
    rates = np.unique(np.round(np.log(np.asarray(strain_rate_per_s, dtype=float)) / SAME_LOG_RATE))
    out = {}
    if temps.size < 2:
        out.update({k: f"one temperature only: {k} fixed at 0" for k in ("m1", "m5", "m8")})
    if temps.size < 3:
        out["m9"] = f"{temps.size} temperature(s): m9 (T^m9) needs 3, fixed at 0"
    if np.min(temperature_C) <= 0:
        out["m9"] = "a temperature at or below 0 °C: T^m9 is undefined there, fixed at 0"
    if rates.size < 2:
        out.update({k: f"one strain rate only: {k} fixed at 0" for k in ("m3", "m8")})
    return out


@register
class HenselSpittel(Law):
    """Hensel–Spittel in the forming codes' form, T in °C (see the module docstring)."""

    name = "hensel_spittel"
    display_name = "Hensel–Spittel"
    parameters = (
        Parameter("A", "A_MPa", "MPa", 0.0, np.inf, "stress scale"),
        Parameter("m1", "m1_per_C", "1/°C", -0.1, 0.1, "exponential temperature softening e^(m1·T)"),
        Parameter("m2", "m2", "", -2.0, 2.0, "strain hardening εp^m2"),
        Parameter("m3", "m3", "", -1.0, 1.0, "strain-rate sensitivity ε̇^m3"),
        Parameter("m4", "m4", "", -1.0, 1.0, "low-strain term e^(m4/εp)"),
        Parameter("m5", "m5_per_C", "1/°C", -0.05, 0.05, "strain–temperature coupling (1+εp)^(m5·T)"),
        Parameter("m7", "m7", "", -20.0, 20.0, "softening at large strain e^(m7·εp)"),
        Parameter("m8", "m8_per_C", "1/°C", -0.01, 0.01, "rate–temperature coupling ε̇^(m8·T)"),
        Parameter("m9", "m9", "", -10.0, 10.0, "power of the temperature T^m9 (°C)"),
    )
    rate_dependent = True
    temperature_dependent = True
    equation = EQUATION
    latex = (r"\sigma = A\,e^{m_1 T}\,T^{m_9}\,\varepsilon_p^{m_2}\,e^{m_4/\varepsilon_p}\,(1+\varepsilon_p)^{m_5 T}"
             r"\,e^{m_7\varepsilon_p}\,\dot\varepsilon^{m_3}\,\dot\varepsilon^{m_8 T},\quad T\ \mathrm{in\ ^\circ C}")
    source = ("A. Hensel, T. Spittel, Kraft- und Arbeitsbedarf bildsamer Formgebungsverfahren, VEB Deutscher Verlag für "
              "Grundstoffindustrie, Leipzig, 1978; the nine-constant form of the forming codes (FORGE, QForm, Simufact)")

    def evaluate(self, eps_p, strain_rate_per_s, temperature_C, **values):
        """Hensel–Spittel flow stress, MPa."""
        # (HS)
        return hensel_spittel(eps_p, strain_rate_per_s, temperature_C, **values)

    def unsupported(self, eps_p, strain_rate_per_s, temperature_C) -> dict[str, str]:
        """The constants the data cannot tell (:func:`unsupported_terms`), fixed at 0 by a fit."""
        return unsupported_terms(strain_rate_per_s, temperature_C)

    def guess(self, eps_p, stress_MPa, strain_rate_per_s=None, temperature_C=None, **conditions):
        """# (HS) least squares of ln σ, linear in ln A and m1…m9, over the supported terms; the others 0."""
        eps = np.asarray(eps_p, dtype=float)
        rate = np.broadcast_to(np.asarray(1.0 if strain_rate_per_s is None else strain_rate_per_s, dtype=float), eps.shape)
        temp = np.broadcast_to(np.asarray(20.0 if temperature_C is None else temperature_C, dtype=float), eps.shape)
        weights = np.broadcast_to(np.asarray(conditions.get("weights", 1.0), dtype=float), eps.shape)
        drop = set(self.unsupported(eps, rate, temp))
        cols = {k: v for k, v in _terms(eps, rate, temp).items() if k not in drop}
        M = np.column_stack(list(cols.values())) * weights[:, None]
        scale = np.maximum(np.max(np.abs(M), axis=0), 1e-300)
        coef = np.linalg.lstsq(M / scale, np.log(np.asarray(stress_MPa, dtype=float)) * weights, rcond=1e-10)[0] / scale
        out = {p.name: 0.0 for p in self.parameters}
        out.update({k: float(np.clip(c, self.parameter(k).lower, self.parameter(k).upper)) for k, c in zip(cols, coef)})
        out["A"] = float(np.exp(coef[0]))
        return out
