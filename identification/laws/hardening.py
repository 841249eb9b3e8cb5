"""Strain-hardening laws σ(εp) identified from one true stress-strain curve.

Any registered static law (Hollomon, Ludwik, Swift, Voce, Hockett–Sherby, Swift–Voce: one module
each in this package) and Johnson–Cook's static part ``A + B·εp^n`` (the default, under JC's
names), through :func:`static_form`; ``best`` fits every one and keeps the lowest AIC
(:func:`choose_law`). docs/methods.md has each law's equation.

Two ways to identify one:

* :func:`fit_hardening` — least squares (lmfit) over the uniform range plus extra points
  (e.g. the neck-corrected fracture point), with standard errors and correlations;
* :func:`three_point_fit` — the seed's method (end of 3.1.2): the law passes exactly through
  three characteristic points, the nonlinear constant found by a bracketing root search.

Both return a :class:`HardeningFit`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Callable, Iterable, Mapping, Sequence

import logging

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.bounds import bound_sides, central_jacobian
from flowcurve.identification.laws.static import StaticLaw
from flowcurve.identification.laws.swift import swift  # noqa: F401 (today's callers import the functions from here)
from flowcurve.identification.laws.voce import voce  # noqa: F401

logger = logging.getLogger(__name__)

# Plausibility limits used to catch unit mistakes (Pa for MPa, % for fractions).
MAX_STRESS_MPa = 20_000.0
MAX_STRAIN = 5.0


def johnson_cook_static(eps_p, A, B, n):
    """Johnson–Cook static flow stress (2.19), first bracket: A + B·εp^n (MPa)."""
    eps_p = np.maximum(np.asarray(eps_p, dtype=float), 0.0)  # np.clip(…, 0, None) without its dispatch
    return A + B * np.power(eps_p, n)


# a rate/temperature law one record identifies by its static part: (the static law of that form,
# the function under the law's own names). Johnson–Cook's A + B·εp^n is Ludwik's form.
STATIC_PARTS: dict[str, tuple[str, Callable]] = {"johnson_cook": ("ludwik", johnson_cook_static)}


@dataclass(frozen=True)
class StaticForm:
    """A registered law as one record's fit sees it: its static law (profile, data start,
    bounds) under the names and JSON keys the result carries (Johnson–Cook: A, B, n)."""

    name: str
    law: StaticLaw
    names: tuple[str, ...]
    keys: tuple[str, ...]
    bounds: dict[str, tuple[float, float]]
    func: Callable  # σ(eps_p, *constants in the order of names), MPa

    def renamed(self, values: dict[str, float]) -> dict[str, float]:
        """The static law's values under this form's names."""
        return {mine: values[theirs] for mine, theirs in zip(self.names, self.law.names)}

    def grid_starts(self, eps, sig, w, count: int) -> list[dict[str, float]] | None:
        """The ``count`` best basins (:func:`_grid_minima`) of the static law's variable-projection
        profile (global stage) under this form's names; None where no row of the profile is finite
        (the data do not harden)."""
        ss, cands = self.law.profile(eps, sig, w)
        if not np.any(np.isfinite(ss)):
            return None
        return [self.renamed(cands[i]) for i in _grid_minima(ss, count)]

    def data_start(self, eps, sig) -> dict[str, float]:
        """The static law's start values read off the data, under this form's names."""
        return self.renamed(self.law.data_start(eps, sig))


@lru_cache(maxsize=None)
def static_form(name: str) -> StaticForm:
    """The law ``name`` as one record's fit sees it; a one-line error for an unknown law (with
    the nearest name) and for a rate or temperature law (those are fitted over a series)."""
    from flowcurve.identification.laws.base import get_law

    law = get_law(name)
    if name in STATIC_PARTS:
        static_name, func = STATIC_PARTS[name]
        static = get_law(static_name)
        names = law.names[: len(static.names)]
        return StaticForm(name, static, names, tuple(law.parameter(n).key for n in names),
                          {mine: (p.lower, p.upper) for mine, p in zip(names, static.parameters)}, func)
    if law.rate_dependent or law.temperature_dependent:
        raise IdentificationError(f"{law.display_name} ({name}) depends on the strain rate or temperature: one record cannot identify it; "
                                  f"fit it over a series of records with `flowcurve fit --law {name}`")
    return StaticForm(name, law, law.names, tuple(p.key for p in law.parameters),
                      {p.name: (p.lower, p.upper) for p in law.parameters}, type(law).function)


def static_law_names() -> tuple[str, ...]:
    """Every registered law one record can identify (static ones, and those with a static part)."""
    from flowcurve.identification.laws.base import registered_laws

    return tuple(name for name, law in registered_laws().items()
                 if name in STATIC_PARTS or not (law.rate_dependent or law.temperature_dependent))


def best_candidates() -> tuple[str, ...]:
    """The laws ``--law best`` compares: every static one, a static part standing for the
    static law of its form (johnson_cook for ludwik: one form, one AIC)."""
    forms = {static for static, _ in STATIC_PARTS.values()}
    return tuple(name for name in static_law_names() if name not in forms)


@dataclass
class HardeningFit:
    """An identified hardening law: constants, their uncertainties and the quality of fit."""

    law: str
    method: str
    params: dict[str, float]
    stderr: dict[str, float | None]
    correlations: dict[str, dict[str, float]] = field(default_factory=dict)
    fit_error_pct: float = float("nan")  # max |σ_law/σ − 1| over the fitted points, %
    rms_error_pct: float = float("nan")
    strain_range: tuple[float, float] = (float("nan"), float("nan"))
    report: str = ""
    warnings: list[str] = field(default_factory=list)
    doubt: str = ""  # evidence outside the fit that the curve is not to be trusted (then "poor")
    aic: float = float("nan")  # Akaike's information criterion of a least-squares fit, N·ln(χ²/N) + 2k
    law_choice: dict | None = None  # set when --law best chose this law: by how much (as_dict's "law_choice")
    on_bound: dict[str, str] = field(default_factory=dict)  # constant → "lower"/"upper" where it sits on a bound (laws.bounds)
    undetermined: list[str] = field(default_factory=list)  # keys of the constants the curve does not determine (undetermined())
    flat: bool = False  # the least-squares minimum is flat: the local refit did not settle (the global stage's optimum is stated)

    @property
    def quality(self) -> str:
        """"good", or "poor" when the largest relative error exceeds 10 % or ``doubt`` is set."""
        return "poor" if self.doubt or not self.fit_error_pct <= POOR_FIT_PCT else "good"

    def __call__(self, eps_p):
        """Flow stress (MPa) of the identified law at true plastic strain ``eps_p``."""
        return static_form(self.law).func(eps_p, **self.params)

    def as_dict(self) -> dict:
        """JSON-able summary with unit-carrying keys (``A_MPa``, ``A_MPa_stderr`` …)."""
        law = static_form(self.law)
        out: dict = {"law": self.law, "method": self.method}
        for name, key in zip(law.names, law.keys):
            out[key] = float(self.params[name])
        for name, key in zip(law.names, law.keys):
            se = self.stderr.get(name)
            out[f"{key}_stderr"] = None if se is None or not np.isfinite(se) else float(se)
        out["fit_error_pct"] = float(self.fit_error_pct)
        out["rms_error_pct"] = float(self.rms_error_pct)
        out["strain_range"] = [float(self.strain_range[0]), float(self.strain_range[1])]
        out["quality"] = self.quality
        out["warnings"] = list(self.warnings)
        if self.law_choice is not None:
            out["law_choice"] = self.law_choice
        return out


# -- input checks ------------------------------------------------------------------------


def _check_points(eps_p, stress_MPa, what: str) -> tuple[np.ndarray, np.ndarray]:
    eps = np.asarray(eps_p, dtype=float).ravel()
    sig = np.asarray(stress_MPa, dtype=float).ravel()
    if eps.shape != sig.shape:
        raise IdentificationError(f"{what}: strain and stress have different lengths ({eps.size} and {sig.size})")
    ok = np.isfinite(eps) & np.isfinite(sig)
    eps, sig = eps[ok], sig[ok]
    if eps.size and np.nanmax(np.abs(sig)) > MAX_STRESS_MPa:
        raise IdentificationError(f"{what}: stress up to {np.max(np.abs(sig)):.4g} MPa is implausible (> {MAX_STRESS_MPa:g} MPa) - check units (MPa expected)")
    if eps.size and np.max(np.abs(eps)) > MAX_STRAIN:
        raise IdentificationError(f"{what}: plastic strain up to {np.max(np.abs(eps)):.4g} is implausible (> {MAX_STRAIN:g}) - check units (a fraction, not %)")
    if eps.size and np.min(eps) < 0:
        raise IdentificationError(f"{what}: negative plastic strain {np.min(eps):.4g}; pass the plastic part only (εp ≥ 0)")
    return eps, sig


def _errors_pct(fit_values: np.ndarray, stress: np.ndarray) -> tuple[float, float]:
    rel = (fit_values - stress) / stress
    return float(100 * np.max(np.abs(rel))), float(100 * np.sqrt(np.mean(rel**2)))


# -- least squares -----------------------------------------------------------------------


def _grid_minima(ss: np.ndarray, count: int, within: float = 10.0) -> list[int]:
    """Indices of the ``count`` lowest local minima of ``ss`` along the grid (distinct basins),
    those no more than ``within`` times the lowest."""
    finite = np.isfinite(ss)
    left = np.concatenate([[np.inf], ss[:-1]])
    right = np.concatenate([ss[1:], [np.inf]])
    minima = np.flatnonzero(finite & (ss <= left) & (ss <= right))
    minima = minima[ss[minima] <= within * np.min(ss[minima])]
    return [int(i) for i in minima[np.argsort(ss[minima])][:count]]


# a fit whose largest relative error exceeds this is marked poor
POOR_FIT_PCT = 10.0
GRID_STARTS = 4  # local fits started from the best basins of the global grid stage
MAX_EVALUATIONS = 500  # per local fit: a start crawling along a bound is cut short, the others finish


FORWARD_STEP = float(np.finfo(float).eps) ** 0.5  # scipy's relative step of a 2-point difference


def forward_jacobian(residual: Callable, x: np.ndarray, lo: np.ndarray, hi: np.ndarray, f0: np.ndarray | None = None) -> np.ndarray:
    """The Jacobian of ``residual`` at ``x`` by forward differences, step for step scipy's
    ``jac="2-point"`` within bounds (lo, hi), without its per-call overhead (the fits' largest cost).

    J[:, i] = (r(x + h_i e_i) − r(x)) / h_i, h_i = √ε·max(1, |x_i|) signed as x_i (0 counts as +),
    turned back where the step leaves the bounds, the distance to the farther bound where neither
    side has room; returned Fortran-ordered (a transposed (n, m) array) as scipy's is, so the
    solver's linear algebra rounds alike. x: (n,) values; residual: x → (m,) array; f0: r(x)
    when the caller has it."""
    f0 = residual(x) if f0 is None else f0
    jt = np.empty((x.size, f0.size))
    for i, (xi, low, high) in enumerate(zip(x.tolist(), lo.tolist(), hi.tolist())):  # a few constants: scalars, not arrays
        size = abs(xi)
        h = FORWARD_STEP * (1.0 if xi >= 0 else -1.0) * (size if size > 1.0 or size != size else 1.0)  # np.maximum(1, |x|), NaN kept
        below, above = xi - low, high - xi
        fits = abs(h) <= (above if above > below or above != above else below)  # np.maximum(below, above)
        if not fits:
            h = above if above >= below else -below
        elif xi + h < low or xi + h > high:
            h = -h
        step = x.copy()
        step[i] = xi + h
        jt[i] = (residual(step) - f0) / ((xi + h) - xi)
    return jt.T


def _polish(spec: StaticForm, starts: list[dict[str, float]], eps: np.ndarray, sig: np.ndarray, w: np.ndarray) -> dict[str, float]:
    """Local bounded least squares (scipy, trust region) from every start; the lowest cost wins.

    The winner is then refitted once with lmfit by the caller, for its uncertainties and report."""
    from scipy.optimize import least_squares

    lo = np.array([spec.bounds[n][0] for n in spec.names])
    hi = np.array([spec.bounds[n][1] for n in spec.names])

    last: list = [None, None]  # the last point evaluated and its residuals: the Jacobian at an accepted step starts there

    def residual(x):
        """Weighted residuals of the law at ``x`` (1e12 where not finite); called under the caller's errstate."""
        r = w * (spec.func(eps, *x) - sig)
        last[:] = x.copy(), np.where(np.isfinite(r), r, 1e12)
        return last[1]

    def jacobian(x):
        """:func:`forward_jacobian` at ``x``, from the residuals already evaluated there."""
        return forward_jacobian(residual, x, lo, hi, f0=last[1].copy() if np.array_equal(last[0], x) else None)

    best_x, best_cost = None, np.inf
    for start in starts:
        x0 = np.clip([start[n] for n in spec.names], lo, hi)
        x0 = np.where(x0 <= lo, lo + 1e-9 * np.maximum(np.abs(lo), 1.0), x0)  # strictly inside for trf
        with np.errstate(all="ignore"):  # trial steps may overflow; such steps are rejected by the solver
            sol = least_squares(residual, x0, jac=jacobian, bounds=(lo, hi), x_scale="jac", max_nfev=MAX_EVALUATIONS)
        if np.isfinite(sol.cost) and sol.cost < best_cost:
            best_x, best_cost = sol.x, sol.cost
    if best_x is None:
        raise IdentificationError(f"the {spec.func.__name__} fit did not converge from any start value")
    return dict(zip(spec.names, (float(v) for v in best_x)))


def _weighted_points(eps_p, stress_MPa, extra_points, weights) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The fit's points and weights: the curve's finite points (weights default 1) plus the extra
    (εp, σ[, weight]) points; at least 4 spanning a strain range."""
    raw_eps = np.asarray(eps_p, dtype=float).ravel()
    w = np.ones_like(raw_eps) if weights is None else np.asarray(weights, dtype=float).ravel()
    if w.shape != raw_eps.shape:
        raise IdentificationError(f"hardening fit: weights must have one value per curve point ({raw_eps.size}), got {w.size}")
    w = w[np.isfinite(raw_eps) & np.isfinite(np.asarray(stress_MPa, dtype=float).ravel())]
    eps, sig = _check_points(raw_eps, stress_MPa, "hardening fit")
    extra = [tuple(float(v) for v in p) for p in extra_points]
    if extra:
        if any(len(p) not in (2, 3) for p in extra):
            raise IdentificationError("hardening fit: extra points are (strain, stress_MPa[, weight])")
        e_x, s_x = _check_points([p[0] for p in extra], [p[1] for p in extra], "hardening fit, extra points")
        w_x = np.array([p[2] if len(p) == 3 else 1.0 for p in extra])
        eps, sig, w = np.concatenate([eps, e_x]), np.concatenate([sig, s_x]), np.concatenate([w, w_x])
    if eps.size < 4 or np.ptp(eps) <= 0:
        raise IdentificationError(f"hardening fit: need at least 4 points spanning a strain range, got {eps.size}")
    return eps, sig, w


def undetermined(spec, values: dict[str, float], stderr: dict[str, float | None], on_bound: Iterable[str] = ()) -> list[str]:
    """The keys of the constants a fit does not determine: not ``on_bound`` (the names sitting on a
    bound, :func:`.bounds.bound_sides`), and with a standard error at least the value itself (|v| ≤ se:
    the interval v ± se holds 0), or with none where no constant sits on a bound (a singular
    covariance; with one on its bound lmfit states no errors at all, and that constant's own warning
    says why)."""
    bound = set(on_bound)
    out = []
    for name, key in zip(spec.names, spec.keys):
        if name in bound:
            continue  # named by its own warning
        se = stderr.get(name)
        if (se is None or not np.isfinite(se)) and not bound or (se is not None and np.isfinite(se) and se >= abs(values[name])):
            out.append(key)
    return out


def _free_stderr(spec, values: dict[str, float], stderr: dict[str, float | None], on_bound: Mapping[str, str],
                 eps: np.ndarray, sig: np.ndarray, w: np.ndarray) -> dict[str, float | None]:
    """``stderr`` with, where a constant sits on a bound and lmfit states none, the free constants' own:
    the bound ones held, the weighted least squares linearised at the fit (the trade-off among the free
    ones, which :func:`undetermined` judges). Inputs: the law's form, its fitted constants and the points."""
    # cov_free = s²·(J_fᵀJ_f)⁻¹ = s²·V·S⁻²·Vᵀ (J_f = U·S·Vᵀ), s² = Σ(w·r)² / (N − p_free), J_f = w·∂f/∂p_free
    free = [k for k in spec.names if k not in on_bound]
    if not on_bound or not free or any(stderr.get(k) is not None for k in free) or eps.size <= len(free):
        return stderr
    with np.errstate(all="ignore"):
        J = central_jacobian(spec.func, values, eps)[:, [spec.names.index(k) for k in free]] * w[:, None]
        r = (sig - spec.func(eps, **values)) * w
    if not (np.all(np.isfinite(J)) and np.all(np.isfinite(r))):
        return stderr
    _, sv, vt = np.linalg.svd(J, full_matrices=False)  # no truncation: a trade-off's tiny singular value is its variance
    with np.errstate(divide="ignore"):
        var = np.sum((vt / sv[:, None]) ** 2, axis=0) * float(np.dot(r, r)) / (eps.size - len(free))
    return {**stderr, **{k: float(np.sqrt(var[i])) for i, k in enumerate(free)}}


def _lmfit_refit(spec: StaticForm, start: dict[str, float], eps: np.ndarray, sig: np.ndarray, w: np.ndarray):
    """lmfit's Levenberg–Marquardt from ``start`` within the bounds, for the constants' standard
    errors, correlations, AIC and report: lmfit.Model.fit's residual (σ − law)·w and its report
    (R² included), through ``lmfit.minimize``, which spares Model.fit's parameter copies (most
    of its cost). Returns (lmfit's MinimizerResult, report text)."""
    import lmfit  # here, so `flowcurve --help` stays fast

    params = lmfit.Parameters()
    for name in spec.names:
        lo, hi = spec.bounds[name]
        params.add(name, value=float(np.clip(start[name], lo, hi)), min=lo, max=hi)

    def residual(p):
        """(σ − law)·w, Model.fit's residual; non-finite law values end the fit as Model.fit's do."""
        model = spec.func(eps, **p.valuesdict())
        if not np.all(np.isfinite(model)):
            raise ValueError("The model function generated NaN values and the fit aborted! Please check your model function "
                             "and/or set boundaries on parameters where applicable.")
        diff = sig - model
        diff *= w
        return diff

    best = lmfit.minimize(residual, params, max_nfev=MAX_EVALUATIONS)
    law = spec.func(eps, **best.params.valuesdict())
    best.rsquared = 1.0 - ((sig - law) ** 2).sum() / max(1e-15, ((sig - sig.mean()) ** 2).sum())  # R² as Model.fit reports it
    return best, f"[[Model]]\n    Model({spec.func.__name__})\n{lmfit.fit_report(best)}"


def _settled(best) -> bool:
    """Whether lmfit's Levenberg–Marquardt refit ended on its own tolerances, not cut short at
    MAX_EVALUATIONS along a flat valley (its end point then differs between identical runs:
    docs/methods.md §5.1)."""
    return not getattr(best, "aborted", False)


def _linearised_fit(spec: StaticForm, values: dict[str, float], eps: np.ndarray, sig: np.ndarray, w: np.ndarray):
    """The statistics lmfit's refit states, at fixed constants (the global stage's optimum of a flat
    minimum), deterministically: standard errors and correlations from the weighted least squares
    linearised there, none where a constant sits on a bound (lmfit's rule), AIC and a report.
    Returns (an object with lmfit's ``params`` and ``aic``, report text)."""
    # cov = s²·(JᵀJ)⁻¹ = s²·V·S⁻²·Vᵀ (J = w·∂f/∂p = U·S·Vᵀ), s² = χ²/(N − k); AIC = N·ln(χ²/N) + 2k
    import types

    import lmfit

    n, k = eps.size, len(spec.names)
    with np.errstate(all="ignore"):
        r = (sig - spec.func(eps, **values)) * w
        J = central_jacobian(spec.func, values, eps) * w[:, None]
    chisqr = float(np.dot(r, r))
    params = lmfit.Parameters()
    for name in spec.names:
        lo, hi = spec.bounds[name]
        params.add(name, value=float(values[name]), min=lo, max=hi)
    if not bound_sides(spec.func, values, spec.bounds, eps) and n > k and np.all(np.isfinite(J)) and chisqr > 0:
        _, sv, vt = np.linalg.svd(J, full_matrices=False)
        with np.errstate(divide="ignore", invalid="ignore"):
            scaled = vt / sv[:, None]
            cov = scaled.T @ scaled * chisqr / (n - k)
        se = np.sqrt(np.diag(cov))
        if np.all(np.isfinite(se)) and np.all(se > 0):
            corr = cov / np.outer(se, se)
            for i, name in enumerate(spec.names):
                params[name].stderr = float(se[i])
                params[name].correl = {other: float(corr[i, j]) for j, other in enumerate(spec.names) if j != i}
    aic = n * np.log(max(chisqr, 1e-250) / n) + 2 * k
    report = (f"[[Model]]\n    Model({spec.func.__name__})\n[[Fit Statistics]]\n"
              f"    # fitting method   = trust region (global stage); the Levenberg-Marquardt refit did not settle "
              f"within {MAX_EVALUATIONS} evaluations: a flat minimum\n"
              f"    # data points      = {n}\n    # variables        = {k}\n    chi-square         = {chisqr:.8g}\n"
              f"    Akaike info crit   = {aic:.8g}\n{lmfit.fit_report(params)}")
    return types.SimpleNamespace(params=params, aic=float(aic)), report


def fit_hardening(eps_p, stress_MPa, law: str = "johnson_cook", *, extra_points: Iterable[Sequence[float]] = (),
                  weights=None) -> HardeningFit:
    """Least-squares fit of a hardening law (lmfit) to a true curve σ(εp), global then local.

    eps_p, stress_MPa: the uniform range (true plastic strain, true stress in MPa).
    extra_points: further (εp, σ_MPa) or (εp, σ_MPa, weight) points, e.g. the neck-corrected
        fracture point; their default weight is 1, like every curve point.
    weights: per-point weights of the curve points (multiply the residuals in MPa).

    Global stage: the nonlinear constant scanned over its whole range with the linear ones
    solved exactly (the law's ``profile``, :mod:`.static`); local stage: lmfit from the best basins of that scan
    and from start values read off the data (the law's ``data_start``); the lowest residual wins.
    A constant left on a bound and a fit with a max error above 10 % are reported in
    ``warnings``; the latter makes ``quality`` "poor".
    """
    spec = static_form(law)
    eps, sig, w = _weighted_points(eps_p, stress_MPa, extra_points, weights)
    grid = spec.grid_starts(eps, sig, w, GRID_STARTS)
    if grid is None:
        raise IdentificationError(f"the data do not harden (stress does not rise with strain): a {law} law cannot be fitted")
    polished = _polish(spec, grid + [spec.data_start(eps, sig)], eps, sig, w)
    best, report = _lmfit_refit(spec, polished, eps, sig, w)
    flat = not _settled(best)
    if flat:  # its end point is not reproducible: the global stage's optimum, stated with linearised errors
        best, report = _linearised_fit(spec, polished, eps, sig, w)
    values = {name: float(best.params[name].value) for name in spec.names}
    stderr = {name: (None if best.params[name].stderr is None else float(best.params[name].stderr)) for name in spec.names}
    correl = {name: {k: float(v) for k, v in (best.params[name].correl or {}).items()} for name in spec.names}
    max_pct, rms_pct = _errors_pct(spec.func(eps, **values), sig)
    warnings = []
    sides = bound_sides(spec.func, values, spec.bounds, eps)
    for name, key in zip(spec.names, spec.keys):
        side = sides.get(name)
        if side:
            warnings.append(f"{law} {key} = {values[name]:.4g} sits on its {side} bound: the law does not describe this curve well "
                            "(another law, --fit-range or --fracture-point exclude may)")
    if flat:
        warnings.append(f"{law}: the least-squares minimum is flat (the local refit did not settle within {MAX_EVALUATIONS} "
                        "evaluations): the constants are the global stage's optimum, their errors linearised there")
    if max_pct > POOR_FIT_PCT:
        warnings.append(f"{law} fit is poor: max error {max_pct:.3g} % (> {POOR_FIT_PCT:g} %), rms {rms_pct:.3g} %")
    loose = undetermined(spec, values, _free_stderr(spec, values, stderr, sides, eps, sig, w), sides)  # the warning's and --law best's
    if loose:
        warnings.append(f"{law} {', '.join(loose)} not determined by this curve (no standard error, or one above the value): "
                        f"the constants trade off and only their set traces the curve (max error {max_pct:.3g} %); "
                        "do not read or compare them one by one (a law with fewer constants may be determined)")
    return HardeningFit(law=law, method="least_squares", params=values, stderr=stderr, correlations=correl,
                        fit_error_pct=max_pct, rms_error_pct=rms_pct,
                        strain_range=(float(np.min(eps)), float(np.max(eps))), report=report, warnings=warnings,
                        aic=float(best.aic), on_bound=sides, undetermined=loose, flat=flat)


PARSIMONY_DELTA_AIC = 2.0  # laws this close to the lowest AIC are as good: the one with the fewest constants is kept


def choose_law(eps_p, stress_MPa, *, weights=None, extra_points: Iterable[Sequence[float]] = ()) -> HardeningFit:
    """``--law best``: every static law (:func:`best_candidates`) fitted to the same weighted
    points and ranked by AIC (N·ln(χ²/N) + 2k, k the law's constants), those with undetermined
    constants or a flat minimum (:attr:`HardeningFit.flat`) passed over; among the laws within
    :data:`PARSIMONY_DELTA_AIC` of the lowest, the one with the fewest constants wins (a law that
    nests another fits the noise too). The winner's ``law_choice`` says which won, by which rule,
    and ΔAIC to the next (the next law's AIC − the winner's; negative when parsimony chose), with
    every law's AIC."""
    fits, failed = {}, {}
    for name in best_candidates():
        try:
            fits[name] = fit_hardening(eps_p, stress_MPa, name, weights=weights, extra_points=extra_points)
        except IdentificationError as exc:
            failed[name] = str(exc)
    ranked = sorted((f for f in fits.values() if np.isfinite(f.aic)), key=lambda f: f.aic)
    if not ranked:
        raise IdentificationError(f"--law best: no law could be fitted ({'; '.join(f'{k}: {v}' for k, v in failed.items())})")
    loose = {f.law: f.undetermined for f in ranked}
    eligible = [f for f in ranked if not loose[f.law] and not f.flat] or ranked  # a flat minimum's point is not its optimum
    close = [f for f in eligible if f.aic - eligible[0].aic <= PARSIMONY_DELTA_AIC]
    won = min(close, key=lambda f: (len(f.params), f.aic))
    runner = next((f for f in eligible if f is not won), None)
    won.law_choice = {
        "by": (f"AIC on the same weighted points among the laws whose constants the curve determines and whose "
               f"minimum is not flat; within "
               f"{PARSIMONY_DELTA_AIC:g} of the lowest, the fewest constants"),
        "chosen": won.law, "lowest_aic": ranked[0].law,
        "undetermined": {law: keys for law, keys in loose.items() if keys},
        "next": None if runner is None else runner.law,
        "delta_aic_to_next": None if runner is None else float(runner.aic - won.aic),
        "aic": {f.law: float(f.aic) for f in ranked}, "failed": failed,
        "flat": [f.law for f in ranked if f.flat],  # AIC at the global stage's optimum: the local refit did not settle
    }
    return won


def law_choice_text(choice: dict) -> str:
    """One line: which law --law best chose and by how much."""
    if choice.get("next") is None:
        return f"--law best: {choice['chosen']} (the only law that could be fitted)"
    delta = choice["delta_aic_to_next"]
    how = (f"AIC {delta:.1f} below the next ({choice['next']})" if delta >= 0 else
           f"AIC {-delta:.1f} above {choice['next']}, within {PARSIMONY_DELTA_AIC:g}: as good with fewer constants")
    support = ("; ΔAIC > 10: the next has essentially no support" if delta > 10 else
               "; ΔAIC 2–10: the next has less support, not none" if delta > PARSIMONY_DELTA_AIC else "")
    lower = choice.get("lowest_aic")
    loose = choice.get("undetermined") or {}
    passed = (f"; {lower} fits closer but the curve does not determine its {', '.join(loose[lower])}"
              if lower and lower != choice["chosen"] and lower in loose else "")
    flat = choice.get("flat") or []
    flats = f"; flat minimum (refit not settled, AIC at the global stage's optimum): {', '.join(flat)}" if flat else ""
    return f"--law best: {choice['chosen']} by {how}{support}{passed}{flats}"


def resolve_law(law: str, eps_p, stress_MPa) -> tuple[str, dict | None]:
    """The law one record's fits use: ``law`` itself (checked: a one-line error for an unknown or
    a rate law), or for ``best`` the winner of :func:`choose_law` on (εp, σ) with its choice."""
    if law != "best":
        static_form(law)
        return law, None
    won = choose_law(eps_p, stress_MPa)
    return won.law, won.law_choice


RANGE_SHARE_PART = 0.5  # the range-stability refit uses this first part of the fitted strain range


def range_shift(eps_p, stress_MPa, law: str = "johnson_cook") -> dict[str, float]:
    """Per constant: |fit over the first half of the strain range − fit over the whole|.

    Near zero (noise) when the law describes the curve's shape; a curve whose shape departs
    from the law (a correction's model form, another law) moves the correlated constants
    apart (A and n trade off). {} when the first half holds fewer than 4 points or fails."""
    eps, sig = _check_points(eps_p, stress_MPa, "range shift")
    first = eps <= np.min(eps) + RANGE_SHARE_PART * np.ptp(eps)
    if first.sum() < 4:
        return {}
    try:
        whole, part = fit_hardening(eps, sig, law), fit_hardening(eps[first], sig[first], law)
    except IdentificationError:
        return {}
    return {k: abs(part.params[k] - whole.params[k]) for k in whole.params}


def pattern_shift(eps_p, stress_MPa, u: float, pattern, law: str = "johnson_cook") -> dict[str, float]:
    """Per constant: half the change between fits to σ·(1 − u·g) and σ·(1 + u·g), g = ``pattern``
    (one value per point): what a relative stress error of that shape does to the constants."""
    eps, sig, g = (np.asarray(v, dtype=float).ravel() for v in (eps_p, stress_MPa, pattern))
    ok = np.isfinite(eps) & np.isfinite(sig) & np.isfinite(g)
    eps, sig, g = eps[ok], sig[ok], g[ok]
    try:
        lo, hi = (fit_hardening(eps, sig * (1.0 + sign * u * g), law) for sign in (-1.0, 1.0))
    except IdentificationError:
        return {}
    return {k: abs(hi.params[k] - lo.params[k]) / 2.0 for k in lo.params}


# -- three characteristic points ------------------------------------------------------------


THREE_POINT_LAWS = ("johnson_cook", "swift", "voce")  # the laws three_point_fit solves


def _root(g: Callable[[float], float], lo: float, hi: float, what: str) -> float:
    """Bracketing root of a monotone g on [lo, hi] (log-spaced scan, then Brent). The scan
    evaluates g on the whole grid at once (g takes arrays); the bracket is then checked point by
    point, so a sign that the vectorised arithmetic rounds the other way falls back to the scan
    point by point."""
    grid = np.geomspace(lo, hi, 400)
    with np.errstate(all="ignore"):  # inf or nan where g has none: left out of the brackets
        vals = np.asarray(g(grid), dtype=float)
    try:
        return _bracketed_root(g, grid, vals)
    except (ValueError, IndexError):  # no bracket, or brentq: the points' own values do not bracket a root
        vals = np.array([g(x) for x in grid])
        if not _brackets(vals).size:
            raise IdentificationError(f"three-point fit: no {what} makes the law pass through the three points (the points are not consistent with this law)") from None
        return _bracketed_root(g, grid, vals)


def _brackets(vals: np.ndarray) -> np.ndarray:
    """The cells of a grid where the finite values ``vals`` change sign (or reach 0)."""
    sign = np.sign(vals)
    return np.nonzero(np.isfinite(vals[:-1]) & np.isfinite(vals[1:]) & (sign[:-1] * sign[1:] <= 0))[0]


def _bracketed_root(g: Callable[[float], float], grid: np.ndarray, vals: np.ndarray) -> float:
    """Brent's root of g in the first cell of ``grid`` where ``vals`` (g on the grid) change sign
    (IndexError: none)."""
    i = _brackets(vals)[0]
    if g(grid[i]) == 0:
        return float(grid[i])
    from scipy.optimize import brentq

    return float(brentq(g, grid[i], grid[i + 1], xtol=1e-14, rtol=1e-13, maxiter=200))


def three_point_fit(points: Sequence[Sequence[float]], law: str = "johnson_cook", *, curve=None) -> HardeningFit:
    """The law passing exactly through three points (εp, σ_MPa) — the seed's method.

    Typically (0.002, Rp0.2 true), (εp at Rm, true stress at Rm), (ε_f, S_k).
    curve: optional (eps_p, stress_MPa) against which ``fit_error_pct`` is also evaluated
        (otherwise it is the error at the three points, ≈ 0 by construction).
    """
    pts = sorted((float(p[0]), float(p[1])) for p in points)
    if len(pts) != 3:
        raise IdentificationError(f"three-point fit needs exactly 3 points, got {len(pts)}")
    (e1, s1), (e2, s2), (e3, s3) = pts
    _check_points([e1, e2, e3], [s1, s2, s3], "three-point fit")
    if not (e1 < e2 < e3):
        raise IdentificationError("three-point fit: the three strains must be different")
    if not (s1 < s2 < s3):
        raise IdentificationError(f"three-point fit: stress must rise with strain ({s1:.1f}, {s2:.1f}, {s3:.1f} MPa) for a hardening law")
    r = (s3 - s1) / (s2 - s1)
    if law == "johnson_cook":
        # (ε3^n − ε1^n)/(ε2^n − ε1^n) = r, increasing in n
        def g(n):
            """Hollomon/Ludwik ratio of the three points at exponent ``n``, minus its target."""
            return (e3**n - e1**n) / (e2**n - e1**n) - r
        n = _root(g, 1e-4, 20.0, "exponent n")
        B = (s2 - s1) / (e2**n - e1**n)
        params = {"A": s1 - B * e1**n, "B": B, "n": n}
    elif law == "voce":
        # (e^{−bε1} − e^{−bε3})/(e^{−bε1} − e^{−bε2}) = r
        def g(b):
            """Voce ratio of the three points at ``b``, minus its target."""
            return -np.expm1(-b * (e3 - e1)) / -np.expm1(-b * (e2 - e1)) - r
        b = _root(g, 1e-6 / e3, 1e4 / e3, "saturation rate b")
        Q = (s2 - s1) / (np.exp(-b * e1) - np.exp(-b * e2))
        params = {"sigma0": s1 - Q * (1 - np.exp(-b * e1)), "Q": Q, "b": b}
    elif law == "swift":
        # ln(σ3/σ1)/ln(σ2/σ1) = ln((ε0+ε3)/(ε0+ε1)) / ln((ε0+ε2)/(ε0+ε1))
        rl = np.log(s3 / s1) / np.log(s2 / s1)

        def g(e0):
            """Swift ratio of the three points at ``e0``, minus its target."""
            return np.log((e0 + e3) / (e0 + e1)) / np.log((e0 + e2) / (e0 + e1)) - rl
        e0 = _root(g, 1e-9, 100.0, "pre-strain ε0")
        n = np.log(s2 / s1) / np.log((e0 + e2) / (e0 + e1))
        params = {"K": s1 / (e0 + e1) ** n, "eps0": e0, "n": n}
    else:
        static_form(law)  # an unknown or rate law: its own error
        raise IdentificationError(f"three-point fit: written for {', '.join(THREE_POINT_LAWS)}, not {law}; use the least-squares fit (--hardening lsq)")
    params = {k: float(v) for k, v in params.items()}
    func = static_form(law).func
    eps_chk, sig_chk = np.array([e1, e2, e3]), np.array([s1, s2, s3])
    if curve is not None:
        ce, cs = _check_points(curve[0], curve[1], "three-point fit, curve")
        eps_chk, sig_chk = np.concatenate([ce, eps_chk]), np.concatenate([cs, sig_chk])
    max_pct, rms_pct = _errors_pct(func(eps_chk, **params), sig_chk)
    lines = [f"[[Three-point fit: {law}]]", "    points (eps_p, stress_MPa):"]
    lines += [f"        ({e:.6g}, {s:.6g})" for e, s in pts]
    lines += ["[[Variables]]"] + [f"    {k}: {v:.6g} (exact solution, no uncertainty)" for k, v in params.items()]
    lines += [f"    max |relative error| {max_pct:.3g} %, rms {rms_pct:.3g} % over {eps_chk.size} points"]
    return HardeningFit(law=law, method="three_point", params=params, stderr={k: None for k in params},
                        correlations={}, fit_error_pct=max_pct, rms_error_pct=rms_pct,
                        strain_range=(float(np.min(eps_chk)), float(np.max(eps_chk))), report="\n".join(lines))
