"""A held-out hot upsetting series in closed form (independent of the identification): 700/800/900 °C ×
0.001/0.01/0.1 1/s at constant true strain rate, 50 Hz.

A Hensel–Spittel material σ = A·e^(m1·T)·(ε0 + εp)^m2·ε̇^m3·e^(m7·εp) (T in °C; ε0 keeps a finite
yield), a cylinder d0 10 × h0 12 mm. The controller holds the specimen's true strain rate: its
height h(t) = h0·e^(−ε̇t), the crosshead v = ε̇·h(t), plus the frame's P/C and an optional seating toe. At 0.1 1/s one
50 Hz sample is 0.002 strain, more than the whole elastic line (σ/E ≈ 0.001): the fast records
have no elastic window. ``mu`` > 0 puts Coulomb friction on the platens (the slab profile and the
bulge of compression_series.py); ``beta`` > 0 heats the specimen adiabatically,
T = T0 + β/(ρc_p)·∫σ dεp, and the law is evaluated at that temperature.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from flowcurve.record.format import Record

from .compression_series import _bulge, _pressure_factor, unload_and_digitise

LAW = {"A": 1800.0, "m1": -0.0028, "m2": 0.18, "m3": 0.13, "m7": -0.35, "eps0": 0.01}
E_MPa = 140_000.0  # one hot modulus, given to the fit (--E)
D0_MM, H0_MM = 10.0, 12.0
STIFFNESS_N_PER_UM = 80.0
DENSITY_KG_PER_M3, HEAT_CAPACITY_J_PER_KG_K = 7850.0, 650.0
SERIES = [(T, r) for T in (700.0, 800.0, 900.0) for r in (0.001, 0.01, 0.1)]


def flow(eps_p, rate, temperature_C):
    """σ (MPa) of the Hensel–Spittel-like law: A·e^(m1·T)·(ε0 + εp)^m2·ε̇^m3·e^(m7·εp)."""
    p = LAW
    eps_p = np.asarray(eps_p, dtype=float)
    return p["A"] * np.exp(p["m1"] * np.asarray(temperature_C)) * (p["eps0"] + eps_p) ** p["m2"] * np.asarray(rate) ** p["m3"] * np.exp(p["m7"] * eps_p)


def hot_record(temperature_C: float, rate_per_s: float, *, rate_hz: float = 50.0, eps_end: float = 0.7, mu: float = 0.0,
               beta: float = 0.0, noise_N: float = 20.0, toe_mm: float = 0.0, toe_force_N: float = 2000.0, step_mm: float = 0.001, seed: int = 0,
               source: str | None = None) -> tuple[Record, dict]:
    """(record, truth): truth holds the fine εp grid, its isothermal stress at the nominal temperature,
    the stress the specimen flowed at (heated when ``beta`` > 0), its temperature and its strain rate."""
    area0 = math.pi * D0_MM**2 / 4.0
    ep = np.concatenate([[0.0], np.geomspace(1e-6, eps_end, 4000)])
    temperature = np.full(ep.size, float(temperature_C))
    for _ in range(30):  # fixed point on the adiabatic temperature: T = T0 + β/(ρc_p)·∫σ dεp
        sig = flow(ep, rate_per_s, temperature)
        work = np.concatenate([[0.0], np.cumsum(0.5 * (sig[1:] + sig[:-1]) * np.diff(ep))])  # MJ/m³
        temperature = temperature_C + beta * work * 1e6 / (DENSITY_KG_PER_M3 * HEAT_CAPACITY_J_PER_KG_K)
    eps = ep + sig / E_MPa
    # the elastic branch, then the plastic one; the specimen's total true strain runs at ε̇: t = ε/ε̇
    s_el = np.linspace(0.0, sig[0], 50, endpoint=False)
    eps_all = np.concatenate([s_el / E_MPa, eps])
    sig_all = np.concatenate([s_el, sig])
    h = H0_MM * np.exp(-eps_all)
    force = sig_all * area0 * H0_MM / h * _pressure_factor(mu, D0_MM / 2.0 * np.sqrt(H0_MM / h) / h)
    seat = toe_mm * (1.0 - np.clip(1.0 - force / toe_force_N, 0.0, 1.0) ** 2)  # a seating toe closing at toe_force_N
    cross = (H0_MM - h) + force / (STIFFNESS_N_PER_UM * 1000.0) + seat
    t_all = eps_all / rate_per_s
    ts = np.append(np.arange(0.0, t_all[-1], 1.0 / rate_hz), t_all[-1])
    f_load, c_load = np.interp(ts, t_all, force), np.interp(ts, t_all, cross)
    ts, F, C = unload_and_digitise(ts, f_load, c_load, springback_mm=h[-1] * sig[-1] / E_MPa, stiffness_N_per_um=STIFFNESS_N_PER_UM,
                                   rate_hz=rate_hz, seconds=2.0, noise_N=noise_N, step_mm=step_mm, seed=seed)
    hk = h[-1] * (1.0 + sig[-1] / E_MPa)
    meta = {"test": "compression", "material": "hot steel (Hensel-Spittel, closed form)", "nominal_temperature_C": repr(temperature_C),
            "rig.frame_stiffness_N_per_um": repr(STIFFNESS_N_PER_UM), "specimen.d0_mm": repr(D0_MM), "specimen.h0_mm": repr(H0_MM),
            "post.hk_mm": f"{hk:.4f}", "post.dmax_mm": f"{D0_MM * math.sqrt(H0_MM / hk) + 2.0 * hk * _bulge(math.log(H0_MM / hk), mu):.4f}"}
    rec = Record(meta=meta, data=pd.DataFrame({"time_s": ts, "force_N": -F, "crosshead_mm": -C}),
                 source=source or f"hot_T{temperature_C:g}_rate{rate_per_s:g}")
    rate = np.gradient(ep, ep / rate_per_s + sig / (E_MPa * rate_per_s))  # dεp/dt with t = (εp + σ/E)/ε̇
    return rec, {"eps_p": ep, "stress_MPa": sig, "isothermal_MPa": flow(ep, rate_per_s, temperature_C),
                 "temperature_C": temperature, "rate_per_s": rate, "nominal_temperature_C": temperature_C}
