"""The virtual rig's tension neck from its own copy of CalculiX necking runs (docs/methods.md §3.6).

``data/tension_response.npz`` (``python -m flowcurve.identification.fe.make_tension_response``;
provenance in the ``.json`` beside it) holds, for Swift laws σ = K·(ε0 + ε_p)^n over n and the
neck's plastic strain ε_n = 2·ln(a0/a): the force factor β = F/(σ_f(ε_n)·π·a²), the neck
elongation over d0 λ and the profile's a/R. :meth:`TensionResponse.curve` reads them for any
material: the neck starts at the Considère strain ε_u (dσ/dε_p = σ); at δ = ε_n − ε_u the runs are
picked by the material's θ/σ read as a Swift exponent n = (θ/σ)·δ/(1 − θ/σ) and interpolated
linearly in n and ε_n; β and λ are taken relative to each run's onset, and beyond the last strain a
run reached every quantity continues with its slope over ``CONTINUATION_SPAN``. The rig layer may
not import :mod:`flowcurve.identification`: the interpolation is this module's own.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from flowcurve.errors import ConfigError
from flowcurve.rig.virtual.fe_data import read_arrays, read_provenance

log = logging.getLogger(__name__)

DATA = Path(__file__).resolve().parent / "data" / "tension_response.npz"
CONTINUATION_SPAN = 0.1  # strain span of the slope continued beyond the last computed strain
QUANTITIES = ("force_factor", "neck_elongation_over_d0", "neck_a_over_R")


def equivalent_swift_exponent(hardening_ratio, delta):
    """# n = (θ/σ)·δ/(1 − θ/σ): the Swift law (ε0 ≪ n) with the same θ/σ = n/(n + δ) at δ past its force maximum."""
    r = np.minimum(np.asarray(hardening_ratio, float), 1.0 - 1e-12)
    return r * np.asarray(delta, float) / (1.0 - r)


def interp_continued(x, xp: np.ndarray, fp: np.ndarray, span: float = CONTINUATION_SPAN) -> np.ndarray:
    """np.interp within [xp[0], xp[-1]]; beyond xp[-1] the slope over the last ``span`` continued."""
    x = np.asarray(x, float)
    out = np.interp(x, xp, fp)
    end = float(xp[-1])
    beyond = np.maximum(x - end, 0.0)
    if np.any(beyond > 0):
        slope = (fp[-1] - np.interp(end - span, xp, fp)) / span
        out = out + beyond * slope
    return out


@dataclass(frozen=True)
class NeckCurve:
    """The FE neck of one material, over the strain beyond its onset δ = ε_n − ε_u ≥ 0."""

    considere_strain: float  # the material's ε_u the curve was made for
    delta: np.ndarray
    force_factor: np.ndarray  # β(δ)/β(0)
    elongation_over_d0: np.ndarray  # λ(δ) − λ(0)
    a_over_R: np.ndarray
    table_end: float  # beyond this δ the curve is a continuation, not FE

    def factor_at(self, delta):
        """F/(σ_f(ε_n)·A0·e^(−ε_n)) at δ = ε_n − ε_u (1 at the onset)."""
        return interp_continued(np.maximum(delta, 0.0), self.delta, self.force_factor)

    def elongation_over_d0_at(self, delta):
        """The neck's elongation since the onset, in units of d0 (0 at the onset)."""
        return interp_continued(np.maximum(delta, 0.0), self.delta, self.elongation_over_d0)

    def a_over_R_at(self, delta):
        """a/R of the neck profile."""
        return interp_continued(np.maximum(delta, 0.0), self.delta, self.a_over_R)


@dataclass(frozen=True)
class TensionResponse:
    """The FE necking runs: β, λ and a/R over (Swift n, ε_n)."""

    n: np.ndarray
    considere_strain: np.ndarray  # n − ε0 per run
    neck_strain: np.ndarray  # ε_n grid
    force_factor: np.ndarray  # (n, ε_n), NaN where a run did not reach
    neck_elongation_over_d0: np.ndarray
    neck_a_over_R: np.ndarray
    reached: np.ndarray  # last finite ε_n per run (all three quantities)
    meta: dict = field(default_factory=dict)
    path: str = ""

    @classmethod
    def load(cls, path: str | Path | None = None) -> "TensionResponse":
        """The tension response at ``path`` (None: the packaged one)."""
        return _load(str(path or DATA))

    def out_of_range(self, n_eff, delta) -> list[str]:
        """What of an equivalent-exponent history lies outside the runs' n (and is clamped), as messages."""
        n_eff, delta = np.asarray(n_eff, float), np.asarray(delta, float)
        out = []
        for side, bad, bound in (("below", n_eff < self.n[0] - 1e-9, self.n[0]), ("above", n_eff > self.n[-1] + 1e-9, self.n[-1])):
            if bad.any():
                d = delta[bad]
                out.append(f"the neck's equivalent Swift exponent is {side} the FE necking runs' {bound:g} for δ = ε_n − ε_u "
                           f"{d.min():.2f}–{d.max():.2f}: clamped")
        return out

    def run_at(self, k: int, quantity: str, eps_n) -> np.ndarray:
        """Run k's ``quantity`` at neck strains eps_n (continued beyond the strain it reached)."""
        row = getattr(self, quantity)[k]
        ok = np.isfinite(row)
        return interp_continued(eps_n, self.neck_strain[ok], row[ok])

    def weights(self, n_eff) -> np.ndarray:
        """(runs, points) weights linear in n between the two runs bracketing each n_eff (clamped)."""
        x = np.clip(np.asarray(n_eff, float), self.n[0], self.n[-1])
        return np.array([np.interp(x, self.n, np.eye(self.n.size)[k]) for k in range(self.n.size)])

    def curve(self, considere_strain: float, hardening_ratio, delta_end: float = 3.0, step: float = 0.005,
              fracture_delta: float | None = None) -> NeckCurve:
        """The neck of a material whose force maximum is at ``considere_strain`` and whose
        θ/σ at plastic strain ε is ``hardening_ratio(ε)`` (see the module docstring)."""
        cs = self.considere_strain
        delta = np.round(np.arange(0.0, delta_end + 1e-12, step), 6)
        d_eval = np.maximum(delta, step)  # θ/σ → 1 at the onset: n_eff is a limit there, taken one step on
        n_eff = equivalent_swift_exponent(hardening_ratio(considere_strain + d_eval), d_eval)
        upto = delta <= (delta_end if fracture_delta is None else fracture_delta)
        for message in self.out_of_range(n_eff[upto & (delta >= 0.05)], delta[upto & (delta >= 0.05)]):
            log.warning("virtual rig: %s", message)
        w = self.weights(n_eff)
        runs = {q: np.array([self.run_at(k, q, cs[k] + delta) for k in range(cs.size)]) for q in QUANTITIES}
        beta = runs["force_factor"] / runs["force_factor"][:, :1]  # each run relative to its onset
        lam = runs["neck_elongation_over_d0"] - runs["neck_elongation_over_d0"][:, :1]
        lam = np.maximum.accumulate(np.sum(w * lam, axis=0))  # the neck does not shorten
        used = np.any(w[:, upto] > 0, axis=1) if upto.any() else np.any(w > 0, axis=1)  # (fracture before the neck)
        end = float(min(self.reached[k] - cs[k] for k in np.nonzero(used)[0]))
        return NeckCurve(float(considere_strain), delta, np.sum(w * beta, axis=0), lam,
                         np.maximum(np.sum(w * runs["neck_a_over_R"], axis=0), 0.0), end)


@lru_cache(maxsize=2)
def _load(path: str) -> TensionResponse:
    p = Path(path)
    arrays = read_arrays(p, ("n", "considere_strain", "neck_strain", *QUANTITIES), "the virtual rig's FE tension response",
                         "python -m flowcurve.identification.fe.make_tension_response")
    cs, eps = arrays["considere_strain"], arrays["neck_strain"]
    shape = (cs.size, eps.size)
    if cs.size < 2 or np.any(np.diff(cs) <= 0) or np.any(np.diff(eps) <= 0):
        raise ConfigError(f"{p}: the FE tension response needs ≥ 2 runs in rising n and a rising strain grid")
    if any(arrays[q].shape != shape for q in QUANTITIES):
        raise ConfigError(f"{p}: the FE tension response's arrays are not (runs, strains) = {shape}")
    finite = np.all([np.isfinite(arrays[q]) for q in QUANTITIES], axis=0)
    reached = np.array([eps[np.nonzero(row)[0][-1]] if row.any() else -np.inf for row in finite])
    short = [f"n {n:g}" for n, r, c in zip(arrays["n"], reached, cs) if not r > c + 2 * CONTINUATION_SPAN]
    if short:
        raise ConfigError(f"{p}: FE necking runs ({', '.join(short)}) stop before their force maximum is well passed")
    return TensionResponse(arrays["n"], cs, eps, arrays["force_factor"], arrays["neck_elongation_over_d0"],
                           arrays["neck_a_over_R"], reached, read_provenance(p), str(p))
