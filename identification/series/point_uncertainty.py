"""Each fit point's standard uncertainty in a series fit (docs/methods.md §5.10), one function per term.

The stress terms (MPa, added in quadrature): the series' ``floor`` (its shape error), the ``start``
(the strain zero's δε0 through the curve's slope), the ``friction`` correction (u(μ)·|∂σ/∂μ|), the
correction's model form (``correction_form``) and its growth over the band before the FE table's
fold-over onset (``fold_over``). The x terms (the point's strain rate and temperature) enter through
the effective variance (Orear 1982) with the law's own slopes: ``rate`` and ``temperature``.
:mod:`identification.series.law_fit` stacks them and weighs the least squares by 1/u.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from flowcurve.identification.series.members import SeriesMember

Y_TERMS = ("floor", "start", "friction", "correction_form", "fold_over")  # on the stress, MPa
X_TERMS = ("rate", "temperature")  # on the point's conditions, through the law's slopes
LN_RATE_STEP = 0.01  # the central difference's half step in ln ε̇ for ∂σ/∂ln ε̇
TEMPERATURE_STEP_K = 0.5  # the central difference's half step in T for ∂σ/∂T
MAD_TO_SIGMA = 1.4826  # σ of a normal sample = 1.4826 × its median absolute deviation


def floor_u(stress_MPa, shape_error_pct: float) -> float:
    """The series' floor (MPa): its shape error of the RMS stress, the same for every point; never 0
    (a point is never exact: at least 10⁻³ %)."""
    # u_floor = s·√(mean σ²)
    return max(shape_error_pct, 1e-3) / 100.0 * float(np.sqrt(np.mean(np.asarray(stress_MPa, dtype=float) ** 2)))


def strain_zero_u(member: SeriesMember) -> float:
    """δε0 of a member (strain): its stated one (``delta_eps0``, from identify's start_uncertainty) when
    it carries it; else, for a curve read from a record or result folder (one point per sample), one
    sample's plastic strain at its start, uniform: Δε_first/√12; 0 for a curve given in memory."""
    stated = member.delta_eps0
    if stated is not None and math.isfinite(stated):
        return float(stated)
    eps = member.plastic_strain
    if member.kind not in ("record", "result") or eps.size < 2:
        return 0.0
    return float((eps[1] - eps[0]) / math.sqrt(12.0))  # δε0 = Δε_first/√12


def start_u(member: SeriesMember, eps_p) -> np.ndarray:
    """The strain zero's share (MPa) at plastic strains ``eps_p``: how far the member's own curve moves
    when its εp moves by δε0 (:func:`strain_zero_u`), the secant over ±δε0 (smooth where the curve is
    noisy on a finer sample spacing; the slope times δε0 where δε0 is small)."""
    # u_start = |σ(εp + δε0) − σ(εp − δε0)|/2 ≈ |dσ/dεp|·δε0, σ(εp) on the member's own curve (clamped at its ends)
    eps = np.asarray(eps_p, dtype=float)
    delta = strain_zero_u(member)
    if delta == 0.0:
        return np.zeros(eps.shape)
    curve_e, curve_s = member.plastic_strain, member.stress_MPa
    return np.abs(np.interp(eps + delta, curve_e, curve_s) - np.interp(eps - delta, curve_e, curve_s)) / 2.0


def friction_u(member: SeriesMember, eps_p) -> np.ndarray:
    """The friction correction's share (MPa): u(μ) (half the friction method's μ range) times the applied
    correction's |∂σ/∂μ| at each point; 0 where the member states either not."""
    # u_μ = u(μ)·|∂σ/∂μ|
    eps = np.asarray(eps_p, dtype=float)
    sensitivity = member.along_curve("dsigma_dmu_MPa", eps)
    if sensitivity is None or not member.friction_mu_u:
        return np.zeros(eps.shape)
    return float(member.friction_mu_u) * np.abs(sensitivity)


def correction_form_u(member: SeriesMember, eps_p, stress_MPa) -> np.ndarray:
    """The correction's model form (MPa): the FE table's force share at μ, the smallest per-point
    correction uncertainty the member states (true_curve.csv correction_uncertainty_pct), of the stress."""
    # u_form = σ·min(u_corr)/100
    eps = np.asarray(eps_p, dtype=float)
    if member.correction_u_pct is None:
        return np.zeros(eps.shape)
    return np.asarray(stress_MPa, dtype=float) * float(np.min(member.correction_u_pct)) / 100.0


def fold_over_u(member: SeriesMember, eps_p, stress_MPa) -> np.ndarray:
    """The growth of the correction's uncertainty over the band before the FE table's fold-over onset
    (MPa): the stated per-point correction uncertainty above its model-form floor, of the stress; 0 before
    the band (fe.model.model_form.corrected_stress_uncertainty_pct)."""
    # u_fold = σ·(u_corr(εp) − min u_corr)/100
    eps = np.asarray(eps_p, dtype=float)
    grown = member.along_curve("correction_u_pct", eps)
    if grown is None:
        return np.zeros(eps.shape)
    return np.asarray(stress_MPa, dtype=float) * np.clip(grown - float(np.min(member.correction_u_pct)), 0.0, None) / 100.0


def rate_u_ln(member: SeriesMember, eps_p) -> np.ndarray:
    """u(ln ε̇) of each point: the member's stated ``strain_rate_u_ln``; else, where the fit takes each
    point's own rate, those rates' scatter about their local trend (the robust σ of their second
    differences); else, with one rate per member, |ln(ε̇/ε̇_commanded)| (the measured rate against the
    crosshead speed / gauge length: the drift a one-rate member hides); else 0 (a curve given in memory)."""
    eps = np.asarray(eps_p, dtype=float)
    if member.strain_rate_u_ln is not None and math.isfinite(member.strain_rate_u_ln):
        return np.full(eps.shape, abs(float(member.strain_rate_u_ln)))
    rates = member.point_rates_per_s
    if rates is not None and rates.size >= 5:
        # u = 1.4826·median|Δ² ln ε̇|/√6: white noise of σ gives second differences of σ·√6
        return np.full(eps.shape, MAD_TO_SIGMA * float(np.median(np.abs(np.diff(np.log(rates), 2)))) / math.sqrt(6.0))
    commanded = member.nominal_strain_rate_per_s
    if rates is None and commanded and commanded > 0:
        return np.full(eps.shape, abs(math.log(member.strain_rate_per_s / commanded)))  # u = |ln(ε̇/ε̇_cmd)|
    return np.zeros(eps.shape)


def temperature_u(member: SeriesMember, eps_p) -> np.ndarray:
    """u(T) of each point (K): the member's stated ``temperature_u_C`` (from a record, the spread of its
    measured temperature over the plastic range), else 0."""
    eps = np.asarray(eps_p, dtype=float)
    stated = member.temperature_u_C
    return np.full(eps.shape, abs(float(stated)) if stated is not None and math.isfinite(stated) else 0.0)


@dataclass
class LawSlopes:
    """The law's slopes at the fit points: ∂σ/∂ln ε̇ (MPa) and ∂σ/∂T (MPa/K)."""

    ln_rate: np.ndarray
    temperature: np.ndarray


def law_slopes(law, values: dict, eps, rate, temp) -> LawSlopes:
    """The slopes of ``law`` at ``values`` and the points by central differences (on a clamp, as Johnson–Cook's
    below its reference rate: half the slope there); non-finite (at or above the melt) as 0."""
    # ∂σ/∂x ≈ (σ(x + h) − σ(x − h))/2h for x = ln ε̇ (h 0.01) and T (h 0.5 K)
    h, k = LN_RATE_STEP, TEMPERATURE_STEP_K
    d_rate = (law.stress(eps, rate * math.exp(h), temp, **values) - law.stress(eps, rate * math.exp(-h), temp, **values)) / (2 * h)
    d_temp = (law.stress(eps, rate, temp + k, **values) - law.stress(eps, rate, temp - k, **values)) / (2 * k)
    return LawSlopes(*(np.nan_to_num(d, nan=0.0, posinf=0.0, neginf=0.0) for d in (d_rate, d_temp)))


def effective_u(terms: "PointUncertainty", slopes: LawSlopes) -> np.ndarray:
    """The effective-variance uncertainty (MPa, Orear 1982): the stress terms and the point's rate and
    temperature uncertainties carried through the law's slopes, in quadrature."""
    # u_eff² = u_σ² + (∂σ/∂ln ε̇·u_lnε̇)² + (∂σ/∂T·u_T)²
    stress = sum(v**2 for name, v in terms.stress.items())
    return np.sqrt(stress + (slopes.ln_rate * terms.u_ln_rate) ** 2
                   + (slopes.temperature * terms.u_T) ** 2)


@dataclass
class PointUncertainty:
    """Every fit point's uncertainty terms: ``stress`` by name (MPa, :data:`Y_TERMS`) and the x terms
    ``u_ln_rate`` (1) and ``u_T`` (K) that the law's slopes turn into stress (:func:`effective_u`)."""

    stress: dict[str, np.ndarray] = field(default_factory=dict)
    u_ln_rate: np.ndarray = field(default_factory=lambda: np.zeros(0))
    u_T: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def u(self) -> np.ndarray:
        """The stress terms in quadrature (MPa): the weights of the first pass."""
        return np.sqrt(sum(v**2 for v in self.stress.values()))

    @property
    def has_x(self) -> bool:
        """Whether any point states an uncertainty of its rate or temperature (a second pass is needed)."""
        return bool(np.any(self.u_ln_rate > 0) or np.any(self.u_T > 0))

    def terms(self, slopes: LawSlopes | None = None) -> list[str]:
        """The names of the terms that weigh some point (fit.json ``point_u_terms``), the rate and
        temperature terms where the law's slope turns them into stress."""
        out = [name for name, v in self.stress.items() if np.any(v > 0)]
        if slopes is not None and np.any(np.abs(slopes.ln_rate) * self.u_ln_rate > 0):
            out.append("rate")
        if slopes is not None and np.any(np.abs(slopes.temperature) * self.u_T > 0):
            out.append("temperature")
        return out


def member_terms(member: SeriesMember, eps_p, stress_MPa, floor_MPa: float) -> PointUncertainty:
    """One member's points' terms (:data:`Y_TERMS` and the x terms) at ``eps_p`` with stresses ``stress_MPa``."""
    eps = np.asarray(eps_p, dtype=float)
    stress = {"floor": np.full(eps.shape, floor_MPa), "start": start_u(member, eps), "friction": friction_u(member, eps),
              "correction_form": correction_form_u(member, eps, stress_MPa), "fold_over": fold_over_u(member, eps, stress_MPa)}
    return PointUncertainty(stress=stress, u_ln_rate=rate_u_ln(member, eps), u_T=temperature_u(member, eps))


def joined(parts: list[PointUncertainty]) -> PointUncertainty:
    """The members' terms end to end, in the order of ``parts``."""
    return PointUncertainty(stress={name: np.concatenate([p.stress[name] for p in parts]) for name in Y_TERMS},
                            u_ln_rate=np.concatenate([p.u_ln_rate for p in parts]), u_T=np.concatenate([p.u_T for p in parts]))
