"""The global fit of a series over any registered law with rate and temperature (docs/methods.md §5.10):
:class:`LawFit` (the law, its constants, uncertainties, what was fixed and why, the fit errors) and
:func:`fit_law`, a least-squares problem over every record's points weighted by each point's stated
uncertainty (:func:`point_u`), so a record that cannot tell its strain zero does not pull the start.

Part of :mod:`identification.series`; the Johnson–Cook reference, the stepwise procedure and the
whole-series result are in :mod:`identification.series.fit`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.base import Law, get_law
from flowcurve.identification.series.members import MAX_POINTS, SeriesMember
from flowcurve.identification.series.point_uncertainty import (floor_u, law_slopes, effective_u, joined, member_terms,
                                                               strain_zero_u)  # noqa: F401 - strain_zero_u: callers read it here

# the RMS shape error the friction correction leaves on CalculiX compression records with a known law
# (0.40 % over the fit points of six records, docs/methods.md §5.7): how well the curves tell the constants apart
SHAPE_ERROR_PCT = 0.4
BOUND_REL = 1e-6  # a constant within this share of its range from a bound is on it


def point_u(member: SeriesMember, eps_p, floor_MPa: float, stress_MPa=None) -> np.ndarray:
    """Each fit point's standard uncertainty on the stress (MPa): the stress terms of
    :mod:`.point_uncertainty` in quadrature (floor, start, friction, correction form, fold-over band), at
    the member's own stresses unless ``stress_MPa`` is given."""
    eps = np.asarray(eps_p, dtype=float)
    sig = np.interp(eps, member.plastic_strain, member.stress_MPa) if stress_MPa is None else stress_MPa
    return member_terms(member, eps, sig, floor_MPa).u


def stack_terms(members: Sequence[SeriesMember], max_points: int, shape_error_pct: float = SHAPE_ERROR_PCT):
    """All fit points: εp, σ, each point's own rate (1/s), T (°C), member index, and their uncertainty
    terms (:class:`.point_uncertainty.PointUncertainty`; the floor is the shape error of the series' RMS stress)."""
    cols = [[], [], [], [], []]
    for i, m in enumerate(members):
        eps, sig = m.fit_points(max_points)
        for col, values in zip(cols, (eps, sig, m.rates_at(eps), m.temperatures_at(eps), np.full(eps.size, i))):
            col.append(values)
    eps, sig, rate, temp, idx = (np.concatenate(c) for c in cols)
    idx = idx.astype(int)
    floor = floor_u(sig, shape_error_pct)
    terms = joined([member_terms(m, eps[idx == i], sig[idx == i], floor) for i, m in enumerate(members)])
    return eps, sig, rate, temp, idx, terms


def stack_points(members: Sequence[SeriesMember], max_points: int, shape_error_pct: float = SHAPE_ERROR_PCT):
    """All fit points: εp, σ, each point's own rate (1/s), T (°C), u (MPa, the stress terms in quadrature,
    :func:`point_u`) and member index. A series whose curves state nothing but the floor is fitted as
    unweighted least squares."""
    eps, sig, rate, temp, idx, terms = stack_terms(members, max_points, shape_error_pct)
    return eps, sig, rate, temp, terms.u, idx


@dataclass
class LawFit:
    """Identified constants of a registered law with their uncertainties and the quality of fit.

    Attributes
    ----------
    method : str
        How it was fitted.
    params, stderr : dict
        Constants by name, in the law's units; their standard errors (None: fixed or not estimated).
    reference : object, optional
        Johnson–Cook's Reference; None for other laws.
    fixed, fixed_why : dict
        Constants not fitted, and why.
    correlations : dict
        Correlation coefficients between fitted constants.
    fit_error_pct, rms_error_pct : float
        Largest and RMS relative misfit, %.
    record_errors : dict
        Each record's misfit, %.
    report : str
        lmfit's report.
    law, conditions : Law, dict
        The law and its stated inputs.
    at_bound : dict
        Constants that ended on a bound ("lower", "upper").
    point_u_terms : list of str
        The terms of each point's uncertainty that weighed the fit (``floor``, ``start``, ``friction`` …).
    """

    method: str
    params: dict[str, float]
    stderr: dict[str, float | None]
    reference: object | None = None
    fixed: dict[str, float] = field(default_factory=dict)
    correlations: dict[str, dict[str, float]] = field(default_factory=dict)
    fit_error_pct: float = float("nan")
    rms_error_pct: float = float("nan")
    record_errors: dict[str, dict[str, float]] = field(default_factory=dict)
    report: str = ""
    law: Law = field(default_factory=lambda: get_law("johnson_cook"))
    conditions: dict[str, float] = field(default_factory=dict)
    fixed_why: dict[str, str] = field(default_factory=dict)
    at_bound: dict[str, str] = field(default_factory=dict)
    point_u_terms: list[str] = field(default_factory=list)  # the uncertainty terms that weighed the points (§5.10)

    @property
    def values(self) -> dict[str, float]:
        """Every parameter and condition by name, as ``law.stress`` takes them."""
        ref = self.reference
        cond = dict(self.conditions)
        if ref is not None:
            cond.update(ref_strain_rate_per_s=ref.strain_rate_per_s, ref_temperature_C=ref.temperature_C,
                        melt_temperature_C=ref.melt_temperature_C)
        return {**cond, **self.params}

    def __call__(self, eps_p, strain_rate_per_s, temperature_C):
        """Flow stress (MPa) of the identified law."""
        return self.law.stress(eps_p, strain_rate_per_s, temperature_C, **self.values)

    def as_dict(self) -> dict:
        """The parameter block of fit.json (keys with units, see docs/fit-json.md)."""
        key = {p.name: p.key for p in self.law.parameters}
        out: dict = {"method": self.method}
        out.update({key[p]: float(v) for p, v in self.params.items()})
        for p in self.params:
            se = self.stderr.get(p)
            out[f"{key[p]}_stderr"] = None if se is None or not math.isfinite(se) else float(se)
        out["fixed"] = {p: float(v) for p, v in self.fixed.items()}
        if self.fixed_why:
            out["fixed_why"] = dict(self.fixed_why)
        out["at_bound"] = {key[p]: side for p, side in self.at_bound.items()}
        out["point_u_terms"] = list(self.point_u_terms)
        out["correlations"] = {key[p]: {key[q]: float(c) for q, c in row.items()} for p, row in self.correlations.items()}
        out["fit_error_pct"] = float(self.fit_error_pct)
        out["rms_error_pct"] = float(self.rms_error_pct)
        out["record_errors"] = self.record_errors
        out["report"] = self.report
        return out


def fill_errors(fit: LawFit, members: Sequence[SeriesMember], max_points: int) -> None:
    """Fill the overall and per-record errors (max and RMS of |σ_model/σ − 1|, %)."""
    all_rel = []
    for m in members:
        eps, sig = m.fit_points(max_points)
        rel = fit(eps, m.rates_at(eps), m.temperatures_at(eps)) / sig - 1.0
        all_rel.append(rel)
        fit.record_errors[m.name] = {"fit_error_pct": float(100 * np.max(np.abs(rel))),
                                     "rms_error_pct": float(100 * np.sqrt(np.mean(rel**2)))}
    rel = np.concatenate(all_rel)
    fit.fit_error_pct = float(100 * np.max(np.abs(rel)))
    fit.rms_error_pct = float(100 * np.sqrt(np.mean(rel**2)))


def on_bound(law: Law, params: dict[str, float], free) -> dict[str, str]:
    """The free constants within BOUND_REL of a bound: {name: "lower"/"upper"}."""
    out = {}
    for p in (law.parameter(n) for n in free):
        v, span = params[p.name], (p.upper - p.lower if math.isfinite(p.upper - p.lower) else max(abs(params[p.name]), 1.0))
        if math.isfinite(p.lower) and v - p.lower <= BOUND_REL * span:
            out[p.name] = "lower"
        elif math.isfinite(p.upper) and p.upper - v <= BOUND_REL * span:
            out[p.name] = "upper"
    return out


def fit_law(members: Sequence[SeriesMember], law: Law | str, *, conditions: dict[str, float] | None = None,
            fixed: dict[str, float] | None = None, fixed_why: dict[str, str] | None = None, start: dict[str, float] | None = None,
            max_points: int = MAX_POINTS, shape_error_pct: float = SHAPE_ERROR_PCT, reference=None) -> LawFit:
    """Fit every free constant of ``law`` in one least-squares problem over all the series' true curves.

    Residuals (σ_law − σ)/u with u each point's stated uncertainty (:func:`point_u`); terms the
    law says the series cannot support (``law.unsupported``) are fixed at 0 with the reason.

    Parameters
    ----------
    members : sequence of SeriesMember
        The series' plastic curves.
    law : Law or str
        A law or a registered law's name.
    conditions, reference : optional
        The law's stated inputs (reference rate 1/s, temperatures °C); Johnson–Cook's Reference.
    fixed, fixed_why, start : dict, optional
        Constants held at a value, and why; starting values overriding the law's ``guess``.
    max_points, shape_error_pct : int, float
        Points taken from each curve; the model-form error added to each u, %.

    Returns
    -------
    LawFit
        The constants with standard errors, correlations and errors filled.
    """
    import lmfit

    law = get_law(law) if isinstance(law, str) else law
    conditions = dict(conditions or {})
    fixed, why = dict(fixed or {}), dict(fixed_why or {})
    eps, sig, rate, temp, _, terms = stack_terms(members, max_points, shape_error_pct)
    u = terms.u
    _fix_unsupported(law, eps, rate, temp, fixed, why)
    params = _parameters(law, fixed, start or law.guess(eps, sig, rate, temp, weights=1.0 / u, **conditions))

    def residual(pars, weights_u):
        """Misfits of the law at ``pars``, in units of each point's uncertainty ``weights_u``."""
        return (law.stress(eps, rate, temp, **conditions, **pars.valuesdict()) - sig) / weights_u

    result = _minimize(residual, params, u, law)
    slopes = None
    if terms.has_x:  # the effective variance (Orear 1982) with the law's slopes at the first pass's constants, then again
        slopes = law_slopes(law, {**conditions, **result.params.valuesdict()}, eps, rate, temp)
        result = _minimize(residual, result.params, effective_u(terms, slopes), law)
    names = law.names
    free = [p for p in names if p not in fixed]
    values = {p: float(result.params[p].value) for p in names}
    fit = LawFit(method="global", params=values, law=law, conditions=conditions, reference=reference,
                 stderr={p: (None if p in fixed or result.params[p].stderr is None else float(result.params[p].stderr)) for p in names},
                 fixed=fixed, fixed_why=why, at_bound=on_bound(law, values, free),
                 correlations={p: {q: float(c) for q, c in (result.params[p].correl or {}).items()} for p in free},
                 report=lmfit.fit_report(result), point_u_terms=terms.terms(slopes))
    fill_errors(fit, members, max_points)
    return fit


def _fix_unsupported(law: Law, eps, rate, temp, fixed: dict[str, float], why: dict[str, str]) -> None:
    """Fix at 0, with the reason, the terms ``law.unsupported`` says the points cannot tell (in place)."""
    unsupported = getattr(law, "unsupported", None)
    for name, reason in (unsupported(eps, rate, temp) if unsupported else {}).items():
        if name not in fixed:
            fixed[name], why[name] = 0.0, reason


def _parameters(law: Law, fixed: dict[str, float], first: dict[str, float]):
    """lmfit Parameters of ``law``: the fixed ones held, the others from ``first`` clipped to their bounds."""
    import lmfit

    params = lmfit.Parameters()
    for p in law.parameters:
        value = fixed.get(p.name, first[p.name])
        params.add(p.name, value=float(np.clip(value, p.lower, p.upper)), min=p.lower, max=p.upper, vary=p.name not in fixed)
    return params


def _minimize(residual, params, weights_u, law):
    """One weighted least-squares pass (lmfit, trust region); an IdentificationError when it fails."""
    import lmfit

    result = lmfit.minimize(residual, params, args=(weights_u,), method="least_squares")
    if not result.success:
        raise IdentificationError(f"the global {law.display_name} fit did not converge: {result.message}")
    return result


def law_shape_uncertainty(members: Sequence[SeriesMember], fit: LawFit, *, max_points: int = MAX_POINTS,
                          shape_error_pct: float = SHAPE_ERROR_PCT) -> dict:
    """How far each fitted constant can move when the curves carry a shape error of RMS
    ``shape_error_pct`` (a systematic error the fit's own residual does not show): the linearised
    least-squares bound δp = s·√N·√diag((JᵀJ)⁻¹) with J the relative sensitivities ∂σ/σ∂p at the
    fit points. Strongly correlated constants (JC's A and n) get a wide band. Keys are the law's."""
    # δp_max over ‖J·δp‖₂/√N ≤ s: the covariance of a residual of RMS s
    eps, _, rate, temp, _, _ = stack_points(members, max_points, shape_error_pct)
    key = {p.name: p.key for p in fit.law.parameters}
    free = [p for p in fit.law.names if p not in fit.fixed and p not in fit.at_bound]
    values = fit.values
    base = fit.law.stress(eps, rate, temp, **values)
    keep = np.isfinite(base) & (base > 0)  # a point at or above the melt has no relative sensitivity
    eps, rate, temp, base = eps[keep], rate[keep], temp[keep], base[keep]
    cols = []
    for p in free:
        h = 1e-6 * max(abs(values[p]), 1e-3)
        cols.append((fit.law.stress(eps, rate, temp, **{**values, p: values[p] + h}) - base) / (h * base))
    J = np.array(cols).T
    try:
        cov = np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        return {"curve_shape_error_pct": shape_error_pct, **{key[p]: None for p in free}}
    band = shape_error_pct / 100.0 * math.sqrt(eps.size) * np.sqrt(np.clip(np.diag(cov), 0.0, None))
    return {"curve_shape_error_pct": shape_error_pct, **{key[p]: float(v) for p, v in zip(free, band)}}


def total_uncertainty(fit: LawFit, band: dict) -> dict[str, float | None]:
    """Each constant's total standard uncertainty by key: its statistical stderr and the shape band in
    quadrature (None for a fixed constant or one on its bound: not identified)."""
    out: dict[str, float | None] = {}
    for p in fit.law.parameters:
        se, shape = fit.stderr.get(p.name), band.get(p.key)
        if p.name in fit.fixed or p.name in fit.at_bound or (se is None and shape is None):
            out[p.key] = None
        else:
            out[p.key] = float(math.hypot(se or 0.0, shape or 0.0))
    return out
