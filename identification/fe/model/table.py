"""The FE upsetting table (package data made by :mod:`.make_table`) and its inverse.

The table holds, for μ × h0/d0 × Swift hardening (n, ε0) × strain ε = ln(h0/h):

* the force factor F/(σ_f·A), A = π·d0²·h0/(4h), normalised by the μ = 0 run (CalculiX's own
  0.3–0.6 % mesh deficit cancels);
* the bulge ΔR/h (3.29) as it is measured, on the unloaded specimen against ln(h0/hk)
  (:func:`bulge_as_measured`; 0 at μ = 0);
* the original end face's diameter over d_n under load, less the μ = 0 run's (the rim node's
  mesh lag, 0.2 %): near sticking it still moves with μ where the bulge has stopped;
* the start of the curve, below the first strain (0.02): the force factor of short runs on the
  plastic strain ε_p (``start_plastic_strain``), read at the curve's own ε_p where it is given.
* each run's fold-over onset, read from its force factor (:func:`fold_over_onsets`): where the
  side folds onto the platen the model's force depends on its discretisation (docs/methods.md §4a.7).

Values between grid points: linear in n, ln ε0 and ε and in d0/h0 (the force factor and the
end face: the slab solution's friction term grows with d/h) or ln(h0/d0) (the bulge), then
monotone cubic (PCHIP) along μ; a plane of the table held out is predicted best that way.

The hardening of a measured curve enters as its Swift fit σ ≈ K·(ε0 + ε_p)^n
(:func:`swift_hardening`): n alone (a table of one ε0) does not carry the barrel of a law with a
high yield or a saturating one; the pair does (docs/methods.md §4a). The force factor at a
strain is read at the curve's Swift exponent near that strain (:func:`local_swift_exponent`).
A table without an ε0 axis (the first, n only) still loads, as one ε0.
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
SWIFT_FIT_FROM = 0.002  # the Swift fit (n, ε0) from the 0.2 % offset on
# the force factor at a strain follows the hardening near that strain, not the whole curve's: on a CalculiX record of a
# saturating (Voce) law the factor at ε 0.6 is that of Swift n 0.09 (its local exponent) where the whole-curve fit has
# 0.2 — 1.9 % apart (docs/methods.md §4a.2). The local exponent: least squares over ε_p ± this half-width
LOCAL_HALF_WIDTH = 0.2


@dataclass(frozen=True)
class UpsettingTable:
    mu: np.ndarray
    h0_d0: np.ndarray
    n: np.ndarray
    eps0: np.ndarray  # Swift ε0 (one value in a table of n only)
    strain: np.ndarray  # with a leading 0 (factor 1, bulge 0)
    force_factor: np.ndarray  # (mu, h0_d0, n, eps0, strain)
    bulge: np.ndarray
    reached: np.ndarray  # (mu, h0_d0, n, eps0): the last strain each run converged to (beyond: continued)
    meta: dict = field(default_factory=dict)
    path: str = ""
    face: np.ndarray | None = None  # original end face d/d_n (mu, h0_d0, n, eps0, strain); None in older tables
    start_plastic_strain: np.ndarray | None = None  # ε_p of the start (below the first strain); None in older tables
    start_force_factor: np.ndarray | None = None  # (mu, h0_d0, n, eps0, start_plastic_strain)
    fold_over: np.ndarray | None = None  # (mu, h0_d0, n, eps0): each run's fold-over onset (inf: none), fold_over_onsets

    def fold_over_at(self, mu: float, h0_d0: float, n: float, eps0: float | None = None) -> float | None:
        """The fold-over's onset (strain) for a reading at (μ, h0/d0, n, ε0): the earliest of the
        runs of its cell (the two μ rows around μ, the corners in h0/d0, n and ε0), conservative;
        None when none of them folds over within the table."""
        if self.fold_over is None:
            return None
        m = int(np.clip(np.searchsorted(self.mu, mu), 1, self.mu.size - 1))
        low = min(float(self.fold_over[row, i, j, k]) for row in (m - 1, m) for (i, j, k), _ in self._corners(h0_d0, n, eps0, slender=True))
        return low if math.isfinite(low) else None

    @classmethod
    def load(cls, path: str | Path | None = None) -> "UpsettingTable":
        """The friction table at ``path`` (None: the packaged one)."""
        return _load(str(path or PACKAGE_TABLE))

    # -- interpolation --------------------------------------------------------------------
    def _check(self, h0_d0: float, n: float) -> tuple[float, float]:
        lo, hi = float(self.h0_d0[0]), float(self.h0_d0[-1])
        if not (lo - 1e-9 <= h0_d0 <= hi + 1e-9):
            raise IdentificationError(f"FE table: h0/d0 = {h0_d0:.3g} is outside the table's range {lo:g}–{hi:g} ({self.path})")
        return min(max(h0_d0, lo), hi), float(np.clip(n, self.n[0], self.n[-1]))

    def continued_at(self, mu: float, h0_d0: float, n: float, strain: float, eps0: float | None = None) -> float | None:
        """The smallest last converged strain of the runs a reading at (μ, h0/d0, n, ε0, ε) rests
        on, when it is below ``strain`` (the reading used continued runs); else None."""
        m = int(np.clip(np.searchsorted(self.mu, mu), 1, self.mu.size - 1))  # the two μ rows around μ
        low = float(min(self.reached[row, i, j, k] for row in (m - 1, m) for (i, j, k), _ in self._corners(h0_d0, n, eps0)))
        return low if low < strain - 1e-9 else None

    def clamp_eps0(self, eps0: float | None) -> float:
        """ε0 within the table's range (None: its first, the n-only table's ε0)."""
        return float(self.eps0[0]) if eps0 is None else float(np.clip(eps0, self.eps0[0], self.eps0[-1]))

    @staticmethod
    def _bracket(axis: np.ndarray, x: float) -> tuple[int, float]:
        """(i, w): x = (1 − w)·axis[i] + w·axis[i + 1]; an axis of one value → (0, 0)."""
        if axis.size == 1:
            return 0, 0.0
        i = int(np.clip(np.searchsorted(axis, x) - 1, 0, axis.size - 2))
        return i, (x - axis[i]) / (axis[i + 1] - axis[i])

    def _corners(self, h0_d0: float, n: float, eps0: float | None, slender: bool = False):
        """The grid points (i, j, k) of (h0/d0, n, ε0) a reading weighs and their weights
        (linear in n, ln ε0 and in ln h0/d0, or with ``slender`` in d0/h0); points of zero
        weight left out."""
        from itertools import product

        h0_d0, n = self._check(h0_d0, n)
        proportion = self._bracket(-1.0 / self.h0_d0, -1.0 / h0_d0) if slender else self._bracket(np.log(self.h0_d0), math.log(h0_d0))
        brackets = (proportion, self._bracket(self.n, n),
                    self._bracket(np.log(self.eps0), math.log(self.clamp_eps0(eps0))))
        for steps in product((0, 1), repeat=3):
            weight = math.prod(w if step else 1.0 - w for step, (_, w) in zip(steps, brackets))
            if weight:
                yield tuple(i + step for step, (i, _) in zip(steps, brackets)), weight

    def _mu_rows(self, values: np.ndarray, h0_d0: float, n: float, strain, eps0: float | None = None, axis: np.ndarray | None = None,
                 slender: bool = False) -> np.ndarray:
        """Linear interpolation in ln(h0/d0) (``slender``: d0/h0), n, ln ε0 and ε (or along
        ``axis``, held at its ends) at every grid μ → (n_mu, n_strain)."""
        strain = np.atleast_1d(np.asarray(strain, dtype=float))
        grid = self.strain if axis is None else axis
        block = np.zeros((self.mu.size, grid.size))
        for (i, j, k), weight in self._corners(h0_d0, n, eps0, slender):
            block = block + weight * values[:, i, j, k]
        s = np.clip(strain, grid[0], None)
        out = np.empty((self.mu.size, s.size))
        for m in range(self.mu.size):
            out[m] = np.interp(s, grid, block[m], right=np.nan if axis is None else block[m, -1])
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

    def force_factor_at(self, mu: float, h0_d0: float, n, strain, eps0: float | None = None, eps_p=None) -> np.ndarray:
        """F/(σ_f·A) at the strains ``strain`` (NaN beyond the table). With the plastic strains
        ``eps_p`` of the same points, those below the table's first strain are read from its
        start, on ε_p (held below its first ε_p). ``n`` is one Swift exponent, or one per point
        (the curve's local exponent, :func:`local_swift_exponent`)."""
        strain = np.atleast_1d(np.asarray(strain, dtype=float))
        out = self._along_mu(self._rows_at_n(self.force_factor, h0_d0, n, strain, eps0), mu)
        if eps_p is None or self.start_force_factor is None:
            return out
        early = strain < self.strain[1]
        if early.any():
            eps_p = np.broadcast_to(np.asarray(eps_p, dtype=float), strain.shape)[early]
            n_early = n if not np.ndim(n) else np.broadcast_to(np.asarray(n, dtype=float), strain.shape)[early]
            out[early] = self._along_mu(self._rows_at_n(self.start_force_factor, h0_d0, n_early, eps_p, eps0, axis=self.start_plastic_strain), mu)
        return out

    def _rows_at_n(self, values: np.ndarray, h0_d0: float, n, x: np.ndarray, eps0, axis: np.ndarray | None = None) -> np.ndarray:
        """:meth:`_mu_rows` of the force factor (in d0/h0) at one n or one n per point: the
        reading is linear in n between the table's nodes, so per point it weighs the rows read
        at the two nodes around its n (each node read once for all points)."""
        if not np.ndim(n) or self.n.size == 1:
            return self._mu_rows(values, h0_d0, float(np.mean(n)) if np.ndim(n) else n, x, eps0, axis=axis, slender=True)
        n = np.clip(np.broadcast_to(np.asarray(n, dtype=float), x.shape), self.n[0], self.n[-1])
        j = np.clip(np.searchsorted(self.n, n) - 1, 0, self.n.size - 2)
        w = (n - self.n[j]) / (self.n[j + 1] - self.n[j])
        rows = np.zeros((self.n.size, self.mu.size, x.size))
        for k in np.unique(np.concatenate([j, j + 1])):
            rows[k] = self._mu_rows(values, h0_d0, float(self.n[k]), x, eps0, axis=axis, slender=True)
        points = np.arange(x.size)
        low, high = rows[j, :, points].T, rows[j + 1, :, points].T  # (μ, points)
        return np.where(w == 0.0, low, np.where(w == 1.0, high, (1.0 - w) * low + w * high))

    def bulge_at(self, mu: float, h0_d0: float, n: float, strain, eps0: float | None = None) -> np.ndarray:
        """ΔR/h at the strains ``strain``."""
        return self._along_mu(self._mu_rows(self.bulge, h0_d0, n, strain, eps0), mu)

    def face_at(self, mu: float, h0_d0: float, n: float, strain, eps0: float | None = None) -> np.ndarray:
        """The original end face's diameter over d_n at the strains ``strain``."""
        if self.face is None:
            raise IdentificationError(f"FE table {self.path}: no end-face array (regenerate it)")
        return self._along_mu(self._mu_rows(self.face, h0_d0, n, strain, eps0, slender=True), mu)

    def mu_from_bulge(self, dR_over_h: float, h0_d0: float, n: float, strain: float, *, eps0: float | None = None, clamp: bool = False) -> float:
        """The μ whose bulge at (h0/d0, n, ε) is ``dR_over_h`` (inverse of :meth:`bulge_at`);
        a bulge beyond the table's largest is an error, or with ``clamp`` its largest μ."""
        return self._mu_from(self.bulge, "bulge ΔR/h", dR_over_h, h0_d0, n, strain, eps0, clamp, grows=True)

    def mu_from_face(self, d_over_dn: float, h0_d0: float, n: float, strain: float, *, eps0: float | None = None, clamp: bool = False) -> float:
        """The μ whose original end face at (h0/d0, n, ε) is ``d_over_dn`` of d_n (inverse of
        :meth:`face_at`; the face shrinks with μ); one smaller than the table's smallest is an
        error, or with ``clamp`` its largest μ."""
        if self.face is None:
            raise IdentificationError(f"FE table {self.path}: no end-face array (regenerate it)")
        return self._mu_from(self.face, "end face d/d_n", d_over_dn, h0_d0, n, strain, eps0, clamp, grows=False, slender=True)

    def _mu_from(self, values: np.ndarray, what: str, target: float, h0_d0: float, n: float, strain: float, eps0, clamp: bool, grows: bool,
                 slender: bool = False) -> float:
        from scipy.interpolate import PchipInterpolator

        if not (math.isfinite(target) and math.isfinite(strain) and strain > 0):
            raise IdentificationError(f"FE table: need a finite {what} and a strain > 0 ({what} = {target}, ε = {strain})")
        if strain > self.strain[-1] + 1e-9:
            raise IdentificationError(f"FE table: the final strain ε = {strain:.3g} is beyond the table's {self.strain[-1]:g}")
        col = self._mu_rows(values, h0_d0, n, [strain], eps0, slender=slender)[:, 0]
        ok = np.isfinite(col)
        if ok.sum() < 2:
            raise IdentificationError(f"FE table: no converged runs at h0/d0 = {h0_d0:.3g}, ε = {strain:.3g}")
        sign = 1.0 if grows else -1.0  # read a shrinking quantity as its negative: one code path
        mus = np.linspace(0.0, self.mu[ok][-1], 701)
        b = np.maximum.accumulate(sign * PchipInterpolator(self.mu[ok], col[ok])(mus))  # monotone in μ; flat once the face sticks
        x = sign * target
        if x <= b[0]:
            return 0.0
        if x > b[-1] and clamp:
            return float(mus[-1])
        if x > b[-1]:
            raise IdentificationError(f"FE table: {what} = {target:.4g} is beyond the {'largest' if grows else 'smallest'} the table gives at ε = {strain:.3g}, h0/d0 = {h0_d0:.3g} ({sign * b[-1]:.4g} at μ = {mus[-1]:g})")
        k = int(np.argmax(b >= x))
        if b[k] == b[k - 1]:
            return float(mus[k])
        return float(mus[k - 1] + (x - b[k - 1]) / (b[k] - b[k - 1]) * (mus[k] - mus[k - 1]))


@lru_cache(maxsize=4)
def _load(path: str) -> UpsettingTable:
    p = Path(path)
    try:
        z = np.load(p)
    except FileNotFoundError:
        raise IdentificationError(f"{p}: FE table missing (regenerate: python -m flowcurve.identification.fe.make_table)") from None
    except (OSError, ValueError) as exc:
        raise IdentificationError(f"{p}: FE table unreadable ({exc})") from None
    meta = table_provenance(p)
    with z:
        mu = z["mu"]
        if mu[0] != 0.0:
            raise IdentificationError(f"{p}: FE table needs μ = 0 first")
        strain = np.concatenate([[0.0], z["strain"]])
        factor, bulge = z["force_factor"], z["bulge_dR_over_h"]
        if "eps0" in z:
            eps0 = z["eps0"]
        else:  # the first table: n only, at the Swift ε0 of its provenance
            eps0 = np.array([0.002])
            factor, bulge = factor[:, :, :, None], bulge[:, :, :, None]
        start = {}  # the optional arrays of later tables
        pad = lambda a, v: np.concatenate([np.full(a.shape[:4] + (1,), v), a], axis=4)  # noqa: E731
        material = table_material(meta)
        if material is not None and "force_factor_raw" in z and "eps0" in z:
            bulge = bulge_as_measured(bulge, z["force_factor_raw"], z["strain"], z["h0_d0"], z["n"], eps0, **material)
        else:  # an older table without its raw force or material: under load, less the μ = 0 run's largest radius
            log.warning("%s: no raw force factor or material in the FE table; its bulge is read under load (regenerate the table)", p)
            bulge = bulge - bulge[0][None]
        bulge = pad(bulge, 0.0)
        factor = pad(factor, 1.0)
        reached = np.where(np.isnan(factor), -np.inf, strain).max(axis=-1)
        start["fold_over"] = fold_over_onsets(factor, strain, reached)
        if "face_d_over_dn" in z:
            face = pad(z["face_d_over_dn"], 1.0)
            start["face"] = continue_stopped_runs(face - (face[0][None] - 1.0), "mu_scaled")  # less the μ = 0 run's mesh offset
        if "start_force_factor" in z:
            start.update(start_plastic_strain=z["start_plastic_strain"], start_force_factor=continue_stopped_runs(z["start_force_factor"]))
        tab = UpsettingTable(mu=mu, h0_d0=z["h0_d0"], n=z["n"], eps0=eps0, strain=strain, force_factor=continue_stopped_runs(factor),
                             bulge=continue_stopped_runs(bulge, "mean"), reached=reached, path=str(p), **start)
    object.__setattr__(tab, "meta", meta)
    return tab


def table_material(meta: dict) -> dict | None:
    """The Swift K, E and ν the table's runs were made with (from its provenance ``meta``), or None."""
    material = meta.get("material", {})
    if not all(k in material for k in ("K_MPa", "E_MPa", "nu")):
        return None
    return {"K_MPa": float(material["K_MPa"]), "E_MPa": float(material["E_MPa"]), "nu": float(material["nu"])}


def plastic_strain_at(eps, flow, *, E: float, iterations: int = 8):
    """ε_p with ε_p + σ_f(ε_p)/E = ε (fixed point; σ/E ≪ 1)."""
    # (3.7) ε_p = ε − σ/E
    eps_p = np.asarray(eps, dtype=float).copy()
    for _ in range(iterations):
        eps_p = np.clip(eps - flow(eps_p) / E, 0.0, None)
    return eps_p


def swift_stress_on_grid(strain, n, eps0, K_MPa: float, E_MPa: float) -> np.ndarray:
    """σ_f = K·(ε0 + ε_p)^n of the table's runs at the height strains ``strain``, with
    ε_p = ε − σ_f/E (:func:`plastic_strain_at`) → shape (n, ε0, strain)."""
    n = np.asarray(n, dtype=float)[:, None, None]
    eps0 = np.asarray(eps0, dtype=float)[None, :, None]
    e = np.broadcast_to(np.asarray(strain, dtype=float)[None, None, :], (n.shape[0], eps0.shape[1], np.size(strain)))

    def flow(eps_p):
        """Swift flow stress K·(ε0 + εp)^n, MPa."""
        return K_MPa * np.power(eps0 + eps_p, n)

    return flow(plastic_strain_at(e, flow, E=E_MPa))


def table_provenance(path) -> dict:
    """The provenance beside a table file (its ``.json``), {} when there is none."""
    meta_path = Path(path).with_suffix(".json")
    return json.loads(meta_path.read_text()) if meta_path.exists() else {}


def bulge_as_measured(bulge, factor_raw, strain, h0_d0, n, eps0, *, K_MPa: float, E_MPa: float, nu: float) -> np.ndarray:
    """The runs' bulge ΔR/h as it is measured: on the unloaded specimen, against its height hk.

    ``bulge`` (μ, h0/d0, n, ε0, ε) is what the runs printed under load: (d_max − d_n)/(2h) with
    d_n = d0·√(h0/h) at ε = ln(h0/h). Under load the specimen is elastically compressed: its
    volume is V0·(1 − (1 − 2ν)·σ/E), so even without friction d_max lies below d_n (by
    (½ − ν)·σ/E·d_n, ~0.001 in ΔR/h at ε 0.7). After the test the elastic part springs back,
    h → h·(1 + σ/E) and d → d·(1 − ν·σ/E), σ = F/A the mean axial stress (``factor_raw``·σ_f),
    the same spring-back the inverse FE and the FE records apply. The result is on the same grid
    of the measured strain ln(h0/hk) (a run's last ~0.005 of strain continued linearly); NaN
    where a run did not reach.

    The μ = 0 row is 0: without friction there is no barrel. The μ = 0 runs' largest radius is
    the rim corner's mesh bump (at 0.8–0.95 of the half height; at d0 6, h 3 it stands 0.0071 mm
    above the mid-plane with 24 elements, 0.0022 mm with 64, while the mid-plane radius is the
    homogeneous one within 0.8 µm), not a barrel; with friction the barrel at mid-height is the
    largest radius. The table used to subtract that bump from every row and read the bulge under
    load: together 0.0006–0.0018 low in ΔR/h at ε 0.7, μ 0.03–0.04 high near sticking.
    """
    # (3.28) d_n = d0·√(h0/h); (3.29) ΔR/h = (d_max − d_n)/(2h); elastic spring-back h(1 + σ/E), d(1 − ν·σ/E)
    bulge = np.asarray(bulge, dtype=float)
    eps_l = np.asarray(strain, dtype=float)
    s = np.asarray(factor_raw, dtype=float) * swift_stress_on_grid(eps_l, n, eps0, K_MPa, E_MPa)[None, None] / E_MPa
    h_l = np.asarray(h0_d0, dtype=float)[None, :, None, None, None] * np.exp(-eps_l)  # in units of d0
    d_max = np.exp(eps_l / 2.0) + 2.0 * h_l * bulge
    h_u = h_l * (1.0 + s)
    eps_u = eps_l - np.log1p(s)
    measured = (d_max * (1.0 - nu * s) - np.exp(eps_u / 2.0)) / (2.0 * h_u)
    out = np.full(bulge.shape, np.nan)
    for run in np.ndindex(bulge.shape[:-1]):
        ok = np.isfinite(measured[run]) & np.isfinite(eps_u[run])
        if ok.sum() < 2:
            continue
        x, y = eps_u[run][ok], measured[run][ok]
        reach = eps_l[ok][-1]  # the loaded strain it got to: the grid up to there is the run's
        row = np.interp(eps_l, x, y)
        beyond = eps_l > x[-1]
        row[beyond] = y[-1] + (eps_l[beyond] - x[-1]) * (y[-1] - y[-2]) / (x[-1] - x[-2])
        out[run] = np.where(eps_l <= reach + 1e-12, row, np.nan)
    out[0] = 0.0
    return out


# the side folding onto the platen shows in a run's force factor as its first upward jump after the slow decline: a
# step's relative rise exceeds the step before's by more than this (steps of 0.02 in ε). Over the table's μ > 0 runs
# from ε 0.1, 90 % of the step-to-step changes are below 0.23 % (the mesh's sawtooth alternates by ±0.05 %); the
# fold-over's first step is 0.4–1.3 %. The step's start is within 0.02 of the model's geometric onset
# (UpsettingResult.fold_over_strain) on the runs compared in docs/methods.md §4a.7.
FOLD_OVER_JUMP = 0.003
FOLD_OVER_FROM = 0.1  # the elastic–plastic start's curvature is not a fold-over


def fold_over_onsets(factor: np.ndarray, strain: np.ndarray, reached: np.ndarray, jump: float = FOLD_OVER_JUMP,
                     start: float = FOLD_OVER_FROM) -> np.ndarray:
    """Per run of ``factor`` (…, strain; the runs as they stopped, NaN beyond): the strain at the start
    of the first step from ``start`` on whose relative rise exceeds the step before's by ``jump``,
    or where the run stopped (``reached`` below the last strain: it stops as its side folds), the
    earlier; inf where neither."""
    # Δ_k = (F_k+1 − F_k)/F_k; onset: first ε_k+1 ≥ start with Δ_k+1 − Δ_k > jump
    with np.errstate(invalid="ignore", divide="ignore"):
        rise = np.diff(factor, axis=-1) / factor[..., :-1]
    change = np.diff(rise, axis=-1)
    begins = np.asarray(strain, float)[1:-1]
    hit = np.nan_to_num(change, nan=-np.inf) > jump
    hit &= begins >= start
    onset = np.where(hit.any(axis=-1), begins[np.argmax(hit, axis=-1)], np.inf)
    stopped = reached < strain[-1] - 1e-9
    return np.where(stopped, np.minimum(onset, reached), onset)


# how a stopped run's tail is continued, per array (measured on the table's complete runs cut at ε 0.3/0.4/0.5 and
# continued to 0.7, 166 runs each, tests/fe/test_table_continuation.py): the bulge's difference to the run one μ step
# lower grows with ε, so holding it ("difference") read ΔR/h low by 0.0014–0.0036 on average (max 0.0095) and holding
# the ratio read it high by 0.002–0.004; their mean is within ±0.0002 (max 0.006). The end face's departure from the
# lower run scales with that run's own departure from the one below it ("mu_scaled"): mean −0.003, rms 0.011 in d/d_n,
# where holding the difference read it 0.02–0.04 high. The force factor keeps the difference (mean −1 %, the ratio no better).
CONTINUATION_RULES = ("difference", "mean", "mu_scaled")


def continue_stopped_runs(values: np.ndarray, rule: str = "difference") -> np.ndarray:
    """NaN tails (a run that stopped with too many cutbacks as the side folds onto the platen)
    continued along the run one μ step lower, which the μ = 0 runs anchor, strain step by strain
    step, with ``rule``:

    * ``difference``: v(μ_k, ε_s) = v(μ_k, ε_s−1) + v(μ_k−1, ε_s) − v(μ_k−1, ε_s−1);
    * ``mean``: the mean of that and of the ratio held, v(μ_k, ε_s−1)·v(μ_k−1, ε_s)/v(μ_k−1, ε_s−1);
    * ``mu_scaled``: v(μ_k) − v(μ_k−1) scales with v(μ_k−1) − v(μ_k−2) as at ε_s−1 (``difference`` at μ_1).

    An estimate, not a run: :meth:`UpsettingTable.continued_at` says when a reading used it."""
    if rule not in CONTINUATION_RULES:
        raise ValueError(f"unknown continuation rule {rule!r}")
    out = values.copy()
    if np.isnan(out[0]).any():
        raise IdentificationError("FE table: the μ = 0 runs must be complete (they anchor the continuation of stopped runs)")
    for i in range(1, out.shape[0]):
        row, ref = out[i], out[i - 1]
        for s in range(1, out.shape[-1]):
            gap = np.isnan(row[..., s])
            if not gap.any():
                continue
            prev, step = row[..., s - 1], ref[..., s] - ref[..., s - 1]
            held = prev + step
            with np.errstate(divide="ignore", invalid="ignore"):
                if rule == "mean":
                    ratio = np.where(np.abs(ref[..., s - 1]) > 1e-12, prev * ref[..., s] / ref[..., s - 1], held)
                    held = 0.5 * (held + ratio)
                elif rule == "mu_scaled" and i >= 2:
                    below = ref[..., s - 1] - out[i - 2][..., s - 1]
                    scale = (prev - ref[..., s - 1]) / below
                    held = np.where(np.abs(below) > 1e-12, ref[..., s] + scale * (ref[..., s] - out[i - 2][..., s]), held)
            row[..., s] = np.where(gap, held, row[..., s])
    return out


def _log_curve_on_grid(eps_p, stress_MPa, start: float, size: int):
    """(uniform ε_p grid from ``start`` on, ln σ on it), so that the samples' density does not
    weigh a fit; None for a curve too short to fit (< 5 samples, or ending before 10 × start)."""
    e = np.asarray(eps_p, dtype=float)
    s = np.asarray(stress_MPa, dtype=float)
    ok = np.isfinite(e) & np.isfinite(s) & (e >= start) & (s > 0)
    if ok.sum() < 5 or e[ok].max() < 10 * start:
        return None
    order = np.argsort(e[ok], kind="stable")
    e, s = e[ok][order], s[ok][order]
    grid = np.linspace(e[0], e[-1], size)
    return grid, np.log(np.interp(grid, e, s))


def swift_hardening(eps_p, stress_MPa, start: float = SWIFT_FIT_FROM) -> tuple[float, float]:
    """(n, ε0) of the Swift law σ = K·(ε0 + ε_p)^n fitted to the curve for ε_p ≥ ``start``:
    the table's hardening axes. Least squares in ln σ on a uniform ε_p grid (the samples'
    density does not weigh), linear in (ln K, n) at each ε0, ε0 by a bounded scalar search."""
    # ln σ = ln K + n·ln(ε0 + ε_p)
    from scipy.optimize import minimize_scalar

    curve = _log_curve_on_grid(eps_p, stress_MPa, start, 200)
    if curve is None:
        return 0.3, 0.002  # too short a curve: a mid-range hardening
    grid, ln_s = curve

    def fit(log_eps0):
        """(coefficients, squared residual) of the Swift line in log space at ``log_eps0``."""
        A = np.column_stack([np.ones_like(grid), np.log(math.exp(log_eps0) + grid)])
        coef, *_ = np.linalg.lstsq(A, ln_s, rcond=None)
        return coef, float(np.sum((A @ coef - ln_s) ** 2))

    best = minimize_scalar(lambda x: fit(x)[1], bounds=(math.log(1e-5), math.log(2.0)), method="bounded", options={"xatol": 1e-3})
    coef, _ = fit(best.x)
    return float(coef[1]), float(math.exp(best.x))


def local_swift_exponent(eps_p, stress_MPa, eps0: float, at, *, half_width: float | None = None, start: float = SWIFT_FIT_FROM,
                         fallback: float | None = None) -> np.ndarray:
    """The Swift exponent of the curve near each strain of ``at``: the slope of ln σ against
    ln(ε0 + ε_p) by least squares over ε_p within ± ``half_width`` (cut at the curve's ends;
    held beyond them). For a Swift curve of this ε0 it is n everywhere; for a saturating law it
    falls with the strain. Too short a curve: ``fallback`` everywhere."""
    # n(ε) = d ln σ / d ln(ε0 + ε_p), windowed least squares on a uniform ε_p grid (sums by cumulative sums)
    at = np.asarray(at, dtype=float)
    curve = _log_curve_on_grid(eps_p, stress_MPa, start, 400)
    if curve is None:
        return np.full(at.shape, np.nan if fallback is None else fallback)
    grid, y = curve
    x = np.log(eps0 + grid)
    half_width = LOCAL_HALF_WIDTH if half_width is None else half_width
    sums = [np.concatenate([[0.0], np.cumsum(v)]) for v in (np.ones_like(x), x, y, x * x, x * y)]
    lo = np.searchsorted(grid, grid - half_width, side="left")
    hi = np.searchsorted(grid, grid + half_width, side="right")
    c, sx, sy, sxx, sxy = (v[hi] - v[lo] for v in sums)
    slope = (c * sxy - sx * sy) / np.maximum(c * sxx - sx * sx, 1e-300)
    return np.interp(at, grid, slope)


def specimen_proportion(strain, radius_mm, height_mm) -> float:
    """h0/d0 recovered from a volume-constant state: h0 = h·e^ε, d0 = 2r·e^(−ε/2)."""
    # (3.28) d = d0·√(h0/h), ε = ln(h0/h)
    strain = np.asarray(strain, dtype=float)
    h0 = np.asarray(height_mm, dtype=float) * np.exp(strain)
    d0 = 2.0 * np.asarray(radius_mm, dtype=float) * np.exp(-strain / 2.0)
    return float(np.median(h0 / d0))
