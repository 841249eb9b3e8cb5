"""Synthetic Johnson-Cook series from known constants (4340 steel, Johnson & Cook 1983/1985)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flowcurve.identification.laws.johnson_cook import johnson_cook
from flowcurve.identification.series.series import SeriesMember

# 4340 steel: A 792 MPa, B 510 MPa, n 0.26, C 0.014, m 1.03; T_m 1793 K, reference 1/s and 298 K
TRUE = {"A": 792.0, "B": 510.0, "n": 0.26, "C": 0.014, "m": 1.03}
REF = {"ref_strain_rate_per_s": 1.0, "ref_temperature_C": 298.0 - 273.15, "melt_temperature_C": 1793.0 - 273.15}
TEMPERATURES_C = (REF["ref_temperature_C"], 300.0, 600.0)
RATES_PER_S = (1.0, 100.0)
NOISE_MPa = 2.0  # load-cell-like scatter, absolute


def true_stress(eps_p, rate, temperature_C):
    return johnson_cook(eps_p, rate, temperature_C, **TRUE, **REF)


def synthetic_members(seed: int = 7, noise_MPa: float = NOISE_MPa, points: int = 40,
                      temperatures=TEMPERATURES_C, rates=RATES_PER_S) -> list[SeriesMember]:
    """One curve per (temperature, rate), εp 0.002–0.3, Gaussian noise of ``noise_MPa``."""
    rng = np.random.default_rng(seed)
    members = []
    for T in temperatures:
        for rate in rates:
            eps = np.linspace(0.002, 0.3, points)
            sig = true_stress(eps, rate, T) + rng.normal(0.0, noise_MPa, eps.size)
            members.append(SeriesMember(f"T{T:.0f}C_{rate:g}per_s", eps, sig, rate, T))
    return members


def write_result_folder(folder, member: SeriesMember, *, test="tension", with_rate=True, l0_mm=30.0,
                        friction_mu=None, E_MPa=None, temperature=True):
    """A result folder of 'flowcurve identify' written by hand in the documented format."""
    folder.mkdir(parents=True)
    block = {"path": f"{member.name}.csv", "name": member.name, "test": test, "material": "4340",
             "crosshead_speed_mm_per_s": member.strain_rate_per_s * l0_mm,
             "specimen": {"d0_mm": 6.0, "l0_mm" if test == "tension" else "h0_mm": l0_mm}}
    if temperature:
        block["nominal_temperature_C"] = member.temperature_C
    if with_rate:
        block["strain_rate_per_s"] = member.strain_rate_per_s
    result = {"test": test, "E_MPa": E_MPa, "record": block}
    if friction_mu is not None:
        result["friction_mu"] = friction_mu
    (folder / "result.json").write_text(json.dumps(result), encoding="utf-8")
    lines = ["true_plastic_strain,true_stress_MPa"]
    lines += [f"{e:.8g},{s:.8g}" for e, s in zip(member.plastic_strain, member.stress_MPa)]
    (folder / "true_curve.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return folder


@pytest.fixture
def members():
    return synthetic_members()


@pytest.fixture
def syn():
    """The synthetic-series helpers (test modules cannot import conftest under importlib mode)."""
    from types import SimpleNamespace

    return SimpleNamespace(TRUE=TRUE, REF=REF, members=synthetic_members, true_stress=true_stress,
                           write_result_folder=write_result_folder, tension_record=tension_record)


def tension_record(temperature_C: float, speed_mm_per_s: float, law_rate_per_s: float, *, E_MPa=205_000.0, d0_mm=6.0,
                   l0_mm=30.0, stiffness_N_per_um=136.0, noise_N=0.0, seed=0, source="synthetic.csv", ref_rate_per_s=None):
    """A tension record of a Johnson-Cook 4340 at (temperature, rate), crosshead at constant speed.

    Constant volume up to the force maximum, then the force falls (neck) for a few samples.
    The crosshead includes the frame (P/C); time = crosshead travel / speed. The law is
    evaluated at ``law_rate_per_s`` throughout (reference rate ``ref_rate_per_s``, default REF's). Returns the record and the exact εp(t), so the
    mean plastic strain rate is known in closed form.
    """
    import math

    import pandas as pd

    from flowcurve.record.format import Record

    s0 = math.pi * d0_mm**2 / 4
    ref = {**REF, "ref_strain_rate_per_s": ref_rate_per_s or REF["ref_strain_rate_per_s"]}
    A_T = float(johnson_cook(0.0, law_rate_per_s, temperature_C, **TRUE, **ref))
    sig_el = np.linspace(0.0, A_T, 60, endpoint=False)
    eps_pl = np.linspace(0.0, 0.12, 500)
    sig = np.concatenate([sig_el, johnson_cook(eps_pl, law_rate_per_s, temperature_C, **TRUE, **ref)])
    eps_p = np.concatenate([np.zeros_like(sig_el), eps_pl])
    e = np.expm1(eps_p + sig / E_MPa)
    force = sig * s0 / (1 + e)
    i_m = int(np.argmax(force))
    force, e, eps_p = force[: i_m + 1], e[: i_m + 1], eps_p[: i_m + 1]
    force = np.concatenate([force, np.linspace(force[-1], 0.8 * force[-1], 31)[1:]])
    e = np.concatenate([e, e[-1] + np.linspace(0, 0.03, 31)[1:]])
    cross = e * l0_mm + force / (stiffness_N_per_um * 1000)
    rng = np.random.default_rng(seed)
    data = pd.DataFrame({"time_s": cross / speed_mm_per_s, "force_N": force + rng.normal(0, noise_N, force.size),
                         "crosshead_mm": cross, "temperature_C": temperature_C + rng.normal(0, 0.5, force.size)})
    meta = {"test": "tension", "material": "4340 (synthetic)", "specimen.d0_mm": repr(d0_mm), "specimen.l0_mm": repr(l0_mm),
            "rig.frame_stiffness_N_per_um": repr(stiffness_N_per_um), "crosshead_speed_mm_per_s": repr(speed_mm_per_s),
            "nominal_temperature_C": repr(float(round(temperature_C)))}
    return Record(meta=meta, data=data, source=source), {"time_s": data["time_s"].to_numpy()[: i_m + 1], "eps_p": eps_p}
