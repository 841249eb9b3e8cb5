"""Johnson-Cook fracture strain (2.22) and the identification of D1-D5 (docs/methods.md §5).

    eps_f = [D1 + D2 exp(D3 sigma*)] [1 + D4 ln eps_dot*] [1 + D5 T*]

Conventions (stated in fit.json as ``damage.conventions``):

* **sigma\\* = sigma_m / sigma_eq, positive in tension** (a smooth bar before necking: 1/3),
  the convention of Johnson and Cook (1985) and of LS-DYNA, Abaqus (-p/q) and OpenRadioss.
  The seed writes sigma* = p/sigma_s with p the hydrostatic pressure, positive in
  compression, i.e. the negative of this; table 3.2's D3 < 0 (the fracture strain falls as
  the triaxiality rises) reads right only in the tension-positive convention.
* ln eps_dot* = ln(eps_dot/eps_dot0) clamped at 0 and T* clamped to [0, 1], with the
  reference rate, reference and melting temperature of the flow-stress fit (the same
  conventions as (2.19), identification.johnson_cook).
* Triaxiality of a bar (initial geometry, Bridgman): smooth 1/3; notched
  sigma* = 1/3 + ln(1 + a/(2R)), a the radius of the notch root section (d0/2), R the notch
  radius (``specimen.notch_radius_mm``).
* Fracture strain of a bar: eps_f = ln(A0/Af) = 2 ln(d0/dk) from the section after fracture.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np

from flowcurve.errors import IdentificationError, RecordError
from flowcurve.identification.laws.johnson_cook import homologous_temperature, log_rate_ratio

log = logging.getLogger(__name__)

PARAMS = ("D1", "D2", "D3", "D4", "D5")
COLUMNS = ("triaxiality", "strain_rate_per_s", "temperature_C", "fracture_strain")
SMOOTH_BAR_TRIAXIALITY = 1.0 / 3.0
DISTINCT_TRIAXIALITY = 0.02
DISTINCT_LOG_RATE = 0.05
DISTINCT_T_STAR = 1e-3
NARROW_TRIAXIALITY = 0.5  # a range narrower than this cannot separate D1, D2 and D3
STRONG_CORRELATION = 0.95

EQUATION = ("eps_f = (D1 + D2*exp(D3*triaxiality)) * (1 + D4*ln(max(rate/ref_rate, 1))) * (1 + D5*Tstar), "
            "Tstar = clamp((T - T_ref)/(T_melt - T_ref), 0, 1)")
CONVENTIONS = {
    "triaxiality": "sigma_m/sigma_eq, positive in tension (smooth bar 1/3), as LS-DYNA, Abaqus (-p/q) and OpenRadioss; "
                   "the seed's p/sigma_s with p positive in compression is its negative",
    "notched_bar_triaxiality": "Bridgman, initial geometry: 1/3 + ln(1 + a/(2R)), a = d0/2, R = specimen.notch_radius_mm",
    "fracture_strain": "ln(A0/Af) from the section after fracture",
    "strain_rate": "ln(rate/ref_rate) clamped at 0, the flow-stress fit's ref_strain_rate_per_s",
    "homologous_temperature": "clamped to [0, 1], the flow-stress fit's ref_temperature_C and melt_temperature_C",
}


@dataclass(frozen=True)
class FracturePoint:
    """One measured fracture: triaxiality (tension positive), rate 1/s, temperature C, strain."""

    triaxiality: float
    strain_rate_per_s: float
    temperature_C: float
    fracture_strain: float
    source: str = "<memory>"


# -- the model and the bar formulas ------------------------------------------------------------------------------
def fracture_strain(triaxiality, log_rate, t_star, D1, D2, D3, D4, D5):
    """# (2.22) Johnson-Cook fracture strain from the reduced variables (clamped ln eps_dot*, T*)."""
    return ((D1 + D2 * np.exp(D3 * np.asarray(triaxiality, float)))
            * (1.0 + D4 * np.asarray(log_rate, float)) * (1.0 + D5 * np.asarray(t_star, float)))


def bridgman_triaxiality(section_radius_mm, notch_radius_mm):
    """# Bridgman (docs/methods.md §5): sigma* = 1/3 + ln(1 + a/(2R)) at the centre of a notched bar."""
    return SMOOTH_BAR_TRIAXIALITY + np.log1p(np.asarray(section_radius_mm, float) / (2.0 * np.asarray(notch_radius_mm, float)))


def fracture_strain_from_diameters(d0_mm, dk_mm):
    """# (3.13) eps_f = ln(A0/Af) = 2 ln(d0/dk)."""
    return 2.0 * np.log(np.asarray(d0_mm, float) / np.asarray(dk_mm, float))


def bar_triaxiality(d0_mm: float | None, notch_radius_mm: float | None) -> float:
    """Smooth bar 1/3; a notched bar (notch radius given) by Bridgman on its initial geometry."""
    if notch_radius_mm is None:
        return SMOOTH_BAR_TRIAXIALITY
    if d0_mm is None:
        raise IdentificationError("a notched bar needs specimen.d0_mm (the notch root diameter) for its triaxiality")
    return float(bridgman_triaxiality(d0_mm / 2.0, notch_radius_mm))


# -- fracture data ---------------------------------------------------------------------------------------------
def read_fracture_points(path) -> list[FracturePoint]:
    """A fracture table (CSV, '#' comments; columns triaxiality, strain_rate_per_s,
    temperature_C, fracture_strain); a one-line error naming the file, line and column."""
    import pandas as pd

    path = Path(path)
    try:
        table = pd.read_csv(path, comment="#", dtype=str, skip_blank_lines=True)
    except FileNotFoundError:
        raise RecordError(path, "no such fracture table") from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise RecordError(path, f"cannot be read as CSV ({exc})") from None
    table.columns = [str(c).strip() for c in table.columns]
    missing = [c for c in COLUMNS if c not in table.columns]
    if missing:
        raise RecordError(path, f"missing column(s) {', '.join(missing)} (expected {', '.join(COLUMNS)})")
    lines = _data_line_numbers(path)
    points = []
    for i, row in enumerate(table[list(COLUMNS)].itertuples(index=False)):
        line = lines[i] if i < len(lines) else i + 2
        values = []
        for column, text in zip(COLUMNS, row):
            try:
                value = float(text)
            except (TypeError, ValueError):
                raise RecordError(path, f"line {line}, column {column}: {text!r} is not a number") from None
            if not math.isfinite(value):
                raise RecordError(path, f"line {line}, column {column}: {text!r} is not a finite number")
            values.append(value)
        tri, rate, temp, eps_f = values
        if rate <= 0:
            raise RecordError(path, f"line {line}, column strain_rate_per_s: must be > 0, got {rate:g}")
        if eps_f <= 0:
            raise RecordError(path, f"line {line}, column fracture_strain: must be > 0, got {eps_f:g}")
        points.append(FracturePoint(tri, rate, temp, eps_f, f"{path}:{line}"))
    if not points:
        raise RecordError(path, "the fracture table has no rows")
    return points


def _data_line_numbers(path: Path) -> list[int]:
    """File line numbers of the data rows (after the header; comments and blanks skipped)."""
    numbers, header_seen = [], False
    for number, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        if header_seen:
            numbers.append(number)
        header_seen = True
    return numbers


def fracture_point_from_result(result: dict, meta, strain_rate_per_s: float, temperature_C: float,
                               source: str) -> FracturePoint | None:
    """The fracture of a tension test (``fracture_true_strain`` of its identification), at the
    triaxiality of its bar; None for a compression test or a tension test without a section
    after fracture. ``meta``: the record header (or result.json's record block)."""
    eps_f = result.get("fracture_true_strain")
    if result.get("test", meta.get("test")) == "compression" or eps_f is None:
        return None
    notch = _positive(meta.get("specimen.notch_radius_mm"), "specimen.notch_radius_mm", source)
    d0 = _positive(meta.get("specimen.d0_mm"), "specimen.d0_mm", source)
    try:
        tri = bar_triaxiality(d0, notch)
    except IdentificationError as exc:
        raise RecordError(source, str(exc)) from None
    return FracturePoint(tri, strain_rate_per_s, temperature_C, float(eps_f), source)


def _positive(value, key: str, source) -> float | None:
    if value is None or value == "":
        return None
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise RecordError(source, f"{key} is not a number: {value!r}") from None
    if not (math.isfinite(number) and number > 0):
        raise RecordError(source, f"{key} must be a positive number of mm, got {value!r}")
    return number


# -- the fit -----------------------------------------------------------------------------------------------------
@dataclass
class DamageFit:
    """D1-D5 with one standard error each, their correlations and what they were fitted on."""

    params: dict[str, float]
    stderr: dict[str, float | None]
    correlations: dict[str, dict[str, float]]
    fixed: dict[str, float]
    points: list[FracturePoint]
    ref_strain_rate_per_s: float
    ref_temperature_C: float
    melt_temperature_C: float
    fit_error_pct: float
    rms_error_pct: float
    warnings: list[str] = field(default_factory=list)
    report: str = ""

    def __call__(self, triaxiality, strain_rate_per_s, temperature_C):
        """# (2.22) the fitted fracture strain at triaxiality, rate (1/s) and temperature (C)."""
        return fracture_strain(triaxiality, log_rate_ratio(strain_rate_per_s, self.ref_strain_rate_per_s),
                               homologous_temperature(temperature_C, self.ref_temperature_C, self.melt_temperature_C),
                               **self.params)

    def covered(self) -> dict[str, list[float]]:
        """The triaxiality, rate and temperature ranges the fracture points cover."""
        pts = self.points
        return {"triaxiality_range": [min(p.triaxiality for p in pts), max(p.triaxiality for p in pts)],
                "strain_rate_per_s": [min(p.strain_rate_per_s for p in pts), max(p.strain_rate_per_s for p in pts)],
                "temperature_C": [min(p.temperature_C for p in pts), max(p.temperature_C for p in pts)]}

    def as_dict(self) -> dict:
        """The fit.json keys: D1..D5 and D*_stderr at the top level, the rest under ``damage``."""
        out: dict = {}
        for p in PARAMS:
            out[p] = self.params[p]
            out[f"{p}_stderr"] = self.stderr.get(p)
        out["damage"] = {"equation": EQUATION, "conventions": CONVENTIONS, **self.covered(),
                         "points": len(self.points), "fixed": dict(self.fixed), "correlations": self.correlations,
                         "fit_error_pct": self.fit_error_pct, "rms_error_pct": self.rms_error_pct,
                         "warnings": list(self.warnings),
                         "fracture_points": [{"triaxiality": p.triaxiality, "strain_rate_per_s": p.strain_rate_per_s,
                                              "temperature_C": p.temperature_C, "fracture_strain": p.fracture_strain,
                                              "source": p.source} for p in self.points]}
        return out


def _distinct(values, tol: float) -> int:
    out: list[float] = []
    for v in sorted(values):
        if not out or v - out[-1] > tol:
            out.append(v)
    return len(out)


def fit_damage(points: Sequence[FracturePoint], *, ref_strain_rate_per_s: float, ref_temperature_C: float,
               melt_temperature_C: float) -> DamageFit:
    """Fit D1-D5 to the fracture points by least squares on the relative error (lmfit).

    What the points cannot determine is fixed and said so: D1 = 0 (table 3.2's value for all
    three steels) when only two triaxialities were tested or D1, D2, D3 cannot be told apart
    (a weak triaxiality effect makes exp(D3 sigma*) nearly linear), D4 = 0 with one (clamped)
    rate, D5 = 0 with one temperature. Fewer than two triaxialities: an error (D1-D3 unknown).
    """
    pts = list(points)
    tri = np.array([p.triaxiality for p in pts])
    eps_f = np.array([p.fracture_strain for p in pts])
    lr = log_rate_ratio([p.strain_rate_per_s for p in pts], ref_strain_rate_per_s)
    ts = homologous_temperature([p.temperature_C for p in pts], ref_temperature_C, melt_temperature_C)
    n_tri = _distinct(tri, DISTINCT_TRIAXIALITY)
    if n_tri < 2:
        raise IdentificationError(f"fracture data at {n_tri} triaxiality: D1-D3 need at least two (smooth and notched bars, "
                                  "specimen.notch_radius_mm, or --fracture-points)")
    fixed: dict[str, float] = {}
    warnings: list[str] = []
    if n_tri == 2:
        fixed["D1"] = 0.0
        warnings.append("fracture data at two triaxialities: D1 fixed at 0 (table 3.2's value), D2 and D3 fitted")
    if _distinct(lr, DISTINCT_LOG_RATE) < 2:
        fixed["D4"] = 0.0
        warnings.append("fracture data at one strain rate (at or below the reference rate): D4 not identified, fixed at 0")
    if _distinct(ts, DISTINCT_T_STAR) < 2:
        fixed["D5"] = 0.0
        warnings.append("fracture data at one temperature (at or below the reference temperature): D5 not identified, fixed at 0")
    free = [p for p in PARAMS if p not in fixed]
    if len(pts) <= len(free):
        raise IdentificationError(f"{len(pts)} fracture points for {len(free)} constants ({', '.join(free)}): "
                                  "at least one more point is needed for their uncertainties")
    result = _least_squares(tri, lr, ts, eps_f, fixed)
    if "D1" not in fixed and not _separable(result):
        fixed["D1"] = 0.0
        warnings.append(f"D1, D2 and D3 cannot be told apart on triaxiality {tri.min():.3g} to {tri.max():.3g} "
                        "(the fit's covariance is singular or their correlation above 0.99): D1 fixed at 0 (table "
                        "3.2's value), D2 and D3 fitted")
        result = _least_squares(tri, lr, ts, eps_f, fixed)
    free = [p for p in PARAMS if p not in fixed]
    params = {p: float(result.params[p].value) for p in PARAMS}
    stderr = {p: _finite(None if p in fixed else result.params[p].stderr) for p in PARAMS}
    correlations = {p: {q: _finite(c) for q, c in (result.params[p].correl or {}).items()} for p in free}
    rel = fracture_strain(tri, lr, ts, **params) / eps_f - 1.0
    span = (float(tri.min()), float(tri.max()))
    tradeoff = [f"{p}-{q} {c:+.2f}" for p in ("D1", "D2", "D3") for q, c in correlations.get(p, {}).items()
                if q in ("D1", "D2", "D3") and p < q and c is not None and abs(c) > STRONG_CORRELATION]
    if span[1] - span[0] < NARROW_TRIAXIALITY or tradeoff:
        warnings.append(f"triaxiality covered only from {span[0]:.3g} to {span[1]:.3g}: D1, D2 and D3 trade off against "
                        "each other there (" + (", ".join(tradeoff) if tradeoff else "narrow range") + "); the locus is "
                        "determined on that range, the constants one by one are not, and the locus outside it is extrapolation")
    for w in warnings:
        log.warning(w)
    return DamageFit(params=params, stderr=stderr, correlations=correlations, fixed=fixed, points=pts,
                     ref_strain_rate_per_s=ref_strain_rate_per_s, ref_temperature_C=ref_temperature_C,
                     melt_temperature_C=melt_temperature_C, fit_error_pct=float(100 * np.max(np.abs(rel))),
                     rms_error_pct=float(100 * np.sqrt(np.mean(rel ** 2))), warnings=warnings,
                     report=result.fit_report_text)


def _least_squares(tri, lr, ts, eps_f, fixed: dict[str, float]):
    """lmfit on the relative error, from a start by ln eps_f = ln D2 + D3 sigma* (D1 = 0)."""
    import lmfit

    base = (lr == 0) & (ts == 0)
    sel = base if _distinct(tri[base], DISTINCT_TRIAXIALITY) >= 2 else np.ones_like(base)
    d3, ln_d2 = np.polyfit(tri[sel], np.log(eps_f[sel]), 1)
    start = {"D1": 0.0, "D2": math.exp(ln_d2), "D3": d3, "D4": 0.0, "D5": 0.0}
    pars = lmfit.Parameters()
    for p in PARAMS:
        pars.add(p, value=fixed.get(p, start[p]), vary=p not in fixed)

    def residual(par):
        """Relative misfit of the fracture strains at ``par``."""
        return fracture_strain(tri, lr, ts, **par.valuesdict()) / eps_f - 1.0

    with np.errstate(invalid="ignore"):
        result = lmfit.minimize(residual, pars, method="least_squares")
    if not result.success:
        raise IdentificationError(f"the D1-D5 fit did not converge: {result.message}")
    result.fit_report_text = lmfit.fit_report(result)
    return result


def _finite(value) -> float | None:
    """A number for fit.json: None for unknown or not finite (never NaN)."""
    return None if value is None or not math.isfinite(float(value)) else float(value)


def _separable(result) -> bool:
    """D1, D2 and D3 (those fitted) have finite errors and no correlation above 0.99."""
    fitted = [p for p in ("D1", "D2", "D3") if result.params[p].vary]
    for p in fitted:
        par = result.params[p]
        if _finite(par.stderr) is None:
            return False
        if any(q in fitted and (_finite(c) is None or abs(c) > 0.99) for q, c in (par.correl or {}).items()):
            return False
    return True
