"""Compression records at constant true strain rate in closed form, for any flow law σ(εp, ε̇, T)
(independent of the identification; like compression_series.py, which runs the crosshead at constant speed).

A frictionless cylinder (d0 6, h0 7 mm: the mean pressure is the flow stress); the controller holds the
specimen's true strain rate: ε = ε̇·t. crosshead = specimen shortening + P/K (frame) + seating toe
(0.02 mm closing at 600 N); 1 µm steps, force noise, sampled at ``rate_hz`` and at the stop, then an
elastic unloading in 5 s. The elastic branch runs from zero to the law's stress at the first plastic
point; on a fast record it is shorter than one sample.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from flowcurve.record.format import Record

D0_MM, H0_MM = 6.0, 7.0


def constant_rate_record(flow, temperature_C: float, rate_per_s: float, *, E_MPa: float, rate_hz: float = 10.0,
                         eps_end: float = 0.7, stiffness_N_per_um: float = 136.0, toe_mm: float = 0.02, toe_force_N: float = 600.0,
                         noise_N: float = 10.0, step_mm: float = 0.001, seed: int = 0, material: str = "closed form") -> tuple[Record, dict]:
    """(record, truth) of a compression at constant true strain rate; ``flow(eps_p, rate, T)`` in MPa.
    truth holds the fine εp grid and its stress."""
    area0 = math.pi * D0_MM**2 / 4.0
    ep = np.concatenate([[0.0], np.geomspace(1e-6, eps_end, 4000)])
    sig = flow(ep, rate_per_s, temperature_C)
    s_el = np.linspace(0.0, sig[0], 200, endpoint=False)  # the elastic branch before yield
    s_all = np.concatenate([s_el, sig])
    eps = np.concatenate([s_el / E_MPa, ep + sig / E_MPa])  # total true strain
    force = s_all * area0 * np.exp(eps)  # volume constancy: A = A0·h0/h
    seat = toe_mm * (1.0 - np.clip(1.0 - force / toe_force_N, 0.0, 1.0) ** 2)
    cross = H0_MM * (1.0 - np.exp(-eps)) + force / (stiffness_N_per_um * 1000.0) + seat
    t_all = eps / rate_per_s  # ε = ε̇·t
    ts = np.append(np.arange(0.0, t_all[-1], 1.0 / rate_hz), t_all[-1])  # the controller logs the stop
    f_load, c_load = np.interp(ts, t_all, force), np.interp(ts, t_all, cross)
    frac = 1.0 - np.arange(1, int(5 * rate_hz) + 1) / (5 * rate_hz)  # elastic unloading in 5 s
    h_end = H0_MM * math.exp(-eps[-1])
    c_un = cross[-1] - force[-1] * (1.0 - frac) / (stiffness_N_per_um * 1000.0) - h_end * sig[-1] / E_MPa * (1.0 - frac)
    ts = np.concatenate([ts, ts[-1] + np.arange(1, frac.size + 1) / rate_hz])
    rng = np.random.default_rng(seed)
    F = np.concatenate([f_load, force[-1] * frac]) + rng.normal(0.0, noise_N, ts.size)
    C = np.round(np.concatenate([c_load, c_un]) / step_mm) * step_mm
    hk = h_end * (1.0 + sig[-1] / E_MPa)
    meta = {"test": "compression", "material": material, "nominal_temperature_C": repr(temperature_C),
            "rig.frame_stiffness_N_per_um": repr(stiffness_N_per_um), "specimen.d0_mm": repr(D0_MM),
            "specimen.h0_mm": repr(H0_MM), "post.hk_mm": f"{hk:.4f}", "post.dmax_mm": f"{D0_MM * math.sqrt(H0_MM / hk):.4f}"}
    rec = Record(meta=meta, data=pd.DataFrame({"time_s": ts, "force_N": -F, "crosshead_mm": -C}),
                 source=f"T{temperature_C:g}C_rate{rate_per_s * 1000:g}e-3")
    return rec, {"eps_p": ep, "stress_MPa": sig, "temperature_C": temperature_C, "rate_per_s": rate_per_s}
