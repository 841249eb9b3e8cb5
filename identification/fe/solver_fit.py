"""Least squares with CalculiX in the loop: the machinery the inverse identifications share.

scipy ``least_squares`` over a few parameters whose residuals come from one solver run each.
The Jacobian's finite-difference runs go side by side (:func:`.pool.run_many`: ``workers``
processes or a Dask ``scheduler``); a parameter set seen before is not run again. A run that
fails (``run`` returns None) gets residuals of 1e3, which steers the optimiser away from it.
Uncertainties from the Gauss–Newton covariance (JᵀJ)⁻¹·s², s² = rᵀr/(m − p).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.fe.pool import run_many

FAILED_RUN_RESIDUAL = 1e3


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

    def optimizer(self) -> dict:
        return {"status": self.status, "message": self.message, "nfev": self.nfev}


def fit_with_solver(run: Callable[[np.ndarray], Any], residuals_of: Callable[[Any], np.ndarray], x0, lo, hi, *,
                    n_residuals: int, steps: Callable[[np.ndarray], np.ndarray], x_scale, workers: int | None = None,
                    scheduler=None, max_runs: int = 150, max_nfev: int = 20, xtol: float = 1e-6, ftol: float = 1e-6,
                    progress=None, what: str = "inverse FE", other_starts=()) -> SolverFit:
    """Minimise |residuals_of(run(x))|² over lo ≤ x ≤ hi from x0.

    ``run`` must be picklable (a module-level function or a ``functools.partial`` of one) and
    return an object with ``wall_s`` and ``cached`` attributes, or None for a failed run. When
    the run at x0 fails, ``other_starts`` are tried in turn; a Jacobian step whose run fails is
    taken the other way.
    """
    from scipy.optimize import least_squares

    t0 = time.perf_counter()
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    runs = {"count": 0, "solver_s": 0.0}
    memo: dict[tuple, np.ndarray] = {}

    def evaluate(points: list[np.ndarray]) -> list[np.ndarray]:
        todo = list({tuple(p): p for p in points if tuple(p) not in memo}.values())
        if todo:
            if runs["count"] + len(todo) > max_runs:
                raise IdentificationError(f"{what}: more than {max_runs} solver runs without convergence")
            for p, out in zip(todo, run_many(run, todo, workers=workers, scheduler=scheduler)):
                runs["count"] += 1
                if out is not None and not out.cached:
                    runs["solver_s"] += out.wall_s
                memo[tuple(p)] = np.full(n_residuals, FAILED_RUN_RESIDUAL) if out is None else residuals_of(out)
            if progress:
                progress(runs["count"], time.perf_counter() - t0)
        return [memo[tuple(p)] for p in points]

    def fun(x):
        return evaluate([np.asarray(x, float)])[0]

    def failed(r) -> bool:
        return bool(r[0] == FAILED_RUN_RESIDUAL)

    def jac(x):
        # forward differences, backward at an upper bound or where the forward run failed; the runs of one Jacobian go side by side
        x = np.asarray(x, float)
        h = steps(x)
        pts = []
        for i in range(x.size):
            xp = x.copy()
            xp[i] = x[i] + h[i] if x[i] + h[i] <= hi[i] else x[i] - h[i]
            pts.append(xp)
        res = evaluate([x] + pts)
        flip = [i for i in range(x.size) if failed(res[i + 1]) and lo[i] <= 2.0 * x[i] - pts[i][i] <= hi[i]]
        for i in flip:
            pts[i] = pts[i].copy()
            pts[i][i] = 2.0 * x[i] - pts[i][i]
        if flip:
            res = evaluate([x] + pts)
        return np.column_stack([(res[i + 1] - res[0]) / (pts[i][i] - x[i]) for i in range(x.size)])

    starts = [np.asarray(x0, float)] + [np.clip(np.asarray(s, float), lo, hi) for s in other_starts]
    for x0 in starts:  # no Jacobian can be formed around a failed run
        if not failed(evaluate([x0])[0]):
            break
    else:
        raise IdentificationError(f"{what}: the solver run failed at the warm start {np.round(starts[0], 4).tolist()} and at "
                                  f"{len(starts) - 1} other starts (see the log); the fast result is the one to use for this record")
    sol = least_squares(fun, np.asarray(x0, float), jac=jac, bounds=(lo, hi), x_scale=x_scale, xtol=xtol, ftol=ftol,
                        gtol=1e-8, max_nfev=max_nfev)
    r, J = sol.fun, sol.jac
    s2 = float(r @ r) / max(1, r.size - sol.x.size)
    try:
        se = np.sqrt(np.clip(np.diag(np.linalg.inv(J.T @ J) * s2), 0.0, None))
    except np.linalg.LinAlgError:
        se = np.full(sol.x.size, np.nan)
    return SolverFit(x=sol.x, stderr=se, residuals=r, runs=runs["count"], solver_s=runs["solver_s"],
                     wall_s=time.perf_counter() - t0, status=int(sol.status), message=str(sol.message), nfev=int(sol.nfev))
