"""Johnson–Cook constants of a test series: the reference condition, the global and stepwise
fits, the tabulated curves per condition, and :func:`fit_series` that does it all (fit.json).

Part of :mod:`identification.series` (which re-exports these names); the members the fits take
are in :mod:`identification.series_members`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import lmfit
import numpy as np
import pandas as pd

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.base import get_law
from flowcurve.identification.laws.hardening import POOR_FIT_PCT, fit_hardening
from flowcurve.identification.laws.johnson_cook import (CONVENTIONS, homologous_temperature, johnson_cook_reduced,
                                                  log_rate_ratio)
from flowcurve.identification.outcome import TRUE_CURVE_COLUMNS
from flowcurve.identification.series.damage import DamageFit, FracturePoint, fit_damage
from flowcurve.identification.quality import uncertainty as un
from flowcurve.identification.elastic_modulus import series_modulus
from flowcurve.identification.series.law_fit import (SHAPE_ERROR_PCT, LawFit, fill_errors, fit_law, law_shape_uncertainty,
                                                     total_uncertainty)
from flowcurve.identification.series.members import MAX_POINTS, SeriesMember, stream_gap_warnings

PARAMS = ("A", "B", "n", "C", "m")
KEYS = {"A": "A_MPa", "B": "B_MPa", "n": "n", "C": "C", "m": "m"}
LOOSE_CONSTANT_PCT = 3.0  # a constant the shape error can move more than this is flagged
BOUNDS = {"A": (0.0, np.inf), "B": (0.0, np.inf), "n": (1e-3, 1.5), "C": (0.0, 5.0), "m": (1e-3, 20.0)}

# the reference condition of the stepwise procedure
REF_TEMPERATURE_TOL_C = 5.0
REF_RATE_FACTOR = 1.25
# two records are at the same condition (one tabulated curve) within these
SAME_TEMPERATURE_C = 1.0
SAME_RATE_REL = 0.02
# distinct conditions: clamped ln ε̇* and T* differing by more than these
DISTINCT_LOG_RATE = 0.05
DISTINCT_T_STAR = 1e-3



# -- reference and what the series can determine ------------------------------------------


@dataclass(frozen=True)
class Reference:
    """The stated inputs of the model: ε̇0 (1/s), T_r and T_m (°C), with where they came from."""

    strain_rate_per_s: float
    temperature_C: float
    melt_temperature_C: float
    strain_rate_source: str = "given"
    temperature_source: str = "given"

    def reduced(self, member: SeriesMember) -> tuple[float, float]:
        """(clamped ln ε̇*, clamped T*) of a member."""
        return (float(log_rate_ratio(member.strain_rate_per_s, self.strain_rate_per_s)),
                float(homologous_temperature(member.temperature_C, self.temperature_C, self.melt_temperature_C)))


def make_reference(members: Sequence[SeriesMember], *, ref_strain_rate_per_s: float | None = None,
                   ref_temperature_C: float | None = None, melt_temperature_C: float | None = None) -> Reference:
    """The reference condition: given values, else the lowest rate / temperature of the series.

    The melting temperature is a property of the material and must be given.
    """
    if not members:
        raise IdentificationError("the series is empty: give at least one record or result folder")
    rate_src = temp_src = "given"
    if ref_strain_rate_per_s is None:
        ref_strain_rate_per_s, rate_src = min(m.strain_rate_per_s for m in members), "lowest in the series"
    if ref_temperature_C is None:
        ref_temperature_C, temp_src = min(m.temperature_C for m in members), "lowest in the series"
    if not (math.isfinite(ref_strain_rate_per_s) and ref_strain_rate_per_s > 0):
        raise IdentificationError(f"the reference strain rate must be > 0 1/s, got {ref_strain_rate_per_s:g}")
    if melt_temperature_C is None:
        raise IdentificationError("the melting temperature is needed for T* = (T - T_ref)/(T_melt - T_ref): give it (--melt-temp, °C)")
    if not melt_temperature_C > ref_temperature_C:
        raise IdentificationError(f"the melting temperature ({melt_temperature_C:g} °C) must be above the reference temperature ({ref_temperature_C:g} °C)")
    hot = [m.name for m in members if m.temperature_C >= melt_temperature_C]
    if hot:
        raise IdentificationError(f"record(s) {', '.join(hot)} at or above the melting temperature {melt_temperature_C:g} °C: check --melt-temp (°C, not K)")
    return Reference(float(ref_strain_rate_per_s), float(ref_temperature_C), float(melt_temperature_C), rate_src, temp_src)


def _distinct(values: Sequence[float], tol: float) -> list[float]:
    out: list[float] = []
    for v in sorted(values):
        if not out or v - out[-1] > tol:
            out.append(v)
    return out


def check_identifiable(members: Sequence[SeriesMember], ref: Reference, fixed: dict[str, float]) -> None:
    """Refuse, with the reason, to fit C or m from a series that cannot determine it."""
    reduced = [ref.reduced(m) for m in members]
    if "C" not in fixed and len(_distinct([r[0] for r in reduced], DISTINCT_LOG_RATE)) < 2:
        rates = ", ".join(sorted({f"{m.strain_rate_per_s:.3g}" for m in members}))
        raise IdentificationError(
            f"the series has one strain rate only as the model sees it (rates {rates} 1/s with the reference "
            f"{ref.strain_rate_per_s:g} 1/s; rates below the reference count as the reference): C cannot be identified - "
            "add records at other rates or fix C (--fix-C VALUE)")
    if "m" not in fixed and len(_distinct([r[1] for r in reduced], DISTINCT_T_STAR)) < 2:
        temps = ", ".join(sorted({f"{m.temperature_C:g}" for m in members}))
        raise IdentificationError(
            f"the series has one temperature only as the model sees it ({temps} °C with the reference "
            f"{ref.temperature_C:g} °C; temperatures below the reference count as the reference): m cannot be identified - "
            "add records at other temperatures or fix m (--fix-m VALUE)")
    bad = {k: v for k, v in fixed.items() if k not in ("C", "m")}
    if bad:
        raise IdentificationError(f"only C and m can be fixed, not {', '.join(bad)}")
    for k, v in fixed.items():
        lo, hi = BOUNDS[k]
        if not (lo <= v <= hi):
            raise IdentificationError(f"fixed {k} = {v:g} is outside its range [{lo:g}, {hi:g}]")


# -- fits ---------------------------------------------------------------------------------


JohnsonCookFit = LawFit  # a Johnson–Cook fit is a LawFit whose law is JC and whose reference is set


def _stack(members: Sequence[SeriesMember], ref: Reference, max_points: int):
    """All fit points: εp, σ, clamped ln ε̇* (each point's own rate when the member has them), clamped T*,
    and each point's member index."""
    cols = [[], [], [], [], []]
    for i, m in enumerate(members):
        eps, sig = m.fit_points(max_points)
        ts = homologous_temperature(m.temperatures_at(eps), ref.temperature_C, ref.melt_temperature_C)  # each point's own T (adiabatic rise)
        lr = log_rate_ratio(m.rates_at(eps), ref.strain_rate_per_s)
        for col, values in zip(cols, (eps, sig, lr, ts, np.full(eps.size, i))):
            col.append(values)
    eps, sig, lr, ts, idx = (np.concatenate(c) for c in cols)
    return eps, sig, lr, ts, idx.astype(int)


def _start_static(members: Sequence[SeriesMember], ref: Reference, max_points: int) -> dict[str, float]:
    """Start values of A, B, n: a hardening fit to the members nearest the reference condition."""
    reduced = [ref.reduced(m) for m in members]
    best = min(reduced, key=lambda r: (r[1], r[0]))
    near = [m for m, r in zip(members, reduced) if abs(r[1] - best[1]) <= DISTINCT_T_STAR and abs(r[0] - best[0]) <= DISTINCT_LOG_RATE]
    pts = [m.fit_points(max_points) for m in near]
    hf = fit_hardening(np.concatenate([p[0] for p in pts]), np.concatenate([p[1] for p in pts]), "johnson_cook")
    return {"A": max(hf.params["A"], 0.0), "B": hf.params["B"], "n": float(np.clip(hf.params["n"], 0.01, 1.5))}


def fit_global(members: Sequence[SeriesMember], ref: Reference, *, fixed: dict[str, float] | None = None,
               max_points: int = MAX_POINTS, shape_error_pct: float = SHAPE_ERROR_PCT) -> LawFit:
    """# (2.19) A, B, n, C, m in one least-squares problem over all true curves (:func:`.law_fit.fit_law`),
    each point weighed by its stated uncertainty; each record contributes at most ``max_points`` points
    evenly spaced in εp. ``fixed`` holds constants that are not fitted (``{"m": 1.0}``).
    """
    fixed = dict(fixed or {})
    check_identifiable(members, ref, fixed)
    start = {**_start_static(members, ref, max_points), "C": 0.01, "m": 1.0}
    conditions = {"ref_strain_rate_per_s": ref.strain_rate_per_s, "ref_temperature_C": ref.temperature_C,
                  "melt_temperature_C": ref.melt_temperature_C}
    fit = fit_law(members, "johnson_cook", conditions=conditions, fixed=fixed, start=start, max_points=max_points,
                  shape_error_pct=shape_error_pct, reference=ref)
    fit.conditions = {}  # the reference carries them
    return fit


def _is_reference_temperature(m: SeriesMember, ref: Reference) -> bool:
    return m.temperature_C <= ref.temperature_C + REF_TEMPERATURE_TOL_C


def _fit_one(name: str, func, points, start: float, what: str) -> tuple[float, float | None, str]:
    """Least squares of one constant ``name`` with the others fixed (a stepwise step)."""
    eps, sig, lr, ts = points
    lo, hi = BOUNDS[name]
    params = lmfit.Parameters()
    params.add(name, value=start, min=lo, max=hi)
    result = lmfit.minimize(lambda p: func(p[name].value, eps, lr, ts) - sig, params, method="least_squares")
    if not result.success:
        raise IdentificationError(f"stepwise fit of {name} ({what}) did not converge: {result.message}")
    se = result.params[name].stderr
    return float(result.params[name].value), (None if se is None else float(se)), lmfit.fit_report(result)


def fit_stepwise(members: Sequence[SeriesMember], ref: Reference, *, fixed: dict[str, float] | None = None,
                 max_points: int = MAX_POINTS) -> JohnsonCookFit:
    """The classic stepwise identification: A, B, n, then C, then m.

    1. A, B, n: :func:`identification.hardening.fit_hardening` on the records at the reference
       condition (T within 5 °C of T_r or below it, ε̇ ≤ 1.25·ε̇0); with each point's own rate
       their stresses are brought to ε̇0 with C of step 2 and steps 1–2 repeated (3 rounds);
    2. C: records at the reference temperature, A, B, n fixed;
    3. m: records above the reference temperature, A, B, n, C fixed.
    Each step's uncertainties are conditional on the constants of the previous steps.
    """
    fixed = dict(fixed or {})
    check_identifiable(members, ref, fixed)
    at_ref_t = [m for m in members if _is_reference_temperature(m, ref)]
    at_ref = [m for m in at_ref_t if m.strain_rate_per_s <= REF_RATE_FACTOR * ref.strain_rate_per_s]
    if not at_ref:
        raise IdentificationError(
            f"stepwise fit needs records at the reference condition ({ref.temperature_C:g} °C, "
            f"{ref.strain_rate_per_s:g} 1/s); none is within {REF_TEMPERATURE_TOL_C:g} °C and a factor {REF_RATE_FACTOR:g} of the rate")
    def points(group):
        eps, sig, lr, ts, _ = _stack(group, ref, max_points)
        return eps, sig, lr, ts

    # step 1 on the reference records' stresses brought to the reference rate with C (none at first); when the records carry
    # each point's own rate (it drifts within a record: ε̇ = v/h in compression), steps 1 and 2 are repeated with the C found
    ref_eps, ref_sig, ref_lr, _ = points(at_ref)
    C = fixed.get("C", 0.0)
    for _ in range(3 if any(m.point_rates_per_s is not None for m in at_ref) else 1):
        hf = fit_hardening(ref_eps, ref_sig / (1.0 + C * ref_lr), "johnson_cook")
        A, B, n = hf.params["A"], hf.params["B"], hf.params["n"]
        stderr: dict[str, float | None] = {p: hf.stderr.get(p) for p in ("A", "B", "n")}
        reports = ["[[Step 1: A, B, n at the reference condition]]", hf.report]
        if "C" in fixed:
            C, stderr["C"] = fixed["C"], None
        else:
            faster = [m for m in at_ref_t if ref.reduced(m)[0] > DISTINCT_LOG_RATE]
            if not faster:
                raise IdentificationError(
                    f"stepwise fit: no record at the reference temperature ({ref.temperature_C:g} °C) above the reference rate "
                    f"{ref.strain_rate_per_s:g} 1/s, so step 2 cannot give C; use the global fit or fix C (--fix-C VALUE)")
            C, stderr["C"], rep = _fit_one("C", lambda c, e, lr, ts: johnson_cook_reduced(e, lr, 0.0, A, B, n, c, 1.0),
                                           points(at_ref_t), 0.01, "reference-temperature records")
            reports += ["[[Step 2: C at the reference temperature]]", rep]
    if "m" in fixed:
        m_, stderr["m"] = fixed["m"], None
    else:
        hot = [m for m in members if not _is_reference_temperature(m, ref)]
        if not hot:
            raise IdentificationError(
                f"stepwise fit: no record more than {REF_TEMPERATURE_TOL_C:g} °C above the reference temperature "
                f"{ref.temperature_C:g} °C, so step 3 cannot give m; fix m (--fix-m VALUE)")
        m_, stderr["m"], rep = _fit_one("m", lambda mm, e, lr, ts: johnson_cook_reduced(e, lr, ts, A, B, n, C, mm),
                                        points(hot), 1.0, "records above the reference temperature")
        reports += ["[[Step 3: m above the reference temperature]]", rep]
    fit = JohnsonCookFit(method="stepwise", params={"A": A, "B": B, "n": n, "C": C, "m": m_}, stderr=stderr,
                         reference=ref, fixed=fixed,
                         correlations={p: {q: c for q, c in hf.correlations.get(p, {}).items()} for p in ("A", "B", "n")},
                         report="\n".join(reports))
    fill_errors(fit, members, max_points)
    return fit


# -- the whole series ---------------------------------------------------------------------


@dataclass
class ConditionCurve:
    """The measured true curve at one (temperature, strain rate), averaged over its records."""

    temperature_C: float
    strain_rate_per_s: float
    records: list[str]
    table: pd.DataFrame  # columns true_plastic_strain, true_stress_MPa
    repeats: dict | None = None  # the Type A spread of its repeats at TYPE_A_STRAINS (:func:`repeats_type_a`), None for one record

    @property
    def filename(self) -> str:
        """The curve's CSV name: its temperature and strain rate."""
        return f"T{self.temperature_C:.0f}C_rate{self.strain_rate_per_s:.3g}_per_s.csv"


def condition_curves(members: Sequence[SeriesMember], max_points: int = MAX_POINTS) -> list[ConditionCurve]:
    """Group the records by condition and tabulate one curve each (mean over the shared εp range)."""
    groups: list[list[SeriesMember]] = []
    for m in sorted(members, key=lambda m: (m.temperature_C, m.strain_rate_per_s)):
        for g in groups:
            g0 = g[0]
            if (abs(g0.temperature_C - m.temperature_C) <= SAME_TEMPERATURE_C
                    and abs(m.strain_rate_per_s / g0.strain_rate_per_s - 1.0) <= SAME_RATE_REL):
                g.append(m)
                break
        else:
            groups.append([m])
    out = []
    for g in groups:
        lo = max(m.plastic_strain[0] for m in g)
        hi = min(m.plastic_strain[-1] for m in g)
        if hi <= lo:  # no shared range: keep the longest curve
            g = [max(g, key=lambda m: np.ptp(m.plastic_strain))]
            lo, hi = g[0].plastic_strain[0], g[0].plastic_strain[-1]
        grid = np.linspace(lo, hi, max_points) if len(g) > 1 or g[0].plastic_strain.size > max_points else g[0].plastic_strain
        stress = np.mean([np.interp(grid, m.plastic_strain, m.stress_MPa) for m in g], axis=0)
        out.append(ConditionCurve(float(np.mean([m.temperature_C for m in g])),
                                  float(np.exp(np.mean([np.log(m.strain_rate_per_s) for m in g]))),
                                  [m.name for m in g],
                                  pd.DataFrame({TRUE_CURVE_COLUMNS[0]: grid, TRUE_CURVE_COLUMNS[1]: stress}),
                                  repeats_type_a(g, lo, hi)))
    return out


TYPE_A_STRAINS = (0.002, 0.05, 0.1, 0.2, 0.3, 0.5)  # plastic strains the repeats' spread is stated at (within their shared range)


def repeats_type_a(group: Sequence[SeriesMember], lo: float, hi: float) -> dict | None:
    """The Type A uncertainty of a condition's mean curve from its repeats (GUM 4.2): at each of
    :data:`TYPE_A_STRAINS` within [lo, hi], the mean σ̄, the repeats' standard deviation s and
    u = s/√n with n − 1 degrees of freedom (U = t·u, Student's t); None for a single record."""
    if len(group) < 2:
        return None
    n = len(group)
    out = {}
    for at in (a for a in TYPE_A_STRAINS if lo <= a <= hi):
        values = np.array([float(np.interp(at, m.plastic_strain, m.stress_MPa)) for m in group])
        s = float(values.std(ddof=1))  # the repeats' spread
        comp = un.Component(f"repeats (Type A, {n} records)", float(values.mean()), "MPa", s / math.sqrt(n), 1.0,
                            f"standard deviation {s:.3g} MPa of {n} repeats, of the mean s/√n", dof=n - 1.0)
        out[f"{at:g}"] = {**un.budget(float(values.mean()), "MPa", [comp], note=f"at true plastic strain {at:g}"), "s_MPa": s, "n": n,
                          "values_MPa": [float(v) for v in values]}
    return out or None


@dataclass
class SeriesFit:
    """Everything ``flowcurve fit`` writes: the chosen fit, the other for comparison, the series.

    Attributes
    ----------
    method : str
        The chosen method ("global", "stepwise").
    fit, global_fit, stepwise_fit : JohnsonCookFit or LawFit
        The chosen fit and each method's (None when not run).
    stepwise_note : str, optional
        Why the stepwise fit was not run.
    members, curves : list
        The series' members; one ConditionCurve per condition.
    warnings : list of str
        The fit's warnings.
    max_points : int
        Points taken from each curve.
    damage, shape_uncertainty : optional
        The Johnson–Cook damage fit (D1–D5); the law's shape uncertainty band.
    """

    method: str
    fit: JohnsonCookFit
    global_fit: JohnsonCookFit | None
    stepwise_fit: JohnsonCookFit | None
    stepwise_note: str | None
    members: list[SeriesMember]
    curves: list[ConditionCurve]
    warnings: list[str] = field(default_factory=list)
    max_points: int = MAX_POINTS
    damage: DamageFit | None = None  # D1-D5 when the series holds fracture data
    shape_uncertainty: dict | None = None  # how far each constant can move under a SHAPE_ERROR_PCT shape error of the curves

    @property
    def quality(self) -> str:
        """"good", or "poor" when the chosen fit's largest relative error exceeds 10 %."""
        return "poor" if not self.fit.fit_error_pct <= POOR_FIT_PCT else "good"

    def point_rates(self) -> pd.DataFrame:
        """The points each record was fitted on with the strain rate the model took at each
        (point_rates.csv): its own from the record's time and strain when the member has them
        (ε̇ = v/h drifts over a compression stroke), else the record's one rate."""
        parts = []
        for m in self.members:
            eps, sig = m.fit_points(self.max_points)
            parts.append(pd.DataFrame({"record": m.name, "true_plastic_strain": eps, "true_stress_MPa": sig,
                                       "strain_rate_per_s": m.rates_at(eps), "temperature_C": m.temperatures_at(eps),
                                       "strain_rate_source": "point" if m.point_rates_per_s is not None else "record"}))
        return pd.concat(parts, ignore_index=True)

    def covered_range(self) -> dict[str, list[float]]:
        """The plastic strain, strain rate (1/s) and temperature (°C) the constants were identified on."""
        ms = self.members
        return {"plastic_strain": [min(float(m.plastic_strain[0]) for m in ms), max(float(m.plastic_strain[-1]) for m in ms)],
                "strain_rate_per_s": [min(m.strain_rate_per_s for m in ms), max(m.strain_rate_per_s for m in ms)],
                "temperature_C": [min(m.temperature_C for m in ms), max(m.temperature_C for m in ms)]}

    def as_dict(self) -> dict:
        """fit.json (docs/fit-json.md) without the file references of records and curves."""
        ref, law = self.fit.reference, self.fit.law
        top = self.fit.as_dict()
        out: dict = {"schema": "flowcurve-fit/2", "model": law.name, "method": self.method, "equation": law.equation}
        if law.name == "johnson_cook":
            out["conventions"] = CONVENTIONS
        material = " / ".join(dict.fromkeys(m.material for m in self.members if m.material))
        if material:  # absent, not null, when unknown: readers default it
            out["material"] = material
        out.update({k: v for k, v in top.items() if k not in ("method", "record_errors", "report")})
        out["quality"] = self.quality
        if ref is not None:
            out.update({"ref_strain_rate_per_s": ref.strain_rate_per_s, "ref_strain_rate_source": ref.strain_rate_source,
                        "ref_temperature_C": ref.temperature_C, "ref_temperature_source": ref.temperature_source,
                        "melt_temperature_C": ref.melt_temperature_C})
        out["law"] = law_block(self.fit)
        ms = self.members
        out["range"] = self.covered_range()
        out["records"] = [{"name": m.name, "source": m.source, "kind": m.kind, "test": m.test,
                           "temperature_C": m.temperature_C, "temperature_source": m.temperature_source,
                           "strain_rate_per_s": m.strain_rate_per_s, "strain_rate_source": m.strain_rate_source,
                           "plastic_strain": [float(m.plastic_strain[0]), float(m.plastic_strain[-1])],
                           "points": int(m.fit_points(self.max_points)[0].size), **self.fit.record_errors[m.name],
                           **({"identify_law": identify_law_range(m)} if m.identified_law else {})} for m in ms]
        out["curves"] = [{"temperature_C": c.temperature_C, "strain_rate_per_s": c.strain_rate_per_s,
                          "file": f"curves/{c.filename}", "records": c.records,
                          "plastic_strain": [float(c.table.iloc[0, 0]), float(c.table.iloc[-1, 0])],
                          "model_stress_at_zero_strain_MPa": float(self.fit(0.0, c.strain_rate_per_s, c.temperature_C)),
                          **({"repeats_type_a": c.repeats} if c.repeats else {})}
                         for c in self.curves]
        out["global"] = self.global_fit.as_dict() if self.global_fit else None
        out["stepwise"] = self.stepwise_fit.as_dict() if self.stepwise_fit else None
        out["stepwise_note"] = self.stepwise_note
        mus = [m.friction_mu for m in ms if m.test == "compression" and m.friction_mu is not None]
        out["friction_mu"] = float(np.mean(mus)) if mus else None
        out["friction_mu_records"] = len(mus)
        out.update(series_modulus([(m.name, m.E_material_MPa, m.E_source) for m in ms]))  # given, handbook or measured; never apparent
        nus = [m.poisson_ratio for m in ms if m.poisson_ratio is not None]
        out["poisson_ratio"] = float(np.mean(nus)) if nus else None
        out["shape_uncertainty"] = self.shape_uncertainty
        out["total_uncertainty"] = total_uncertainty(self.fit, self.shape_uncertainty or {})
        out["warnings"] = list(self.warnings)
        if self.damage is not None:
            out.update(self.damage.as_dict())
        return out


def law_block(fit: LawFit) -> dict:
    """fit.json's "law" block (flowcurve-fit/2, docs/fit-json.md): name, equation, parameters and
    stderr by key, the stated conditions, temperature unit °C, and the uncertainty terms that weighed the
    points (``point_u_terms``, docs/methods.md §5.10)."""
    law, values = fit.law, fit.values
    return {"name": law.name, "display_name": law.display_name, "equation": law.equation,
            "parameters": {p.key: float(values[p.name]) for p in law.parameters},
            "stderr": {p.key: (None if fit.stderr.get(p.name) is None or not math.isfinite(fit.stderr[p.name])
                               else float(fit.stderr[p.name])) for p in law.parameters},
            "conditions": {p.key: float(values[p.name]) for p in law.conditions},
            "temperature_unit": "C", "point_u_terms": list(fit.point_u_terms)}


def _check_fit_options(method: str, max_points: int, shape_error_pct: float) -> None:
    """IdentificationError for an unknown method, fewer than 5 points per record or a shape error not ≥ 0 %."""
    if method not in ("global", "stepwise"):
        raise IdentificationError(f"unknown fit method {method!r}; choose global or stepwise")
    if max_points < 5:
        raise IdentificationError(f"max_points must be at least 5 points per record, got {max_points}")
    if not (math.isfinite(shape_error_pct) and shape_error_pct >= 0):
        raise IdentificationError(f"the curves' shape error must be a finite percentage ≥ 0 (--shape-error), got {shape_error_pct:g}")


def fit_series(members: Sequence[SeriesMember], *, method: str = "global", ref_strain_rate_per_s: float | None = None,
               ref_temperature_C: float | None = None, melt_temperature_C: float | None = None,
               fixed: dict[str, float] | None = None, max_points: int = MAX_POINTS,
               fracture_points: Sequence[FracturePoint] = (), shape_error_pct: float = SHAPE_ERROR_PCT,
               law: str = "johnson_cook") -> SeriesFit:
    """Fit a registered law to a series (Johnson–Cook by default), σ = f(εp, ε̇, T).

    For Johnson–Cook the other method is fitted for comparison, and D1–D5 from the members'
    fractures and ``fracture_points``.

    Parameters
    ----------
    members : sequence of SeriesMember
        The series' plastic curves with their rates and temperatures.
    method : str
        "global" (one least squares) or "stepwise" (Johnson–Cook only).
    ref_strain_rate_per_s, ref_temperature_C, melt_temperature_C : float, optional
        Johnson–Cook's reference rate (1/s) and temperatures (°C); default from the series.
    fixed : dict, optional
        Constants held, not fitted (``{"C": 0.0}``).
    max_points, shape_error_pct : int, float
        Points taken from each curve; the model-form error added to each point's u, %.
    fracture_points : sequence of FracturePoint
        Fracture points measured elsewhere.
    law : str
        A registered law's name.

    Returns
    -------
    SeriesFit
        The chosen fit, the other for comparison, the curves and the warnings.
    """
    _check_fit_options(method, max_points, shape_error_pct)
    members = list(members)
    chosen_law = get_law(law)
    if chosen_law.name != "johnson_cook":
        return _fit_series_law(members, chosen_law, method=method, fixed=dict(fixed or {}), max_points=max_points,
                               shape_error_pct=shape_error_pct, fracture_points=fracture_points)
    ref = make_reference(members, ref_strain_rate_per_s=ref_strain_rate_per_s, ref_temperature_C=ref_temperature_C,
                         melt_temperature_C=melt_temperature_C)
    fixed = dict(fixed or {})
    warnings = [f"{k} was not identified but fixed at {v:g} by the user" for k, v in fixed.items()]
    stepwise, note = None, None
    if method == "stepwise":
        stepwise = fit_stepwise(members, ref, fixed=fixed, max_points=max_points)
    else:
        try:
            stepwise = fit_stepwise(members, ref, fixed=fixed, max_points=max_points)
        except IdentificationError as exc:
            note = f"no stepwise comparison: {exc}"
    glob = fit_global(members, ref, fixed=fixed, max_points=max_points, shape_error_pct=shape_error_pct)
    chosen = glob if method == "global" else stepwise
    band = shape_uncertainty(members, ref, chosen, max_points=max_points, shape_error_pct=shape_error_pct)
    warnings += _fit_warnings(chosen, band, shape_error_pct, ("A", "B", "n"))
    warnings += [law["why_different"] for law in map(identify_law_range, members) if law and "why_different" in law]
    warnings += stream_gap_warnings(members)
    damage = _fit_damage(members, list(fracture_points), ref, warnings)
    return SeriesFit(method=method, fit=chosen, global_fit=glob, stepwise_fit=stepwise, stepwise_note=note,
                     members=members, curves=condition_curves(members, max_points), warnings=warnings,
                     max_points=max_points, damage=damage, shape_uncertainty=band)


def _fit_series_law(members: list[SeriesMember], law, *, method: str, fixed: dict[str, float], max_points: int,
                    shape_error_pct: float, fracture_points: Sequence[FracturePoint]) -> SeriesFit:
    """The global fit of a law other than Johnson–Cook (no stepwise procedure, no D1-D5)."""
    if method != "global":
        raise IdentificationError(f"the stepwise procedure is Johnson–Cook's own: fit {law.name} with --method global")
    if not (law.rate_dependent and law.temperature_dependent):
        raise IdentificationError(f"{law.display_name} carries no strain rate or temperature: a series fit takes a law with both "
                                  f"(fit one record with 'flowcurve identify --law {law.name}')")
    if fixed:
        raise IdentificationError(f"--fix-{'/--fix-'.join(fixed)} fix Johnson–Cook's constants: {law.display_name} fixes the terms "
                                  "the series cannot tell itself")
    fit = fit_law(members, law, max_points=max_points, shape_error_pct=shape_error_pct)
    band = law_shape_uncertainty(members, fit, max_points=max_points, shape_error_pct=shape_error_pct)
    warnings = [f"{law.display_name}: {why}" for why in fit.fixed_why.values()]
    warnings += _fit_warnings(fit, band, shape_error_pct, law.names)
    warnings += stream_gap_warnings(members)
    if any(m.fracture is not None for m in members) or fracture_points:
        warnings.append(f"no fracture constants: D1-D5 are Johnson–Cook's and the series was fitted with {law.display_name}")
    return SeriesFit(method="global", fit=fit, global_fit=fit, stepwise_fit=None,
                     stepwise_note="no stepwise comparison: the stepwise procedure is Johnson–Cook's own",
                     members=members, curves=condition_curves(members, max_points), warnings=warnings,
                     max_points=max_points, shape_uncertainty=band)


def _fit_warnings(fit: LawFit, band: dict, shape_error_pct: float, names: Sequence[str]) -> list[str]:
    """A poor fit (worst records named), constants on a bound (stated as such, no percentage), constants
    whose total uncertainty (:func:`.law_fit.total_uncertainty`) reaches their value (not determined), and
    constants among ``names`` a ``shape_error_pct`` shape error moves more than LOOSE_CONSTANT_PCT."""
    out = []
    if fit.fit_error_pct > POOR_FIT_PCT:
        worst = sorted(fit.record_errors.items(), key=lambda kv: -kv[1]["fit_error_pct"])[:3]
        out.append(f"the {fit.method} fit is poor: max error {fit.fit_error_pct:.3g} % (> {POOR_FIT_PCT:g} %); worst records "
                   + ", ".join(f"{name} {e['fit_error_pct']:.3g} %" for name, e in worst))
    out += [f"{p} ended on its {side} bound ({fit.params[p]:g}): the series does not identify it; no uncertainty is stated"
            for p, side in fit.at_bound.items()]
    key = {p.name: p.key for p in fit.law.parameters}
    total = total_uncertainty(fit, band)
    free = [p for p in fit.law.names if p not in fit.fixed and p not in fit.at_bound]
    open_ = [key[p] for p in free if total.get(key[p]) is None or not math.isfinite(total[key[p]]) or total[key[p]] >= abs(fit.params[p])]
    if open_:
        out.append(f"{', '.join(open_)} not determined by the series (no uncertainty, or a total one — fit and curve shape — "
                   "above the value): the "
                   "constants trade off and only their set traces the curves; do not read or compare them one by one")
    loose = {p: 100.0 * band[key[p]] / abs(fit.params[p]) for p in names
             if band.get(key[p]) is not None and abs(fit.params[p]) > 0 and p not in fit.at_bound}
    loose = {p: v for p, v in loose.items() if v > LOOSE_CONSTANT_PCT}
    if loose:
        corr = fit.correlations.get("A", {}).get("n")
        out.append("the curves do not tell " + ", ".join(loose) + f" apart well{f' (A–n correlation {corr:.2f})' if corr is not None else ''}: "
                   f"a {shape_error_pct:g} % shape error of the curves moves "
                   + ", ".join(f"{p} by up to {v:.2g} %" for p, v in loose.items())
                   + "; the fitted law is better determined than these constants (fit.json shape_uncertainty)")
    return out


LAW_CONSTANTS = ("A_MPa", "B_MPa", "n", "K_MPa", "eps0", "sigma0_MPa", "Q_MPa", "b")
RANGE_SLACK = 1.05  # identify's law reaching this much further than the fit's points is another strain range


def identify_law_range(member: SeriesMember) -> dict | None:
    """What 'flowcurve identify' fitted for this member (fit.json records[].identify_law): its law,
    constants and strain range beside this fit's, and why they differ when they do (a plain reason:
    identify adds the neck-corrected fracture point; a series fit has the true curve only)."""
    law = member.identified_law
    if not law or not isinstance(law.get("strain_range"), list) or len(law["strain_range"]) != 2:
        return None
    own = [float(member.plastic_strain[0]), float(member.plastic_strain[-1])]
    theirs = [float(v) for v in law["strain_range"]]
    out = {"law": law.get("law"), **{k: law[k] for k in LAW_CONSTANTS if isinstance(law.get(k), (int, float))},
           "plastic_strain": theirs, "fit_plastic_strain": own}
    if theirs[1] <= RANGE_SLACK * own[1]:
        return out
    uniform = law.get("fit_range")
    fracture = law.get("fracture_point") == "included"
    consts = ", ".join(f"{k.removesuffix('_MPa')} {law[k]:.4g}" for k in LAW_CONSTANTS if isinstance(law.get(k), (int, float)))
    how = (f"the uniform range to εp {uniform[1]:.3g} and the neck-corrected fracture point at εp {theirs[1]:.3g}"
           if fracture and isinstance(uniform, list) else f"εp {theirs[0]:.3g}–{theirs[1]:.3g}")
    out["why_different"] = (
        f"{member.name}: 'flowcurve identify' fitted its {law.get('law', 'law')} ({consts}) over εp {theirs[0]:.3g}–{theirs[1]:.3g} "
        f"({how}); this fit has the record's true curve only, εp {own[0]:.3g}–{own[1]:.3g} (up to maximum force), so the two "
        f"laws follow the same points to εp {own[1]:.3g} and part beyond it, where identify's rests on the measured fracture "
        "point and this one on extrapolation")
    return out


def shape_uncertainty(members: Sequence[SeriesMember], ref: Reference | None, fit: LawFit, *,
                      max_points: int = MAX_POINTS, shape_error_pct: float = SHAPE_ERROR_PCT) -> dict:
    """How far each fitted constant can move under a curve shape error of RMS ``shape_error_pct``
    (:func:`.law_fit.law_shape_uncertainty`; ``ref`` is kept for the callers, the fit carries it)."""
    return law_shape_uncertainty(members, fit, max_points=max_points, shape_error_pct=shape_error_pct)


def _fit_damage(members, extra: list[FracturePoint], ref: Reference, warnings: list[str]) -> DamageFit | None:
    """D1-D5 at the flow fit's reference, or None with a warning saying why (no fracture data: silent)."""
    points = [m.fracture for m in members if m.fracture is not None] + extra
    if not points:
        return None
    try:
        damage = fit_damage(points, ref_strain_rate_per_s=ref.strain_rate_per_s, ref_temperature_C=ref.temperature_C,
                            melt_temperature_C=ref.melt_temperature_C)
    except IdentificationError as exc:
        warnings.append(f"no Johnson-Cook fracture constants: {exc}")
        return None
    warnings.extend(f"fracture: {w}" for w in damage.warnings)
    return damage
