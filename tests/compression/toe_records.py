"""Compression records with a soft start (toe): the crosshead runs at constant speed while the
platens seat, so the force rises slowly over the first ``toe_mm`` of travel.

Forward model as in conftest (Johnson–Cook flow curve, elastic strain σ/E, volume constancy,
Coulomb slab pressure integrated numerically), on a dense strain grid, then inverted on the
crosshead: travel = specimen shortening + P/C + seating(P), seating(P) = toe·(1 − (1 − P/P_toe)²)
below P_toe. The crosshead moves at constant speed; samples at ``rate_hz``, 10 µm encoder steps,
force noise.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from flowcurve.record.format import Record

from .conftest import E_HANDBOOK_MPa, SEED_LAW, flow_stress


def mean_pressure_factor(mu: float, r_over_h: np.ndarray) -> np.ndarray:
    """p_mean/σ_f: trapezoidal integral of exp(2μ(R − r)/h)·2(r/R) over the face (vectorized)."""
    s = np.linspace(0.0, 1.0, 2001)
    f = np.exp(2 * mu * np.asarray(r_over_h)[:, None] * (1 - s)[None, :]) * (2 * s)[None, :]
    return np.sum((f[:, 1:] + f[:, :-1]) / 2 * np.diff(s)[None, :], axis=1)


def make_toe_compression(*, toe_mm=0.05, toe_force_N=600.0, rate_hz=10.0, mu=0.11, d0=5.989, h0=6.982,
                         eps_end=0.65, speed=0.01, stiffness=136.0, step_mm=0.01, noise_N=20.0, seed=2,
                         law=SEED_LAW, E=E_HANDBOOK_MPa, handbook_E=False):
    """(Record, truth): truth["rp02_pressure_MPa"] is the mean pressure at εp = 0.002 of the model,
    truth["springback_mm"] the elastic height the unloading gives back."""
    rng = np.random.default_rng(seed)
    eps_el = np.linspace(0.0, law["A"] / E, 400, endpoint=False)
    eps_p = np.concatenate([np.zeros_like(eps_el), np.geomspace(1e-6, eps_end, 4000)])
    sigma = np.concatenate([E * eps_el, flow_stress(eps_p[eps_el.size:], **law)])
    eps = eps_p + sigma / E
    h = h0 * np.exp(-eps)
    r = d0 / 2 * np.sqrt(h0 / h)
    force = sigma * math.pi * r**2 * mean_pressure_factor(mu, r / h)
    seat = toe_mm * (1 - np.clip(1 - force / toe_force_N, 0, 1) ** 2)
    travel = (h0 - h) + force / (stiffness * 1000.0) + seat
    t = np.arange(0.0, travel[-1] / speed, 1.0 / rate_hz)
    F = np.interp(speed * t, travel, force)
    hh = np.interp(speed * t, travel, h)
    # unloading in 10 s, elastic
    t_un = np.arange(1, int(10 * rate_hz) + 1) / rate_hz
    frac = 1 - t_un / t_un[-1]
    F_un = F[-1] * frac
    cross_un = speed * t[-1] - (F[-1] - F_un) / (stiffness * 1000.0) - hh[-1] * sigma[-1] / E * (1 - frac)
    cross = np.concatenate([speed * t, cross_un])
    cross = np.round(cross / step_mm) * step_mm
    F_all = np.concatenate([F, F_un]) + rng.normal(0.0, noise_N, t.size + t_un.size)
    hk = hh[-1] * (1 + sigma[-1] / E)
    eps_k = math.log(h0 / hk)
    bulge = 0.0683 * eps_k**0.83 * (1 - math.exp(-26.7 * mu**1.53))  # (3.18) at the known μ
    dmax = d0 * math.sqrt(h0 / hk) + 2 * hk * bulge
    meta = {"test": "compression", "material": "synthetic with toe", "nominal_temperature_C": "20",
            "crosshead_speed_mm_per_s": repr(speed), "rig.frame_stiffness_N_per_um": repr(stiffness),
            "specimen.d0_mm": repr(d0), "specimen.h0_mm": repr(h0), "post.hk_mm": f"{hk:.4f}", "post.dmax_mm": f"{dmax:.4f}"}
    if handbook_E:
        meta["material.E_MPa"] = repr(E)
    data = pd.DataFrame({"time_s": np.concatenate([t, t[-1] + t_un]), "force_N": -F_all, "crosshead_mm": -cross})
    i = int(np.searchsorted(eps_p, 0.002))
    r_y = d0 / 2 * math.sqrt(h0 / h[i])
    truth = {"rp02_pressure_MPa": float(flow_stress(0.002, **law) * mean_pressure_factor(mu, np.array([r_y / h[i]]))[0]),
             "elastic_samples": int(np.sum((F > 0.05 * force[i]) & (F < 0.9 * force[i]))), "law": law,
             "springback_mm": float(hh[-1] * sigma[-1] / E)}  # what the unloading gives back
    return Record(meta=meta, data=data, source="synthetic-toe"), truth
