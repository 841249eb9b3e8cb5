"""Strain-hardening laws σ(εp) and their identification from a true stress-strain curve.

Three laws (docs/methods.md §3, §5):

* Johnson–Cook static part ``A + B·εp^n`` (the default),
* Swift ``K·(ε0 + εp)^n``,
* Voce ``σ0 + Q·(1 − exp(−b·εp))``.

Two ways to identify one:

* :func:`fit_hardening` — least squares (lmfit) over the uniform range plus extra points
  (e.g. the neck-corrected fracture point), with standard errors and correlations;
* :func:`three_point_fit` — the seed's method (end of 3.1.2): the law passes exactly through
  three characteristic points, the nonlinear constant found by a bracketing root search.

Both return a :class:`HardeningFit`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Iterable, Sequence

import logging

import numpy as np

from flowcurve.errors import IdentificationError

logger = logging.getLogger(__name__)

# Plausibility limits used to catch unit mistakes (Pa for MPa, % for fractions).
MAX_STRESS_MPa = 20_000.0
MAX_STRAIN = 5.0


def johnson_cook_static(eps_p, A, B, n):
    """Johnson–Cook static flow stress (2.19), first bracket: A + B·εp^n (MPa)."""
    eps_p = np.clip(np.asarray(eps_p, dtype=float), 0.0, None)
    return A + B * np.power(eps_p, n)


def swift(eps_p, K, eps0, n):
    """Swift hardening: K·(ε0 + εp)^n (MPa)."""
    eps_p = np.clip(np.asarray(eps_p, dtype=float), 0.0, None)
    return K * np.power(eps0 + eps_p, n)


def voce(eps_p, sigma0, Q, b):
    """Voce saturation hardening: σ0 + Q·(1 − exp(−b·εp)) (MPa)."""
    eps_p = np.clip(np.asarray(eps_p, dtype=float), 0.0, None)
    return sigma0 + Q * (1.0 - np.exp(-b * eps_p))


@dataclass(frozen=True)
class _Law:
    func: Callable
    names: tuple[str, str, str]  # parameter names of func
    keys: tuple[str, str, str]  # the same with units, for JSON
    bounds: dict[str, tuple[float, float]]


LAWS: dict[str, _Law] = {
    "johnson_cook": _Law(johnson_cook_static, ("A", "B", "n"), ("A_MPa", "B_MPa", "n"),
                         {"A": (0.0, np.inf), "B": (0.0, np.inf), "n": (1e-4, 5.0)}),
    "swift": _Law(swift, ("K", "eps0", "n"), ("K_MPa", "eps0", "n"),
                  {"K": (0.0, np.inf), "eps0": (1e-9, 10.0), "n": (1e-4, 5.0)}),
    "voce": _Law(voce, ("sigma0", "Q", "b"), ("sigma0_MPa", "Q_MPa", "b"),
                 {"sigma0": (0.0, np.inf), "Q": (0.0, np.inf), "b": (1e-6, 1e5)}),
}


def _law(name: str) -> _Law:
    try:
        return LAWS[name]
    except KeyError:
        raise IdentificationError(f"unknown hardening law {name!r}; choose one of {', '.join(LAWS)}") from None


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

    @property
    def quality(self) -> str:
        """"good", or "poor" when the largest relative error exceeds 10 % or ``doubt`` is set."""
        return "poor" if self.doubt or not self.fit_error_pct <= POOR_FIT_PCT else "good"

    def __call__(self, eps_p):
        """Flow stress (MPa) of the identified law at true plastic strain ``eps_p``."""
        return _law(self.law).func(eps_p, **self.params)

    def as_dict(self) -> dict:
        """JSON-able summary with unit-carrying keys (``A_MPa``, ``A_MPa_stderr`` …)."""
        law = _law(self.law)
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


def _linear_on_grid(X: np.ndarray, y: np.ndarray, w: np.ndarray, *, nonnegative_c0: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Weighted least squares y ≈ c0 + c1·x for every row x of X at once (normal equations).

    nonnegative_c0: where the free solution has c0 < 0, the best line with c0 = 0 instead
    (c1 = Σw²xy/Σw²x²), so the grid search respects the bound A ≥ 0 / σ0 ≥ 0 exactly.
    Returns c0, c1 and the weighted residual sum of squares, one value per row of X."""
    w2 = w**2
    sw, sy = np.sum(w2), np.sum(w2 * y)
    sx, sxx, sxy = X @ w2, (X**2) @ w2, X @ (w2 * y)
    det = sw * sxx - sx**2
    with np.errstate(divide="ignore", invalid="ignore"):
        c1 = (sw * sxy - sx * sy) / det
        c0 = (sy - c1 * sx) / sw
        if nonnegative_c0:
            through_zero = c0 < 0
            c1 = np.where(through_zero, sxy / sxx, c1)
            c0 = np.where(through_zero, 0.0, c0)
        ss = ((c0[:, None] + c1[:, None] * X - y) ** 2) @ w2
    return c0, c1, np.where(np.isfinite(ss), ss, np.inf)


def _grid_search(law: str, eps: np.ndarray, sig: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, list[dict[str, float]]]:
    """Global stage by variable projection: the nonlinear constant (n, b or ε0) scanned over a
    dense log grid across its whole plausible range, the two linear ones solved exactly (weighted
    linear least squares, the lower bound of A / σ0 respected) for every grid value.

    Returns the residual sum of squares per grid value and the constants per grid value."""
    if law == "johnson_cook":
        grid = np.geomspace(0.005, 3.0, 240)
        A, B, ss = _linear_on_grid(np.power(eps[None, :], grid[:, None]), sig, w, nonnegative_c0=True)
        ok = B > 0
        cands = [{"A": A[i], "B": B[i], "n": grid[i]} for i in range(grid.size)]
    elif law == "voce":
        span = max(np.max(eps), 1e-6)
        grid = np.geomspace(0.05 / span, 2000.0 / span, 240)
        s0, Q, ss = _linear_on_grid(-np.expm1(-grid[:, None] * eps[None, :]), sig, w, nonnegative_c0=True)
        ok = Q > 0
        cands = [{"sigma0": s0[i], "Q": Q[i], "b": grid[i]} for i in range(grid.size)]
    else:  # swift, in log form: ln σ = ln K + n·ln(ε0 + εp), then scored in MPa
        if np.min(sig) <= 0:
            raise IdentificationError("Swift law needs positive stresses")
        grid = np.geomspace(1e-7, 1.0, 240)
        base = grid[:, None] + eps[None, :]
        lnK, n, _ = _linear_on_grid(np.log(base), np.log(sig), w)
        with np.errstate(over="ignore", invalid="ignore"):
            pred = np.exp(lnK)[:, None] * np.power(base, n[:, None])
        ss = np.where(np.isfinite(pred).all(axis=1), ((pred - sig) ** 2) @ (w**2), np.inf)
        ok = n > 0
        cands = [{"K": float(np.exp(lnK[i])), "eps0": grid[i], "n": n[i]} for i in range(grid.size)]
    ss = np.where(ok & np.isfinite(ss), ss, np.inf)
    return ss, [{k: float(v) for k, v in c.items()} for c in cands]


def data_start(law: str, eps: np.ndarray, sig: np.ndarray) -> dict[str, float]:
    """Start values read off the data: A (σ0) = the flow stress at the first plastic point
    (≈ Rp0.2), B and n from the log–log slope of σ − A against εp (ln(σ − A) = ln B + n ln εp)."""
    order = np.argsort(eps)
    e, s = eps[order], sig[order]
    first = float(s[0])
    A = max(first - 0.05 * max(np.ptp(s), 1e-9), 0.0)  # just below the first point: σ − A > 0
    rise = s - A
    use = (e > 0) & (rise > 0)
    if use.sum() >= 2 and np.ptp(np.log(e[use])) > 0:
        n, lnB = np.polyfit(np.log(e[use]), np.log(rise[use]), 1)
    else:
        n, lnB = 0.5, np.log(max(np.ptp(s), 1.0) / max(np.ptp(e), 1e-6) ** 0.5)
    n = float(np.clip(n, 0.01, 2.0))
    B = float(np.exp(lnB))
    if law == "johnson_cook":
        return {"A": A, "B": B, "n": n}
    if law == "voce":
        top = float(np.max(s))
        half = e[np.argmax(s >= A + 0.63 * (top - A))] if top > A else float(np.max(e))
        return {"sigma0": A, "Q": max(top - A, 1e-3), "b": 1.0 / max(half, 1e-6)}
    ln_e = np.log(np.clip(e, 1e-9, None))
    n_sw, lnK = np.polyfit(ln_e, np.log(np.clip(s, 1e-9, None)), 1) if np.ptp(ln_e) > 0 else (0.2, np.log(first))
    return {"K": float(np.exp(lnK)), "eps0": 1e-3, "n": float(np.clip(n_sw, 1e-3, 2.0))}


def _grid_minima(ss: np.ndarray, count: int, within: float = 10.0) -> list[int]:
    """Indices of the ``count`` lowest local minima of ``ss`` along the grid (distinct basins),
    those no more than ``within`` times the lowest."""
    finite = np.isfinite(ss)
    left = np.concatenate([[np.inf], ss[:-1]])
    right = np.concatenate([ss[1:], [np.inf]])
    minima = np.flatnonzero(finite & (ss <= left) & (ss <= right))
    minima = minima[ss[minima] <= within * np.min(ss[minima])]
    return [int(i) for i in minima[np.argsort(ss[minima])][:count]]


def _on_bound(value: float, lo: float, hi: float) -> str | None:
    """'lower'/'upper' when a fitted value sits on a finite bound (within a relative 1e-6)."""
    for bound, name in ((lo, "lower"), (hi, "upper")):
        if np.isfinite(bound) and abs(value - bound) <= 1e-6 * max(abs(bound), 1e-3):
            return name
    return None


# a fit whose largest relative error exceeds this is marked poor
POOR_FIT_PCT = 10.0
GRID_STARTS = 4  # local fits started from the best basins of the global grid stage
MAX_EVALUATIONS = 500  # per local fit: a start crawling along a bound is cut short, the others finish


def _polish(spec: _Law, starts: list[dict[str, float]], eps: np.ndarray, sig: np.ndarray, w: np.ndarray) -> dict[str, float]:
    """Local bounded least squares (scipy, trust region) from every start; the lowest cost wins.

    The winner is then refitted once with lmfit by the caller, for its uncertainties and report."""
    from scipy.optimize import least_squares

    lo = np.array([spec.bounds[n][0] for n in spec.names])
    hi = np.array([spec.bounds[n][1] for n in spec.names])

    def residual(x):
        with np.errstate(over="ignore", invalid="ignore"):
            r = w * (spec.func(eps, *x) - sig)
        return np.where(np.isfinite(r), r, 1e12)

    best_x, best_cost = None, np.inf
    for start in starts:
        x0 = np.clip([start[n] for n in spec.names], lo, hi)
        x0 = np.where(x0 <= lo, lo + 1e-9 * np.maximum(np.abs(lo), 1.0), x0)  # strictly inside for trf
        with np.errstate(all="ignore"):  # trial steps may overflow; such steps are rejected by the solver
            sol = least_squares(residual, x0, bounds=(lo, hi), x_scale="jac", max_nfev=MAX_EVALUATIONS)
        if np.isfinite(sol.cost) and sol.cost < best_cost:
            best_x, best_cost = sol.x, sol.cost
    if best_x is None:
        raise IdentificationError(f"the {spec.func.__name__} fit did not converge from any start value")
    return dict(zip(spec.names, (float(v) for v in best_x)))


def fit_hardening(eps_p, stress_MPa, law: str = "johnson_cook", *, extra_points: Iterable[Sequence[float]] = (),
                  weights=None) -> HardeningFit:
    """Least-squares fit of a hardening law (lmfit) to a true curve σ(εp), global then local.

    eps_p, stress_MPa: the uniform range (true plastic strain, true stress in MPa).
    extra_points: further (εp, σ_MPa) or (εp, σ_MPa, weight) points, e.g. the neck-corrected
        fracture point; their default weight is 1, like every curve point.
    weights: per-point weights of the curve points (multiply the residuals in MPa).

    Global stage: the nonlinear constant scanned over its whole range with the linear ones
    solved exactly (:func:`_grid_search`); local stage: lmfit from the best basins of that scan
    and from start values read off the data (:func:`data_start`); the lowest residual wins.
    A constant left on a bound and a fit with a max error above 10 % are reported in
    ``warnings``; the latter makes ``quality`` "poor".
    """
    import lmfit  # here, so `flowcurve --help` stays fast

    spec = _law(law)
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

    ss, candidates = _grid_search(law, eps, sig, w)
    if not np.any(np.isfinite(ss)):
        raise IdentificationError(f"the data do not harden (stress does not rise with strain): a {law} law cannot be fitted")
    starts = [candidates[i] for i in _grid_minima(ss, GRID_STARTS)] + [data_start(law, eps, sig)]
    polished = _polish(spec, starts, eps, sig, w)
    model = lmfit.Model(spec.func, independent_vars=["eps_p"])
    params = model.make_params()
    for name in spec.names:
        lo, hi = spec.bounds[name]
        params[name].set(value=float(np.clip(polished[name], lo, hi)), min=lo, max=hi)
    best = model.fit(sig, params, eps_p=eps, weights=w, nan_policy="raise", max_nfev=MAX_EVALUATIONS)
    values = {name: float(best.params[name].value) for name in spec.names}
    stderr = {name: (None if best.params[name].stderr is None else float(best.params[name].stderr)) for name in spec.names}
    correl = {name: {k: float(v) for k, v in (best.params[name].correl or {}).items()} for name in spec.names}
    max_pct, rms_pct = _errors_pct(spec.func(eps, **values), sig)
    warnings = []
    for name, key in zip(spec.names, spec.keys):
        side = _on_bound(values[name], *spec.bounds[name])
        if side:
            warnings.append(f"{law} {key} = {values[name]:.4g} sits on its {side} bound: the law does not describe this curve well "
                            "(another law, --fit-range or --fracture-point exclude may)")
    if max_pct > POOR_FIT_PCT:
        warnings.append(f"{law} fit is poor: max error {max_pct:.3g} % (> {POOR_FIT_PCT:g} %), rms {rms_pct:.3g} %")
    return HardeningFit(law=law, method="least_squares", params=values, stderr=stderr, correlations=correl,
                        fit_error_pct=max_pct, rms_error_pct=rms_pct,
                        strain_range=(float(np.min(eps)), float(np.max(eps))), report=best.fit_report(), warnings=warnings)


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


def _root(g: Callable[[float], float], lo: float, hi: float, what: str) -> float:
    """Bracketing root of a monotone g on [lo, hi] (log-spaced scan, then Brent)."""
    grid = np.geomspace(lo, hi, 400)
    vals = np.array([g(x) for x in grid])
    sign = np.sign(vals)
    idx = np.nonzero(np.isfinite(vals[:-1]) & np.isfinite(vals[1:]) & (sign[:-1] * sign[1:] <= 0))[0]
    if idx.size == 0:
        raise IdentificationError(f"three-point fit: no {what} makes the law pass through the three points (the points are not consistent with this law)")
    i = idx[0]
    if vals[i] == 0:
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
            return (e3**n - e1**n) / (e2**n - e1**n) - r
        n = _root(g, 1e-4, 20.0, "exponent n")
        B = (s2 - s1) / (e2**n - e1**n)
        params = {"A": s1 - B * e1**n, "B": B, "n": n}
    elif law == "voce":
        # (e^{−bε1} − e^{−bε3})/(e^{−bε1} − e^{−bε2}) = r
        def g(b):
            return -np.expm1(-b * (e3 - e1)) / -np.expm1(-b * (e2 - e1)) - r
        b = _root(g, 1e-6 / e3, 1e4 / e3, "saturation rate b")
        Q = (s2 - s1) / (np.exp(-b * e1) - np.exp(-b * e2))
        params = {"sigma0": s1 - Q * (1 - np.exp(-b * e1)), "Q": Q, "b": b}
    elif law == "swift":
        # ln(σ3/σ1)/ln(σ2/σ1) = ln((ε0+ε3)/(ε0+ε1)) / ln((ε0+ε2)/(ε0+ε1))
        rl = np.log(s3 / s1) / np.log(s2 / s1)

        def g(e0):
            return np.log((e0 + e3) / (e0 + e1)) / np.log((e0 + e2) / (e0 + e1)) - rl
        e0 = _root(g, 1e-9, 100.0, "pre-strain ε0")
        n = np.log(s2 / s1) / np.log((e0 + e2) / (e0 + e1))
        params = {"K": s1 / (e0 + e1) ** n, "eps0": e0, "n": n}
    else:
        _law(law)
        raise AssertionError("unreachable")
    params = {k: float(v) for k, v in params.items()}
    func = _law(law).func
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
