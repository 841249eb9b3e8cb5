"""What every static law σ(εp) shares (not a law itself): evaluation through its pure function,
a variable-projection profile over its nonlinear constant(s) for a global start, and a guess.

A static law's module sets ``function`` (σ in MPa from εp and the constants by name, the
signature lmfit's ``Model`` reads), :meth:`profile` and :meth:`data_start`; the fits of one
record (:mod:`.hardening`) use them, and any series fit can use :meth:`Law.guess`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Callable, ClassVar

import numpy as np

from flowcurve.identification.laws.base import Law

STRAIN_GRID_POINTS = 240  # values of a nonlinear constant scanned by a profile


def linear_on_grid(X: np.ndarray, y: np.ndarray, w: np.ndarray, *, nonnegative_c0: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Weighted least squares y ≈ c0 + c1·x for every row x of X at once (normal equations).

    nonnegative_c0: where the free solution has c0 < 0, the best line with c0 = 0 instead
    (c1 = Σw²xy/Σw²x²), so a profile respects a lower bound 0 of the intercept exactly.
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


def first_and_rise(eps: np.ndarray, sig: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, float, float]:
    """The points sorted by strain, a level just below the first stress, and the log–log slope
    and intercept of σ − level against εp (ln(σ − σ0) = ln K + n·ln εp): (e, s, σ0, K, n)."""
    order = np.argsort(eps)
    e, s = eps[order], sig[order]
    level = max(float(s[0]) - 0.05 * max(np.ptp(s), 1e-9), 0.0)  # just below the first point: σ − σ0 > 0
    rise = s - level
    use = (e > 0) & (rise > 0)
    if use.sum() >= 2 and np.ptp(np.log(e[use])) > 0:
        n, lnK = np.polyfit(np.log(e[use]), np.log(rise[use]), 1)
    else:
        n, lnK = 0.5, np.log(max(np.ptp(s), 1.0) / max(np.ptp(e), 1e-6) ** 0.5)
    return e, s, level, float(np.exp(lnK)), float(np.clip(n, 0.01, 2.0))


class StaticLaw(Law):
    """A law of εp alone: ``function(eps_p, **constants)`` is its equation."""

    function: ClassVar[Callable]

    def evaluate(self, eps_p, strain_rate_per_s, temperature_C, **values):
        """The static law's flow stress, MPa (rate and temperature ignored)."""
        return type(self).function(eps_p, **{name: values[name] for name in self.names})

    def profile(self, eps: np.ndarray, sig: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, Sequence[dict[str, float]]]:
        """(weighted residual sum of squares, constants) over a grid of the nonlinear constant(s),
        the linear ones solved exactly (variable projection); inf where a row breaks a bound."""
        raise NotImplementedError

    def data_start(self, eps: np.ndarray, sig: np.ndarray) -> dict[str, float]:
        """Start values read off the data (log-linear slopes, first and last stresses)."""
        raise NotImplementedError

    def guess(self, eps_p, stress_MPa, strain_rate_per_s=None, temperature_C=None, **conditions):
        """The best row of :meth:`profile` (unit weights), else :meth:`data_start`."""
        eps, sig = np.asarray(eps_p, dtype=float).ravel(), np.asarray(stress_MPa, dtype=float).ravel()
        ss, cands = self.profile(eps, sig, np.ones_like(eps))
        return cands[int(np.argmin(ss))] if np.any(np.isfinite(ss)) else self.data_start(eps, sig)


class Rows(Sequence):
    """A profile's candidate constants, row i (as floats) built when it is read: a profile scans
    hundreds of rows, a fit starts from a few of them."""

    def __init__(self, size: int, row: Callable[[int], dict]):
        self.size, self.row = size, row

    def __len__(self) -> int:
        return self.size

    def __getitem__(self, i):
        """Row ``i`` as {name: float}; a slice gives a list of them."""
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(self.size))]
        if not -self.size <= i < self.size:
            raise IndexError(f"row {i} of {self.size}")
        return {k: float(v) for k, v in self.row(int(i) % self.size).items()}


def best_rows(ss: np.ndarray, row: Callable[[int], dict], ok: np.ndarray) -> tuple[np.ndarray, Rows]:
    """A profile's result: inf where a row breaks a bound or is not finite; the constants of row i
    as ``row(i)`` gives them, as floats, built only for the rows read (:class:`Rows`)."""
    ss = np.where(ok & np.isfinite(ss), ss, np.inf)
    return ss, Rows(ss.size, row)
