"""A synthetic compression record generated from a known flow curve and friction coefficient.

Forward model, independent of the identification code: a Johnson–Cook flow curve
σ_f = A + B·εp^n (the seed's 12Kh18N12M3TL constants), elastic strain σ/E, volume constancy,
and the mean platen pressure of Coulomb friction obtained by integrating the slab pressure
profile p(r) = σ_f·exp(2μ(R − r)/h) numerically over the face (not the closed form that the
identification uses). Then the frame compliance, 10 µm encoder steps and force noise of the
rig, an unloading branch, and the post-test measurements hk (after spring-back) and dmax from
the bulge regression (3.18) at the known μ.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq

from flowcurve.record.format import Record

SEED_LAW = {"A": 105.0, "B": 1392.0, "n": 0.642}
E_HANDBOOK_MPa = 194_000.0  # docs/methods.md table 1.1, 12Kh18N12M3TL


def flow_stress(eps_p, A=105.0, B=1392.0, n=0.642):
    return A + B * np.power(np.clip(eps_p, 0.0, None), n)


def coulomb_mean_pressure_factor(mu: float, r_over_h: np.ndarray) -> np.ndarray:
    """p_mean/σ_f by trapezoidal integration of exp(2μ(R − r)/h) over the disc (2000 rings)."""
    s = np.linspace(0.0, 1.0, 2001)  # r/R
    out = np.empty_like(r_over_h)
    for i, k in enumerate(r_over_h):
        f = np.exp(2 * mu * k * (1 - s)) * 2 * s
        out[i] = np.sum((f[1:] + f[:-1]) / 2 * np.diff(s))
    return out


def make_compression(tmp_path=None, *, mu=0.11, d0=5.989, h0=6.982, hk_target=3.55, speed=0.01, rate_hz=5.0,
                     stiffness=136.0, step_mm=0.01, noise_N=50.0, seed=1, law=SEED_LAW, E=E_HANDBOOK_MPa,
                     meta_extra=None, drop=()):
    """(Record, truth) of a synthetic compression test; ``drop`` removes metadata keys."""
    rng = np.random.default_rng(seed)
    # loaded final height such that the unloaded height is hk_target
    sig_end_guess = flow_stress(math.log(h0 / hk_target), **law)
    h_end = hk_target / (1 + sig_end_guess / E)
    s_end = h0 - h_end
    t_load = np.arange(0.0, s_end / speed, 1.0 / rate_hz)
    s = speed * t_load
    h = h0 - s
    eps = np.log(h0 / h)
    # total strain = plastic + σ_f(εp)/E, elastic below A/E
    eps_p = np.zeros_like(eps)
    for i, e in enumerate(eps):
        if e * E > law["A"]:
            eps_p[i] = brentq(lambda x: x + flow_stress(x, **law) / E - e, 0.0, e, xtol=1e-14)
    sigma = np.where(eps_p > 0, flow_stress(eps_p, **law), E * eps)
    r = d0 / 2 * np.sqrt(h0 / h)
    factor = coulomb_mean_pressure_factor(mu, r / h)
    force = sigma * math.pi * r**2 * factor
    # unloading branch: elastic, force to zero in 20 s
    t_un = np.arange(1, int(20 * rate_hz) + 1) / rate_hz
    frac = 1 - t_un / t_un[-1]
    force_un = force[-1] * frac
    s_un = s[-1] - h[-1] * sigma[-1] / E * (1 - frac)
    time = np.concatenate([t_load, t_load[-1] + t_un])
    F = np.concatenate([force, force_un])
    spec = np.concatenate([s, s_un])
    cross = spec + F / (stiffness * 1000.0)
    cross = np.round(cross / step_mm) * step_mm
    F_meas = F + rng.normal(0.0, noise_N, F.size)
    hk = h[-1] * (1 + sigma[-1] / E)
    eps_k = math.log(h0 / hk)
    d_n = d0 * math.sqrt(h0 / hk)
    bulge = 0.0683 * eps_k**0.83 * (1 - math.exp(-26.7 * mu**1.53))  # (3.18) at the known μ
    dmax = d_n + 2 * hk * bulge
    meta = {
        "test": "compression", "material": "12Kh18N12M3TL (synthetic)", "specimen.id": "synthetic-c1",
        "nominal_temperature_C": "20", "crosshead_speed_mm_per_s": repr(speed),
        "rig.frame_stiffness_N_per_um": repr(stiffness), "specimen.d0_mm": repr(d0), "specimen.h0_mm": repr(h0),
        "post.hk_mm": f"{hk:.4f}", "post.dmax_mm": f"{dmax:.4f}",
    }
    meta.update(meta_extra or {})
    for key in drop:
        meta.pop(key, None)
    # the compression channel as the rig gives it: force and travel negative
    data = pd.DataFrame({"time_s": time, "force_N": -F_meas, "crosshead_mm": -cross})
    truth = {"mu": mu, "law": law, "E": E, "hk": hk, "dmax": dmax, "eps_end": float(np.log(h0 / h[-1])),
             "eps_p_end": float(eps_p[-1]), "sigma_end": float(sigma[-1])}
    return Record(meta=meta, data=data, source="synthetic-c1"), truth


@pytest.fixture(scope="session")
def seed_like_record():
    """The seed's specimen and law at μ = 0.11 (generated once per session)."""
    return make_compression()


@pytest.fixture
def make_record():
    return make_compression
