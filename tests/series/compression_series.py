"""Coarse, fast Johnson–Cook compression records in closed form (independent of the identification).

The 12Kh18N10T constants of the virtual rig (A 280, B 1215, n 0.43, C 0.031, m 1.0, E 180 GPa,
T_m 1420 °C, reference 20 °C and 0.005 /s), a frictionless cylinder (d0 6, h0 7 mm; μ = 0, so the
mean pressure is the flow stress and dmax the volume-constant diameter). The crosshead runs at
constant speed v = ε̇_nominal·h0: the specimen's true strain rate ε̇ = dε/dt grows as it
shortens (about v/h, doubled by ε = 0.7), and the flow stress of every point is the law at that
point's own rate. With friction (μ > 0) the force factor F/(σ_f·A) and the barrel come from one model,
``response``: ``"fe"`` the CalculiX upsetting runs (the virtual rig's own copy and interpolation,
rig/virtual/fe_response.py, at the law's effective Swift exponent: the relation the product's default
fe_table method inverts, from code of the rig layer), or ``"slab"`` the seed's pair (slab Coulomb
pressure and the (3.18) barrel: the exact mirror of the slab correction and (3.19)). The seed's
barrel is the FE runs' at μ ≈ 0.3, not 0.2 (docs/methods.md §4.9). crosshead = specimen shortening + P/C (136 N/µm) + seating toe (0.02 mm closing
at 600 N); 1 µm steps, 10 N force noise, sampled at ``rate_hz`` and at the stop, then an elastic
unloading. Solved by fixed point on a fine
plastic-strain grid: σ(εp, ε̇) → ε = εp + σ/E → h, P → crosshead → t = crosshead/v → ε̇ = dε/dt.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pandas as pd

from flowcurve.identification.laws.johnson_cook import johnson_cook
from flowcurve.record.format import Record

LAW = {"A": 280.0, "B": 1215.0, "n": 0.43, "C": 0.031, "m": 1.0}
REF = {"ref_strain_rate_per_s": 0.005, "ref_temperature_C": 20.0, "melt_temperature_C": 1420.0}
E_MPa = 180_000.0
D0_MM, H0_MM = 6.0, 7.0


def flow(eps_p, rate, temperature_C):
    return johnson_cook(eps_p, rate, temperature_C, **LAW, **REF)


def compression_record(temperature_C: float, nominal_rate_per_s: float, *, rate_hz: float = 10.0, eps_end: float = 0.7,
                       stiffness_N_per_um: float = 136.0, toe_mm: float = 0.02, toe_force_N: float = 600.0, noise_N: float = 10.0,
                       step_mm: float = 0.001, seed: int = 0, mu: float = 0.0, response: str = "slab",
                       reading_mm: float | None = None) -> tuple[Record, dict]:
    """(record, truth): truth holds the fine εp grid, its stress and its own strain rate ε̇(εp).
    With ``mu`` > 0 the platens carry Coulomb friction, by ``response`` (:func:`force_factor`, :func:`bulge`):
    ``"slab"`` the slab profile σ·exp(2μ(R − r)/h) integrated over the face and dmax the barrel of (3.18);
    ``"fe"`` the CalculiX runs' force factor and barrel at μ. ``reading_mm``: hk and dmax as a micrometer
    of that resolution reads them (rounded), else to 0.1 µm."""
    speed = nominal_rate_per_s * H0_MM  # mm/s
    area0 = math.pi * D0_MM**2 / 4.0
    ep = np.concatenate([[0.0], np.geomspace(1e-6, eps_end, 3000)])
    rate = np.full(ep.size, nominal_rate_per_s)
    for _ in range(8):  # fixed point on the rate
        sig = flow(ep, rate, temperature_C)
        eps = ep + sig / E_MPa
        h = H0_MM * np.exp(-eps)
        force = sig * area0 * H0_MM / h * force_factor(mu, h, response)  # volume constancy
        seat = toe_mm * (1.0 - np.clip(1.0 - force / toe_force_N, 0.0, 1.0) ** 2)
        cross = (H0_MM - h) + force / (stiffness_N_per_um * 1000.0) + seat
        t = cross / speed
        rate = np.gradient(eps, t)
        rate = np.where(np.isfinite(rate) & (rate > 0), rate, nominal_rate_per_s)  # the first point's one-sided difference
    # the elastic branch before yield, at the rate of the first plastic point
    s_el = np.linspace(0.0, sig[0], 200, endpoint=False)
    f_el = s_el * area0 * H0_MM / (H0_MM * np.exp(-s_el / E_MPa))
    c_el = H0_MM * (1.0 - np.exp(-s_el / E_MPa)) + f_el / (stiffness_N_per_um * 1000.0) + toe_mm * (1.0 - np.clip(1.0 - f_el / toe_force_N, 0.0, 1.0) ** 2)
    c_all = np.concatenate([c_el, cross])
    f_all = np.concatenate([f_el, force])
    keep = np.concatenate([[True], np.diff(c_all) > 0])
    c_all, f_all = c_all[keep], f_all[keep]
    ts = np.arange(0.0, c_all[-1] / speed, 1.0 / rate_hz)
    ts = np.append(ts, c_all[-1] / speed)  # the controller logs the stop at the end of the stroke
    f_load = np.interp(ts * speed, c_all, f_all)
    c_load = ts * speed
    ts, F, C = unload_and_digitise(ts, f_load, c_load, springback_mm=h[-1] * sig[-1] / E_MPa, stiffness_N_per_um=stiffness_N_per_um,
                                   rate_hz=rate_hz, seconds=5.0, noise_N=noise_N, step_mm=step_mm, seed=seed)
    sig_end = sig[-1]
    hk = h[-1] * (1.0 + sig_end / E_MPa)
    dmax = D0_MM * math.sqrt(H0_MM / hk) + 2.0 * hk * bulge(math.log(H0_MM / hk), mu, response)
    read = (lambda x: round(x / reading_mm) * reading_mm) if reading_mm else (lambda x: x)  # noqa: E731
    meta = {"test": "compression", "material": "12Kh18N10T (closed form)", "nominal_temperature_C": repr(temperature_C),
            "crosshead_speed_mm_per_s": repr(speed), "rig.frame_stiffness_N_per_um": repr(stiffness_N_per_um),
            "specimen.d0_mm": repr(D0_MM), "specimen.h0_mm": repr(H0_MM), "post.hk_mm": f"{read(hk):.4f}",
            "post.dmax_mm": f"{read(dmax):.4f}"}
    rec = Record(meta=meta, data=pd.DataFrame({"time_s": ts, "force_N": -F, "crosshead_mm": -C}),
                 source=f"T{temperature_C:g}_rate{nominal_rate_per_s * 1000:g}e-3")
    return rec, {"eps_p": ep, "stress_MPa": sig, "rate_per_s": rate, "temperature_C": temperature_C}


RESPONSES = ("slab", "fe")


def force_factor(mu: float, h_mm, response: str = "slab") -> np.ndarray:
    """F/(σ_f·A) at the heights ``h_mm`` (A = π·d0²·h0/(4h)): the slab profile's, or the FE runs' at ε = ln(h0/h)."""
    h = np.asarray(h_mm, dtype=float)
    if response == "fe":
        table, n = _fe_table()
        return table.force_factor_at(mu, H0_MM / D0_MM, n, np.log(H0_MM / h)) if mu > 0 else np.ones_like(h)
    if response != "slab":
        raise ValueError(f"response {response!r}: one of {RESPONSES}")
    return _pressure_factor(mu, D0_MM / 2.0 * np.sqrt(H0_MM / h) / h)


def bulge(eps_k: float, mu: float, response: str = "slab") -> float:
    """ΔR/h of the unloaded specimen at ε = ln(h0/hk): the seed's (3.18), or the FE runs'."""
    if response == "fe":
        table, n = _fe_table()
        return float(table.bulge_at(mu, H0_MM / D0_MM, n, eps_k)) if mu > 0 else 0.0
    if response != "slab":
        raise ValueError(f"response {response!r}: one of {RESPONSES}")
    return _bulge(eps_k, mu)


@functools.lru_cache(maxsize=1)
def _fe_table():
    """(the virtual rig's CalculiX response, the law's effective Swift exponent d ln σ/d ln εp): rate and
    temperature enter Johnson–Cook as factors, so one exponent serves every record."""
    from flowcurve.rig.virtual.fe_response import UpsettingResponse, effective_hardening_exponent

    return UpsettingResponse.load(), effective_hardening_exponent(lambda e: flow(e, REF["ref_strain_rate_per_s"], REF["ref_temperature_C"]))


def unload_and_digitise(ts, f_load, c_load, *, springback_mm: float, stiffness_N_per_um: float, rate_hz: float, seconds: float,
                        noise_N: float, step_mm: float, seed: int):
    """(time s, force N, crosshead mm) of the loading and an elastic unloading in ``seconds``: the force to zero,
    the crosshead back by the frame's F/C and the specimen's ``springback_mm``; force noise, crosshead in ``step_mm``."""
    frac = 1.0 - np.arange(1, int(seconds * rate_hz) + 1) / (seconds * rate_hz)
    f_un = f_load[-1] * frac
    c_un = c_load[-1] - (f_load[-1] - f_un) / (stiffness_N_per_um * 1000.0) - springback_mm * (1.0 - frac)
    ts = np.concatenate([ts, ts[-1] + np.arange(1, frac.size + 1) / rate_hz])
    rng = np.random.default_rng(seed)
    F = np.concatenate([f_load, f_un]) + rng.normal(0.0, noise_N, ts.size)
    return ts, F, np.round(np.concatenate([c_load, c_un]) / step_mm) * step_mm


def _pressure_factor(mu: float, r_over_h: np.ndarray) -> np.ndarray:
    """p_mean/σ_f: trapezoidal integral of exp(2μ(R − r)/h)·2(r/R) over the face."""
    if mu == 0.0:
        return np.ones_like(r_over_h)
    x = np.linspace(0.0, 1.0, 801)
    f = np.exp(2 * mu * np.asarray(r_over_h)[:, None] * (1 - x)[None, :]) * (2 * x)[None, :]
    return np.sum((f[:, 1:] + f[:, :-1]) / 2 * np.diff(x)[None, :], axis=1)


def _bulge(eps_k: float, mu: float) -> float:
    """ΔR/h of the seed's bulge regression (3.18) at μ."""
    return 0.0683 * eps_k**0.83 * (1 - math.exp(-26.7 * mu**1.53)) if mu > 0 else 0.0


SERIES = [(T, r) for T in (20.0, 300.0, 600.0) for r in (0.005, 0.05)]
