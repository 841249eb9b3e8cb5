"""Least squares with CalculiX in the loop: the machinery the inverse identifications share.

scipy ``least_squares`` over a few parameters whose residuals come from one solver run each.
The Jacobian's finite-difference runs go side by side (:func:`.pool.run_many`: ``workers``
processes or a Dask ``scheduler``); a parameter set seen before is not run again. A run that
fails (``run`` returns None) gets residuals of 1e3, which steers the optimiser away from it.
Uncertainties from the Gauss–Newton covariance (JᵀJ)⁻¹·s², s² = rᵀr/(m − rank J), taken through the
SVD of the scaled Jacobian (:func:`parameter_stderr`): a parameter the residuals do not tell at
the solution — a null direction of J, or a Jacobian column whose runs on both sides failed — has
no standard error (NaN, ``SolverFit.undetermined``), never a clipped 0. Residuals whose errors run
along them (a model's smooth error) count as fewer independent ones (``correlated``: AR(1) inflation).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any, Callable

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.fe.pool import run_many

FAILED_RUN_RESIDUAL = 1e3
RCOND = 1e-7  # singular values below RCOND·s_max of the scaled Jacobian are null directions (finite-difference noise)
FAILED_SHARE_WARN = 0.2  # a fit whose runs failed this often says so (the optimiser steered around what it could not run)
MAX_SERIAL_CORRELATION = 0.9  # the pooled rows' lag-1 autocorrelation is held below this (an information of ≥ 1/19 of the rows')


def serial_correlation(residuals) -> float:
    """Lag-1 autocorrelation of residuals in their order, ρ̂ = Σ r_i·r_i+1 / Σ r_i², with the
    small-sample correction ρ̂ + (1 + 3ρ̂)/m (Kendall's: over 30 residuals ρ̂ reads an AR(1)'s 0.6
    as 0.42 on average), held within [0, :data:`MAX_SERIAL_CORRELATION`] (alternating residuals
    do not make the data worth more)."""
    r = np.asarray(residuals, float)
    ss = float(r @ r)
    if r.size < 3 or ss <= 0.0:
        return 0.0
    rho = float(r[1:] @ r[:-1]) / ss
    return float(np.clip(rho + (1.0 + 3.0 * rho) / r.size, 0.0, MAX_SERIAL_CORRELATION))


def serial_inflation(residuals) -> float:
    """(1 + ρ)/(1 − ρ), ρ = :func:`serial_correlation`: the variance factor of a least-squares
    estimate whose errors are AR(1) along slowly varying regressors (m such points tell as much
    as m·(1 − ρ)/(1 + ρ) independent ones)."""
    rho = serial_correlation(residuals)
    return (1.0 + rho) / (1.0 - rho)


def parameter_stderr(jac, residuals, x_scale=None, *, rcond: float = RCOND, row_sigma=None,
                     correlated: bool = False) -> tuple[np.ndarray, tuple[int, ...]]:
    """(standard errors, undetermined parameters) of a least-squares solution: the square roots
    of :func:`parameter_covariance`'s diagonal."""
    cov, undetermined = parameter_covariance(jac, residuals, x_scale, rcond=rcond, row_sigma=row_sigma, correlated=correlated)
    return np.sqrt(np.diag(cov)), undetermined


def parameter_covariance(jac, residuals, x_scale=None, *, rcond: float = RCOND, row_sigma=None,
                         correlated: bool = False) -> tuple[np.ndarray, tuple[int, ...]]:
    """(covariance, undetermined parameters) of a least-squares solution.

    Gauss–Newton covariance C = (JᵀJ)⁻¹·s², s² = rᵀr/(m − rank J), computed as V·diag(1/σ²)·Vᵀ·s² from
    the SVD J·D = U·diag(σ)·Vᵀ of the Jacobian scaled by D = diag(x_scale) (so the rank test does
    not depend on the parameters' units). A parameter with a share (|V_ki| > √rcond) in a direction
    whose σ_i ≤ rcond·σ_max is not told by the residuals: its standard error is NaN, not the 0 or
    the negative variance an explicit inverse of a singular JᵀJ gives.

    ``row_sigma``: a residual's standard deviation where it is known beforehand (NaN where it is
    not). A row the fit can match exactly — one measured diameter against as many parameters —
    has a residual near 0, which says nothing about how well it was measured or modelled; pooling
    it into s² would credit it with the scatter of the others. With ``row_sigma`` the rows are
    weighted by 1/σ: s² is pooled over the unknown rows only, m counting those, and the known ones
    enter with their own σ — C = (JᵀWJ)⁻¹, W = diag(1/σ²) (weighted least squares).

    ``correlated``: the pooled rows' errors run along them (a model's error that is smooth in the
    record, as an FE mesh's or its fold-over sawtooth), so neighbouring residuals are alike and
    fewer of them are independent: s² is multiplied by :func:`serial_inflation` of those rows.
    """
    # C = (Jᵀ W J)⁻¹, W = diag(1/σ_i²) with σ_i² = s² (pooled) on the rows of unknown variance
    J = np.asarray(jac, float)
    r = np.asarray(residuals, float)
    m, p = J.shape
    d = np.ones(p) if x_scale is None else np.asarray(x_scale, float)
    if not np.all(np.isfinite(J)):
        return np.full((p, p), np.nan), tuple(range(p))
    _, sv, vt = np.linalg.svd(J * d, full_matrices=False)
    null = sv <= rcond * (sv[0] if sv.size and sv[0] > 0 else 1.0)
    undetermined = tuple(int(k) for k in range(p) if np.any(np.abs(vt[null, k]) > np.sqrt(rcond)))
    rank = int((~null).sum())
    if row_sigma is None:
        s2 = float(r @ r) / max(1, m - rank)  # the degrees of freedom count the parameters the data tell
        s2 *= serial_inflation(r) if correlated else 1.0
        half = vt[~null].T / sv[~null] * np.sqrt(s2)  # V·Σ⁻¹·s: the covariance is half·halfᵀ
    else:
        sigma = np.asarray(row_sigma, float)
        pooled = ~np.isfinite(sigma)
        s2 = float(r[pooled] @ r[pooled]) / max(1, int(pooled.sum()) - rank) if pooled.any() else 1.0
        s2 *= serial_inflation(r[pooled]) if correlated and pooled.any() else 1.0
        sigma = np.where(pooled, np.sqrt(s2), sigma)
        _, sw, vw = np.linalg.svd(J * d / sigma[:, None], full_matrices=False)
        keep = sw > rcond * (sw[0] if sw.size and sw[0] > 0 else 1.0)
        half = vw[keep].T / sw[keep]
    cov = (half @ half.T) * np.outer(d, d)  # back from the scaled parameters
    cov[list(undetermined), :] = np.nan
    cov[:, list(undetermined)] = np.nan
    return cov, undetermined


@dataclass
class SolverFit:
    x: np.ndarray
    stderr: np.ndarray
    residuals: np.ndarray
    runs: int  # solver runs started (cached ones included)
    solver_s: float  # solver time of the runs not taken from the cache
    wall_s: float
    status: int
    message: str
    nfev: int
    undetermined: tuple[int, ...] = ()  # parameters the residuals do not tell at x (stderr NaN)
    jac: np.ndarray | None = None  # the Jacobian at x (residuals × parameters)
    covariance: np.ndarray | None = None  # of x (NaN rows and columns for the undetermined)
    failed_runs: int = 0  # runs that did not converge (counted in runs), whose parameter sets the optimiser was steered from
    retried_runs: int = 0  # runs that converged only when run again with other settings (an output's ``retried``)
    cut: bool = False  # the time limit stopped the optimiser: x is the best parameter set run so far
    time_limit_s: float | None = None

    def stderr_from_rows(self, k: int, rows, row_sigma) -> float:
        """The standard error of parameter ``k`` that ``rows`` alone give, the other parameters
        held: 1/√Σ(J_ik/σ_i)² (NaN without a Jacobian, inf where the rows do not move with it)."""
        # σ_k = (Σ_i (∂r_i/∂x_k / σ_i)²)^(−1/2) over the given rows
        if self.jac is None:
            return float("nan")
        info = float(np.sum((np.asarray(self.jac, float)[rows, k] / np.asarray(row_sigma, float)[rows]) ** 2))
        return 1.0 / np.sqrt(info) if info > 0 else float("inf")

    def optimizer(self) -> dict:
        """The optimizer's status, message and function evaluations."""
        return {"status": self.status, "message": self.message, "nfev": self.nfev}

    def failed_runs_warnings(self, what: str = "inverse FE") -> list[str]:
        """A warning when at least :data:`FAILED_SHARE_WARN` of the runs failed: each failed one
        stood in the fit as a misfit of 1e3, so the optimiser went round its parameter set, and
        may have stopped short of the best fit or left a parameter undetermined."""
        if not (self.runs and self.failed_runs >= FAILED_SHARE_WARN * self.runs):
            return []
        return [f"{what}: {self.failed_runs} of {self.runs} solver runs did not converge (also when run again with other "
                "settings); the optimiser was steered around those parameter sets, so the fit may have stopped short of the "
                "best one — compare it with the fast result"]

    def cut_warnings(self, what: str = "inverse FE", time_limit_s: float | None = None) -> list[str]:
        """A warning when the time limit cut the fit (``time_limit_s``: the whole identification's, as
        the user gave it; default the fit's own): its answer is not a converged one."""
        if not self.cut:
            return []
        limit = self.time_limit_s if time_limit_s is None else time_limit_s
        errors = "its standard errors from the last Jacobian" if self.jac is not None and np.any(self.jac) else \
            "no Jacobian was formed: no standard errors"
        return [f"{what}: cut by the time limit ({limit:g} s, --time-limit) after {self.runs} solver runs: the answer "
                f"is the best parameter set run so far, not a converged fit ({errors})"]

    def undetermined_warnings(self, names, what: str = "inverse FE") -> list[str]:
        """One warning per parameter the residuals do not tell at the solution (no standard error)."""
        return [f"{what}: the record does not determine {names[k]} at the fit (its value is where the optimiser left it; "
                f"no standard error: the residuals do not change with it, or its runs failed on both sides)" for k in self.undetermined]


TYPICAL_JACOBIANS = 8  # Jacobians a fit takes (the compression inverse: 6–12), for the time-left estimate


class _OutOfTime(Exception):
    """The next batch of runs would end past the time limit."""


def time_left_s(runs: int, elapsed_s: float, n_params: int, time_limit_s: float | None) -> float | None:
    """An estimate of a fit's time left: the runs of :data:`TYPICAL_JACOBIANS` Jacobians (at
    least one more) at the rate so far, held to the time limit; None before the first run."""
    if runs <= 0:
        return None
    expected = max(runs + n_params + 1, TYPICAL_JACOBIANS * (n_params + 1))
    left = elapsed_s / runs * (expected - runs)
    return max(0.0, min(left, time_limit_s - elapsed_s)) if time_limit_s is not None else left


def fit_time_limit(time_limit_s: float | None, before_s: float) -> float | None:
    """The fit's share of an identification's wall-time budget: what the ``before_s`` spent before
    it (the fast identification, warm-start runs) left, at least 1 s; None without a limit. The
    runs keep it as a deadline, ``time.time()`` + this, each with :func:`.ccx.timeout_by` as its time-out."""
    return None if time_limit_s is None else max(1.0, time_limit_s - before_s)


def progress_on_whole_clock(progress, before_s: float, n_params: int, time_limit_s: float | None):
    """A ``progress(runs, elapsed_s, left_s)`` for :func:`fit_with_solver` whose elapsed time and time
    left count the ``before_s`` an identification spent before its fit (the fast identification,
    warm-start runs): the time left at the whole run's rate, held to ``time_limit_s``; None without
    ``progress``."""
    if progress is None:
        return None

    def shown(runs, elapsed, _left=None):
        """Tell ``progress`` with the time before this fit added."""
        progress(runs, before_s + elapsed, time_left_s(runs, before_s + elapsed, n_params, time_limit_s))

    return shown


class _Runs:
    """The runs of one fit: each parameter set run once (side by side per batch), its residuals kept, the least
    misfit so far, the last Jacobian, and the columns whose runs failed on both sides; the time limit kept."""

    def __init__(self, run, residuals_of, *, n_residuals: int, n_params: int, workers, scheduler, max_runs: int, progress,
                 what: str, time_limit_s: float | None):
        self.run, self.residuals_of, self.n_residuals, self.n_params = run, residuals_of, n_residuals, n_params
        self.workers, self.scheduler, self.max_runs, self.progress, self.what = workers, scheduler, max_runs, progress, what
        self.time_limit_s = time_limit_s
        self.t0 = time.perf_counter()
        self.count, self.solver_s, self.failed_count, self.retried, self.longest_batch_s = 0, 0.0, 0, 0, 0.0
        self.memo: dict[tuple, np.ndarray] = {}
        self.best: dict = {}  # the least misfit run so far: x, residuals
        self.last_jac: dict = {}  # x, J of the last Jacobian
        self.blind: dict[tuple, list[int]] = {}  # at x: the Jacobian columns whose runs failed on both sides

    def evaluate(self, points: list[np.ndarray]) -> list[np.ndarray]:
        """The residuals at each point, running the sets not seen before as one batch."""
        todo = list({tuple(p): p for p in points if tuple(p) not in self.memo}.values())
        if todo:
            self._batch(todo)
        return [self.memo[tuple(p)] for p in points]

    def _batch(self, todo: list[np.ndarray]) -> None:
        if self.count + len(todo) > self.max_runs:
            raise IdentificationError(f"{self.what}: more than {self.max_runs} solver runs without convergence")
        elapsed = time.perf_counter() - self.t0
        # the next batch at the longest so far: where the side folds over a batch's runs stop and are retried, and at the
        # mean batch time a tall record's fit ended 27 s past its limit (597 s for 570)
        if self.time_limit_s is not None and self.best and elapsed + self.longest_batch_s > self.time_limit_s:
            raise _OutOfTime
        t_batch = time.perf_counter()
        outs = run_many(self.run, todo, workers=self.workers, scheduler=self.scheduler)
        # past the limit a run that did not end was stopped by it (a ``run`` that keeps a deadline), not failed
        over = bool(self.time_limit_s is not None and time.perf_counter() - self.t0 >= self.time_limit_s)
        for p, out in zip(todo, outs):
            self.count += 1
            if out is None and over:
                continue
            self._keep(p, out)
        self.longest_batch_s = max(self.longest_batch_s, time.perf_counter() - t_batch)
        if over:
            raise _OutOfTime
        if self.progress:
            elapsed = time.perf_counter() - self.t0
            self.progress(self.count, elapsed, time_left_s(self.count, elapsed, self.n_params, self.time_limit_s))

    def _keep(self, p: np.ndarray, out) -> None:
        """One run's residuals (1e3 for a failed run) kept, its counts, the best so far."""
        self.failed_count += out is None
        self.retried += bool(getattr(out, "retried", False))
        if out is not None and not out.cached:
            self.solver_s += out.wall_s
        r = np.full(self.n_residuals, FAILED_RUN_RESIDUAL) if out is None else self.residuals_of(out)
        self.memo[tuple(p)] = r
        if out is not None and (not self.best or float(r @ r) < float(self.best["r"] @ self.best["r"])):
            self.best.update(x=np.asarray(p, float), r=r)

    def fun(self, x):
        """The residual vector at ``x`` (one FE run)."""
        return self.evaluate([np.asarray(x, float)])[0]

    def jacobian(self, x, steps, lo, hi):
        """Forward differences, backward at an upper bound or where the forward run failed; the runs of one Jacobian
        go side by side. A column whose runs failed both ways is unknown, not the 1e3 of a failed run over a step: a
        zero column keeps the optimiser from moving on it, and the parameter is reported undetermined if it stays so."""
        x = np.asarray(x, float)
        h = steps(x)
        pts = []
        for i in range(x.size):
            xp = x.copy()
            xp[i] = x[i] + h[i] if x[i] + h[i] <= hi[i] else x[i] - h[i]
            pts.append(xp)
        res = self.evaluate([x] + pts)
        flip = [i for i in range(x.size) if _failed(res[i + 1]) and lo[i] <= 2.0 * x[i] - pts[i][i] <= hi[i]]
        for i in flip:
            pts[i] = pts[i].copy()
            pts[i][i] = 2.0 * x[i] - pts[i][i]
        if flip:
            res = self.evaluate([x] + pts)
        self.blind[tuple(x)] = [i for i in range(x.size) if _failed(res[i + 1])]
        J = np.column_stack([np.zeros(len(res[0])) if i in self.blind[tuple(x)] else (res[i + 1] - res[0]) / (pts[i][i] - x[i])
                             for i in range(x.size)])
        self.last_jac.update(x=x, J=J)
        return J


def _failed(r) -> bool:
    return bool(r[0] == FAILED_RUN_RESIDUAL)


def _first_start(runs: _Runs, starts: list[np.ndarray], best_start: bool) -> np.ndarray:
    """The start the fit goes from: the first whose run did not fail (no Jacobian can be formed around a failed run);
    with ``best_start`` all run side by side first and tried in order of their misfit (a failed run's 1e3 last)."""
    if best_start:
        costs = [float(r @ r) for r in runs.evaluate(starts)]
        starts = [starts[k] for k in np.argsort(costs, kind="stable")]
    for x0 in starts:
        if not _failed(runs.evaluate([x0])[0]):
            return x0
    raise IdentificationError(f"{runs.what}: the solver run failed at the warm start {np.round(starts[0], 4).tolist()} and at "
                              f"{len(starts) - 1} other starts (see the log); the fast result is the one to use for this record")


def _cut_solution(runs: _Runs) -> SimpleNamespace:
    """The answer of a fit the time limit cut: the best set run so far; its covariance from the last Jacobian (at it,
    or at the optimiser's last x); an error when the limit stopped the first runs before one ended."""
    if not runs.best:
        raise IdentificationError(f"{runs.what}: the time limit ({runs.time_limit_s:g} s for the fit, --time-limit) stopped the first "
                                  f"{runs.count} solver runs before one ended; give a longer --time-limit "
                                  "(the fast result is the one to use meanwhile)") from None
    last_jac, best = runs.last_jac, runs.best
    J = last_jac["J"] if last_jac else np.zeros((runs.n_residuals, runs.n_params))
    at = ("at it" if np.array_equal(last_jac["x"], best["x"]) else "at the optimiser's last point") if last_jac else "none formed"
    return SimpleNamespace(x=best["x"], fun=best["r"], jac=J, status=0, nfev=runs.count,
                           message=f"cut by the time limit of {runs.time_limit_s:g} s: the best of {runs.count} runs, the Jacobian {at}")


def _solver_fit(sol, runs: _Runs, cut: bool, x_scale, row_sigma, correlated: bool) -> SolverFit:
    """The fit's answer with its covariance (:func:`parameter_covariance`); the parameters the residuals do not tell,
    or whose Jacobian column failed both ways at the answer, undetermined (NaN)."""
    cov, undetermined = parameter_covariance(sol.jac, sol.fun, x_scale, row_sigma=row_sigma, correlated=correlated)
    undetermined = tuple(sorted({*undetermined, *runs.blind.get(tuple(sol.x), [])}))
    cov[list(undetermined), :] = np.nan
    cov[:, list(undetermined)] = np.nan
    return SolverFit(x=sol.x, stderr=np.sqrt(np.diag(cov)), residuals=sol.fun, runs=runs.count, solver_s=runs.solver_s,
                     wall_s=time.perf_counter() - runs.t0, status=int(sol.status), message=str(sol.message), nfev=int(sol.nfev),
                     undetermined=undetermined, jac=np.asarray(sol.jac, float), covariance=cov, failed_runs=runs.failed_count,
                     retried_runs=runs.retried, cut=cut, time_limit_s=runs.time_limit_s)


def fit_with_solver(run: Callable[[np.ndarray], Any], residuals_of: Callable[[Any], np.ndarray], x0, lo, hi, *,
                    n_residuals: int, steps: Callable[[np.ndarray], np.ndarray], x_scale, workers: int | None = None,
                    scheduler=None, max_runs: int = 150, max_nfev: int = 20, xtol: float = 1e-6, ftol: float = 1e-6,
                    progress=None, what: str = "inverse FE", other_starts=(), best_start: bool = False, row_sigma=None,
                    correlated: bool = False, time_limit_s: float | None = None) -> SolverFit:
    """Minimise |residuals_of(run(x))|² over lo ≤ x ≤ hi from x0.

    ``run`` must be picklable (a module-level function or a ``functools.partial`` of one) and
    return an object with ``wall_s`` and ``cached`` attributes (and ``retried``, counted when true:
    a run only a retry's settings carried), or None for a failed run. When
    the run at x0 fails, ``other_starts`` are tried in turn; with ``best_start`` they are all run at
    once (side by side) and the fit starts from the one that misses least. A Jacobian step whose run
    fails is taken the other way. ``row_sigma``: the residuals' known standard deviations, NaN where the
    fit's scatter stands in (:func:`parameter_stderr`); ``correlated``: that scatter runs along the
    rows (its variance inflated by :func:`serial_inflation`).
    ``time_limit_s``: no batch of runs is started that would end past it (at the longest batch time so
    far), and a batch that ends past it ends the fit (its runs stopped there by a ``run`` that keeps
    a deadline: None, not counted failed); the fit then ends with the best parameter set run so far,
    its covariance from the last Jacobian, ``cut`` set (an error naming the limit when no run had ended by then).
    ``progress(runs, elapsed_s, left_s)``: left_s from :func:`time_left_s`.
    """
    from scipy.optimize import least_squares

    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    runs = _Runs(run, residuals_of, n_residuals=n_residuals, n_params=len(x0), workers=workers, scheduler=scheduler,
                 max_runs=max_runs, progress=progress, what=what, time_limit_s=time_limit_s)
    starts = [np.asarray(x0, float)] + [np.clip(np.asarray(s, float), lo, hi) for s in other_starts]
    try:
        x0 = _first_start(runs, starts, best_start)
        sol = least_squares(runs.fun, np.asarray(x0, float), jac=lambda x: runs.jacobian(x, steps, lo, hi), bounds=(lo, hi),
                            x_scale=x_scale, xtol=xtol, ftol=ftol, gtol=1e-8, max_nfev=max_nfev)
        cut = False
    except _OutOfTime:
        sol, cut = _cut_solution(runs), True
    return _solver_fit(sol, runs, cut, x_scale, row_sigma, correlated)
