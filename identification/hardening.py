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

import numpy as np

from flowcurve.errors import IdentificationError

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


def _linear_on_grid(X: np.ndarray, y: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Weighted least squares y ≈ c0 + c1·x for every row x of X at once (normal equations).

    Returns c0, c1 and the weighted residual sum of squares, one value per row of X."""
    w2 = w**2
    sw, sy = np.sum(w2), np.sum(w2 * y)
    sx, sxx, sxy = X @ w2, (X**2) @ w2, X @ (w2 * y)
    det = sw * sxx - sx**2
    with np.errstate(divide="ignore", invalid="ignore"):
        c1 = (sw * sxy - sx * sy) / det
        c0 = (sy - c1 * sx) / sw
    ss = ((c0[:, None] + c1[:, None] * X - y) ** 2) @ w2
    return c0, c1, np.where(np.isfinite(ss), ss, np.inf)


def _start_values(law: str, eps: np.ndarray, sig: np.ndarray, w: np.ndarray) -> dict[str, float]:
    """Start values by variable projection: scan the nonlinear constant on a grid and solve
    the two linear ones by weighted linear least squares for each grid value (vectorized)."""
    if law == "johnson_cook":
        grid = np.geomspace(0.02, 3.0, 120)
        A, B, ss = _linear_on_grid(np.power(eps[None, :], grid[:, None]), sig, w)
        ok = B > 0
        values = lambda i: {"A": A[i], "B": B[i], "n": grid[i]}  # noqa: E731
    elif law == "voce":
        span = max(np.max(eps), 1e-6)
        grid = np.geomspace(0.1 / span, 200.0 / span, 150)
        s0, Q, ss = _linear_on_grid(1 - np.exp(-grid[:, None] * eps[None, :]), sig, w)
        ok = Q > 0
        values = lambda i: {"sigma0": s0[i], "Q": Q[i], "b": grid[i]}  # noqa: E731
    else:  # swift, in log form: ln σ = ln K + n·ln(ε0 + εp)
        if np.min(sig) <= 0:
            raise IdentificationError("Swift law needs positive stresses")
        grid = np.geomspace(1e-5, 1.0, 120)
        base = grid[:, None] + eps[None, :]
        lnK, n, _ = _linear_on_grid(np.log(base), np.log(sig), w)
        with np.errstate(over="ignore", invalid="ignore"):
            pred = np.exp(lnK)[:, None] * np.power(base, n[:, None])
        ss = np.where(np.isfinite(pred).all(axis=1), ((pred - sig) ** 2) @ (w**2), np.inf)
        ok = n > 0
        values = lambda i: {"K": float(np.exp(lnK[i])), "eps0": grid[i], "n": n[i]}  # noqa: E731
    ok &= np.isfinite(ss)
    if not np.any(ok):
        raise IdentificationError(f"the data do not harden (stress does not rise with strain): a {law} law cannot be fitted")
    best = int(np.flatnonzero(ok)[np.argmin(ss[ok])])
    return {k: float(v) for k, v in values(best).items()}


def fit_hardening(eps_p, stress_MPa, law: str = "johnson_cook", *, extra_points: Iterable[Sequence[float]] = (),
                  weights=None) -> HardeningFit:
    """Least-squares fit of a hardening law (lmfit) to a true curve σ(εp).

    eps_p, stress_MPa: the uniform range (true plastic strain, true stress in MPa).
    extra_points: further (εp, σ_MPa) or (εp, σ_MPa, weight) points, e.g. the neck-corrected
        fracture point; their default weight is 1, like every curve point.
    weights: per-point weights of the curve points (multiply the residuals in MPa).
    """
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

    start = _start_values(law, eps, sig, w)
    import lmfit  # here, so `flowcurve --help` stays fast

    model = lmfit.Model(spec.func, independent_vars=["eps_p"])
    params = model.make_params()
    for name in spec.names:
        lo, hi = spec.bounds[name]
        params[name].set(value=float(np.clip(start[name], lo if np.isfinite(lo) else -np.inf, hi)), min=lo, max=hi)
    result = model.fit(sig, params, eps_p=eps, weights=w, nan_policy="raise")
    values = {name: float(result.params[name].value) for name in spec.names}
    stderr = {name: (None if result.params[name].stderr is None else float(result.params[name].stderr)) for name in spec.names}
    correl = {name: {k: float(v) for k, v in (result.params[name].correl or {}).items()} for name in spec.names}
    max_pct, rms_pct = _errors_pct(spec.func(eps, **values), sig)
    return HardeningFit(law=law, method="least_squares", params=values, stderr=stderr, correlations=correl,
                        fit_error_pct=max_pct, rms_error_pct=rms_pct,
                        strain_range=(float(np.min(eps)), float(np.max(eps))), report=result.fit_report())


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
