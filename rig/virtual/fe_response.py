"""The virtual rig's compression response from its own copy of CalculiX upsetting runs (docs/methods.md §4.7).

``data/upsetting_response.npz`` (written by ``python -m flowcurve.identification.fe.make_table
--virtual-copy-only``; provenance in the ``.json`` beside it) holds, over μ × h0/d0 × Swift n ×
strain ε = ln(h0/h):

* ``force_factor`` F/(σ_f·A), A = π·d0²·h0/(4h), normalised by the μ = 0 run;
* ``bulge_dR_over_h`` ΔR/h of the barrel as measured on the unloaded specimen, against ln(h0/hk)
  (the table's ``bulge_as_measured``; 0 at μ = 0).

The rig layer may not import :mod:`flowcurve.identification`, so this module reads the copy
and interpolates it with code of its own. What it does with the table's gaps and edges:

* **Stopped runs.** 35 of the 112 CalculiX runs stopped early (too many cutbacks near
  sticking, all at μ ≥ 0.15); their tails are NaN in the file. Each missing point is filled
  by continuing the run with the strain increments of its neighbour one μ step lower (same
  h0/d0 and n), processed in increasing μ so that neighbour is complete: no jump where the run
  stopped, and the shape of a nearby converged run after it. Logged at load (INFO).
* **ε = 0.** The file's leading ε = 0 column (factor 1, bulge 0) is padding, not a run result:
  friction acts from the first yield (the slab solution gives 1 + c/3 there, not 1), so the
  force factor below the first computed strain is held at that strain's value; the bulge does
  go to 0 at ε = 0. Between 0 and the long runs' first strain (0.02) the copy holds the short
  runs' factor on the plastic strain (the table's start, 0.0005–0.015), the axis the rig reads.
* **Edges.** μ, h0/d0 and n are clamped to the table's range (a μ above the largest is near
  sticking already); beyond the last strain the force factor is held and the bulge continues
  with its slope over the last 0.1 of strain.

Interpolation is multilinear in (μ, ln h0/d0, n, ε): it returns the table's values at its
nodes and stays between neighbouring nodes.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from flowcurve.errors import ConfigError
from flowcurve.rig.virtual.fe_data import read_arrays, read_provenance

log = logging.getLogger(__name__)

DATA = Path(__file__).resolve().parent / "data" / "upsetting_response.npz"
BULGE_SLOPE_SPAN = 0.1  # strain span of the bulge's slope continued beyond the table
HARDENING_FIT_RANGE = (0.05, 0.9)  # plastic strains of the effective exponent (the table's ε range)


@dataclass(frozen=True)
class UpsettingResponse:
    """The FE compression response: force factor and bulge over (μ, h0/d0, n, ε)."""

    mu: np.ndarray
    h0_d0: np.ndarray
    n: np.ndarray
    strain: np.ndarray  # ln(h0/h), from 0
    force_factor: np.ndarray  # (mu, h0_d0, n, strain), no NaN
    bulge_dR_over_h: np.ndarray  # (mu, h0_d0, n, strain), no NaN
    filled_runs: tuple = ()  # (mu, h0_d0, n, last computed strain) of the runs whose tail was filled
    meta: dict = field(default_factory=dict)
    path: str = ""

    @classmethod
    def load(cls, path: str | Path | None = None) -> "UpsettingResponse":
        """The compression response at ``path`` (None: the packaged one)."""
        return _load(str(path or DATA))

    # -- interpolation ----------------------------------------------------------------------
    def _corners(self, values: np.ndarray, mu, h0_d0, n, strain) -> np.ndarray:
        """Multilinear interpolation at broadcast (μ, h0/d0, n, ε), every axis clamped."""
        # multilinear interpolation in (μ, ln h0/d0, n, ε) of the CalculiX upsetting runs
        coords = [(self.mu, np.asarray(mu, float)), (np.log(self.h0_d0), np.log(np.asarray(h0_d0, float))),
                  (self.n, np.asarray(n, float)), (self.strain, np.asarray(strain, float))]
        idx, wts = [], []
        for grid, x in coords:
            x = np.clip(x, grid[0], grid[-1])
            i = np.clip(np.searchsorted(grid, x, side="right") - 1, 0, grid.size - 2)
            idx.append(i)
            wts.append((x - grid[i]) / (grid[i + 1] - grid[i]))
        idx = np.broadcast_arrays(*idx)
        wts = np.broadcast_arrays(*wts)
        out = np.zeros(idx[0].shape)
        for corner in range(16):
            bits = [(corner >> a) & 1 for a in range(4)]
            w = np.ones(idx[0].shape)
            for a, b in enumerate(bits):
                w = w * (wts[a] if b else 1.0 - wts[a])
            out = out + w * values[idx[0] + bits[0], idx[1] + bits[1], idx[2] + bits[2], idx[3] + bits[3]]
        return out

    def force_factor_at(self, mu, h0_d0, n, strain) -> np.ndarray:
        """F/(σ_f·A) at (μ, h0/d0, n, ε = ln(h0/h)), arrays broadcast; held beyond the last ε."""
        return self._corners(self.force_factor, mu, h0_d0, n, strain)

    def bulge_at(self, mu, h0_d0, n, strain) -> np.ndarray:
        """ΔR/h of the barrel at (μ, h0/d0, n, ε), arrays broadcast; continued linearly beyond the last ε."""
        strain = np.asarray(strain, float)
        out = self._corners(self.bulge_dR_over_h, mu, h0_d0, n, strain)
        end = float(self.strain[-1])
        beyond = np.maximum(strain - end, 0.0)
        if np.any(beyond > 0):
            at_end = self._corners(self.bulge_dR_over_h, mu, h0_d0, n, end)
            before = self._corners(self.bulge_dR_over_h, mu, h0_d0, n, end - BULGE_SLOPE_SPAN)
            out = out + beyond * (at_end - before) / BULGE_SLOPE_SPAN
        return out

    def in_range(self, mu: float, h0_d0: float, n: float) -> list[str]:
        """What of (μ, h0/d0, n) lies outside the table (and is clamped), as messages."""
        out = []
        for name, grid, x in (("μ", self.mu, mu), ("h0/d0", self.h0_d0, h0_d0), ("n", self.n, n)):
            if not (grid[0] - 1e-9 <= x <= grid[-1] + 1e-9):
                out.append(f"{name} = {x:.3g} is outside the FE table's {grid[0]:g}–{grid[-1]:g}: clamped")
        return out


def _fill_stopped_runs(values: np.ndarray, mu: np.ndarray, h0_d0: np.ndarray, n: np.ndarray, strain: np.ndarray):
    """Fill NaN points with the strain increments of the run one μ step lower (see the module
    docstring); returns the filled array and (μ, h0/d0, n, last computed ε) per filled run."""
    out = values.copy()
    filled = []
    if np.isnan(out[0]).any():
        raise ConfigError("FE response: the μ = 0 runs must be complete (they are the reference of the fill)")
    for i in range(1, mu.size):
        for j in range(h0_d0.size):
            for k in range(n.size):
                row, ref = out[i, j, k], out[i - 1, j, k]
                gaps = np.nonzero(np.isnan(row))[0]
                if not gaps.size:
                    continue
                for s in gaps:  # s ≥ 1: ε = 0 is always set
                    row[s] = row[s - 1] + (ref[s] - ref[s - 1])
                filled.append((float(mu[i]), float(h0_d0[j]), float(n[k]), float(strain[gaps[0] - 1])))
    return out, tuple(filled)


@lru_cache(maxsize=2)
def _load(path: str) -> UpsettingResponse:
    p = Path(path)
    z = read_arrays(p, ("mu", "h0_d0", "n", "strain", "force_factor", "bulge_dR_over_h"), "the virtual rig's FE response",
                    "python -m flowcurve.identification.fe.make_table --virtual-copy-only")
    mu, h0_d0, n, strain = z["mu"], z["h0_d0"], z["n"], z["strain"]
    factor, bulge = z["force_factor"], z["bulge_dR_over_h"]
    if mu[0] != 0.0 or strain[0] != 0.0:
        raise ConfigError(f"{p}: the FE response needs μ = 0 and ε = 0 first")
    factor, filled = _fill_stopped_runs(factor, mu, h0_d0, n, strain)
    bulge, _ = _fill_stopped_runs(bulge, mu, h0_d0, n, strain)
    factor[..., 0] = factor[..., 1]  # friction acts from the first yield: the padded 1 at ε = 0 is not a result
    if filled:
        log.info("FE response %s: %d stopped CalculiX runs continued with their lower-μ neighbour's increments: %s", p.name,
                 len(filled), ", ".join(f"μ {m:g} h0/d0 {h:g} n {e:g} after ε {s:.2f}" for m, h, e, s in filled))
    return UpsettingResponse(mu=mu, h0_d0=h0_d0, n=n, strain=strain, force_factor=factor, bulge_dR_over_h=bulge,
                             filled_runs=filled, meta=read_provenance(p), path=str(p))


def effective_hardening_exponent(flow_stress, strain_range=HARDENING_FIT_RANGE, points: int = 60) -> float:
    """The Swift exponent a flow curve looks like to the table: the least-squares slope of
    ln σ over ln ε_p on ``points`` strains evenly spread over ``strain_range``."""
    # σ ≈ K·ε_p^n → n = d ln σ / d ln ε_p
    eps = np.linspace(strain_range[0], strain_range[1], points)
    sigma = np.asarray(flow_stress(eps), float)
    if not np.all(np.isfinite(sigma) & (sigma > 0)):
        raise ConfigError("FE response: the flow curve must be positive and finite for the hardening exponent")
    slope = float(np.polyfit(np.log(eps), np.log(sigma), 1)[0])
    return slope if math.isfinite(slope) else 0.0
