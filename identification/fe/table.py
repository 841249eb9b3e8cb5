"""The FE upsetting table (package data made by :mod:`.make_table`) and its inverse.

The table holds, for μ × h0/d0 × n (Swift hardening exponent) × strain ε = ln(h0/h):

* the force factor F/(σ_f·A), A = π·d0²·h0/(4h), normalised by the μ = 0 run (CalculiX's own
  0.3–0.6 % mesh deficit cancels);
* the bulge ΔR/h (3.29), less the μ = 0 run's (the same mesh offset, ~0.003 at ε = 0.9).

Values between grid points: linear in ln(h0/d0), n and ε, then monotone cubic (PCHIP) along μ.
The hardening of a measured curve enters as its effective exponent n = d ln σ / d ln ε_p,
fitted over ε_p ≥ 0.05 (:func:`effective_hardening_exponent`).
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from flowcurve.errors import IdentificationError

log = logging.getLogger(__name__)

PACKAGE_TABLE = Path(__file__).resolve().parent / "data" / "upsetting_table.npz"
HARDENING_FIT_FROM = 0.05  # effective n fitted from this plastic strain on


@dataclass(frozen=True)
class UpsettingTable:
    mu: np.ndarray
    h0_d0: np.ndarray
    n: np.ndarray
    strain: np.ndarray  # with a leading 0 (factor 1, bulge 0)
    force_factor: np.ndarray  # (mu, h0_d0, n, strain)
    bulge: np.ndarray
    meta: dict = field(default_factory=dict)
    path: str = ""

    @classmethod
    def load(cls, path: str | Path | None = None) -> "UpsettingTable":
        return _load(str(path or PACKAGE_TABLE))

    # -- interpolation --------------------------------------------------------------------
    def _check(self, h0_d0: float, n: float) -> tuple[float, float]:
        lo, hi = float(self.h0_d0[0]), float(self.h0_d0[-1])
        if not (lo - 1e-9 <= h0_d0 <= hi + 1e-9):
            raise IdentificationError(f"FE table: h0/d0 = {h0_d0:.3g} is outside the table's range {lo:g}–{hi:g} ({self.path})")
        return min(max(h0_d0, lo), hi), float(np.clip(n, self.n[0], self.n[-1]))

    def _mu_rows(self, values: np.ndarray, h0_d0: float, n: float, strain) -> np.ndarray:
        """Linear interpolation in ln(h0/d0), n and ε at every grid μ → (n_mu, n_strain)."""
        h0_d0, n = self._check(h0_d0, n)
        strain = np.atleast_1d(np.asarray(strain, dtype=float))
        lh = np.log(self.h0_d0)
        i = int(np.clip(np.searchsorted(lh, math.log(h0_d0)) - 1, 0, lh.size - 2))
        wi = (math.log(h0_d0) - lh[i]) / (lh[i + 1] - lh[i])
        j = int(np.clip(np.searchsorted(self.n, n) - 1, 0, self.n.size - 2))
        wj = (n - self.n[j]) / (self.n[j + 1] - self.n[j])
        block = ((1 - wi) * (1 - wj) * values[:, i, j] + wi * (1 - wj) * values[:, i + 1, j]
                 + (1 - wi) * wj * values[:, i, j + 1] + wi * wj * values[:, i + 1, j + 1])  # (mu, strain grid)
        s = np.clip(strain, self.strain[0], None)
        out = np.empty((self.mu.size, s.size))
        for k in range(self.mu.size):
            out[k] = np.interp(s, self.strain, block[k], right=np.nan)
        return out

    def _along_mu(self, rows: np.ndarray, mu: float) -> np.ndarray:
        """Monotone cubic (PCHIP) along μ in every column of ``rows`` (μ, strain); one
        interpolant per pattern of converged runs, not one per column (a record has thousands)."""
        from scipy.interpolate import PchipInterpolator

        out = np.full(rows.shape[1], np.nan)
        patterns, which = np.unique(np.isfinite(rows).T, axis=0, return_inverse=True)
        for k, ok in enumerate(patterns):
            cols = np.flatnonzero(which.ravel() == k)
            if ok.sum() >= 2 and mu <= self.mu[ok][-1] + 1e-12:
                out[cols] = PchipInterpolator(self.mu[ok], rows[np.ix_(ok, cols)], axis=0)(mu)
        return out

    def force_factor_at(self, mu: float, h0_d0: float, n: float, strain) -> np.ndarray:
        """F/(σ_f·A) at the strains ``strain`` (NaN beyond the table)."""
        return self._along_mu(self._mu_rows(self.force_factor, h0_d0, n, strain), mu)

    def bulge_at(self, mu: float, h0_d0: float, n: float, strain) -> np.ndarray:
        """ΔR/h at the strains ``strain``."""
        return self._along_mu(self._mu_rows(self.bulge, h0_d0, n, strain), mu)

    def mu_from_bulge(self, dR_over_h: float, h0_d0: float, n: float, strain: float, *, clamp: bool = False) -> float:
        """The μ whose bulge at (h0/d0, n, ε) is ``dR_over_h`` (inverse of :meth:`bulge_at`);
        a bulge beyond the table's largest is an error, or with ``clamp`` its largest μ."""
        from scipy.interpolate import PchipInterpolator

        if not (math.isfinite(dR_over_h) and math.isfinite(strain) and strain > 0):
            raise IdentificationError(f"FE table: need a finite bulge and a strain > 0 (ΔR/h = {dR_over_h}, ε = {strain})")
        if strain > self.strain[-1] + 1e-9:
            raise IdentificationError(f"FE table: the final strain ε = {strain:.3g} is beyond the table's {self.strain[-1]:g}")
        col = self._mu_rows(self.bulge, h0_d0, n, [strain])[:, 0]
        ok = np.isfinite(col)
        if ok.sum() < 2:
            raise IdentificationError(f"FE table: no converged runs at h0/d0 = {h0_d0:.3g}, ε = {strain:.3g}")
        mus = np.linspace(0.0, self.mu[ok][-1], 701)
        b = PchipInterpolator(self.mu[ok], col[ok])(mus)
        b = np.maximum.accumulate(b)  # the bulge grows with μ; flat once the face sticks
        if dR_over_h <= b[0]:
            return 0.0
        if dR_over_h > b[-1] and clamp:
            return float(mus[-1])
        if dR_over_h > b[-1]:
            raise IdentificationError(f"FE table: bulge ΔR/h = {dR_over_h:.4g} is beyond the largest the table gives at ε = {strain:.3g}, h0/d0 = {h0_d0:.3g} ({b[-1]:.4g} at μ = {mus[-1]:g})")
        k = int(np.argmax(b >= dR_over_h))
        if b[k] == b[k - 1]:
            return float(mus[k])
        return float(mus[k - 1] + (dR_over_h - b[k - 1]) / (b[k] - b[k - 1]) * (mus[k] - mus[k - 1]))


@lru_cache(maxsize=4)
def _load(path: str) -> UpsettingTable:
    p = Path(path)
    try:
        z = np.load(p)
    except FileNotFoundError:
        raise IdentificationError(f"{p}: FE table missing (regenerate: python -m flowcurve.identification.fe.make_table)") from None
    except (OSError, ValueError) as exc:
        raise IdentificationError(f"{p}: FE table unreadable ({exc})") from None
    with z:
        mu = z["mu"]
        if mu[0] != 0.0:
            raise IdentificationError(f"{p}: FE table needs μ = 0 first")
        strain = np.concatenate([[0.0], z["strain"]])
        pad = lambda a, v: np.concatenate([np.full(a.shape[:3] + (1,), v), a], axis=3)  # noqa: E731
        factor = pad(z["force_factor"], 1.0)
        bulge = z["bulge_dR_over_h"] - z["bulge_dR_over_h"][0][None]  # less the μ = 0 mesh offset
        bulge = pad(bulge, 0.0)
        tab = UpsettingTable(mu=mu, h0_d0=z["h0_d0"], n=z["n"], strain=strain, force_factor=factor, bulge=bulge, path=str(p))
    meta_path = p.with_suffix(".json")
    if meta_path.exists():
        object.__setattr__(tab, "meta", json.loads(meta_path.read_text()))
    return tab


def effective_hardening_exponent(eps_p, stress_MPa, start: float = HARDENING_FIT_FROM) -> float:
    """Slope of ln σ over ln ε_p for ε_p ≥ ``start`` (least squares): the table's n axis."""
    # σ ≈ K·ε_p^n → n = d ln σ / d ln ε_p
    e = np.asarray(eps_p, dtype=float)
    s = np.asarray(stress_MPa, dtype=float)
    ok = np.isfinite(e) & np.isfinite(s) & (e >= start) & (s > 0)
    if ok.sum() < 3 or e[ok].max() < 1.5 * start:
        return 0.3  # too short a curve: a mid-range hardening
    return float(np.polyfit(np.log(e[ok]), np.log(s[ok]), 1)[0])


def specimen_proportion(strain, radius_mm, height_mm) -> float:
    """h0/d0 recovered from a volume-constant state: h0 = h·e^ε, d0 = 2r·e^(−ε/2)."""
    # (3.28) d = d0·√(h0/h), ε = ln(h0/h)
    strain = np.asarray(strain, dtype=float)
    h0 = np.asarray(height_mm, dtype=float) * np.exp(strain)
    d0 = 2.0 * np.asarray(radius_mm, dtype=float) * np.exp(-strain / 2.0)
    return float(np.median(h0 / d0))
